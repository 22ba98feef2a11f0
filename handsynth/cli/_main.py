"""Root ``handsynth`` command group.

Sub-commands live in their own modules and are registered here.  Every
expected error -- a :class:`handsynth.errors.HandsynthError` from the library
or a bad option or argument that click rejects -- becomes one line on stderr,
``handsynth: error: <what>``, and exit status 2, never a traceback.  Every
warning the library issues while a command runs is one line on stderr as it
comes, ``handsynth: warning: <what>``, also when the command then fails (the
warnings are often what explains the error).  A
sub-command module that cannot be imported is a bug of the installation and
raises (it never silently drops its command).
"""

from __future__ import annotations

import importlib
import sys
import warnings
from contextlib import contextmanager

import click

from ..errors import HandsynthError

#: The sub-command modules (``handsynth/cli/_<name>.py``), each adding itself to ``cli``.
COMMAND_MODULES: tuple[str, ...] = ("demo", "build_db", "estimate", "eval", "measure", "joints", "glove",
                                    "imu")


def _error_line(message: str) -> None:
    click.echo(f"handsynth: error: {message}", err=True)


def _warning_line(message, category, filename, lineno, file=None, line=None) -> None:
    click.echo(f"handsynth: warning: {message}", err=True)


@contextmanager
def _warnings_as_lines():
    """Show every warning, each time, as one ``handsynth: warning:`` line."""
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        warnings.showwarning = _warning_line
        yield


class _Group(click.Group):
    def invoke(self, ctx: click.Context):
        try:
            with _warnings_as_lines():
                return super().invoke(ctx)
        except HandsynthError as exc:
            _error_line(str(exc))
            ctx.exit(2)

    def main(self, *args, **kwargs):
        # click prints usage errors itself (a usage line, a hint and "Error: ...")
        # when standalone; turn them into the one-line style of every other error.
        kwargs["standalone_mode"] = False
        try:
            rv = super().main(*args, **kwargs)
        except click.UsageError as exc:
            where = exc.ctx.command_path if exc.ctx is not None else "handsynth"
            _error_line(f"{where}: {exc.format_message()} (see '{where} --help')")
            sys.exit(2)
        except click.exceptions.Exit as exc:
            sys.exit(exc.exit_code)
        except click.Abort:
            _error_line("aborted")
            sys.exit(1)
        except click.ClickException as exc:
            _error_line(exc.format_message())
            sys.exit(exc.exit_code)
        # standalone_mode=False returns the exit code of ctx.exit(...) as an int
        sys.exit(rv if isinstance(rv, int) else 0)


@click.group(cls=_Group)
@click.version_option(package_name="handsynth")
def cli() -> None:
    """handsynth: synthetic hands, back-of-hand camera pose lookup, sensor methods."""


def _register() -> None:
    # Imported here, after ``cli`` exists, because each module adds itself to it.
    for name in COMMAND_MODULES:
        importlib.import_module(f"{__package__}._{name}")


_register()


def main(argv: list[str] | None = None) -> None:
    """Entry point of the ``handsynth`` console script."""
    cli.main(args=argv if argv is not None else sys.argv[1:], prog_name="handsynth")
