"""``handsynth demo``: the main job on an embedded default."""

from __future__ import annotations

from pathlib import Path

import click

from .._checks import check_path_names
from ..db import MAX_LEARNING_HANDS
from ._main import cli, option_names

#: The option each library argument or field of this command's errors comes from.
_OPTION_NAMES = {"tile_width_px": "--tile-width", "LearningSetOptions.hands": "--learned-hands",
                 "ProtocolOptions.frames": "--frames"}


@cli.command()
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default="demo_out",
              show_default=True, help="Folder for the pictures.")
@click.option("--tile-width", type=click.IntRange(64, 1440), default=360, show_default=True,
              help="Width of one picture in pixels.")
@click.option("--frames", type=click.IntRange(0, 10_000), default=200, show_default=True,
              help="Synthetic frames of an off-grid hand to look up in the default database.")
@click.option("--learned-hands", type=click.IntRange(0, MAX_LEARNING_HANDS), default=300, show_default=True,
              help="Random hands of the learned estimator's small demo learning set "
                   "(0: skip that part).")
@option_names(_OPTION_NAMES)
def demo(out_dir: str, tile_width: int, frames: int, learned_hands: int) -> None:
    """Render pictures, build the embedded default database and look up synthetic frames.

    Pictures: the open hand, a fist and a pinch for the smallest and largest
    grid shapes, from the paper mount and the whole-hand mount.  Then the
    standard shape's small default database is built (or verified) in
    OUT/db, and frames of an off-grid hand in paper poses are matched
    against it, plainly and calibrated to the hand's open-hand frame; the
    mean absolute joint-angle error and the rate are printed.  Last, a
    small learned estimator and the shipped perceptrons read the MRTK glTF
    hand beside the constant answer, ``estimates_mrtk.png`` shows four of
    the perceptrons' readings beside the truth, and ``backgrounds_mrtk.png``
    how they tell the hand over photographs, by brightness and by colour.
    """
    import time

    from .._io import make_folder
    from ..models import HandShape
    from ..render import CameraMount, backend, contact_sheet, write_png

    check_path_names([("--out", out_dir)], kind="folder")
    t = time.perf_counter()
    grid = HandShape.grid()
    shapes = {"smallest": grid[0], "largest": grid[-1]}
    folder = make_folder(out_dir, what="--out folder", writable=True)
    for name, mount in (("hands_paper_mount", CameraMount.paper()),
                        ("hands_whole_hand_mount", CameraMount.whole_hand())):
        path = folder / f"{name}.png"
        write_png(path, contact_sheet(shapes, mount=mount, tile_width_px=tile_width))
        click.echo(f"wrote {path}")
    click.echo(f"smallest = {grid[0].name}, largest = {grid[-1].name}; "
               f"MUJOCO_GL={backend()}; {time.perf_counter() - t:.1f} s")
    if frames:
        _lookup_demo(folder / "db", frames)
    if learned_hands:
        _learned_demo(folder, learned_hands, max(frames, 20), tile_width)


def _learned_demo(out_dir: Path, hands: int, frames: int, tile_width: int) -> None:
    import time

    from ..db import LearningSetOptions
    from ..estimate import LEARNED_PERCEPTRONS, EnsembleEstimator, shipped_members
    from ..eval import (
        ProtocolOptions,
        backgrounds_sheet,
        estimates_sheet,
        format_headline,
        mesh_test_hands,
        protocol_headline,
        protocol_methods,
        run_protocol,
    )
    from ..render import write_png

    folder = out_dir / "learned"
    t = time.perf_counter()
    methods = protocol_methods(["fingers"], folder, data=LearningSetOptions(hands=hands))
    click.echo(f"learned estimator ({hands} hands x 100 frames) ready in "
               f"{time.perf_counter() - t:.1f} s in {folder}")
    shipped_ones = shipped_members(members=LEARNED_PERCEPTRONS)
    if shipped_ones and len(shipped_ones) == len(LEARNED_PERCEPTRONS):
        shipped = EnsembleEstimator(shipped_ones, weights=[w for _o, w, _c in LEARNED_PERCEPTRONS])
        methods["perceptrons"] = lambda rest, hand: shipped.calibrated(rest)
        click.echo(f"also read: the default ensemble's {len(shipped_ones)} perceptrons, shipped "
                   "with handsynth (`perceptrons`: their mean, `--learned-kind perceptrons`)")
    else:
        shipped = None
        click.echo("the perceptrons shipped with handsynth are missing or damaged: skipped")
    result = run_protocol(methods, mesh_test_hands(["mrtk"]), ProtocolOptions(frames=frames))
    click.echo(f"learned estimators on {frames} frames of the MRTK glTF hand per pose set, "
               "beside the constant open-hand answer (the full evaluation: handsynth eval "
               "--protocol):")
    click.echo(format_headline(protocol_headline(result)))
    if shipped is not None:
        for name, sheet in (("estimates_mrtk", estimates_sheet), ("backgrounds_mrtk", backgrounds_sheet)):
            path = write_png(out_dir / f"{name}.png", sheet(shipped, tile_width_px=tile_width))
            click.echo(f"wrote {path}")


def _lookup_demo(db_dir: Path, frames: int) -> None:
    import time

    import numpy as np

    from ..db import build_default_database
    from ..estimate import PoseLookup
    from ..models import HandShape, paper_pose_set
    from ..render import SilhouetteRenderer

    t = time.perf_counter()
    path = build_default_database(db_dir)
    click.echo(f"default database {path} ready in {time.perf_counter() - t:.1f} s")
    lookup = PoseLookup.open(db_dir, shape=HandShape())
    user = HandShape(length=1.02, width=0.97, palm=1.01, thumb=1.03)  # off the grid
    poses = paper_pose_set(frames, seed=12345)
    with SilhouetteRenderer(user, lookup.mount) as r:
        masks = r.masks(poses)
        open_mask = r.mask(np.zeros(len(poses[0])))
    click.echo("the paper's lookup on poses from its database's own generator (the paper's "
               "experiment, which flatters it; handsynth eval --protocol does not):")
    _report(f"looked up {frames} frames of hand {user.name}", lookup, masks, poses)
    calibrated = lookup.calibrated(open_mask)
    calibration = calibrated.calibration
    assert calibration is not None  # calibrated() always sets one
    ignored = int(calibration.ignore.sum())
    _report(f"calibrated to its open hand ({ignored} pixels ignored)", calibrated, masks, poses)


def _report(what: str, lookup, masks, poses) -> None:
    import numpy as np

    from ..eval import lookup_errors

    r = lookup_errors(lookup, masks, poses)
    click.echo(f"{what}: {r['frames_per_s']:.0f} frames/s, mean absolute error {r['mae_deg']:.2f} "
               f"deg (index PIP {r['index_pip_mae_deg']:.2f}, thumb CMC flex "
               f"{r['thumb_cmc_flex_mae_deg']:.2f}); the open hand answered on every frame: "
               f"{np.abs(poses).mean():.2f} deg")
