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

The library names a bad value by its argument or field
(``ProtocolOptions.frames must be ...``); a command whose options are
passed on as such fields says which option each one comes from with
:func:`option_names`, so that its error line names the option the user
typed (``--frames must be ...``).
"""

from __future__ import annotations

import functools
import importlib
import re
import sys
import warnings
from collections.abc import Callable, Mapping
from contextlib import contextmanager

import click

from ..errors import HandsynthError

#: The sub-command modules (``handsynth/cli/_<name>.py``), each adding itself to ``cli``.
COMMAND_MODULES: tuple[str, ...] = ("demo", "build_db", "estimate", "eval", "measure", "joints", "glove",
                                    "imu", "bvh")


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


def renamed_message(message: str, names: Mapping[str, str]) -> str | None:
    """`message` with the library name it starts with replaced by its command-line option.

    Parameters
    ----------
    message : str
        An error's message, e.g. ``"ProtocolOptions.frames must be an integer >= 2,
        got 1"``.
    names : mapping of str to str
        Library argument or field name (``"ProtocolOptions.frames"``,
        ``"count"``) to the option (``"--frames"``).

    Returns
    -------
    str or None
        The message starting with the option instead (an option the library
        already named in brackets after the field, ``EvalOptions.count
        (--count)``, is dropped with it); None when it starts with none of
        `names` (only a whole name counts: ``count`` does not match
        ``counts``).
    """
    for name in sorted(names, key=len, reverse=True):
        m = re.match(re.escape(name) + r"(?: \(--[\w-]+\))?(?=[\s:,]|$)", message)
        if m:
            return names[name] + message[m.end():]
    return None


def input_name(stream) -> str:
    """How messages name a ``click.File`` input: its path, or "standard input" for ``-``."""
    name = getattr(stream, "name", "<stdin>")
    return "standard input" if name == "<stdin>" else str(name)


def option_names(names: Mapping[str, str]) -> Callable:
    """Decorator of a command's function: its errors name the options, not the library's fields.

    A :class:`~handsynth.errors.HandsynthError` raised while the command runs
    whose message starts with one of `names` is raised again, the same
    error, with that name replaced by the command-line option the value came
    from (:func:`renamed_message`); any other error passes unchanged.

    Parameters
    ----------
    names : mapping of str to str
        Library argument or field name to the command-line option.

    Returns
    -------
    callable
        The decorator (place it just above the function, below the click
        decorators).
    """
    def decorate(func: Callable) -> Callable:
        @functools.wraps(func)
        def run(*args, **kwargs):
            try:
                return func(*args, **kwargs)
            except HandsynthError as exc:
                if len(exc.args) == 1 and isinstance(exc.args[0], str):
                    renamed = renamed_message(exc.args[0], names)
                    if renamed is not None:
                        exc.args = (renamed,)
                raise
        return run
    return decorate


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
