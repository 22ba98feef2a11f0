"""``handsynth measure PHOTO``: measure a hand on a top-down photo and choose its database."""

from __future__ import annotations

import os
import sys
from contextlib import contextmanager
from pathlib import Path

import click

from .._checks import check_path_names
from ..errors import InvalidInputError
from ..render import read_image
from ._main import cli, option_names

#: The option each library argument of this command's errors comes from.
_OPTION_NAMES = {"mm_per_px": "--mm-per-px", "reference_width_mm": "--reference-width-mm",
                 "MeasureOptions.normalize": "--normalize"}


@contextmanager
def _quiet_native_stderr():
    """Silence what C libraries write to the process's standard error (file descriptor 2).

    OpenCV's PNG and JPEG readers print lines of their own (``libpng error:
    Read Error``) for a damaged file before returning nothing; the error
    handsynth raises names the file, in one line.  Python's ``sys.stderr``
    is untouched; where descriptor 2 cannot be duplicated nothing is done.
    """
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError):
        yield
        return
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 2)
        yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)


def _format(result) -> str:
    m = result.measurements
    q = result.selection.ratios
    lines = [f"scale: {result.mm_per_px:.5g} mm/px ({result.scale_source})"]
    for f in result.fingers:
        lengths = " ".join(f"{v:6.1f}" for v in f.segment_lengths_mm)
        widths = " ".join(f"{v:5.1f}" for v in f.widths_mm)
        lines.append(f"{f.name:7s} lengths {lengths:<20s} widths {widths}  (mm)")
    lines.append(f"palm    P_width {m.P_width:.1f}  P_height {m.P_height:.1f}  "
                 f"T_width {m.T_width:.1f}  T_height {m.T_height:.1f}  (mm)")
    lines.append(f"ratios  length {q.length:.3f}  width {q.width:.3f}  palm {q.palm:.3f}  "
                 f"thumb {q.thumb:.3f}  (formulas (1)-(4))")
    lines.append(f"database: {result.selection.name}")
    lines.append(f"model shape: {result.shape.name} (ratios corrected for the photo method; "
                 f"its own database: handsynth estimate --method paper --shape {result.shape.name} "
                 "--personal)")
    return "\n".join(lines)


@cli.command()
@click.argument("photo", type=click.Path(dir_okay=False))
@click.option("--mm-per-px", type=float, default=None,
              help="Scale at the plane of the hand, mm per pixel.")
@click.option("--reference-width-mm", type=float, default=None,
              help="Instead of --mm-per-px: the longer side, in mm, of a reference object "
                   "lying beside the hand (the second-largest object in the photo), e.g. 85.6 "
                   "for a bank card.")
@click.option("--out", type=click.Path(dir_okay=False), default=None,
              help="Write the measurements to FILE.json or FILE.csv (the format "
                   "--measurements of 'handsynth estimate' reads).")
@click.option("--details", type=click.Path(dir_okay=False), default=None,
              help="Write everything found (joints, axes, valleys, wrist, fit quality, the "
                   "selection) to FILE.json.")
@click.option("--annotate", type=click.Path(dir_okay=False), default=None,
              help="Write the photo with what was found drawn on it to FILE.png.")
@click.option("--normalize", type=click.Choice(["none", "palm_width"]), default="none",
              show_default=True,
              help="Normalisation of formulas (1)-(4): 'none' uses true millimetres, "
                   "'palm_width' the paper's scale-free normalisation.")
@click.option("--raw", is_flag=True,
              help="No corrections from the model (MeasureCalibration, ShapeCorrection).")
@option_names(_OPTION_NAMES)
def measure(photo, mm_per_px, reference_width_mm, out, details, annotate, normalize,
            raw) -> None:
    """Measure the open hand on PHOTO and print the database it selects.

    PHOTO shows one open hand, fingers spread, lying flat on a plain
    background, taken from straight above (a forearm may leave the picture
    at the border).  A scale is required: --mm-per-px, or
    --reference-width-mm with a reference object of known size beside the
    hand.
    """
    from .._io import check_output, write_json
    from ..measure import (
        NO_CALIBRATION,
        NO_SHAPE_CORRECTION,
        MeasureOptions,
        annotate_measurement,
        measure_photo,
        write_measurement_file,
    )
    from ..render import write_png

    check_path_names((("PHOTO", photo), ("--out", out), ("--details", details),
                      ("--annotate", annotate)))
    photo = Path(photo)
    out, details, annotate = (None if p is None else Path(p) for p in (out, details, annotate))
    for path, suffixes, name in ((out, (".json", ".csv"), "--out"),
                                 (details, (".json",), "--details"),
                                 (annotate, (".png",), "--annotate")):
        if path is not None and path.suffix.lower() not in suffixes:
            raise InvalidInputError(f"{name} must end in {' or '.join(suffixes)}, "
                                    f"got {str(path)!r}")
    if (mm_per_px is None) == (reference_width_mm is None):
        raise InvalidInputError(
            "give the photo's scale: exactly one of --mm-per-px X (mm per pixel at the hand) "
            "or --reference-width-mm W (the longer side of a reference object beside the hand)")
    outputs = [p for p in (out, details, annotate) if p is not None]
    for path in outputs:  # before the work: a bad name fails now, not after it
        check_output(path, what="output file", inputs=[photo])
    if len({p.resolve() for p in outputs}) < len(outputs):
        raise InvalidInputError("--out, --details and --annotate must be different files")
    with _quiet_native_stderr():  # libpng's own line about a damaged file; the error says it
        image = read_image(photo, what="photo")
    options = MeasureOptions(normalize=normalize)
    if raw:
        options = MeasureOptions(normalize=normalize, calibration=NO_CALIBRATION,
                                 shape_correction=NO_SHAPE_CORRECTION)
    result = measure_photo(image, mm_per_px=mm_per_px, reference_width_mm=reference_width_mm,
                           options=options)
    click.echo(_format(result))
    for w in result.warnings:
        click.echo(f"handsynth: warning: {w}", err=True)
    if out is not None:
        write_measurement_file(out, result.measurements, inputs=[photo])
        click.echo(f"wrote {out}")
    if details is not None:
        # write_json: a non-finite figure becomes null, never a bare NaN token
        write_json(details, result.as_dict(), what="details file", inputs=[photo], indent=1)
        click.echo(f"wrote {details}")
    if annotate is not None:
        write_png(annotate, annotate_measurement(image, result)[..., ::-1], inputs=[photo])
        click.echo(f"wrote {annotate}")
