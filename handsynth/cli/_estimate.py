"""``handsynth estimate``: the live loop (camera, video file or a synthetic hand) of the learnt
estimator, or with ``--method paper`` of the paper's database lookup."""

from __future__ import annotations

import math
import sys
import warnings
from pathlib import Path

import click

from .._checks import check_path_names
from .._io import check_outputs
from ..errors import EstimationError, InvalidInputError, InvalidShapeError
from ..render import read_image
from ._hand import about_measurements, hand_options, hand_shape, shape_option
from ._main import cli

#: Off-grid hand rendered by ``--synthetic`` unless ``--synthetic-shape`` says otherwise.
SYNTHETIC_SHAPE = "L1.02_W0.97_P1.01_T1.03"
#: Frames of a ``--synthetic`` run without ``--frames`` or ``--seconds``.
SYNTHETIC_FRAMES = 300
#: Reads ``--calibrate`` waits for a frame showing a hand from a camera (10 s at 30 fps).
CALIBRATION_READS = 300
#: Reads a ``--video`` is searched for the rest frame: the whole file (it ends), so that a
#: recording where the hand comes into view after 10 s still calibrates.
VIDEO_CALIBRATION_READS = 1_000_000_000
#: Frames of the source that read as unlike any hand learnt, each skipped as the learnt
#: estimator's rest frame, before the next is taken anyway (with a warning): a hand at rest
#: over a cluttered ground can itself read so.  1 s at 30 fps.
REST_FRAME_PATIENCE = 30
#: Frame rates ``--fps`` accepts, frames per second (a camera reports at most 10,000).
FPS_RANGE = (0.01, 10_000.0)


def _parse_size(text: str, flag: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise InvalidInputError(f"{flag} must be WIDTHxHEIGHT in pixels, e.g. 720x480, "
                                f"got {text!r}") from None
    if w < 8 or h < 8:
        raise InvalidInputError(f"{flag} must be at least 8x8 pixels, got {text!r}")
    if w > 4096 or h > 4096:
        raise InvalidInputError(f"{flag} must be at most 4096x4096 pixels, got {text!r}")
    return w, h


def _replayed_angles(path, fps):
    """The joint angles of ``--synthetic-angles`` FILE at ``--fps``, each frame's pose."""
    import numpy as np

    from ..models import JOINT_LIMITS_DEG, JOINT_NAMES, TIME_COLUMNS, read_angle_table

    table = read_angle_table(path)  # --fps was checked with the other limits
    if table.times_s is None:
        click.echo(f"{path}: no time column ({' or '.join(TIME_COLUMNS)}): one row per frame "
                   f"at --fps {fps:g}", err=True)
    angles, _ = table.resampled(fps)
    if len(angles) < 2:
        raise InvalidInputError(f"--synthetic-angles {path}: {len(angles)} frame at --fps "
                                f"{fps:g}; a replay needs 2 or more")
    lo, hi = JOINT_LIMITS_DEG[:, 0], JOINT_LIMITS_DEG[:, 1]
    beyond = (angles < lo) | (angles > hi)
    if beyond.any():  # another system's readings may pass the model's ranges of motion
        names = [JOINT_NAMES[j] for j in np.flatnonzero(beyond.any(axis=0))]
        click.echo(f"handsynth: warning: --synthetic-angles {path}: {int(beyond.any(axis=1).sum())}"
                   f" of {len(angles)} frames beyond the hand's range of motion "
                   f"({', '.join(names)}); shown at the range's end", err=True)
    return np.clip(angles, lo, hi)


def _check_limits(frames, seconds, max_dead, fps) -> None:
    if frames is not None and frames < 0:
        raise InvalidInputError(f"--frames must be a non-negative integer, got {frames}")
    if seconds is not None and not 0 < seconds < math.inf:
        raise InvalidInputError(f"--seconds must be a positive finite number, got {seconds}")
    if max_dead < 1:
        raise InvalidInputError(f"--max-dead must be a positive integer, got {max_dead}")
    if not 0 < fps < math.inf:
        raise InvalidInputError(f"--fps must be a positive finite number, got {fps}")
    if not FPS_RANGE[0] <= fps <= FPS_RANGE[1]:
        # 1e-310 made the media time infinite (an OverflowError traceback), 1e-300 wrote
        # timestamps of 1e300 s, and above a million every timestamp rounds to the same
        raise InvalidInputError(f"--fps must be within [{FPS_RANGE[0]:g}, {FPS_RANGE[1]:g}] "
                                f"frames per second, got {fps:g}")


def _check_db_folder(db_dir) -> None:
    """--db must be a folder (the library's message would say it does not exist)."""
    from ..errors import DatabaseError

    path = Path(db_dir)
    if path.exists() and not path.is_dir():
        raise DatabaseError(f"--db {str(path)!r} is a file; give the folder that holds the "
                            "<shape>.h5 databases (e.g. --db dbs)")


def _open_lookup(db_dir, shape_name, measurements, temporal, err, personal=False, build=None,
                 side="right"):
    import time

    from ..estimate import PoseLookup, SelectionOptions, select_shape
    from ..live import default_database_dir

    shape, meas = hand_options(shape_name, measurements)
    if personal:
        if shape is None and meas is None:
            raise InvalidInputError("--personal needs --shape NAME or --measurements FILE")
        t = time.perf_counter()
        try:
            lookup = PoseLookup.personal(db_dir or default_database_dir(), shape=shape,
                                         measurements=meas, build=build, temporal=temporal)
        except InvalidShapeError as exc:
            if measurements is None:
                raise
            raise about_measurements(exc, measurements) from None
        click.echo(f"personal database {lookup.database.path} ready in "
                   f"{time.perf_counter() - t:.1f} s", err=err)
        return lookup
    # a measurement file is in millimetres: chosen as `measure` and --personal choose, on
    # the ratios as measured (the paper's palm-width scaling is for photos without a scale)
    selection = SelectionOptions(normalize="none") if meas is not None else None
    if meas is not None:  # values that give no hand (centimetres read as mm) fail before a build
        try:
            select_shape(meas, options=selection)
        except InvalidShapeError as exc:
            raise about_measurements(exc, measurements) from None
    if db_dir is None:
        from ..db import build_default_database

        db_dir = default_database_dir()
        t = time.perf_counter()
        path = build_default_database(db_dir, side=side)
        click.echo(f"default database {path} ready in {time.perf_counter() - t:.1f} s", err=err)
    else:
        _check_db_folder(db_dir)  # names the option; the library names the file
    try:
        return PoseLookup.open(db_dir, shape=shape, measurements=meas, temporal=temporal,
                               side=side, selection=selection)
    except InvalidShapeError as exc:  # values that give no hand (centimetres read as mm)
        if measurements is None:
            raise
        raise about_measurements(exc, measurements) from None


def _calibration_frame(source, image, mount, side, err, *, synthetic: str, prompt: str,
                       accept=None):
    """The calibration frame and where it came from: `image`, the synthetic hand, or the
    source's first frame showing a hand that `accept` (if given) takes (after telling the
    user `prompt`)."""
    from ..live import VideoSource, first_hand_frame

    if image is not None:
        return image, "the calibration image"
    if hasattr(source, "open_frame"):
        return source.open_frame(), synthetic
    click.echo(f"calibrating: {prompt}", err=err)
    reads = VIDEO_CALIBRATION_READS if isinstance(source, VideoSource) else CALIBRATION_READS
    return (first_hand_frame(source, mount=mount, side=side, max_reads=reads, accept=accept),
            "the first frame showing a hand")


def _calibrate(lookup, source, open_image, db_dir, mount, side, build, err):
    """The lookup calibrated to the open hand: `open_image`, or the source's first hand."""
    import time

    from ..estimate import PoseLookup
    from ..live import default_database_dir

    open_frame, where = _calibration_frame(source, open_image, mount, side, err,
                                           synthetic="the synthetic hand held open",
                                           prompt="hold the hand open and flat")
    t = time.perf_counter()
    if lookup is None:
        lookup = PoseLookup.from_open_frame(db_dir or default_database_dir(), open_frame,
                                            mount=mount, build=build)
    else:
        lookup = lookup.calibrated(open_frame)
    cal = lookup.calibration
    click.echo(f"calibrated to {where} in {time.perf_counter() - t:.1f} s: database "
               f"{lookup.database.path.name}, open-hand IoU {cal.open_iou:.3f}, "
               f"{int(cal.ignore.sum())} of {cal.ignore.size} pixels ignored", err=err)
    return lookup


def _check_learned_options(db_dir, shape_name, measurements, personal, build_count,
                           calibrate, no_temporal, keypoints) -> None:
    """The learnt estimator (the default method) replaces the database lookup: its options do
    not apply (but for --shape and --measurements, which with --keypoints say whose keypoints
    to report)."""
    given = [flag for flag, on in (("--db", db_dir is not None),
                                   ("--personal", personal),
                                   ("--build-count", build_count is not None),
                                   ("--calibrate", calibrate), ("--no-temporal", no_temporal))
             if on]
    if given:
        raise InvalidInputError(f"{', '.join(given)} appl{'ies' if len(given) == 1 else 'y'} to "
                                "the paper's database lookup (--method paper), not to the "
                                "learnt estimator, the default (it is calibrated to the hand "
                                "at rest; --calibrate-image gives that frame)")
    if not keypoints and (shape_name is not None or measurements is not None):
        flag = "--shape" if shape_name is not None else "--measurements"
        raise InvalidInputError(f"{flag} with the learnt estimator (the default method) says "
                                "whose keypoints to report, and --keypoints was not given (it "
                                "reads angles whatever the hand's size; --method paper chooses "
                                "a database by it)")


def _keypoint_shape(shape_name, measurements, err):
    """The hand whose keypoints a learnt run reports: --shape, --measurements or the standard."""
    shape = hand_shape(shape_name, measurements)
    click.echo(f"keypoints of the handsynth hand {shape.name} posed by the estimated angles",
               err=err)
    return shape


def _open_learned(cache, kind, hands, rest, smoothing, side, err):
    """The learnt estimator (read from `cache`, or learnt there first)."""
    import dataclasses
    import time

    from ..db import MAX_LEARNING_HANDS, LearningSetOptions, learning_workers
    from ..estimate import (
        LEARNED_ENSEMBLES,
        LearnedOptions,
        largest_learning_set,
        learned_ensemble,
        learned_estimator,
    )
    from ..live import default_database_dir

    if hands is not None and hands < 1:
        raise InvalidInputError(f"--learned-hands must be a positive integer, got {hands}")
    if hands is not None and hands > MAX_LEARNING_HANDS:
        # 99999999999 hands: a numpy MemoryError traceback (12 PiB of learning frames)
        raise InvalidInputError(f"--learned-hands must be at most {MAX_LEARNING_HANDS:,} (as "
                                f"eval --learned-hands; every learning frame is held in "
                                f"memory), got {hands}")
    if smoothing is not None and not 0 <= smoothing < 1:
        raise InvalidInputError(f"--smoothing must be in [0, 1), got {smoothing}")
    folder = Path(cache) if cache is not None else default_database_dir().parent / "learned"
    if folder.exists() and not folder.is_dir():
        raise InvalidInputError(f"--learned-cache {str(folder)!r} is a file; give a folder")
    data = LearningSetOptions()
    data = dataclasses.replace(data, hands=data.hands if hands is None else hands,
                               open_rest_share=0.0 if rest == "relaxed" else data.open_rest_share)
    t = time.perf_counter()

    def say(line: str) -> None:
        if line.startswith("epoch"):
            return
        if line.startswith("learning set:") and " hands x " in line:  # a first run
            line += (" (once, minutes; then read from the cache; --learned-kind perceptrons "
                     "learns nothing)" if kind != "perceptrons" else " (once, minutes)")
        click.echo(line, err=err)

    # a learning set the cache lacks is rendered on every core: the same set, sooner
    workers = learning_workers(largest_learning_set(data, LEARNED_ENSEMBLES.get(kind, ())))
    if kind == "fingers":
        est = learned_estimator(folder, LearnedOptions(kind="fingers"), data=data, side=side,
                                progress=say, workers=workers)
    else:
        est = learned_ensemble(folder, members=LEARNED_ENSEMBLES[kind], data=data, side=side,
                               progress=say, workers=workers)
    for m in (est.members if kind != "fingers" else [est]):
        m.smoothing = smoothing or 0.0
    click.echo(f"learnt estimator ({kind}, {side} hand) ready in "
               f"{time.perf_counter() - t:.1f} s ({folder})", err=err)
    return est


def _read_intrinsics(path):
    """``--intrinsics``: the camera's calibration, or None."""
    if path is None:
        return None
    from ..render import read_intrinsics

    return read_intrinsics(path)


def _corrected(source, open_image, optics, mount, path, image_name, *, half: bool):
    """The source and the calibration image through the camera's lens correction.

    `half`: corrected frames at half the device's size (the learnt estimator reads them as
    well, docs/camera_estimator.md "A real camera's lens", for a quarter of the remap).
    Says how much of the device's view the camera does not see (black, read as
    background) when that is more than 1 %."""
    from ..live import CorrectedSource
    from ..render import LensCorrection

    lens = LensCorrection(optics, mount, scale=0.5 if half else 1.0)
    if lens.unseen_share > 0.01:
        fold = (f"; its lens model folds back beyond {lens.fold_deg:.0f} deg from the axis"
                if lens.fold_deg is not None else "")
        warnings.warn(f"--intrinsics {path}: the camera does not see {lens.unseen_share:.0%} "
                      f"of the device's {mount.fov_deg:g} deg view (its own about "
                      f"{optics.fov_deg:.0f} deg{fold}); that part reads as background",
                      stacklevel=2)
    if open_image is not None:
        try:
            open_image = lens(open_image)
        except InvalidInputError as exc:
            raise InvalidInputError(f"--calibrate-image {image_name}: {exc}") from None
    return CorrectedSource(source, lens), open_image


def _calibrate_learned(est, source, rest_image, mount, side, err, *, segment: str,
                       rest_name=None, mirrored_image: bool = False):
    """The learnt estimator calibrated to the hand at rest.

    A frame of the source where something stands out is the rest frame only when the
    estimator calibrated to it reads the frame itself as a hand (not ``low_confidence``):
    a video's first frames of half the view bright, of noise or of a hand coming into the
    view made every later frame low-confidence.  A --calibrate-image that reads so is
    used as given, with a warning, as is a rest frame that reads mirrored left to right.
    Returns the calibrated estimator and what :func:`_turn_hints` says of the rest frame
    (the advice for a view turned top to bottom or half a turn, and for a mirrored one)."""
    from ..estimate import read_rest_frame

    refused = 0
    last_refused: list = []

    def reads_as_a_hand(frame) -> bool:
        # a frame the estimator refuses (another width-to-height ratio...) is an error, as
        # before: every frame of the source would be refused alike
        nonlocal refused
        if not est.calibrated(frame, segment=segment).estimate(frame).low_confidence:
            return True
        refused += 1
        last_refused[:] = [frame]
        # a hand at rest over a cluttered ground can itself read so (9 of 60 rest frames
        # over photographs): after REST_FRAME_PATIENCE such frames the next one is taken
        return refused > REST_FRAME_PATIENCE

    try:
        rest, where = _calibration_frame(source, rest_image, mount, side, err,
                                         synthetic="the synthetic hand at rest (open)",
                                         prompt="hold the hand open, not stiff",
                                         accept=reads_as_a_hand)
    except EstimationError as exc:
        if not last_refused:
            raise
        turned, mirrored = _turn_hints(read_rest_frame(est, last_refused[0], segment=segment),
                                       side=side, mirrored_image=mirrored_image)
        if turned is None and mirrored is None:
            raise
        said = turned if turned is not None else f"the last frame {mirrored}"
        raise EstimationError(f"{exc}; {said}") from None
    reading = read_rest_frame(est, rest, segment=segment)
    low = reading.low_confidence
    turned, mirrored = _turn_hints(reading, side=side, mirrored_image=mirrored_image)
    # calibrated afresh: a trial's estimate is not a frame of the run (smoothing and the
    # moved check keep what they saw)
    est = est.calibrated(rest, segment=segment)
    told = "by the skin's colour" if est.segment == "colour" else "by brightness"
    click.echo(f"calibrated to {where}; the hand is told {told}", err=err)
    if low:
        what = (f"--calibrate-image {rest_name}: the image" if rest_image is not None else
                f"the rest frame (taken after {refused - 1} frames that read so)" if refused
                else "the rest frame")
        if turned is not None:
            warnings.warn(f"{what} reads as unlike any hand learnt; {turned}", stacklevel=2)
        elif mirrored is not None:
            warnings.warn(f"{what} reads as unlike any hand learnt, and {mirrored}", stacklevel=2)
        else:
            warnings.warn(f"{what} itself reads as unlike any hand learnt (no hand at rest in full "
                          "view, or a cluttered ground?): frames may read low-confidence; give a "
                          "frame of the hand at rest, over a plain ground if it can be", stacklevel=2)
    elif mirrored is not None:
        what = f"--calibrate-image {rest_name}" if rest_image is not None else "the rest frame"
        warnings.warn(f"{what} {mirrored}", stacklevel=2)
    return est, turned, mirrored


def _turn_hints(reading, *, side: str, mirrored_image: bool) -> tuple[str | None, str | None]:
    """What the turn of the rest frame (:func:`~handsynth.estimate.read_rest_frame`) asks of
    the user: ``(turned, mirrored)``, the advice for a view turned top to bottom or half a
    turn (it follows "reads as unlike any hand learnt; "), and for a mirrored view (it
    follows "the rest frame "); None where the reading shows no such turn.

    The view of a left hand is the right hand's turned top to bottom; a camera mounted
    turned half a turn shows the hand turned both ways; a camera set to mirror its image
    shows it turned left to right, which the estimators read with no skill and without
    flagging it (:class:`~handsynth.estimate.MirrorCheck`)."""
    other = "left" if side == "right" else "right"
    if reading.turn == "top to bottom":
        return (f"read turned top to bottom, the rest frame is a {other} hand's: is the device "
                f"on the {other} hand? (give --side {other})"), None
    if reading.turn == "half a turn":
        return ("read turned half a turn, the rest frame is a hand's: is the camera mounted "
                "upside down? (turn it over)"), None
    if reading.turn != "left to right":
        return None, None
    scores = f"(mirror check: {reading.mirror.seen:.2f} as seen, {reading.mirror.turned:.2f} turned)"
    if mirrored_image:
        return None, (f"reads mirrored left to right once turned back by --mirrored-image "
                      f"{scores}: the camera does not seem to mirror its image; leave out "
                      "--mirrored-image")
    return None, (f"reads mirrored left to right {scores}: is the camera set to mirror its "
                  "image? give --mirrored-image to turn every frame back (or turn the camera's "
                  "mirroring off); read as they are, mirrored frames have no skill")


def _build_options(count: int | None, side: str):
    """The options of a database the run builds: --build-count and --side."""
    from ..db import BuildOptions

    if count is None:
        return BuildOptions(side=side)
    if count < 1:
        raise InvalidInputError(f"--build-count must be a positive integer, got {count}")
    return BuildOptions(count=count, side=side)


def _progress(stream):
    def show(s) -> None:
        moved = f", DEVICE MOVED ({s.moved} frames): take the rest frame again" if s.moved else ""
        stream.write(f"\r{s.frames} frames, dropped {s.dropped}, estimate {s.fps_lookup:.0f} fps, "
                     f"loop {s.fps_loop:.0f} fps{moved}   ")
        stream.flush()

    return show


@cli.command()
@click.option("--camera", type=int, default=None, metavar="INDEX",
              help="Read an OpenCV camera (0 for the first one).")
@click.option("--video", "video_in", default=None, metavar="FILE", help="Read a video file.")
@click.option("--synthetic", is_flag=True,
              help="Render a moving hand of --synthetic-shape (no camera needed).")
@click.option("--method", type=click.Choice(["learned", "paper"]), default=None,
              help="learned: the estimator learnt from randomised model hands (beyond the "
                   "paper; docs/camera_estimator.md), calibrated to the user's hand at rest: "
                   "--calibrate-image, else the first frame showing a hand (--synthetic: the "
                   "hand rendered open); learnt once into --learned-cache (minutes), then read. "
                   "paper: the paper's database lookup, kept to reproduce it (on hands whose "
                   "resting fingers are a few degrees off its open hand it reads no better "
                   "than a constant answer; docs/lookup.md).  [default: learned]")
@click.option("--learned", is_flag=True, help="The same as --method learned (the default).")
@click.option("--db", "db_dir", default=None, metavar="FOLDER",
              help="--method paper: database folder (<shape>.h5 files) [default: build or "
                   "verify the embedded default database in ~/.cache/handsynth/db].")
@click.option("--shape", "shape_name", default=None, metavar="NAME",
              help="With --keypoints, the hand whose keypoints are reported (e.g. "
                   "L1.050_W0.900_P1.000_T1.000, or 'standard'); --method paper: use the "
                   "database of the grid shape nearest to it.")
@click.option("--measurements", default=None, metavar="FILE",
              help="Hand measurements in mm (.json or .csv): with --keypoints, the hand whose "
                   "keypoints are reported; --method paper: the database chosen by them.")
@click.option("--personal", is_flag=True,
              help="--method paper: use a database of exactly the --shape or --measurements "
                   "hand (built in --db when missing, 20,448 paper poses, a few seconds) "
                   "instead of the nearest grid shape's.")
@click.option("--build-count", "--personal-count", "build_count", type=int, default=None,
              metavar="N", help="--method paper: poses of a database built for --personal or "
                                "--calibrate [default: the paper's 20,448].")
@click.option("--calibrate", is_flag=True,
              help="--method paper: calibrate to the hand held open and flat (beyond the "
                   f"paper): the first frame showing a hand within {CALIBRATION_READS} reads "
                   "(--synthetic: the hand rendered open) chooses the grid database, built in "
                   "--db when missing, unless --shape, --measurements or --personal chose it, "
                   "and gives the pixels to ignore.")
@click.option("--calibrate-image", default=None, metavar="FILE",
              help="The rest frame from this image of the hand at rest (open, not stiff) "
                   "through the device instead of the first frame showing a hand; --method "
                   "paper: the open, flat hand's image (implies --calibrate).")
@click.option("--intrinsics", default=None, metavar="FILE",
              help="The real camera's calibration (as OpenCV, ROS, Kalibr, Basalt or "
                   "ORB-SLAM write it): every frame, and --calibrate-image, "
                   "is remapped to the device's pinhole view before the estimate (its lens "
                   "distortion, focal length and principal point undone; "
                   "docs/camera_estimator.md).")
@click.option("--mirrored-image", is_flag=True,
              help="The camera, or its driver, mirrors its image left to right (as for a "
                   "video call): every frame, and --calibrate-image, is turned back before "
                   "the estimate. With the learnt estimator the rest frame says when it is needed.")
@click.option("--learned-kind", type=click.Choice(["ensemble", "perceptrons", "fingers"]),
              default="ensemble", show_default=True,
              help="With the learnt estimator: the weighted mean of the per-digit estimator and three "
                   "perceptrons, one of them learnt from hands resting relaxed (the most "
                   "accurate on paper-protocol frames); those three perceptrons alone "
                   "(shipped with handsynth: ready in seconds on a first run, where the "
                   "per-digit estimator is learnt in about 5 min, and about three times as "
                   "fast per frame); or the per-digit estimator alone.")
@click.option("--learned-cache", default=None, metavar="FOLDER",
              help="Folder of the learnt estimator and its learning set [default: "
                   "~/.cache/handsynth/learned].")
@click.option("--learned-hands", type=int, default=None, metavar="N",
              help="Random hands of the learning set [default: 4,000 x 100 frames; the "
                   "ensemble's perceptrons learn from four times as many].")
@click.option("--learned-rest", type=click.Choice(["open", "relaxed"]), default=None,
              help="With the learnt estimator: the rest postures it learns from: three hands in four "
                   "held open [default], or relaxed only (an earlier release's learning set: "
                   "at relaxed rests the glTF test hands read better with it and the model "
                   "test hands worse, near open both much worse, docs/camera_estimator.md; "
                   "the ensemble's relaxed-rest perceptron is then its seed-0 perceptron "
                   "again).")
@click.option("--side", type=click.Choice(["right", "left"]), default=None,
              help="The hand wearing the device [default: right]. With the learnt estimator a left "
                   "hand is read by the right hand's estimator mirrored, nothing learnt "
                   "again; the lookups open (or build) the left hand's databases, "
                   "<shape>_left.h5.")
@click.option("--smoothing", type=float, default=None, metavar="A",
              help="With the learnt estimator: report A * previous + (1 - A) * new angles (0 <= A < 1) "
                   "[default: 0, none]. At 30 fps, 0.3 cut the frame-to-frame jitter by a "
                   "third at no cost in accuracy, 0.5 by half at up to 0.3 deg "
                   "(docs/camera_estimator.md).")
@click.option("--segment", type=click.Choice(["auto", "brightness", "colour"]), default=None,
              help="With the learnt estimator: tell the hand from the background by brightness (Otsu's "
                   "threshold: a dark background), or by the colour of the skin on the back "
                   "of the hand in the rest frame (an ordinary background; colour frames) "
                   "[default: auto, colour where the two disagree on the rest frame] "
                   "(docs/camera_estimator.md, Telling the hand from an ordinary background).")
@click.option("--one-euro", "one_euro", is_flag=True,
              help="With the learnt estimator: steady the angles with the One Euro filter instead (cut-off "
                   "0.5 Hz while still, rising with speed; at the source's frame rate, --fps "
                   "where it reports none); on held-out hands held poses jittered 7 times "
                   "less for 0.02 deg more error (docs/camera_estimator.md).")
@click.option("--frames", type=int, default=None, metavar="N",
              help=f"Stop after N frames [--synthetic default: {SYNTHETIC_FRAMES}].")
@click.option("--seconds", type=float, default=None, metavar="S",
              help="Stop after S seconds of wall-clock time (also when reading a --video; "
                   "--frames stops after a number of frames).")
@click.option("--out", default=None, metavar="FILE",
              help="Write one row per frame (.csv or .jsonl; '-' for standard output, with --format).")
@click.option("--format", "fmt", type=click.Choice(["csv", "jsonl"]), default=None,
              help="Row format [default: from the --out suffix].")
@click.option("--keypoints", is_flag=True,
              help="Add the 21 keypoints (metres, hand frame) to the rows: those of the "
                   "handsynth hand of --shape or --measurements (the standard hand by default) "
                   "posed by the estimated angles; --method paper: the matched entry's.")
@click.option("--video-out", default=None, metavar="FILE",
              help="Write each input frame beside the pose read from it (.mp4 or .avi): the "
                   "estimated angles on the hand of --shape/--measurements (with --keypoints) "
                   "or the standard hand; --method paper: the matched entry's render.")
@click.option("--synthetic-shape", default=SYNTHETIC_SHAPE, show_default=True, metavar="NAME",
              help="Hand shape rendered by --synthetic (off the grid by default).")
@click.option("--synthetic-motion", type=click.Choice(["paper", "natural", "named"]),
              default="paper", show_default=True,
              help="Key poses the synthetic hand moves through.")
@click.option("--synthetic-angles", default=None, metavar="FILE",
              help="Instead of --synthetic-motion: joint angles the synthetic hand replays once, "
                   "at --fps (a CSV or JSON Lines table with the 20 joint columns, as 'handsynth "
                   "bvh' reads: another system's recording, e.g. 'imu track --angles-out' or "
                   "'glove apply'); their truth is the rows'.")
@click.option("--synthetic-size", default="720x480", show_default=True, metavar="WxH",
              help="Frame size of --synthetic.")
@click.option("--fps", type=float, default=30.0, show_default=True,
              help="Media frame rate of --synthetic (timestamps and speed of the motion), and "
                   "the rate --one-euro assumes for a source that reports none.")
@click.option("--no-temporal", is_flag=True,
              help="--method paper: do not score the previous frame's answer first.")
@click.option("--max-dead", type=int, default=100, show_default=True, metavar="N",
              help="Stop when N consecutive reads give no usable frame.")
@click.option("--quiet", "-q", is_flag=True, help="No progress line.")
def estimate(camera, video_in, synthetic, db_dir, shape_name, measurements, personal,
             build_count, calibrate, calibrate_image, intrinsics, mirrored_image, method,
             learned, learned_kind,
             learned_cache, learned_hands, learned_rest, side, smoothing, segment, one_euro,
             frames, seconds, out, fmt,
             keypoints, video_out, synthetic_shape, synthetic_motion, synthetic_angles,
             synthetic_size, fps, no_temporal, max_dead, quiet) -> None:
    """Estimate the hand pose of every frame of a camera, a video file or a synthetic hand.

    By default with the estimator learnt from randomised model hands,
    calibrated to the hand at rest (the first frame that shows a hand, or
    --calibrate-image); --method paper looks each frame up in the paper's
    pose databases instead.  Prints the frame rate of the estimate alone
    and of the whole loop; with
    --out writes one row per frame (frame, timestamp_s, no_hand,
    confidence, low_confidence, moved, entry, the 20 joint angles in degrees,
    optionally the keypoints; synthetic runs add the true angles and report
    the mean absolute error).  The rest frame (and with --method paper
    --calibrate, the open and flat hand's) is not a row.  Dropped or unreadable
    frames are counted and skipped; a source that gives nothing usable for
    --max-dead reads in a row ends the run with an error.  Ctrl-C stops the
    run cleanly.
    """
    from ..live import (
        CameraSource,
        LiveOptions,
        MirroredSource,
        SideBySideWriter,
        SyntheticMotion,
        SyntheticSource,
        VideoSource,
        live_columns,
        open_row_writer,
        run_live,
    )
    from ..render import CameraMount

    chosen = [n for n, on in (("--camera", camera is not None), ("--video", video_in is not None),
                              ("--synthetic", synthetic)) if on]
    if len(chosen) != 1:
        raise InvalidInputError("give exactly one source: --camera INDEX, --video FILE or "
                                f"--synthetic (got {', '.join(chosen) or 'none'})")
    check_path_names((("--video", video_in), ("--measurements", measurements),
                      ("--calibrate-image", calibrate_image), ("--intrinsics", intrinsics),
                      ("--out", out), ("--video-out", video_out)))
    _check_limits(frames, seconds, max_dead, fps)
    to_stdout = out == "-"
    info_err = to_stdout  # keep standard output for the rows
    if to_stdout and fmt is None:
        raise InvalidInputError("--out - (standard output) needs --format csv or jsonl")
    if fmt is not None and out is None:
        raise InvalidInputError(f"--format {fmt} applies to the rows of --out, and no --out "
                                "was given")
    if keypoints and out is None:
        raise InvalidInputError("--keypoints adds columns to the rows of --out, and no --out "
                                "was given")
    if learned and method == "paper":
        raise InvalidInputError("--learned and --method paper name two methods; give one")
    learned = method != "paper"
    kp_shape = None
    if learned:
        _check_learned_options(db_dir, shape_name, measurements, personal, build_count,
                               calibrate, no_temporal, keypoints)
        if keypoints:
            kp_shape = _keypoint_shape(shape_name, measurements, info_err)
    elif learned_cache is not None or learned_hands is not None or smoothing is not None or \
            one_euro or learned_rest is not None or segment is not None or \
            click.get_current_context().get_parameter_source("learned_kind") \
            == click.core.ParameterSource.COMMANDLINE:
        raise InvalidInputError("--learned-kind, --learned-cache, --learned-hands, "
                                "--learned-rest, --smoothing, --segment and --one-euro "
                                "apply to the learnt estimator, not to --method paper")
    if one_euro and smoothing is not None:
        raise InvalidInputError("--one-euro and --smoothing are two ways to steady the angles; "
                                "give one")
    if intrinsics is not None and synthetic:
        raise InvalidInputError("--intrinsics corrects a real camera's frames; --synthetic "
                                "frames are already the device's view")
    camera_optics = _read_intrinsics(intrinsics)
    if synthetic_angles is not None and not synthetic:
        raise InvalidInputError("--synthetic-angles is the motion of --synthetic, which was not "
                                "given")
    inputs = [p for p in (video_in, measurements, calibrate_image, intrinsics, synthetic_angles)
              if p is not None]
    replay = _replayed_angles(synthetic_angles, fps) if synthetic_angles is not None else None
    size = _parse_size(synthetic_size, "--synthetic-size") if synthetic else None
    user_shape = shape_option(synthetic_shape, "--synthetic-shape") if synthetic else None
    if synthetic and frames is None and seconds is None:
        frames = SYNTHETIC_FRAMES
    calibrate = calibrate or calibrate_image is not None
    chosen_db = shape_name is not None or measurements is not None or personal
    if build_count is not None and not (personal or (calibrate and not chosen_db)):
        raise InvalidInputError("--build-count applies to a database built for --personal or "
                                "--calibrate only")
    build = None if build_count is None and side is None else \
        _build_options(build_count, side or "right")
    open_image = read_image(calibrate_image, what="calibration image") \
        if calibrate_image is not None else None

    source: CameraSource | VideoSource | SyntheticSource | MirroredSource | None = None
    video: SideBySideWriter | None = None
    sink = None
    try:
        if camera is not None:
            asked = {} if camera_optics is None else {"width_px": camera_optics.width_px,
                                                      "height_px": camera_optics.height_px}
            source, what = CameraSource(camera, **asked), f"camera {camera}"
        elif video_in is not None:
            source, what = VideoSource(video_in), f"video {video_in}"
        lookup = None
        if learned:
            lookup = _open_learned(learned_cache, learned_kind, learned_hands, learned_rest,
                                   smoothing, side or "right", info_err)
        elif not calibrate or chosen_db:
            lookup = _open_lookup(db_dir, shape_name, measurements,
                                  False if no_temporal else None, info_err,
                                  personal=personal, build=build, side=side or "right")
        mount = getattr(lookup, "mount", None) or CameraMount.paper()
        side = getattr(lookup, "side", None) or side or "right"
        if synthetic:
            # --synthetic parsed its frame size and hand shape above
            assert size is not None and user_shape is not None
            if replay is None:
                source = SyntheticSource(user_shape, mount, side=side,
                                         motion=SyntheticMotion(poses=synthetic_motion), fps=fps,
                                         width_px=size[0], height_px=size[1])
                what = f"synthetic hand {user_shape.name} ({synthetic_motion} poses)"
            else:
                source = SyntheticSource(user_shape, mount, side=side, motion=replay, fps=fps,
                                         seconds_per_pose=1.0 / fps, loop=False,
                                         width_px=size[0], height_px=size[1])
                what = (f"synthetic hand {user_shape.name} (replaying {len(replay)} frames of "
                        f"{synthetic_angles})")
        # exactly one of --camera, --video and --synthetic was given (checked above)
        assert source is not None
        if camera_optics is not None:
            source, open_image = _corrected(source, open_image, camera_optics, mount,
                                            intrinsics, calibrate_image, half=learned)
        if mirrored_image:  # after the lens: a calibration of the mirrored image describes it
            source = MirroredSource(source)
            if open_image is not None:
                open_image = open_image[:, ::-1].copy()
        told = turned = mirrored = None
        try:
            if learned:
                lookup, turned, mirrored = _calibrate_learned(
                    lookup, source, open_image, mount, side, info_err, segment=segment or "auto",
                    rest_name=calibrate_image, mirrored_image=mirrored_image)
            elif calibrate:
                lookup = _calibrate(lookup, source, open_image, db_dir, mount, side, build,
                                    info_err)
        except (InvalidInputError, EstimationError) as exc:
            # the frame came from the image or the source: name the one it came from
            where = what if calibrate_image is None else f"--calibrate-image {calibrate_image}"
            raise type(exc)(f"{where}: {exc}") from None
        if learned:
            assert lookup is not None  # calibrated above
            told = lookup.segment
            if one_euro:
                from ..estimate import SmoothedEstimator

                lookup = SmoothedEstimator(lookup, rate_hz=source.fps or fps)
            if keypoints:
                from ..estimate import KeypointEstimator

                lookup = KeypointEstimator(lookup, shape=kp_shape, side=side)
        # opened above, or made from the open hand by the calibration
        assert lookup is not None
        if not learned:
            inputs.append(lookup.database.path)
        check_outputs([("--out", None if to_stdout else out), ("--video-out", video_out)],
                      inputs=inputs)
        if video_out is not None:  # refuses a bad name before the rows file is touched
            # a lookup draws its matched entries; the learnt estimator its angles on the hand
            # of --shape or --measurements (with --keypoints) or the standard hand
            video = SideBySideWriter(video_out, lookup, fps=source.fps or fps, inputs=inputs,
                                     shape=kp_shape, mount=mount, side=side)
        if out is not None:
            sink = open_row_writer(out, format=fmt, inputs=inputs,
                                   columns=live_columns(keypoints=keypoints, truth=synthetic))
        options = LiveOptions(max_frames=frames, max_seconds=seconds, max_dead_reads=max_dead,
                              keypoints=keypoints)
        if learned:
            click.echo(f"estimating {what} with the learnt estimator ({learned_kind})",
                       err=info_err)
        else:
            click.echo(f"estimating {what} against {lookup.database.path.name} "
                       f"({len(lookup)} entries)", err=info_err)
        show = None if quiet or not sys.stderr.isatty() else _progress(sys.stderr)
        summary = run_live(lookup, source, sink=sink, video_out=video, options=options,
                           progress=show)
    except BaseException:
        if video is not None:
            video.discard()
        raise
    finally:
        if source is not None:
            source.close()
        if sink is not None:
            sink.close()
    if video is not None:
        video.close()  # checks the file and only then gives it its name
    if show is not None:
        sys.stderr.write("\n")
    click.echo(summary.format(), err=info_err)
    many_low = summary.frames and summary.low_confidence > 0.25 * summary.frames
    if many_low and turned is not None:
        click.echo(f"{summary.low_confidence} of {summary.frames} frames were unlike any learnt; "
                   f"{turned}", err=info_err)
    elif many_low and told == "brightness":
        click.echo(f"{summary.low_confidence} of {summary.frames} frames were unlike any learnt: "
                   "if the background is not dark, --segment colour tells the hand by the "
                   "colour of its skin (docs/camera_estimator.md)", err=info_err)
    if mirrored is not None:  # said at the start too; a long run's reader sees this line last
        click.echo(f"the rest frame {mirrored}", err=info_err)
    if sink is not None and not to_stdout:
        plural = "" if sink.rows == 1 else "s"
        click.echo(f"rows: {Path(out)} ({sink.rows} row{plural}, {sink.format})" if sink.rows else
                   f"rows: none, so {Path(out)} was not written", err=info_err)
    if video is not None:
        right = "estimated pose" if learned else "matched entry"
        click.echo(f"video: {Path(video_out)} ({video.frames} frames, input | {right})",
                   err=info_err)
    why = f" (the first refused: {summary.first_refusal})" if summary.first_refusal else ""
    if summary.stop_reason == "dead":
        raise EstimationError(f"{what}: {summary.message}; stopped after {summary.frames} "
                              f"frames{why}")
    if summary.frames == 0 and summary.stop_reason == "ended" and not summary.invalid \
            and not summary.dropped:
        after = " after the rest frame" if (learned or calibrate) and open_image is None else ""
        raise EstimationError(f"{what}: the source gave no frame{after}; no rows were written")
    if summary.frames == 0 and summary.stop_reason == "ended":
        raise EstimationError(
            f"{what}: no frame could be used ({summary.reads} reads: {summary.dropped} empty, "
            f"{summary.invalid} refused){why}; no rows were written")
