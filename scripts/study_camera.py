"""Studies of the learnt camera estimator that docs/camera_estimator.md quotes (beyond the protocol).

Usage::

    python scripts/study_camera.py --cache DIR backgrounds
    python scripts/study_camera.py --cache DIR jitter
    python scripts/study_camera.py --cache DIR holds
    python scripts/study_camera.py observability
    python scripts/study_camera.py --cache DIR bound
    python scripts/study_camera.py bound_mcp
    python scripts/study_camera.py --cache DIR [--rest open] [--ensemble] [--mesh NAMES] rests
    python scripts/study_camera.py [--axis FIELD] moved
    python scripts/study_camera.py --cache DIR [--segment colour] imaging
    python scripts/study_camera.py --cache DIR mounts
    python scripts/study_camera.py --cache DIR sizes
    python scripts/study_camera.py --cache DIR skin
    python scripts/study_camera.py --cache DIR skin_lit
    python scripts/study_camera.py --cache DIR [--kind perceptrons] novelty
    python scripts/study_camera.py --cache DIR [--kind perceptrons] lens
    python scripts/study_camera.py --cache DIR level
    python scripts/study_camera.py --cache DIR [--kind perceptrons] mirror
    python scripts/study_camera.py --cache DIR tones
    python scripts/study_camera.py --cache DIR bent_rest
    python scripts/study_camera.py --cache DIR held
    python scripts/study_camera.py --cache DIR still
    python scripts/study_camera.py --cache DIR imu_motions

``backgrounds``
    Two held-out model hands (seed 3, 1.5 times the learning spread) and the
    two glTF hands, 60 natural frames each from a relaxed rest, painted as
    skin on a dark background, on ten photographs bundled with
    scikit-image, and on those photographs at half brightness.  Per hand and
    background: the finger flexion MAE of the per-digit estimator beside the
    constant open-hand answer, the share of frames flagged
    ``low_confidence`` and the MAE of the frames not flagged.  Last line:
    ``photo_flagged=<mean share> photo_mae=<mean> dark_mae=<mean>``.
``skin``
    The hand told from the background by brightness (Otsu's threshold, the
    default) and by the colour of the skin on the back of the hand in the
    rest frame (``segment="colour"``), and as the default chooses between the
    two on the rest frame (``segment="auto"``), default ensemble.  The hands and poses
    of ``backgrounds`` (the same seeds), each painted in two skin tones
    (BGR 120/150/210 and 60/85/125), shaded from 0.55 to 1 across the frame,
    with noise of 4 grey levels, over the same grounds; the photographs
    split into the four colour ones and the six grey ones.  Per ground and
    method the finger flexion MAE over hands and tones beside the constant
    open-hand answer and the share flagged ``low_confidence``.  Last line:
    ``photo_brightness=<mae> photo_colour=<mae> dark_brightness=<mae>
    dark_colour=<mae>``.
``skin_lit``
    As ``skin`` on the two glTF hands rendered lit by MuJoCo
    (:meth:`handsynth.testhands.MeshHandRenderer.render_rgb`: its own skin
    material, light, shading and highlights), composited by their masks
    over a dark ground and over the photographs; a relaxed rest (seed 9),
    40 natural frames each.  Per hand, ground and method the finger flexion
    MAE beside the constant, the share flagged ``low_confidence`` and what
    ``auto`` chose.  Last line: ``<ground>_<method>=<mae> ...``.
``tones``
    Skin darker than its ground: the default ensemble (``segment="auto"``) on the three
    glTF hands and three held-out model hands (seed 53, 1.5 times the learning spread),
    a relaxed rest each (seed 5) and 30 natural frames, painted in three skin tones (BGR
    120/150/210, 45/60/95 and 30/38/58) over a black ground (15), grey grounds of 100 and
    150 (brighter than the two dark tones) and the photographs, with noise of 4 grey
    levels.  Per hand, tone and ground: what ``auto`` chose, the finger flexion MAE and
    the share flagged ``low_confidence``; then per tone and ground the mean over the
    hands beside the constant.  Last line: ``worst_mae=<deg> constant=<deg>``.
``bent_rest``
    A rest frame taken with the fingers bent: the three glTF hands and two held-out model
    hands (seed 53, 1.5 times the spread), a relaxed rest each (seed 5) and 30 natural
    frames from it, the default ensemble calibrated to a frame of that rest with every
    finger flexion (MCP, PIP, DIP) bent 0, 20, 40 and 60 deg more (at most 90).  Per hand
    and bend: the mean finger flexion the ensemble reads in its own rest frame against
    the truth, whether that frame is flagged, and the natural frames' flexion MAE and
    share flagged.  Last line: ``mae_rest=<deg> mae_bent20=<deg> mae_bent40=<deg>
    mae_bent60=<deg>``.
``held``
    An object in the hand: the three glTF hands (:class:`~handsynth.testhands.MeshHandRenderer`
    with ``holding=True``), a relaxed rest each (seed 5), 30 natural frames each of
    grasps whose four fingers close around a cylinder
    (:func:`~handsynth.testhands.grasped_cylinder`, 200 mm long, across the palm), the
    default ensemble calibrated on the rest frame without the object.  As masks on a
    dark ground: no object, a bright object (it joins the hand's pixels) and a dark one
    (it only hides the fingertips behind it); painted over the photographs (the hand told
    by colour): no object, a blue one and a wood-coloured one near the skin's colour.
    Per hand and set the finger flexion MAE beside the constant open-hand answer, the
    share flagged ``low_confidence`` and the MAE of the frames not flagged; then the
    means.  Last line: ``<set>=<mae> ...``.
``jitter``
    Continuous motions: 8 natural grasps from and back to a relaxed rest,
    each reached in 0.8 s with a minimum-jerk profile at 30 fps, on two
    held-out model hands (seed 7) and the two glTF hands; for exponential
    smoothing 0, 0.3, 0.5, 0.7 the flexion MAE and the RMS second difference
    of the flexion angles (deg/frame^2).  Last line: ``jitter_0=<mean>
    jitter_0.3=<mean> ...``.
``holds``
    Exponential smoothing against the One Euro filter where jitter shows:
    natural grasps from a relaxed rest, each held 10-30 frames and reached in
    12-30 frames (minimum jerk, 30 fps), every frame's outline flickering
    (each pixel within one of the silhouette's edge flipped with
    probability 0.3, as a camera's binarization flickers), per-digit
    estimator.  Per filter: the flexion MAE, its MAE while moving and the RMS
    second difference of the flexion angles while held and over all frames
    (deg/frame^2).  Three held-out model hands (seed 21) to choose the One
    Euro constants on (a grid of minimum cut-offs and speed coefficients),
    then two other model hands (seed 7) and the two glTF hands with the
    defaults of :class:`handsynth.estimate.OneEuroOptions`.  Last line:
    ``hold_jitter_raw=<mean> hold_jitter_exp0.5=<mean> hold_jitter_one_euro=<mean>
    mae_raw=<mean> mae_exp0.5=<mean> mae_one_euro=<mean>`` (the second set).
``observability``
    How many silhouette pixels (720x480) change when the index PIP (DIP
    following at 0.7) flexes by 20 deg from 0, 20, 40, 60 and 80 deg, on
    three held-out model hands (seed 1), beside the change of growing the
    outline by 2 pixels.  Last line: ``pip_60_80_px=<mean>``.

``bound``
    What the silhouette can tell of the index PIP at best.  Four held-out
    model hands (seed 5) and the two glTF hands, 600 paper-protocol frames
    each from a relaxed rest (seed 7); on the frames whose index PIP is
    flexed more than 20 deg beyond rest (at most 30 per hand) an oracle that
    knows the hand and every other joint exactly sweeps the index PIP over
    its range (-5 to 100 deg in 1-deg steps, DIP keeping the frame's
    DIP-to-PIP ratio) and keeps the angles whose silhouette differs from the
    frame's by nothing thicker than 2 pixels (fewer than 20 pixels survive an
    erosion by a 3x3 disc: a 1-pixel outline error is not information);
    under a uniform prior its best answer is the median of those angles.
    Beside it, on the same frames: the per-digit estimator (calibrated on
    the rest frame) and the constant open hand.  Last line:
    ``oracle_mae=<mean> estimator_mae=<mean> constant_mae=<mean>``.

``bound_mcp``
    The same oracle on the same frames (hands, rest postures and poses as
    ``bound``), but not told the index MCP: it sweeps the MCP (-5 to 90 deg)
    and the PIP (-5 to 100 deg) together in 2.5-deg steps and keeps every
    pair whose silhouette differs from the frame's by nothing thicker than 2
    pixels; its answer is the median PIP of the pairs kept (a frame no pair
    of the grid matches so closely is left out).  Beside it the
    oracle told the MCP (the ``bound`` oracle, on the 2.5-deg grid).  How much
    of the index PIP the silhouette holds when the joint next to it is not
    known.  Last line: ``oracle_mcp_known_mae=<mean> oracle_mcp_unknown_mae=<mean>
    constant_mae=<mean>``.

``rests``
    How a hand's paper-frame skill depends on the rest posture drawn: the
    protocol's paper frames (300 per hand) of the two glTF hands under pose
    seeds 0-9 (each seed its own rest posture), per-digit estimator.  Per
    seed and hand the flexion MAE, the constant's, the skill and the index
    PIP error where it moves; per hand the skill's mean, range and its value
    pooled over the seeds (``1 - sum MAE / sum MAE_constant``).  ``--rest
    open``: near-open rest postures instead of relaxed ones; ``--ensemble``:
    the default learnt ensemble (:func:`handsynth.estimate.learned_ensemble`,
    the CLI's default) instead of its per-digit member; ``--mesh NAMES``:
    other glTF hands (``webxr_generic``, or files).  Last line:
    ``<hand>_pooled_skill=<value> ...``.

``moved``
    Whether :class:`handsynth.estimate.MoveCheck` tells a device that slipped
    on the wrist after the rest frame from one that stayed.  Per hand a rest
    frame (near open for even hands, relaxed for odd ones) and 120 frames
    (60 paper-protocol, 60 natural, shuffled), every outline flickering as in
    ``holds``; the frames seen from where the rest frame was and from a
    place drawn at 0.25, 0.5 and 1 times the learning set's mount s.d.s
    (``--axis``: that field of :class:`handsynth.render.MountVariation`
    alone).  Per hand and slip the smallest and largest median change over
    30-frame windows; per set of hands the share of windows over the limit.
    Hands: four model hands of seed 13 (the limit's choice: three times
    their largest unmoved window median), four of seed 21 and the two glTF
    hands.  Last line: ``unmoved_flagged=<share> moved_0.5_flagged=<share>
    moved_1_flagged=<share>`` (seed 21 and glTF hands).

``imaging``
    Imaging conditions no learning frame had: the default ensemble on the
    same frames as a bool mask, painted as skin on a dark background, then
    with Gaussian noise (s.d. 8, 20 and 40 grey levels), 1 % of the pixels
    white, a Gaussian blur (s.d. 2 px), JPEG at quality 40, a vignette (0.3
    of the brightness at the corners), the hand shaded from 0.55 to 1 across
    the frame, the hand dimmed to 0.35 with noise of s.d. 8, a grey
    background (90), the frame at half resolution and as one grey channel.
    Four held-out model hands (seed 31, 1.5 times the learning spread) and
    the two glTF hands, a near-open and a relaxed rest in turn, 40 paper and
    40 natural frames each; the rest frame is taken under the same
    condition.  Per condition the pooled finger flexion MAE beside the
    constant open-hand answer.  Last line: ``largest_change_paper=<deg>
    largest_change_natural=<deg>`` (against the mask, over the conditions).
    ``--segment colour``: camera frames told by the skin's colour
    (``segment="colour"``) instead of brightness, without the grey condition.

``mounts``
    Devices worn beyond the learning set's spread of mounts (s.d. 10 mm in
    height, 6 and 8 mm across and along, 4 deg of tilt and roll), the rest
    frame taken where the device sits: the paper's mount changed by one
    field at a time (height -30 to +60 mm, tilt and roll 8 and 15 deg, 16
    and 30 mm along the hand, 15 mm across).  Four held-out model hands
    (seed 41, 1.5 times the learning spread) and the two glTF hands, a
    near-open and a relaxed rest in turn, 60 paper and 60 natural frames
    each, default ensemble.  Per mount the finger flexion MAE beside the
    constant open-hand answer and the share of frames flagged
    ``low_confidence``.  Last line: ``worst_paper=<deg> worst_natural=<deg>
    flagged=<share>``.
``sizes``
    Hands smaller and larger than any a learning set holds on average: each
    glTF hand made larger or smaller about its wrist joint
    (:meth:`handsynth.testhands.MeshRig.scaled`) to 145-235 mm in steps of
    15 mm from the wrist joint to the middle fingertip (the shipped hands
    measure 216 and 196 mm, the standard model hand 187 mm), a relaxed and
    a near-open rest each (seed 53), 80 paper and 80 natural frames each,
    default ensemble.  Per length the finger flexion MAE beside the constant
    open-hand answer, the index PIP's error where it moves more than 20 deg
    (paper / natural frames) and the share of frames flagged ``low_confidence``.  Last line:
    ``paper_skill_min=<skill> natural_skill_min=<skill>``.
``novelty``
    What ``low_confidence`` flags (the novelty limits, fixed from learning
    frames before this study): the default ensemble, or with ``--kind
    perceptrons`` its perceptrons alone.  The three glTF hands and three
    held-out model hands (seed 3), a relaxed and a near-open rest each
    (seed 5), 100 paper and 100 natural frames each, painted as skin on a
    dark ground and over the photographs (the rest frame over one too, so
    the hand is told by colour); per ground and frame set the share flagged
    and the finger flexion MAE of the frames flagged and not flagged,
    beside the constant open-hand answer.  Then frames that show no hand or
    not as the device sees one, each calibrated on every hand's relaxed
    rest frame on the dark ground: uniform noise, the upper half of the view
    white, a white 300x200 rectangle, a white disc (radius 150 px), the left
    300 columns grey, and a natural frame of the hand shifted 60 and 120 px
    sideways and turned upside down; per kind the share flagged.  Last line:
    ``hands_flagged_dark=<share> hands_flagged_photo=<share> nonhand_flagged=<share>``.
``lens``
    Real cameras at the device's place (same optical centre and axis):
    the device's lens with mild barrel distortion, wide-angle 3:2 and 4:3
    board cameras with strong barrel distortion and an off-centre principal
    point, a 16:9 fisheye (equidistant model) and a narrow 16:9 webcam
    (about 78 deg).  Each camera's frames are made from a 150-deg pinhole
    render (2400x2400) sampled along each of its pixels' rays (OpenCV's
    ``undistortPoints``, the inverse of its forward model), then given to
    the estimator as :class:`~handsynth.render.LensCorrection` corrects
    them (``--intrinsics``; at full and at half size, 360x240) and as a user
    without the calibration would
    (the middle cut to 3:2, resized to 720x480), beside the device's own
    renders.  The three glTF hands and two held-out model hands (seed 3), a
    relaxed rest each (seed 8), 60 paper and 60 natural frames each, skin on
    a dark ground; the rest frame through the same camera.  Per view the
    finger flexion MAE beside the constant and the share flagged
    ``low_confidence``.  Last line: ``<view>_<set>=<mae> ...``.
``level``
    Whether the device's tilt and roll can be read from the rest frame: the
    rotation (tilt and roll on a 4-deg grid, +-20 deg) whose level view of the
    rest frame (a homography: same optical centre) the shipped perceptrons
    find least unlike their learning frames (mean novelty norm).  Three
    held-out model hands (seed 41) and the three glTF hands, a relaxed rest
    each (seed 2), the device tilted and rolled by (0, 0), (+-12, 0), (0,
    +-12) and (8, -8) deg.  Per kind of hand the error of the angles read.
    Last line: ``model_tilt_abs=<deg> model_roll_abs=<deg> glTF_tilt_abs=...``.
``mirror``
    The mirror check (:class:`~handsynth.estimate.MirrorCheck`, shipped) on rest frames
    as the device sees them and turned left to right: the three glTF hands and six
    held-out model hands (seed 53, 1.5 times the learning spread), a relaxed and a
    near-open rest each (seed 11), worn as the paper's device, 40 mm higher, 30 mm lower,
    tilted and rolled 15 deg; as masks, and with the paper's device also painted over
    photographs (the hand told by colour).  Each rest frame's scores as seen and turned,
    whether it reads mirrored, and whether its mirror image does.  With the paper's
    device, 30 natural frames per rest read as seen and mirrored (calibrated to the
    mirrored rest frame): the finger flexion MAE and the share flagged
    ``low_confidence``, beside the open-hand constant; how many mirrored rest frames the
    estimator itself flags.  Last line:
    ``mirror_false_alarms=<n> mirrored_caught=<n> rest_frames=<n>``.
``still``
    Where the paper frames' error lies: the default ensemble on four held-out
    model hands (seed 13, 1.5 times the learning spread) and the three glTF
    hands, three rests of each kind per hand (near open and relaxed, seeds
    ``[99, hand]``), 100 paper-protocol frames per rest.  Per hand and kind
    of rest: the finger flexion MAE beside the constant, the MAE and mean
    signed error (reading minus truth) of the flexions that do not move, the
    MAE of those that do, the share of the error on the still ones, and the
    error of the rest frame read by itself.  Last line:
    ``<rest>_still_bias=<mean over hands> ...``.
``imu_motions``
    Motions of another generator than every camera test pose's: the IMU simulator's free
    motion (30 s, every joint swinging with its own frequency and phase; seed 11) and its
    reaches into the five grasps with holds (seed 12), every joint clipped to the hand's
    range and shown at 10 frames a second (300 and 205 frames).  The three glTF hands and
    two held-out model hands (seed 61, 1.5 times the spread), the default ensemble
    calibrated on a relaxed rest of each hand (seed 9; the motions start from the open
    hand, not from that rest).  Per hand and motion: the finger flexion MAE beside the
    constant open-hand answer and the rest posture held, the index PIP where it moves
    more than 20 deg from the rest, and the share flagged ``low_confidence``.  Last
    line: ``free_mae=<deg> free_constant=<deg> grasps_mae=<deg> grasps_constant=<deg>``.

The learnt estimator is read from ``--cache`` (or learnt there first).
"""

from __future__ import annotations

import argparse
import itertools
import os

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np

from handsynth.eval import (
    background_photos,
    mesh_test_hands,
    model_test_hands,
    natural_test_poses,
    relaxed_rest_posture,
)
from handsynth.render import CameraMount

_FLEX = [4, 6, 7, 8, 10, 11, 12, 14, 15, 16, 18, 19]  # the 12 finger flexions
_SKIN = np.array([120, 150, 210], np.uint8)             # BGR
#: BGR colours of the ``held`` study's objects over photographs: a blue mug, a wooden
#: handle near the skin's colour
_HELD_COLOURS = {"blue": (170, 90, 40), "wood": (90, 140, 190)}
#: wrist joint to the middle fingertip of the sizes study's hands, mm: around the
#: 1988 US Army survey's means (women 180.4, men 193.8; handsynth.models._anthropometry)
#: and well beyond them
_HAND_LENGTHS_MM = (145, 160, 175, 190, 205, 220, 235)


def _estimator(cache):
    from handsynth.estimate import LearnedOptions, learned_estimator

    return learned_estimator(cache, LearnedOptions())


def _painted(mask: np.ndarray, ground, i: int) -> np.ndarray:
    """Ground ``ground(i)`` (BGR uint8, a new array) with the hand's `mask` painted as skin."""
    f = ground(i)
    f[mask] = _SKIN
    return f


def backgrounds(cache) -> None:
    mount = CameraMount.paper()
    est = _estimator(cache)
    photos = background_photos()
    grounds = {"dark": lambda i: np.full((480, 720, 3), 20, np.uint8),
               "photo": lambda i: photos[i % len(photos)].copy(),
               "photo x0.5": lambda i: photos[i % len(photos)] // 2}
    rng = np.random.default_rng(5)
    summary: dict = {g: ([], []) for g in grounds}
    for hand in model_test_hands(2, seed=3, mount=mount, spread=1.5) + mesh_test_hands(mount=mount):
        made = hand.make()
        rest = relaxed_rest_posture(rng)
        poses, _ = natural_test_poses(rest, 60, rng)
        masks = [made.mask(p) for p in poses]
        for name, ground in grounds.items():
            cal = est.calibrated(_painted(made.mask(rest), ground, 0))
            got = [cal.estimate(_painted(m, ground, i + 1)) for i, m in enumerate(masks)]
            angles = np.stack([g.angles for g in got])
            flagged = np.array([g.low_confidence for g in got])
            err = np.abs(angles[:, _FLEX] - poses[:, _FLEX])
            const = np.abs(poses[:, _FLEX]).mean()
            kept = err[~flagged].mean() if (~flagged).any() else float("nan")
            summary[name][0].append(err.mean())
            summary[name][1].append(flagged.mean())
            print(f"{hand.name:15s} {name:11s} flexion MAE {err.mean():6.2f} (constant {const:5.2f}); "
                  f"flagged {flagged.mean():4.2f}; MAE of the frames not flagged {kept:6.2f}",
                  flush=True)
    print(f"photo_flagged={np.mean(summary['photo'][1]):.3f} "
          f"photo_mae={np.mean(summary['photo'][0]):.2f} dark_mae={np.mean(summary['dark'][0]):.2f}")


def _by_method(ens, rest_frame, frames, poses) -> dict:
    """Per way of telling the hand: per-frame flexion MAE, ``low_confidence``, the choice."""
    out = {}
    for method in ("brightness", "colour", "auto"):
        cal = ens.calibrated(rest_frame, segment=method)
        got = [cal.estimate(f) for f in frames]
        e = np.abs(np.stack([g.angles for g in got])[:, _FLEX] - poses[:, _FLEX]).mean(1)
        out[method] = (e, np.array([g.low_confidence for g in got]), cal.segment)
    return out


def skin_lit(cache) -> None:
    from handsynth.estimate import learned_ensemble

    ens = learned_ensemble(cache)
    photos = background_photos()
    rng = np.random.default_rng(9)
    rows: dict = {}
    for hand in mesh_test_hands():
        made = hand.make()
        rest = relaxed_rest_posture(rng)
        poses, _ = natural_test_poses(rest, 40, rng)
        lit = [made.render_rgb(p)[..., ::-1] for p in (rest, *poses)]  # BGR, lit by MuJoCo
        masks = [made.mask(p) for p in (rest, *poses)]
        for name, ground in (("dark", lambda i: np.full((480, 720, 3), 20, np.uint8)),
                             ("photo", lambda i: photos[i % len(photos)])):
            frames = [np.where(m[..., None], f, ground(i)) for i, (f, m) in enumerate(zip(lit, masks))]
            for method, (e, low, segment) in _by_method(ens, frames[0], frames[1:], poses).items():
                rows.setdefault((name, method), []).append((e.mean(), low.mean()))
                print(f"{hand.name:15s} {name:6s} {method:10s} flexion MAE {e.mean():6.2f} (constant "
                      f"{np.abs(poses[:, _FLEX]).mean():5.2f}); flagged {low.mean():.2f}; chose "
                      f"{segment}", flush=True)
    m = {k: np.mean(v, axis=0)[0] for k, v in rows.items()}
    print(" ".join(f"{g}_{meth}={v:.2f}" for (g, meth), v in m.items()))


def skin(cache) -> None:
    from handsynth.estimate import learned_ensemble

    mount = CameraMount.paper()
    ens = learned_ensemble(cache)
    photos = background_photos()
    colour = [i for i, p in enumerate(photos) if not (p[..., 0] == p[..., 1]).all()]
    grounds = {"dark": lambda i: np.full((480, 720, 3), 20, np.float32),
               "photo": lambda i: photos[i % len(photos)].astype(np.float32),
               "photo x0.5": lambda i: photos[i % len(photos)].astype(np.float32) / 2}
    shade = np.linspace(0.55, 1.0, 720, dtype=np.float32)[None, :, None]
    tones = (_SKIN.astype(np.float32), np.array([60, 85, 125], np.float32))
    rng = np.random.default_rng(5)
    err: dict = {}
    chose: dict = {}
    for hand in model_test_hands(2, seed=3, mount=mount, spread=1.5) + mesh_test_hands(mount=mount):
        made = hand.make()
        rest = relaxed_rest_posture(rng)
        poses, _ = natural_test_poses(rest, 60, rng)
        masks = made.masks(poses)
        noise = np.random.default_rng(len(hand.name))
        for tone in tones:
            for name, ground in grounds.items():
                def frame(mask, i, ground=ground, tone=tone, noise=noise):
                    f = ground(i)
                    f[mask] = (tone * shade * np.ones_like(f))[mask]
                    return np.clip(f + noise.normal(0, 4, f.shape), 0, 255).astype(np.uint8)

                frames = [frame(m, i + 1) for i, m in enumerate(masks)]
                kinds = np.array(["colour photo" if (i + 1) % len(photos) in colour else "grey photo"
                                  for i in range(len(masks))]) if name != "dark" else None
                for method, (e, low, segment) in _by_method(ens, frame(made.mask(rest), 0), frames,
                                                             poses).items():
                    if method == "auto":
                        chose.setdefault(name, []).append(segment)
                    groups = {name: np.ones(len(e), bool)}
                    if kinds is not None:
                        groups.update({f"{name}, {k}": kinds == k for k in ("colour photo", "grey photo")})
                    for g, sel in groups.items():
                        err.setdefault((g, method), []).append((e[sel].mean(), low[sel].mean()))
                        err.setdefault((g, "constant"), []).append(
                            (np.abs(poses[sel][:, _FLEX]).mean(), 0.0))
        print(f"{hand.name} done", flush=True)
    for g in dict.fromkeys(k[0] for k in err):
        row = {m: np.mean(err[(g, m)], axis=0) for m in ("brightness", "colour", "auto", "constant")}
        print(f"{g:25s} brightness {row['brightness'][0]:6.2f} (flagged {row['brightness'][1]:.2f})  "
              f"colour {row['colour'][0]:6.2f} (flagged {row['colour'][1]:.2f})  "
              f"auto {row['auto'][0]:6.2f}  constant {row['constant'][0]:6.2f}")
    for name, picks in chose.items():
        print(f"auto chose colour on {picks.count('colour')} of {len(picks)} rest frames ({name})")
    m = {k: np.mean(v, axis=0)[0] for k, v in err.items()}
    print(f"photo_brightness={m[('photo', 'brightness')]:.2f} photo_colour={m[('photo', 'colour')]:.2f} "
          f"dark_brightness={m[('dark', 'brightness')]:.2f} dark_colour={m[('dark', 'colour')]:.2f}")


def _minjerk(n: int) -> np.ndarray:
    t = np.linspace(0, 1, n, endpoint=False)
    return 10 * t**3 - 15 * t**4 + 6 * t**5


def jitter(cache) -> None:
    mount = CameraMount.paper()
    est = _estimator(cache)
    rng = np.random.default_rng(11)
    levels = (0.0, 0.3, 0.5, 0.7)
    totals: dict = {a: [] for a in levels}
    for hand in model_test_hands(2, seed=7, mount=mount, spread=1.5) + mesh_test_hands(mount=mount):
        made = hand.make()
        rest = relaxed_rest_posture(rng)
        keys, _ = natural_test_poses(rest, 8, rng)
        keys = np.vstack([rest, keys, rest])
        seq = np.vstack([a + (b - a) * _minjerk(24)[:, None] for a, b in itertools.pairwise(keys)])
        frames = [made.mask(p) for p in seq]
        truth_jitter = np.sqrt(np.mean(np.diff(seq[:, _FLEX], 2, axis=0) ** 2))
        for a in levels:
            cal = est.calibrated(made.mask(rest))
            cal.smoothing = a
            got = np.stack([cal.estimate(f).angles for f in frames])
            mae = np.abs(got[:, _FLEX] - seq[:, _FLEX]).mean()
            jit = np.sqrt(np.mean(np.diff(got[:, _FLEX], 2, axis=0) ** 2))
            totals[a].append(jit)
            print(f"{hand.name:15s} smoothing {a}: flexion MAE {mae:5.2f}, jitter {jit:5.2f} "
                  f"deg/frame^2 (the true motion's {truth_jitter:4.2f})", flush=True)
    print(" ".join(f"jitter_{a:g}={np.mean(v):.3f}" for a, v in totals.items()))


def _flicker(mask: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """`mask` with each pixel within one of its edge flipped with probability 0.3."""
    import cv2

    m = mask.astype(np.uint8)
    ring = cv2.dilate(m, np.ones((3, 3), np.uint8)) != cv2.erode(m, np.ones((3, 3), np.uint8))
    return mask.astype(bool) ^ (ring & (rng.random(mask.shape) < 0.3))


def _held_motion(rest: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Angles (N, 20) of 8 natural grasps from and back to `rest` with holds, and a moving flag."""
    keys, _ = natural_test_poses(rest, 8, rng)
    keys = np.vstack([rest, keys, rest])
    parts = []
    for a, b in itertools.pairwise(keys):
        parts.append(np.repeat(a[None], int(rng.integers(10, 30)), axis=0))
        parts.append(a + (b - a) * _minjerk(int(rng.integers(12, 30)))[:, None])
    parts.append(np.repeat(keys[-1][None], 20, axis=0))
    seq = np.vstack(parts)
    return seq, np.r_[False, np.any(np.diff(seq, axis=0) != 0, axis=1)]


def _steadiness(got: np.ndarray, seq: np.ndarray, moving: np.ndarray) -> tuple:
    """Flexion MAE, MAE while moving, RMS second difference while held and overall."""
    err = np.abs(got[:, _FLEX] - seq[:, _FLEX])
    d2 = np.diff(got[:, _FLEX], 2, axis=0)
    held = ~(moving[:-2] | moving[1:-1] | moving[2:])
    return (err.mean(), err[moving].mean(), float(np.sqrt(np.mean(d2[held] ** 2))),
            float(np.sqrt(np.mean(d2**2))))


def holds(cache) -> None:
    from handsynth.estimate import OneEuroOptions, one_euro

    mount = CameraMount.paper()
    est = _estimator(cache)
    rate = 30.0

    def exponential(x: np.ndarray, a: float) -> np.ndarray:
        y = x.copy()
        for i in range(1, len(x)):
            y[i] = a * y[i - 1] + (1 - a) * x[i]
        return y

    def answers(hands, seed: int) -> list:
        rng, noise = np.random.default_rng(seed), np.random.default_rng(seed + 1)
        out = []
        for hand in hands:
            made = hand.make()
            rest = relaxed_rest_posture(rng)
            seq, moving = _held_motion(rest, rng)
            cal = est.calibrated(made.mask(rest))
            got = np.stack([cal.estimate(_flicker(made.mask(p), noise)).angles for p in seq])
            out.append((hand.name, got, seq, moving))
        return out

    filters = {"raw": lambda x: x, **{f"exp{a}": (lambda x, a=a: exponential(x, a))
                                      for a in (0.3, 0.5, 0.7)},
               "one_euro": lambda x: one_euro(x, rate_hz=rate)}
    print("-- choosing the One Euro constants: three held-out model hands (seed 21); mean of "
          "MAE, MAE moving, jitter held, jitter (deg, deg/frame^2)")
    chosen = answers(model_test_hands(3, seed=21, mount=mount, spread=1.5), 5)
    grid = {f"exp{a}": filters[f"exp{a}"] for a in (0.3, 0.5, 0.7)}
    for cut in (0.3, 0.5, 1.0, 2.0):
        for beta in (0.01, 0.02, 0.05, 0.1):
            o = OneEuroOptions(min_cutoff_hz=cut, beta=beta)
            grid[f"one_euro {cut} Hz, beta {beta}"] = lambda x, o=o: one_euro(x, rate_hz=rate,
                                                                              options=o)
    raw = np.mean([_steadiness(g, s, m) for _, g, s, m in chosen], axis=0)
    print(f"{'raw':28s} {raw[0]:6.2f} {raw[1]:6.2f} {raw[2]:5.2f} {raw[3]:5.2f}")
    for name, f in grid.items():
        r = np.mean([_steadiness(f(g), s, m) for _, g, s, m in chosen], axis=0)
        print(f"{name:28s} {r[0]:6.2f} {r[1]:6.2f} {r[2]:5.2f} {r[3]:5.2f}  "
              f"(MAE {r[0] - raw[0]:+.2f})", flush=True)
    print(f"-- {OneEuroOptions()}: other hands")
    totals: dict = {k: [] for k in filters}
    for name, got, seq, moving in answers(
            model_test_hands(2, seed=7, mount=mount, spread=1.5) + mesh_test_hands(mount=mount),
            11):
        for k, f in filters.items():
            r = _steadiness(f(got), seq, moving)
            totals[k].append(r)
            print(f"{name:15s} {k:9s} flexion MAE {r[0]:5.2f} (moving {r[1]:5.2f}), jitter held "
                  f"{r[2]:4.2f}, overall {r[3]:4.2f} deg/frame^2", flush=True)
    mean = {k: np.mean(v, axis=0) for k, v in totals.items()}
    print(" ".join(f"hold_jitter_{k}={mean[k][2]:.3f}"
                   for k in ("raw", "exp0.5", "one_euro")) + " " +
          " ".join(f"mae_{k}={mean[k][0]:.2f}" for k in ("raw", "exp0.5", "one_euro")))


def observability() -> None:
    import cv2

    mount = CameraMount.paper()
    late = []
    for hand in model_test_hands(3, seed=1, mount=mount, spread=1.0):
        made = hand.make()

        def mask(pip: float, made=made) -> np.ndarray:
            a = np.zeros(20)
            a[6], a[7] = pip, 0.7 * pip
            return made.mask(a)

        m = {p: mask(p) for p in (0, 20, 40, 60, 80, 100)}
        steps = [(p - 20, p, int((m[p] ^ m[p - 20]).sum())) for p in (20, 40, 60, 80, 100)]
        k = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (5, 5))
        grown = cv2.dilate(m[0].view(np.uint8), k).view(bool)
        late.append(steps[3][2])
        print(f"{hand.name}: " + "; ".join(f"{a}->{b} deg {n} px" for a, b, n in steps)
              + f" | outline grown by 2 px: {int((grown ^ m[0]).sum())} px")
    print(f"pip_60_80_px={np.mean(late):.0f}")


def _bound_frames():
    """The paper frames of ``bound`` and ``bound_mcp``: per hand (hand, its mask maker,
    rest posture, 600 poses, the indices of at most 30 whose index PIP moves > 20 deg)."""
    from handsynth.eval import paper_protocol_poses

    mount = CameraMount.paper()
    rng = np.random.default_rng(7)
    for hand in model_test_hands(4, seed=5, mount=mount) + mesh_test_hands(mount=mount):
        made = hand.make()
        rest = relaxed_rest_posture(rng)
        poses, _ = paper_protocol_poses(rest, 600, rng)
        try:
            yield hand, made, rest, poses, np.nonzero(poses[:, 6] - rest[6] > 20)[0][:30]
        finally:
            close = getattr(made, "close", None)
            if close is not None:
                close()


def bound(cache) -> None:
    import cv2

    from handsynth.models import JOINT_LIMITS_DEG

    est = _estimator(cache)
    disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (3, 3))
    sweep = np.arange(-5.0, 100.5, 1.0)
    rows = []
    for hand, made, rest, poses, moving in _bound_frames():
        cal = est.calibrated(made.mask(rest))
        oracle, spans, mine = [], [], []
        for i in moving:
            pose = poses[i]
            seen = made.mask(pose)
            ratio = pose[7] / pose[6]
            kept = []
            for pip in sweep:
                q = pose.copy()
                q[6], q[7] = pip, np.clip(ratio * pip, *JOINT_LIMITS_DEG[7])
                diff = (made.mask(q) ^ seen).view(np.uint8)
                if cv2.erode(diff, disc).sum() < 20:
                    kept.append(pip)
            oracle.append(abs(np.median(kept) - pose[6]))
            spans.append(max(kept) - min(kept))
            mine.append(abs(cal.estimate(seen).angles[6] - pose[6]))
        const = np.abs(poses[moving, 6])
        rows.append((np.mean(oracle), np.mean(mine), const.mean()))
        print(f"{hand.name:15s} {len(moving):2d} frames: index PIP MAE oracle {rows[-1][0]:5.1f} deg "
              f"(indistinguishable span median {np.median(spans):3.0f} deg), estimator "
              f"{rows[-1][1]:5.1f}, constant {rows[-1][2]:5.1f}", flush=True)
    m = np.mean(rows, axis=0)
    print(f"oracle_mae={m[0]:.2f} estimator_mae={m[1]:.2f} constant_mae={m[2]:.2f}")


def bound_mcp() -> None:
    import cv2

    from handsynth.models import JOINT_LIMITS_DEG

    disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (3, 3))
    mcps, pips = np.arange(-5.0, 90.1, 2.5), np.arange(-5.0, 100.1, 2.5)
    rows = []
    for hand, made, _rest, poses, moving in _bound_frames():
        known, unknown, spans = [], [], []
        for i in moving:
            pose = poses[i]
            seen = made.mask(pose)
            ratio = pose[7] / pose[6]
            grid = np.array([(m, p) for m in mcps for p in pips])
            q = np.tile(pose, (len(grid), 1))
            q[:, 4], q[:, 6] = grid[:, 0], grid[:, 1]
            q[:, 7] = np.clip(ratio * grid[:, 1], *JOINT_LIMITS_DEG[7])
            ok = np.concatenate([[cv2.erode((m ^ seen).view(np.uint8), disc).sum() < 20
                                  for m in made.masks(q[k:k + 256])]
                                 for k in range(0, len(q), 256)])
            near_mcp = np.abs(grid[:, 0] - pose[4]) <= 1.25
            kept_known = grid[ok & near_mcp, 1]
            kept = grid[ok, 1]
            if kept.size == 0:  # nothing on the grid explains the frame: leave it out
                continue
            if kept_known.size:
                known.append(abs(np.median(kept_known) - pose[6]))
            unknown.append(abs(np.median(kept) - pose[6]))
            spans.append(np.ptp(kept))
        const = np.abs(poses[moving, 6])
        rows.append((np.mean(known), np.mean(unknown), const.mean()))
        print(f"{hand.name:15s} {len(unknown):2d} frames: index PIP MAE oracle told the MCP "
              f"{rows[-1][0]:5.1f} deg, not told {rows[-1][1]:5.1f} (span of the PIPs kept, "
              f"median {np.median(spans):3.0f} deg), constant {rows[-1][2]:5.1f}", flush=True)
    m = np.mean(rows, axis=0)
    print(f"oracle_mcp_known_mae={m[0]:.2f} oracle_mcp_unknown_mae={m[1]:.2f} "
          f"constant_mae={m[2]:.2f}")


def rests(cache, rest: str = "relaxed", *, ensemble: bool = False, mesh=None) -> None:
    from handsynth.estimate import learned_ensemble
    from handsynth.eval import ProtocolOptions, run_protocol

    est = learned_ensemble(cache) if ensemble else _estimator(cache)
    rows: dict = {}
    for seed in range(10):
        res = run_protocol({"fingers": lambda rest, _hand: est.calibrated(rest)}, mesh_test_hands(mesh),
                           ProtocolOptions(frames=300, seed=seed, pose_sets=("paper",), rest=rest))
        for name, rec in res["hands"].items():
            st = rec["paper"]["fingers"]
            pip = st["method"]["joints"]["index_pip_flex"]
            row = (st["method"]["groups_mae_deg"]["finger_flexion"],
                   st["constant"]["groups_mae_deg"]["finger_flexion"], st["skill"]["finger_flexion"],
                   pip["moving_mae_deg"] or 0.0, pip["moving_frames"])
            rows.setdefault(name, []).append(row)
            print(f"seed {seed} {name}: flexion MAE {row[0]:.2f} (constant {row[1]:.2f}, skill "
                  f"{row[2]:.2f}); index PIP where it moves {row[3]:.1f} (n={row[4]})", flush=True)
    last = []
    for name, v in rows.items():
        a = np.array(v, float)
        pooled = 1.0 - a[:, 0].sum() / a[:, 1].sum()
        pip = (a[:, 3] * a[:, 4]).sum() / max(a[:, 4].sum(), 1)
        print(f"{name}: skill mean {a[:, 2].mean():.2f}, range {a[:, 2].min():.2f}-{a[:, 2].max():.2f}, "
              f"pooled {pooled:.2f}; index PIP where it moves {pip:.1f} (n={int(a[:, 4].sum())})")
        last.append(f"{name}_pooled_skill={pooled:.3f}")
    print(" ".join(last))


def moved(axis: str | None = None) -> None:
    from dataclasses import fields

    from handsynth.estimate import MoveCheck, MoveCheckOptions
    from handsynth.eval import paper_protocol_poses
    from handsynth.eval._testposes import REST_POSTURES
    from handsynth.render import MountVariation, coverage

    paper = CameraMount.paper()
    flick = np.random.default_rng(7)
    limit, slips = MoveCheckOptions().limit, (0.0, 0.25, 0.5, 1.0)

    def grids(maker, poses):
        return [np.rint(coverage(_flicker(m, flick), paper) * 255).astype(np.uint8)
                for m in maker.masks(poses)]

    sets = {"seed 13": (13, model_test_hands(4, seed=13, spread=1.5)),
            "seed 21": (21, model_test_hands(4, seed=21, spread=1.5)),
            "glTF": (1, mesh_test_hands())}
    medians: dict = {}
    for label, (seed, hands) in sets.items():
        for i, hand in enumerate(hands):
            rng = np.random.default_rng([seed, i, 1])
            rest = REST_POSTURES["relaxed" if i % 2 else "open"](rng)
            poses = np.vstack([paper_protocol_poses(rest, 60, rng)[0],
                               natural_test_poses(rest, 60, rng)[0]])
            poses = poses[rng.permutation(len(poses))]
            rest_grid = grids(hand.make(), rest[None])[0]
            for k in slips:
                var = MountVariation().scaled(k)
                if axis:
                    var = MountVariation(**{f.name: getattr(var, f.name) * (f.name == axis)
                                            for f in fields(var)})
                at = var.sample(paper, np.random.default_rng([98, seed, i])) if k else paper
                check = MoveCheck(rest_grid, paper)
                ch = np.array([check.change(g) for g in grids(hand.make(at), poses)])
                med = np.array([np.median(ch[j - 30:j]) for j in range(30, len(ch) + 1)])
                medians.setdefault((label, k), []).append(med)
                print(f"{label} {hand.name} slip {k}: window medians {med.min():.4f}-{med.max():.4f}",
                      flush=True)
    for label in sets:
        print(f"{label}: " + " | ".join(
            f"slip {k}: {np.mean(np.concatenate(medians[(label, k)]) > limit):.2f} flagged, largest "
            f"{max(m.max() for m in medians[(label, k)]):.4f}" for k in slips))
    held = {k: np.concatenate(medians[("seed 21", k)] + medians[("glTF", k)]) for k in slips}
    print(f"limit {limit}; three times the seed-13 hands' largest unmoved median "
          f"{3 * max(m.max() for m in medians[('seed 13', 0.0)]):.4f}")
    print(f"unmoved_flagged={np.mean(held[0.0] > limit):.3f} "
          f"moved_0.5_flagged={np.mean(held[0.5] > limit):.3f} "
          f"moved_1_flagged={np.mean(held[1.0] > limit):.3f}")


def _imaging_conditions() -> dict:
    import cv2

    yy, xx = np.mgrid[0:480, 0:720].astype(np.float32)
    vignette = (1.0 - 0.35 * (((xx - 360) / 360) ** 2 + ((yy - 240) / 240) ** 2))[..., None]
    shade = 0.55 + 0.45 * xx / 720

    def paint(mask, ground=20, skin=1.0):
        f = np.full((480, 720, 3), ground, np.float32)
        f[mask] = _SKIN * (shade[mask, None] if skin == "shaded" else skin)
        return f

    def u8(f):
        return np.clip(f, 0, 255).astype(np.uint8)

    def noisy(sd, **kw):
        return lambda m, rng: u8(paint(m, **kw) + rng.normal(0, sd, (480, 720, 3)))

    def jpeg(m, rng):
        return cv2.imdecode(cv2.imencode(".jpg", u8(paint(m)), [cv2.IMWRITE_JPEG_QUALITY, 40])[1],
                            cv2.IMREAD_COLOR)

    def salt(m, rng):
        f = u8(paint(m))
        f[rng.random(m.shape) < 0.01] = 255
        return f

    return {"mask": lambda m, rng: m,
            "dark background": lambda m, rng: u8(paint(m)),
            "noise 8": noisy(8), "noise 20": noisy(20), "noise 40": noisy(40),
            "1 % white pixels": salt,
            "blur 2 px": lambda m, rng: cv2.GaussianBlur(u8(paint(m)), (0, 0), 2.0),
            "JPEG 40": jpeg,
            "vignette": lambda m, rng: u8(paint(m) * vignette),
            "shaded hand": lambda m, rng: u8(paint(m, skin="shaded")),
            "dim hand + noise 8": noisy(8, skin=0.35),
            "grey background": lambda m, rng: u8(paint(m, ground=90)),
            "half resolution": lambda m, rng: cv2.resize(u8(paint(m)), (360, 240),
                                                         interpolation=cv2.INTER_AREA),
            "one grey channel": lambda m, rng: cv2.cvtColor(u8(paint(m)), cv2.COLOR_BGR2GRAY)}


def imaging(cache, segment: str = "brightness") -> None:
    from handsynth.estimate import learned_ensemble
    from handsynth.eval import paper_protocol_poses
    from handsynth.eval._testposes import REST_POSTURES

    ens = learned_ensemble(cache)
    conditions = _imaging_conditions()
    if segment == "colour":  # colour frames only; the masks stay as the reference
        for name in ("one grey channel",):
            conditions.pop(name)
    groups = {"model hands": model_test_hands(4, seed=31, spread=1.5), "glTF hands": mesh_test_hands()}
    errors: dict = {}
    constant: dict = {}
    for group, hands in groups.items():
        for i, hand in enumerate(hands):
            made = hand.make()
            rng = np.random.default_rng([31, len(group), i])
            rest = REST_POSTURES["relaxed" if i % 2 else "open"](rng)
            sets = {"paper": paper_protocol_poses(rest, 40, rng)[0],
                    "natural": natural_test_poses(rest, 40, rng)[0]}
            for name, condition in conditions.items():
                noise = np.random.default_rng(5)
                cal = ens.calibrated(condition(made.mask(rest), noise),
                                     segment="brightness" if name == "mask" else segment)
                for kind, poses in sets.items():
                    got = np.stack([cal.estimate(condition(m, noise)).angles for m in made.masks(poses)])
                    errors.setdefault((group, kind, name), []).append(
                        np.abs(got[:, _FLEX] - poses[:, _FLEX]).mean())
            for kind, poses in sets.items():
                constant.setdefault((group, kind), []).append(np.abs(poses[:, _FLEX]).mean())
            print(f"{group}: {hand.name} done", flush=True)
    change = {"paper": 0.0, "natural": 0.0}
    for group in groups:
        print(f"{group}: finger flexion MAE, paper / natural frames (constant "
              f"{np.mean(constant[(group, 'paper')]):.2f} / {np.mean(constant[(group, 'natural')]):.2f})")
        for name in conditions:
            mae = {k: np.mean(errors[(group, k, name)]) for k in change}
            for k in change:
                change[k] = max(change[k], abs(mae[k] - np.mean(errors[(group, k, "mask")])))
            print(f"  {name:20s} {mae['paper']:6.2f} / {mae['natural']:6.2f}")
    print(f"largest_change_paper={change['paper']:.2f} largest_change_natural={change['natural']:.2f}")


def _read_both(cal, made, rest, n, rng, mae: dict) -> dict:
    """`n` paper-protocol and `n` natural frames from `rest`, read by `cal`.

    Appends each set's finger flexion MAE and the constant's to `mae` (keys
    ``kind`` and ``kind + " constant"``); returns ``{kind: (poses, estimates,
    angles)}``.  The paper poses are drawn from `rng` first.
    """
    from handsynth.eval import paper_protocol_poses

    out = {}
    for kind, poses in (("paper", paper_protocol_poses(rest, n, rng)[0]),
                        ("natural", natural_test_poses(rest, n, rng)[0])):
        got = [cal.estimate(m) for m in made.masks(poses)]
        angles = np.stack([g.angles for g in got])
        mae.setdefault(kind, []).append(np.abs(angles[:, _FLEX] - poses[:, _FLEX]).mean())
        mae.setdefault(kind + " constant", []).append(np.abs(poses[:, _FLEX]).mean())
        out[kind] = (poses, got, angles)
    return out


def mounts(cache) -> None:
    from dataclasses import replace

    from handsynth.estimate import learned_ensemble
    from handsynth.eval._testposes import REST_POSTURES

    ens = learned_ensemble(cache)
    paper = CameraMount.paper()
    changes = [("height_mm", -30), ("height_mm", -20), ("height_mm", 20), ("height_mm", 40),
               ("height_mm", 60), ("tilt_deg", 8), ("tilt_deg", 15), ("roll_deg", 8), ("roll_deg", 15),
               ("along_mm", 16), ("along_mm", 30), ("thumb_offset_mm", 15)]
    worst = {"paper": 0.0, "natural": 0.0}
    flagged = []
    for field, delta in [(None, 0)] + changes:
        mount = replace(paper, **{field: getattr(paper, field) + delta}) if field else paper
        groups = {"model hands": model_test_hands(4, seed=41, mount=mount, spread=1.5),
                  "glTF hands": mesh_test_hands(mount=mount)}
        for group, hands in groups.items():
            mae: dict = {}
            low = []
            for i, hand in enumerate(hands):
                made = hand.make()
                rng = np.random.default_rng([41, len(group), i])
                rest = REST_POSTURES["relaxed" if i % 2 else "open"](rng)
                cal = ens.calibrated(made.mask(rest))
                for _poses, got, _angles in _read_both(cal, made, rest, 60, rng, mae).values():
                    low += [g.low_confidence for g in got]
            m = {k: float(np.mean(v)) for k, v in mae.items()}
            for kind in worst:
                worst[kind] = max(worst[kind], m[kind])
            flagged += low
            label = f"{field} {delta:+d}" if field else "paper mount"
            print(f"{label:20s} {group:11s} paper {m['paper']:5.2f} (constant {m['paper constant']:5.2f})"
                  f"  natural {m['natural']:5.2f} (constant {m['natural constant']:5.2f})"
                  f"  low_confidence {np.mean(low):.2f}", flush=True)
    print(f"worst_paper={worst['paper']:.2f} worst_natural={worst['natural']:.2f} "
          f"flagged={np.mean(flagged):.3f}")


def sizes(cache) -> None:
    from handsynth.estimate import learned_ensemble
    from handsynth.eval._testposes import REST_POSTURES
    from handsynth.models import joint_index
    from handsynth.testhands import PROTOCOL_HANDS, MeshHandRenderer, shipped_hand_path

    ens = learned_ensemble(cache)
    native = {}
    for name in PROTOCOL_HANDS:
        with MeshHandRenderer(width_px=72, height_px=48, path=shipped_hand_path(name)) as r:
            native[name] = r.hand_length_mm
    index_pip = joint_index("index_pip_flex")
    skill = {"paper": [], "natural": []}
    for length in _HAND_LENGTHS_MM:
        mae: dict = {}
        pip: dict = {"paper": [], "natural": []}
        low = []
        for name in PROTOCOL_HANDS:
            scale = length / native[name]
            hand = mesh_test_hands([name], scale=scale)[0]
            made = hand.make()
            for r, rest_kind in enumerate(("relaxed", "open")):
                rng = np.random.default_rng([53, r, len(name)])
                rest = REST_POSTURES[rest_kind](rng)
                cal = ens.calibrated(made.mask(rest))
                for kind, (poses, got, angles) in _read_both(cal, made, rest, 80, rng, mae).items():
                    moving = np.abs(poses[:, index_pip] - rest[index_pip]) > 20
                    pip[kind] += list(np.abs(angles[moving, index_pip] - poses[moving, index_pip]))
                    low += [g.low_confidence for g in got]
            made.close()
        m = {k: float(np.mean(v)) for k, v in mae.items()}
        for kind in skill:
            skill[kind].append(1 - m[kind] / m[kind + " constant"])
        print(f"hand length {length:3d} mm: paper {m['paper']:5.2f} (constant {m['paper constant']:5.2f}, "
              f"skill {skill['paper'][-1]:.2f})  natural {m['natural']:5.2f} (constant "
              f"{m['natural constant']:5.2f})  index PIP where it moves {np.mean(pip['paper']):4.1f} / "
              f"{np.mean(pip['natural']):4.1f} (n={len(pip['paper'])} / {len(pip['natural'])})  "
              f"low_confidence {np.mean(low):.2f}", flush=True)
    print(f"paper_skill_min={min(skill['paper']):.2f} natural_skill_min={min(skill['natural']):.2f}")


def _no_hand_frames(natural: np.ndarray) -> dict:
    """Frames of no hand, or of a hand not as the device sees one (720x480, BGR uint8)."""
    import cv2

    h, w = 480, 720
    out = {"uniform noise": np.random.default_rng(1).integers(0, 256, (h, w, 3), dtype=np.uint8)}
    half = np.full((h, w, 3), 20, np.uint8)
    half[: h // 2] = 255
    rect = np.full((h, w, 3), 20, np.uint8)
    rect[140:340, 210:510] = 255
    disc = np.full((h, w, 3), 20, np.uint8)
    cv2.circle(disc, (w // 2, h // 2), 150, (255, 255, 255), -1)
    band = np.full((h, w, 3), 20, np.uint8)
    band[:, :300] = 200
    out.update({"upper half white": half, "white rectangle": rect, "white disc": disc,
                "left band grey": band, "hand shifted 60 px": np.roll(natural, 60, axis=1),
                "hand shifted 120 px": np.roll(natural, 120, axis=1),
                "hand upside down": natural[::-1].copy()})
    return out


def novelty(cache, kind: str = "ensemble") -> None:
    from handsynth.estimate import LEARNED_ENSEMBLES, learned_ensemble
    from handsynth.eval import paper_protocol_poses
    from handsynth.eval._testposes import REST_POSTURES
    from handsynth.testhands import TEST_HANDS

    mount = CameraMount.paper()
    ens = learned_ensemble(cache, members=LEARNED_ENSEMBLES[kind], mount=mount)
    photos = background_photos()
    grounds = {"dark": lambda i: np.full((480, 720, 3), 20, np.uint8),
               "photo": lambda i: photos[i % len(photos)].copy()}
    rng = np.random.default_rng(5)
    rows: dict = {}
    odd: dict = {}
    for hand in mesh_test_hands(sorted(TEST_HANDS), mount=mount) + model_test_hands(3, seed=3,
                                                                                      mount=mount):
        made = hand.make()
        for rest_kind in ("relaxed", "open"):
            rest = REST_POSTURES[rest_kind](rng)
            sets = {"paper": paper_protocol_poses(rest, 100, rng)[0],
                    "natural": natural_test_poses(rest, 100, rng)[0]}
            masks = {k: made.masks(v) for k, v in sets.items()}
            for g, ground in grounds.items():
                cal = ens.calibrated(_painted(made.mask(rest), ground, 0))
                for k, poses in sets.items():
                    got = [cal.estimate(_painted(m, ground, i + 1)) for i, m in enumerate(masks[k])]
                    e = np.abs(np.stack([x.angles for x in got])[:, _FLEX] - poses[:, _FLEX]).mean(1)
                    low = np.array([x.low_confidence for x in got])
                    rows.setdefault((g, k), []).append((e, low, np.abs(poses[:, _FLEX]).mean(1)))
                if g == "dark" and rest_kind == "relaxed":
                    for name, f in _no_hand_frames(_painted(masks["natural"][0], ground, 1)).items():
                        odd.setdefault(name, []).append(cal.estimate(f).low_confidence)
        made.close()
        print(f"{hand.name} done", flush=True)
    for (g, k), parts in rows.items():
        e, low, const = (np.concatenate(x) for x in zip(*parts))
        kept = e[~low].mean() if (~low).any() else float("nan")
        flagged = e[low].mean() if low.any() else float("nan")
        print(f"{g:5s} {k:8s} flagged {low.mean():.3f} ({low.sum()} of {len(low)}); flexion MAE "
              f"not flagged {kept:6.2f}, flagged {flagged:6.2f}; constant {const.mean():6.2f}")
    for name, low in odd.items():
        print(f"{name:22s} flagged {np.mean(low):.2f} ({sum(low)} of {len(low)} calibrations)")
    share = {g: float(np.mean(np.concatenate([np.concatenate([p[1] for p in parts])
                                              for (gg, _k), parts in rows.items() if gg == g])))
             for g in grounds}
    print(f"hands_flagged_dark={share['dark']:.3f} hands_flagged_photo={share['photo']:.3f} "
          f"nonhand_flagged={np.mean([np.mean(v) for v in odd.values()]):.3f}")


#: ``lens``: real cameras at the device's place (name: matrix, distortion, model, frame size)
_LENS_CAMERAS = {
    "device lens, mild barrel": ([[360.0, 0, 365.5], [0, 360.0, 235.5]], (-0.12, 0.02, 0, 0, 0),
                                 "pinhole", (720, 480)),
    "wide 3:2 board camera": ([[302.0, 0, 367.0], [0, 301.0, 233.0]],
                              (-0.30, 0.09, 0.001, -0.0008, -0.012), "pinhole", (720, 480)),
    "wide 4:3 board camera": ([[270.0, 0, 325.0], [0, 270.0, 236.0]],
                              (-0.28, 0.08, 0.001, -0.0008, -0.01), "pinhole", (640, 480)),
    "fisheye 16:9": ([[420.0, 0, 645.0], [0, 420.0, 355.0]], (0.05, -0.01, 0.003, -0.0005),
                     "fisheye", (1280, 720)),
    "narrow 16:9 webcam": ([[395.0, 0, 319.5], [0, 395.0, 179.5]], (-0.05, 0.0, 0, 0, 0),
                           "pinhole", (640, 360)),
}


def _camera_maps(intr, wide: CameraMount) -> tuple[np.ndarray, np.ndarray]:
    """For each pixel of the real camera, where its ray meets a render of the `wide` mount.

    Through OpenCV's ``undistortPoints`` / ``fisheye.undistortPoints`` (the inverse of the
    camera's forward model), not the inverse map :class:`LensCorrection` builds."""
    import cv2

    w, h = intr.width_px, intr.height_px
    u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    pts = np.column_stack([u.ravel(), v.ravel()])[:, None, :]
    d = np.asarray(intr.distortion, np.float64)
    if intr.model == "fisheye":
        rays = cv2.fisheye.undistortPoints(pts, intr.matrix(), d)
    else:
        rays = cv2.undistortPoints(pts, intr.matrix(), d, R=None, P=None,
                                   criteria=(cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 40,
                                             1e-9))
    kw = wide.intrinsics()
    mx = (rays[:, 0, 0] * kw[0, 0] + kw[0, 2]).reshape(h, w).astype(np.float32)
    my = (rays[:, 0, 1] * kw[1, 1] + kw[1, 2]).reshape(h, w).astype(np.float32)
    return mx, my


def _as_device_ratio(frame: np.ndarray) -> np.ndarray:
    """What a user without the calibration gives: the middle cut to 3:2, resized to 720x480."""
    import cv2

    h, w = frame.shape[:2]
    if w * 2 > h * 3:
        c = (w - h * 3 // 2) // 2
        frame = frame[:, c:c + h * 3 // 2]
    elif w * 2 < h * 3:
        c = (h - w * 2 // 3) // 2
        frame = frame[c:c + w * 2 // 3]
    return cv2.resize(frame, (720, 480), interpolation=cv2.INTER_AREA)


def lens(cache, kind: str = "ensemble") -> None:
    import cv2

    from handsynth.estimate import LEARNED_ENSEMBLES, learned_ensemble
    from handsynth.eval import paper_protocol_poses
    from handsynth.render import CameraIntrinsics, LensCorrection
    from handsynth.testhands import TEST_HANDS

    mount = CameraMount.paper()
    wide = mount.replace(fov_deg=150.0, width_px=2400, height_px=2400)
    ens = learned_ensemble(cache, members=LEARNED_ENSEMBLES[kind], mount=mount)
    cams = {}
    for name, (k, dist, model, (w, h)) in _LENS_CAMERAS.items():
        intr = CameraIntrinsics(w, h, k[0][0], k[1][1], k[0][2], k[1][2], distortion=dist,
                                model=model)
        cams[name] = (LensCorrection(intr, mount), _camera_maps(intr, wide),
                      LensCorrection(intr, mount, scale=0.5))
        print(f"{name}: {w}x{h}, about {intr.fov_deg:.0f} deg without distortion, device view "
              f"unseen {cams[name][0].unseen_share:.1%}", flush=True)
    rng = np.random.default_rng(8)
    err: dict = {}
    names = sorted(TEST_HANDS)
    for device_hand, wide_hand in zip(mesh_test_hands(names, mount=mount) +
                                      model_test_hands(2, seed=3, mount=mount),
                                      mesh_test_hands(names, mount=wide) +
                                      model_test_hands(2, seed=3, mount=wide)):
        rest = relaxed_rest_posture(rng)
        sets = {"paper": paper_protocol_poses(rest, 60, rng)[0],
                "natural": natural_test_poses(rest, 60, rng)[0]}
        made = device_hand.make()
        device = {k: [_painted(m, lambda i: np.full((480, 720, 3), 20, np.uint8), 0)
                      for m in made.masks(np.vstack([rest[None], p]))] for k, p in sets.items()}
        made.close()
        made = wide_hand.make()
        big = {k: [m.view(np.uint8) * np.uint8(255) for m in made.masks(np.vstack([rest[None], p]))]
               for k, p in sets.items()}
        made.close()
        for k, poses in sets.items():
            frames = {"device's own view": device[k]}
            for name, (corr, (mx, my), half) in cams.items():
                real = [_painted(cv2.remap(b, mx, my, cv2.INTER_LINEAR) > 127,
                                 lambda i, s=(mx.shape + (3,)): np.full(s, 20, np.uint8), 0)
                        for b in big[k]]
                frames[f"{name}, corrected"] = [corr(f) for f in real]
                frames[f"{name}, corrected at half size"] = [half(f) for f in real]
                frames[f"{name}, as given"] = [_as_device_ratio(f) for f in real]
            for cond, fr in frames.items():
                cal = ens.calibrated(fr[0])
                got = [cal.estimate(f) for f in fr[1:]]
                e = np.abs(np.stack([g.angles for g in got])[:, _FLEX] - poses[:, _FLEX]).mean(1)
                low = np.array([g.low_confidence for g in got])
                err.setdefault((cond, k), []).append((e, low, np.abs(poses[:, _FLEX]).mean(1)))
        print(f"{device_hand.name} done", flush=True)
    print(f"\n{kind}; finger flexion MAE (deg) over {len(names)} glTF hands and 2 model hands, "
          "relaxed rests, 60 frames each; share flagged low_confidence")
    summary = []
    for cond in dict.fromkeys(c for c, _ in err):
        line = f"{cond:42s}"
        for k in ("paper", "natural"):
            e, low, const = (np.concatenate(x) for x in zip(*err[(cond, k)]))
            line += f"  {k} {e.mean():6.2f} ({low.mean():4.0%} flagged; constant {const.mean():5.2f})"
            summary.append(f"{cond.replace(' ', '_').replace(',', '')}_{k}={e.mean():.2f}")
        print(line)
    print(" ".join(summary))


def level(cache) -> None:
    """Can the device's tilt and roll be read from the rest frame (not taken; see the docs)?"""
    import cv2

    from handsynth.estimate import LEARNED_ENSEMBLES, learned_ensemble
    from handsynth.testhands import TEST_HANDS

    paper = CameraMount.paper()
    ens = learned_ensemble(cache, members=LEARNED_ENSEMBLES["perceptrons"], mount=paper)
    k = paper.intrinsics()
    r0 = paper.pose_in_hand()[:3, :3]

    def levelled(frame, tilt, roll):
        # the view of the level device from the same centre: a homography of the frame
        rc = paper.replace(tilt_deg=float(tilt), roll_deg=float(roll)).pose_in_hand()[:3, :3]
        return cv2.warpPerspective(frame, k @ rc.T @ r0 @ np.linalg.inv(k), (720, 480),
                                   flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP)

    def novelty(frame):
        cal = ens.calibrated(frame)
        return float(np.mean([m.estimate(frame).error for m in cal.members]))

    grid = np.arange(-20, 21, 4)
    truths = [(0, 0), (12, 0), (-12, 0), (0, 12), (0, -12), (8, -8)]
    rng = np.random.default_rng(2)
    dark = lambda i: np.full((480, 720, 3), 20, np.uint8)  # noqa: E731
    errors: dict = {"model": [], "glTF": []}
    for name in [h.name for h in model_test_hands(3, seed=41) + mesh_test_hands(sorted(TEST_HANDS))]:
        rest = relaxed_rest_posture(rng)
        for tilt, roll in truths:
            m = paper.replace(tilt_deg=tilt, roll_deg=roll)
            hand = next(h for h in model_test_hands(3, seed=41, mount=m)
                        + mesh_test_hands(sorted(TEST_HANDS), mount=m) if h.name == name)
            made = hand.make()
            frame = _painted(made.mask(rest), dark, 0)
            made.close()
            score = np.array([[novelty(levelled(frame, a, b)) for b in grid] for a in grid])
            i, j = np.unravel_index(np.argmin(score), score.shape)
            errors["glTF" if name in TEST_HANDS else "model"].append(
                (grid[i] - tilt, grid[j] - roll))
            print(f"{name:15s} tilt {tilt:+3d} roll {roll:+3d} -> read {grid[i]:+3d} {grid[j]:+3d}",
                  flush=True)
    out = []
    for kind, e in errors.items():
        e = np.array(e)
        print(f"{kind} hands: tilt error mean {e[:, 0].mean():+.1f}, |error| mean "
              f"{np.abs(e[:, 0]).mean():.1f}, max {np.abs(e[:, 0]).max()}; roll error mean "
              f"{e[:, 1].mean():+.1f}, |error| mean {np.abs(e[:, 1]).mean():.1f}, max "
              f"{np.abs(e[:, 1]).max()}")
        out.append(f"{kind}_tilt_abs={np.abs(e[:, 0]).mean():.1f} {kind}_roll_abs="
                   f"{np.abs(e[:, 1]).mean():.1f}")
    print(" ".join(out))


def mirror(cache, kind: str = "ensemble") -> None:
    """``mirror``: rest frames read mirrored by :class:`~handsynth.estimate.MirrorCheck`."""
    from dataclasses import replace

    from handsynth.estimate import LEARNED_ENSEMBLES, learned_ensemble, mirror_check
    from handsynth.eval._testposes import REST_POSTURES
    from handsynth.testhands import TEST_HANDS

    paper = CameraMount.paper()
    ens = learned_ensemble(cache, members=LEARNED_ENSEMBLES[kind], mount=paper)
    check = mirror_check()
    photos = background_photos()
    mounts = {"paper": paper, "40 mm higher": replace(paper, height_mm=160.0),
              "30 mm lower": replace(paper, height_mm=90.0),
              "tilted 15 deg": replace(paper, tilt_deg=15.0),
              "rolled 15 deg": replace(paper, roll_deg=15.0)}
    rng = np.random.default_rng(11)
    alarms, caught, total, flagged = 0, 0, 0, 0
    mae: dict = {}
    for label, mount in mounts.items():
        hands = (mesh_test_hands(sorted(TEST_HANDS), mount=mount)
                 + model_test_hands(6, seed=53, mount=mount, spread=1.5))
        for hand in hands:
            made = hand.make()
            for rest_kind in ("relaxed", "open"):
                rest = REST_POSTURES[rest_kind](rng)
                mask = made.mask(rest)
                grounds = {"dark": mask}
                if label == "paper":
                    grounds["photo"] = _painted(mask, lambda i: photos[i % len(photos)].copy(),
                                                total)
                for ground, frame in grounds.items():
                    seen = check.read(ens, frame)
                    turned = np.ascontiguousarray(frame[:, ::-1])
                    back = check.read(ens, turned)
                    alarms += seen.mirrored
                    caught += back.mirrored
                    total += 1
                    flagged += ens.calibrated(turned).estimate(turned).low_confidence
                    print(f"{label:13s} {hand.name:15s} {rest_kind:7s} {ground:5s} as seen "
                          f"{seen.seen:5.2f} / turned {seen.turned:5.2f}"
                          f"{' MIRRORED' if seen.mirrored else '         '}  mirrored frame "
                          f"{back.seen:5.2f} / {back.turned:5.2f}"
                          f"{' mirrored' if back.mirrored else ' NOT CAUGHT'}", flush=True)
                if label == "paper":
                    poses = natural_test_poses(rest, 30, rng)[0]
                    masks = made.masks(poses)
                    for view, turn in (("as seen", False), ("mirrored", True)):
                        def shown(m, turn=turn):
                            return np.ascontiguousarray(m[:, ::-1]) if turn else m
                        cal = ens.calibrated(shown(mask))
                        got = [cal.estimate(shown(m)) for m in masks]
                        a = np.stack([g.angles for g in got])
                        mae.setdefault(view, []).append(
                            (np.abs(a[:, _FLEX] - poses[:, _FLEX]).mean(),
                             np.mean([g.low_confidence for g in got])))
                    mae.setdefault("constant", []).append((np.abs(poses[:, _FLEX]).mean(), 0.0))
            made.close()
    for view, rows in mae.items():
        e, low = np.array(rows).T
        print(f"natural frames {view:9s}: flexion MAE {e.min():.1f}-{e.max():.1f} deg "
              f"(mean {e.mean():.1f}), flagged {low.min():.0%}-{low.max():.0%}")
    print(f"mirrored rest frames flagged low_confidence: {flagged} of {total}")
    print(f"mirror_false_alarms={alarms} mirrored_caught={caught} rest_frames={total}")


def tones(cache) -> None:
    """``tones``: skin of three tones over grounds darker and brighter than it."""
    from handsynth.estimate import learned_ensemble
    from handsynth.testhands import TEST_HANDS

    paper = CameraMount.paper()
    ens = learned_ensemble(cache, mount=paper)
    photos = background_photos()
    grounds = {"black": lambda i: np.full((480, 720, 3), 15, np.uint8),
               "grey 100": lambda i: np.full((480, 720, 3), 100, np.uint8),
               "grey 150": lambda i: np.full((480, 720, 3), 150, np.uint8),
               "photographs": lambda i: photos[i % len(photos)].copy()}
    skins = {"light": (120, 150, 210), "dark": (45, 60, 95), "very dark": (30, 38, 58)}
    rng = np.random.default_rng(5)
    rows: dict = {}
    const = []
    for hand in (mesh_test_hands(sorted(TEST_HANDS), mount=paper)
                 + model_test_hands(3, seed=53, mount=paper, spread=1.5)):
        made = hand.make()
        rest = relaxed_rest_posture(rng)
        poses = natural_test_poses(rest, 30, rng)[0]
        masks = [made.mask(rest), *made.masks(poses)]
        made.close()
        const.append(np.abs(poses[:, _FLEX]).mean())
        for tone, colour in skins.items():
            for name, ground in grounds.items():
                noise = np.random.default_rng(1)

                def paint(i, mask, ground=ground, colour=colour, noise=noise):
                    f = ground(i)
                    f[mask] = colour
                    return np.clip(f.astype(np.int16) + noise.integers(-4, 5, f.shape), 0,
                                   255).astype(np.uint8)

                cal = ens.calibrated(paint(0, masks[0]))
                got = [cal.estimate(paint(i, m)) for i, m in enumerate(masks[1:], 1)]
                e = np.abs(np.stack([g.angles for g in got])[:, _FLEX] - poses[:, _FLEX]).mean()
                low = np.mean([g.low_confidence for g in got])
                rows.setdefault((tone, name), []).append((e, low))
                print(f"{hand.name:15s} {tone:9s} {name:11s} {cal.segment:10s} flexion MAE "
                      f"{e:5.2f}, flagged {low:.2f}", flush=True)
    for (tone, name), v in rows.items():
        e, low = np.mean(v, axis=0)
        print(f"{tone:9s} {name:11s} flexion MAE {e:5.2f} (constant {np.mean(const):5.2f}), "
              f"flagged {low:.2f}")
    print(f"worst_mae={max(np.mean(v, axis=0)[0] for v in rows.values()):.2f} "
          f"constant={np.mean(const):.2f}")


def bent_rest(cache) -> None:
    """``bent_rest``: the rest frame taken with the fingers bent."""
    from handsynth.estimate import learned_ensemble
    from handsynth.testhands import TEST_HANDS

    paper = CameraMount.paper()
    ens = learned_ensemble(cache, mount=paper)
    rng = np.random.default_rng(5)
    mae: dict = {}
    for hand in (mesh_test_hands(sorted(TEST_HANDS), mount=paper)
                 + model_test_hands(2, seed=53, mount=paper, spread=1.5)):
        made = hand.make()
        rest = relaxed_rest_posture(rng)
        poses = natural_test_poses(rest, 30, rng)[0]
        masks = list(made.masks(poses))
        row = []
        for bend in (0, 20, 40, 60):
            taken = rest.copy()
            taken[_FLEX] = np.minimum(taken[_FLEX] + bend, 90.0)
            frame = made.mask(taken)
            cal = ens.calibrated(frame)
            own = cal.estimate(frame)
            got = [cal.estimate(m) for m in masks]
            e = np.abs(np.stack([g.angles for g in got])[:, _FLEX] - poses[:, _FLEX]).mean()
            mae.setdefault(bend, []).append(e)
            row.append(f"+{bend}: own {own.angles[_FLEX].mean():4.1f} (true "
                       f"{taken[_FLEX].mean():4.1f}{', flagged' if own.low_confidence else ''}) "
                       f"MAE {e:4.1f}, flagged {np.mean([g.low_confidence for g in got]):.2f}")
        made.close()
        print(f"{hand.name:15s} " + " | ".join(row) +
              f" | constant {np.abs(poses[:, _FLEX]).mean():4.1f}", flush=True)
    print(" ".join(f"mae_{'rest' if b == 0 else f'bent{b}'}={np.mean(v):.2f}"
                   for b, v in mae.items()))


def held(cache) -> None:
    """``held``: power grasps of a cylinder, bright, dark, blue and wood-coloured."""
    from dataclasses import replace

    from handsynth.estimate import learned_ensemble
    from handsynth.testhands import TEST_HANDS, MeshHandRenderer, grasped_cylinder, shipped_hand_path

    paper = CameraMount.paper()
    ens = learned_ensemble(cache, mount=paper)
    photos = background_photos()
    rng = np.random.default_rng(5)
    rows: dict = {}
    const = []
    for name in sorted(TEST_HANDS):
        r = MeshHandRenderer(paper, path=shipped_hand_path(name), holding=True)
        rest = relaxed_rest_posture(rng)
        found: list = []
        while len(found) < 30:
            for p in natural_test_poses(rest, 100, rng)[0]:
                o = grasped_cylinder(r.keypoints(p))
                if o is not None and len(found) < 30:
                    found.append((p, o))
        poses = np.array([p for p, _ in found])
        hand = [r.mask(p) for p in poses]
        bright = [r.mask_holding(p, o) for p, o in found]
        dark = [r.mask_holding(p, replace(o, bright=False)) for p, o in found]
        rest_mask = r.mask(rest)
        r.close()
        const.append(np.abs(poses[:, _FLEX]).mean())

        def photo(i, seen, obj=None, colour=None):
            f = photos[i % len(photos)].copy()
            f[seen] = _SKIN
            if obj is not None:
                f[obj] = colour
            return f

        sets = {"dark ground, no object": (rest_mask, hand),
                "dark ground, bright object": (rest_mask, bright),
                "dark ground, dark object": (rest_mask, dark),
                "photographs, no object": (photo(0, rest_mask),
                                           [photo(i + 1, m) for i, m in enumerate(hand)])}
        for colour_name, colour in _HELD_COLOURS.items():
            sets[f"photographs, {colour_name} object"] = (
                photo(0, rest_mask), [photo(i + 1, d, b & ~d, colour)
                                      for i, (b, d) in enumerate(zip(bright, dark))])
        for label, (rest_frame, frames) in sets.items():
            cal = ens.calibrated(rest_frame)
            got = [cal.estimate(f) for f in frames]
            e = np.abs(np.stack([g.angles for g in got])[:, _FLEX] - poses[:, _FLEX]).mean(axis=1)
            low = np.array([g.low_confidence for g in got])
            rows.setdefault(label, []).append((e.mean(), low.mean(),
                                               e[~low].mean() if (~low).any() else np.nan))
            print(f"{name:15s} {label:32s} flexion MAE {e.mean():5.2f} (constant {const[-1]:5.2f}), "
                  f"flagged {low.mean():.2f}, MAE not flagged {rows[label][-1][2]:5.2f}", flush=True)
    for label, v in rows.items():
        e, low, kept = np.nanmean(np.array(v, float), axis=0)
        print(f"{label:32s} flexion MAE {e:5.2f} (constant {np.mean(const):5.2f}), flagged "
              f"{low:.2f}, MAE not flagged {kept:5.2f}")
    print(" ".join(f"{label.replace(', ', '_').replace(' ', '_')}={np.mean([x[0] for x in v]):.2f}"
                   for label, v in rows.items()))


def still(cache) -> None:
    """``still``: the paper frames' error on the flexions that do not move and on the one that does."""
    from handsynth.estimate import learned_ensemble
    from handsynth.eval import paper_protocol_poses
    from handsynth.eval._testposes import REST_POSTURES

    est = learned_ensemble(cache)
    hands = model_test_hands(4, seed=13, spread=1.5) + mesh_test_hands(
        ["godot_xr_tools", "mrtk", "webxr_generic"])
    last = []
    for rest_kind in ("open", "relaxed"):
        biases = []
        for i, hand in enumerate(hands):
            rng = np.random.default_rng([99, i])
            made = hand.make()
            err, still, const, rest_err = [], [], [], []
            for _ in range(3):
                rest = REST_POSTURES[rest_kind](rng)
                poses, _motion = paper_protocol_poses(rest, 100, rng)
                rest_mask = made.mask(rest)
                cal = est.calibrated(rest_mask)
                got = np.array([cal.estimate(made.mask(p)).angles for p in poses])
                err.append((got - poses)[:, _FLEX])
                still.append(np.abs(poses - rest)[:, _FLEX] < 1e-9)
                const.append(np.abs(poses[:, _FLEX]))
                rest_err.append(np.abs(cal.estimate(rest_mask).angles - rest)[_FLEX])
            e, st = np.concatenate(err), np.concatenate(still)
            mae, c = np.abs(e).mean(), np.concatenate(const).mean()
            biases.append(e[st].mean())
            print(f"{rest_kind:7s} {hand.name:15s} flexion MAE {mae:5.2f} (constant {c:5.2f}, skill "
                  f"{1 - mae / c:+.2f}); still {np.abs(e[st]).mean():5.2f} (mean error "
                  f"{e[st].mean():+5.2f}, n={st.sum()}), moving {np.abs(e[~st]).mean():5.2f} "
                  f"(n={(~st).sum()}); share of the error on the still "
                  f"{np.abs(e[st]).sum() / np.abs(e).sum():.2f}; rest frame read "
                  f"{np.concatenate(rest_err).mean():5.2f}", flush=True)
        last.append(f"{rest_kind}_still_bias={np.mean(biases):+.2f}")
    print(" ".join(last))


def imu_motions(cache) -> None:
    """``imu_motions``: the IMU simulator's motions through the camera."""
    from handsynth.estimate import learned_ensemble
    from handsynth.models import JOINT_LIMITS_DEG, JOINT_NAMES
    from handsynth.sensors.imu import MODEL_JOINTS, free_motion, grasp_motion
    from handsynth.testhands import TEST_HANDS

    paper = CameraMount.paper()
    ens = learned_ensemble(cache, mount=paper)
    cols = [MODEL_JOINTS.index(n) for n in JOINT_NAMES]
    motions = {}
    for name, m in (("free", free_motion(30.0, seed=11)), ("grasps", grasp_motion(seed=12))):
        step = int(round(m.rate_hz / 10))
        motions[name] = np.clip(np.asarray(m.q)[::step, cols], JOINT_LIMITS_DEG[:, 0],
                                JOINT_LIMITS_DEG[:, 1])
    pip = JOINT_NAMES.index("index_pip_flex")
    rng = np.random.default_rng(9)
    out: dict = {}
    for hand in (mesh_test_hands(sorted(TEST_HANDS), mount=paper)
                 + model_test_hands(2, seed=61, mount=paper, spread=1.5)):
        made = hand.make()
        rest = relaxed_rest_posture(rng)
        cal = ens.calibrated(made.mask(rest))
        for name, poses in motions.items():
            got = [cal.estimate(m) for m in made.masks(poses)]
            angles = np.stack([g.angles for g in got])
            mae = np.abs(angles[:, _FLEX] - poses[:, _FLEX]).mean()
            const = np.abs(poses[:, _FLEX]).mean()
            held = np.abs(rest[_FLEX] - poses[:, _FLEX]).mean()
            moving = np.abs(poses[:, pip] - rest[pip]) > 20
            pip_mae = np.abs(angles[moving, pip] - poses[moving, pip]).mean()
            out.setdefault(name, []).append((mae, const))
            print(f"{hand.name:15s} {name:6s} flexion MAE {mae:5.2f} (open hand {const:5.2f}, "
                  f"rest held {held:5.2f}); index PIP moving {pip_mae:5.2f} (n={moving.sum()}); "
                  f"flagged {np.mean([g.low_confidence for g in got]):.2f}", flush=True)
        made.close()
    print(" ".join(f"{k}_mae={np.mean([a for a, _ in v]):.2f} "
                   f"{k}_constant={np.mean([b for _, b in v]):.2f}" for k, v in out.items()))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cache", default=None, help="folder of the learnt estimator")
    ap.add_argument("--rest", choices=["relaxed", "open"], default="relaxed",
                    help="rests: the test hands' rest postures")
    ap.add_argument("--mesh", default=None,
                    help="rests: glTF hands, comma-separated [default: the protocol's two]")
    ap.add_argument("--segment", choices=["brightness", "colour"], default="brightness",
                    help="imaging: how the ensemble tells the hand in camera frames")
    ap.add_argument("--ensemble", action="store_true",
                    help="rests: the default learnt ensemble instead of its per-digit member")
    ap.add_argument("--axis", default=None,
                    choices=["height_mm", "thumb_offset_mm", "along_mm", "tilt_deg", "roll_deg"],
                    help="moved: slip along this field of MountVariation alone")
    ap.add_argument("--kind", choices=["ensemble", "perceptrons"], default="ensemble",
                    help="novelty, lens, mirror: the default ensemble or its perceptrons alone")
    ap.add_argument("study", choices=["backgrounds", "jitter", "holds", "observability", "bound",
                                      "bound_mcp", "rests", "moved", "imaging", "mounts", "sizes",
                                      "skin", "skin_lit", "novelty", "lens", "level", "mirror", "tones",
                                      "bent_rest", "held", "still", "imu_motions"])
    args = ap.parse_args()
    if args.study not in ("observability", "bound_mcp", "moved") and args.cache is None:
        ap.error(f"{args.study} needs --cache DIR")
    studies = {"backgrounds": lambda: backgrounds(args.cache), "jitter": lambda: jitter(args.cache),
               "holds": lambda: holds(args.cache), "observability": observability,
               "bound": lambda: bound(args.cache), "bound_mcp": bound_mcp,
               "rests": lambda: rests(args.cache, args.rest, ensemble=args.ensemble,
                                      mesh=args.mesh.split(",") if args.mesh else None),
               "moved": lambda: moved(args.axis),
               "imaging": lambda: imaging(args.cache, args.segment),
               "mounts": lambda: mounts(args.cache), "sizes": lambda: sizes(args.cache),
               "skin": lambda: skin(args.cache), "skin_lit": lambda: skin_lit(args.cache),
               "novelty": lambda: novelty(args.cache, args.kind),
               "lens": lambda: lens(args.cache, args.kind), "level": lambda: level(args.cache),
               "mirror": lambda: mirror(args.cache, args.kind),
               "tones": lambda: tones(args.cache),
               "bent_rest": lambda: bent_rest(args.cache),
               "held": lambda: held(args.cache), "still": lambda: still(args.cache),
               "imu_motions": lambda: imu_motions(args.cache)}
    studies[args.study]()


if __name__ == "__main__":
    main()
