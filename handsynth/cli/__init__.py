"""The ``handsynth`` command line: it parses arguments and calls the library."""

from __future__ import annotations

import sys

__all__ = ["main"]


def main(argv: list[str] | None = None) -> None:
    """Entry point of the ``handsynth`` console script.

    The commands and the library behind them (numpy, MuJoCo, OpenCV: about a second) are
    imported here rather than when the script starts, so that Ctrl-C while they load ends
    the command as Ctrl-C while it runs does: ``handsynth: error: aborted`` and exit
    status 1, not a traceback.

    Parameters
    ----------
    argv : list of str, optional
        The arguments after the program's name; ``sys.argv[1:]`` by default.
    """
    try:
        from ._main import main as run
    except KeyboardInterrupt:
        sys.stderr.write("\nhandsynth: error: aborted\n")
        raise SystemExit(1) from None
    run(argv)
