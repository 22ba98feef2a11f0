"""``handsynth bvh ANGLES -o OUT.bvh``: joint angles as a BVH motion file."""

from __future__ import annotations

import click

from .._checks import check_path_names
from .._io import check_outputs
from ..errors import InvalidInputError
from ._hand import hand_shape
from ._main import cli, option_names

#: The option each library argument of this command's errors comes from.
_OPTION_NAMES = {"rate_hz": "--rate"}


@cli.command("bvh")
@click.argument("angles", type=click.Path(dir_okay=False))
@click.option("-o", "--out", "out_path", required=True, type=click.Path(dir_okay=False),
              help="The .bvh file to write.")
@click.option("--rate", "rate_hz", type=float, default=None, metavar="HZ",
              help="Frames per second of the file: the angles are resampled to it [default: "
                   "the rows' median rate; needed where the file has no time_s or "
                   "timestamp_s column].")
@click.option("--shape", "shape_name", default=None, metavar="NAME",
              help="The hand whose skeleton carries the angles (e.g. "
                   "L1.050_W0.900_P1.000_T1.000, or 'standard') [default: standard].")
@click.option("--measurements", default=None, metavar="FILE",
              help="Hand measurements in mm (.json or .csv): the skeleton of the nearest "
                   "handsynth hand.")
@click.option("--side", type=click.Choice(["right", "left"]), default="right",
              show_default=True)
@click.option("--units", type=click.Choice(["cm", "mm", "m"]), default="cm", show_default=True,
              help="Unit of the skeleton's offsets.")
@option_names(_OPTION_NAMES)
def bvh_command(angles, out_path, rate_hz, shape_name, measurements, side, units) -> None:
    """Write the joint angles of ANGLES as a BVH motion file on the handsynth hand.

    ANGLES is a CSV or JSON Lines file with the 20 joint columns (degrees) as
    ``estimate --out``, ``imu track --angles-out`` and ``glove apply`` write them. Frames
    without angles (no hand in view) take the angles of the frames either side, with a
    warning. The root is the hand frame (+y toward the middle finger, +z out of the back of
    the hand); BVH is the motion format of animation and motion-capture tools.
    """
    from ..models import TIME_COLUMNS, read_angle_table, write_bvh

    check_path_names([("ANGLES", angles), ("--out", out_path)])
    check_outputs([("--out", out_path)], inputs=[angles])
    shape = hand_shape(shape_name, measurements)
    table = read_angle_table(angles)
    if table.times_s is None and rate_hz is None:
        raise InvalidInputError(f"{angles}: no time column ({' or '.join(TIME_COLUMNS)}): give "
                                "the frame rate with --rate HZ")
    values, rate = table.resampled(rate_hz)
    write_bvh(out_path, values, rate_hz=rate, shape=shape, side=side, units=units,
              inputs=[angles])
    click.echo(f"{len(values)} frames at {rate:g} Hz on the handsynth {side} hand "
               f"{shape.name} -> {out_path}")
