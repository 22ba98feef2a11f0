"""``handsynth build-db``: build the per-shape pose databases (resumable, parallel)."""

from __future__ import annotations

import sys

import click

from .._checks import check_path_names
from .._cores import usable_cores
from ..errors import InvalidInputError
from ._main import cli, option_names

_BAR = 24

#: The option each library argument of this command's errors comes from.
_OPTION_NAMES = {"count": "--count", "seed": "--seed", "render_size": "--render-size",
                 "workers": "--workers", "side": "--side", "pose_set": "--pose-set",
                 "executor": "--executor", "shapes": "--shapes"}


def _parse_shapes(text: str):
    from ..models import HandShape

    text = text.strip()
    if text == "all":
        return HandShape.grid()
    if text == "standard":
        return [HandShape()]
    names = [t.strip() for t in text.split(",") if t.strip()]
    if not names:
        raise InvalidInputError(
            f"--shapes must be 'all', 'standard' or comma-separated shape names, got {text!r}")
    return [HandShape() if n == "standard" else HandShape.from_name(n) for n in names]


def _parse_size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise InvalidInputError(
            f"--render-size must be WIDTHxHEIGHT in pixels, e.g. 240x160, got {text!r}") from None
    return w, h


def _fmt_s(seconds: float | None) -> str:
    if seconds is None:
        return "--:--"
    s = round(seconds)
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}" if s >= 3600 else f"{s // 60}:{s % 60:02d}"


def _progress_line(p) -> str:
    filled = round(p.fraction * _BAR)
    return (f"[{'#' * filled}{'-' * (_BAR - filled)}] {100 * p.fraction:5.1f}% "
            f"{p.entries_done}/{p.entries_total} entries, {p.shapes_done}/{p.shapes_total} shapes, "
            f"{p.rate:.0f} entries/s, elapsed {_fmt_s(p.elapsed_s)}, ETA {_fmt_s(p.eta_s)}")


def _printer(stream):
    def show(p) -> None:
        stream.write("\r" + _progress_line(p))
        if p.finished:
            stream.write("\n")
        stream.flush()

    return show


@cli.command("build-db")
@click.option("--out", "out_dir", type=click.Path(file_okay=False), required=True,
              help="Output folder (one <shape>.h5 per hand shape).")
@click.option("--default", "default", is_flag=True,
              help="Build the small default database (standard shape, 3000 paper poses) "
                   "used by the demo; other database options are ignored.")
@click.option("--shapes", default="all", show_default=True,
              help="'all' (the 81 grid shapes), 'standard', or comma-separated names "
                   "such as L1.000_W0.900_P1.050_T1.000.")
@click.option("--pose-set", type=click.Choice(["paper", "natural"]), default="paper",
              show_default=True)
@click.option("--count", type=int, default=20448, show_default=True, help="Poses per shape.")
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of the pose set.")
@click.option("--side", type=click.Choice(["right", "left"]), default="right", show_default=True)
@click.option("--mount", type=click.Choice(["paper", "whole-hand"]), default="paper",
              show_default=True, help="Camera mount.")
@click.option("--render-size", default=None,
              help="WIDTHxHEIGHT of the masks before preprocessing [default: 720x480].")
@click.option("--workers", type=int, default=None,
              help="Worker processes [default: all cores].")
@click.option("--executor", type=click.Choice(["process", "ray"]), default="process",
              show_default=True, help="Local process pool, or Ray (pip install handsynth[ray]).")
@click.option("--force", is_flag=True, help="Rebuild files that already verify.")
@click.option("--quiet", "-q", is_flag=True, help="No progress line.")
@option_names(_OPTION_NAMES)
def build_db(out_dir, default, shapes, pose_set, count, seed, side, mount, render_size,
             workers, executor, force, quiet) -> None:
    """Build the pose databases, one HDF5 file per hand shape.

    Resumable: files that verify (complete, checksum, same parameters) are
    kept, broken or mismatching ones are rebuilt.  Same seed, same bytes.
    """
    from ..db import (
        DEFAULT_RENDER_SIZE,
        BuildOptions,
        build_databases,
        build_default_database,
    )
    from ..render import CameraMount

    check_path_names([("--out", out_dir)], kind="folder")
    if workers is not None and workers < 1:
        raise InvalidInputError(f"--workers must be a positive integer, got {workers}")
    show = None if quiet else _printer(sys.stderr)
    if default:
        path = build_default_database(out_dir, workers=workers, progress=show)
        click.echo(f"default database: {path}")
        return
    options = BuildOptions(side=side, pose_set=pose_set, count=count, seed=seed,
                           render_size=_parse_size(render_size) if render_size is not None
                           else DEFAULT_RENDER_SIZE)
    cam = CameraMount.paper() if mount == "paper" else CameraMount.whole_hand()
    summary = build_databases(out_dir, _parse_shapes(shapes), cam, options=options,
                              workers=usable_cores() if workers is None else workers,
                              executor=executor, force=force, progress=show)
    click.echo(summary.format())
