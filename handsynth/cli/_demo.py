"""``handsynth demo``: the main job on an embedded default."""

from __future__ import annotations

from pathlib import Path

import click

from ._main import cli


@cli.command()
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path),
              default=Path("demo_out"), show_default=True, help="Folder for the pictures.")
@click.option("--tile-width", type=click.IntRange(64, 1440), default=360, show_default=True,
              help="Width of one picture in pixels.")
@click.option("--frames", type=click.IntRange(0, 10_000), default=200, show_default=True,
              help="Synthetic frames of an off-grid hand to look up in the default database.")
@click.option("--learned-hands", type=click.IntRange(0, 100_000), default=300, show_default=True,
              help="Random hands of the learned estimator's small demo learning set "
                   "(0: skip that part).")
def demo(out_dir: Path, tile_width: int, frames: int, learned_hands: int) -> None:
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

    from ..models import HandShape
    from ..render import CameraMount, backend, contact_sheet, write_png

    t = time.perf_counter()
    grid = HandShape.grid()
    shapes = {"smallest": grid[0], "largest": grid[-1]}
    out_dir.mkdir(parents=True, exist_ok=True)
    for name, mount in (("hands_paper_mount", CameraMount.paper()),
                        ("hands_whole_hand_mount", CameraMount.whole_hand())):
        path = out_dir / f"{name}.png"
        write_png(path, contact_sheet(shapes, mount=mount, tile_width_px=tile_width))
        click.echo(f"wrote {path}")
    click.echo(f"smallest = {grid[0].name}, largest = {grid[-1].name}; "
               f"MUJOCO_GL={backend()}; {time.perf_counter() - t:.1f} s")
    if frames:
        _lookup_demo(out_dir / "db", frames)
    if learned_hands:
        _learned_demo(out_dir, learned_hands, max(frames, 20), tile_width)


def _learned_demo(out_dir: Path, hands: int, frames: int, tile_width: int) -> None:
    import time

    from ..db import LearningSetOptions
    from ..estimate import LEARNED_PERCEPTRONS, EnsembleEstimator, shipped_members
    from ..eval import (
        ProtocolOptions,
        format_headline,
        mesh_test_hands,
        protocol_headline,
        protocol_methods,
        run_protocol,
    )

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
        path = out_dir / "estimates_mrtk.png"
        _estimates_picture(path, shipped, tile_width)
        click.echo(f"wrote {path}")
        path = out_dir / "backgrounds_mrtk.png"
        _backgrounds_picture(path, shipped, tile_width)
        click.echo(f"wrote {path}")


def _estimates_picture(path: Path, estimator, tile_width: int, count: int = 4) -> None:
    """What `estimator` reads on the MRTK glTF hand: the device's view, the truth and the reading.

    Natural poses from a relaxed rest (the protocol's generators); columns are
    frames; rows show the mesh hand as the device sees it, and from the thumb
    side at the true angles and at the estimated ones.
    """
    import cv2
    import numpy as np

    from ..eval import JOINT_GROUPS, natural_test_poses, relaxed_rest_posture
    from ..render import CameraMount, label_image, write_png
    from ..testhands import MeshHandRenderer, shipped_hand_path

    flex = list(JOINT_GROUPS["finger_flexion"])
    mount = CameraMount.paper()
    th = round(tile_width * mount.height_px / mount.width_px)
    rng = np.random.default_rng(7)
    rest = relaxed_rest_posture(rng)
    poses = natural_test_poses(rest, count, rng)[0]
    hand = shipped_hand_path("mrtk")
    with MeshHandRenderer(mount, path=hand) as full:
        reader = estimator.calibrated(full.mask(rest))
        got = [reader.estimate(m).angles for m in full.masks(poses)]
    rows: list[list[np.ndarray]] = [[], [], []]
    with MeshHandRenderer(mount, width_px=tile_width, height_px=th, path=hand) as mesh:
        for i, (truth, est) in enumerate(zip(poses, got)):
            mae = float(np.abs(est[flex] - truth[flex]).mean())
            rows[0].append(label_image(mesh.render_rgb(truth), f"frame {i + 1}: the device's view"))
            rows[1].append(label_image(mesh.render_rgb(truth, camera="side"), "true angles, side view"))
            rows[2].append(label_image(mesh.render_rgb(est, camera="side"),
                                       f"estimated: flexion error {mae:.1f} deg"))
    sheet = np.vstack([np.hstack(r) for r in rows])
    write_png(path, cv2.copyMakeBorder(sheet, 2, 2, 2, 2, cv2.BORDER_CONSTANT, value=(255, 255, 255)))


def _backgrounds_picture(path: Path, estimator, tile_width: int, count: int = 4) -> None:
    """The MRTK glTF hand over photographs, told by brightness and by the skin's colour.

    Natural poses from a relaxed rest, the hand painted in a shaded skin
    colour over photographs bundled with scikit-image (the rest frame over
    one too); columns are frames; rows show the frame, the hand as Otsu's
    threshold tells it and as the skin's colour tells it, each with the
    flexion error of `estimator` calibrated that way.
    """
    import cv2
    import numpy as np

    from ..eval import JOINT_GROUPS, background_photos, natural_test_poses, relaxed_rest_posture
    from ..render import (
        CameraMount,
        binarize,
        label_image,
        skin_mask,
        write_png,
    )
    from ..testhands import MeshHandRenderer, shipped_hand_path

    flex = list(JOINT_GROUPS["finger_flexion"])
    mount = CameraMount.paper()
    th = round(tile_width * mount.height_px / mount.width_px)
    photos = background_photos()
    rng = np.random.default_rng(11)
    rest = relaxed_rest_posture(rng)
    poses = natural_test_poses(rest, count, rng)[0]
    shade = np.linspace(0.55, 1.0, mount.width_px, dtype=np.float32)[None, :, None]
    skin = np.array([95, 125, 180], np.float32)  # BGR

    def paint(mask, photo):
        f = photo.astype(np.float32)
        f[mask] = (skin * shade * np.ones_like(f))[mask]
        return np.clip(f + rng.normal(0.0, 4.0, f.shape), 0, 255).astype(np.uint8)

    with MeshHandRenderer(mount, path=shipped_hand_path("mrtk")) as full:
        rest_frame = paint(full.mask(rest), photos[-1])
        frames = [paint(m, photos[i % (len(photos) - 1)]) for i, m in enumerate(full.masks(poses))]
    readers = {"brightness": estimator.calibrated(rest_frame, segment="brightness"),
               "colour": estimator.calibrated(rest_frame, segment="colour")}
    colour = readers["colour"].members[0].skin  # the skin its members tell the hand by

    def tile(image):  # the label's strip darkened, so that white text reads on white
        out = cv2.resize(image, (tile_width, th), interpolation=cv2.INTER_AREA)
        out[:24] //= 3
        return out

    rows: list[list[np.ndarray]] = [[], [], []]
    for i, (truth, frame) in enumerate(zip(poses, frames)):
        rows[0].append(label_image(tile(frame[..., ::-1]), f"frame {i + 1} over a photograph"))
        told = {"brightness": binarize(frame),
                "colour": skin_mask(frame, colour)}
        for r, (how, mask) in enumerate(told.items(), start=1):
            mae = float(np.abs(readers[how].estimate(frame).angles[flex] - truth[flex]).mean())
            grey = np.repeat(tile(mask.view(np.uint8) * 255)[..., None], 3, axis=2)
            rows[r].append(label_image(grey, f"by {how}: flexion error {mae:.1f} deg"))
    sheet = np.vstack([np.hstack(r) for r in rows])
    write_png(path, cv2.copyMakeBorder(sheet, 2, 2, 2, 2, cv2.BORDER_CONSTANT, value=(255, 255, 255)))


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
    _report(f"looked up {frames} frames of hand {user.name}", lookup, masks, poses)
    calibrated = lookup.calibrated(open_mask)
    calibration = calibrated.calibration
    assert calibration is not None  # calibrated() always sets one
    ignored = int(calibration.ignore.sum())
    _report(f"calibrated to its open hand ({ignored} pixels ignored)", calibrated, masks, poses)


def _report(what: str, lookup, masks, poses) -> None:
    import time

    import numpy as np

    if len(masks):
        lookup.estimate(masks[0])  # compiles the search on a fresh install; not timed
    t = time.perf_counter()
    est = np.array([lookup.estimate(m).angles for m in masks])
    dt = time.perf_counter() - t
    err = np.abs(est - poses)
    click.echo(f"{what}: {len(masks) / dt:.0f} frames/s, mean absolute error {err.mean():.2f} "
               f"deg (index PIP {err[:, 6].mean():.2f}, thumb CMC flex {err[:, 0].mean():.2f})")
