"""Root ``handsynth`` command group.

Sub-commands live in their own modules and are registered here.  Expected
errors (:class:`handsynth.errors.HandsynthError`) become one line on stderr
and exit status 2, never a traceback.
"""

from __future__ import annotations

import sys

import click

from ..errors import HandsynthError


class _Group(click.Group):
    def invoke(self, ctx: click.Context):
        try:
            return super().invoke(ctx)
        except HandsynthError as exc:
            click.echo(f"handsynth: error: {exc}", err=True)
            ctx.exit(2)


@click.group(cls=_Group)
@click.version_option(package_name="handsynth")
def cli() -> None:
    """handsynth: synthetic hands, back-of-hand camera pose lookup, sensor methods."""


def _register() -> None:
    # Each sub-command module adds itself to ``cli``; imported lazily here so
    # that ``handsynth --help`` stays fast.
    import importlib

    for mod in ("demo", "build_db", "estimate", "eval", "measure", "joints"):
        try:
            importlib.import_module(f"{__package__}._{mod}")
        except ModuleNotFoundError as exc:  # sub-command not written yet
            if exc.name != f"{__package__}._{mod}":
                raise


_register()


def main(argv: list[str] | None = None) -> None:
    """Entry point of the ``handsynth`` console script."""
    cli.main(args=argv if argv is not None else sys.argv[1:], prog_name="handsynth")
