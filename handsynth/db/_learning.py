"""A learning set of fixed-frame coverage grids from randomised model hands.

The paper's databases hold one hand shape and one finger moving from the
exact open hand.  A user's hand is never that hand and never rests at
exactly zero, so a lookup in them has no entry for what the camera sees
(issue 15).  This set is made for learning instead: every few frames a new
hand is drawn (:class:`~handsynth.render.HandVariation` on a random grid-range
shape: per-segment lengths and breadths, palm length, MCP places), worn with
the device a little moved (:class:`~handsynth.render.MountVariation`), with
its own rest posture (relaxed, or near open for a share of the hands:
``LearningSetOptions.open_rest_share``); its poses are

* ``from_rest``: the hand at rest with one digit's flexion, one finger's
  abduction or the thumb moving (the paper's motions, from this hand's rest);
* ``fingers``: every finger at its own random closure, some left at rest;
* ``natural``: :func:`~handsynth.models.natural_pose_set` poses.

Every sample keeps its hand's rest frame, so an estimator can learn to use a
frame of the user's own rest posture (a calibration frame).  Masks come from
:class:`~handsynth.render.VariedRasterizer` at the device's frame size and
are stored as :func:`~handsynth.render.coverage` grids (uint8, 255 = covered).

The set is a pure function of its options; :func:`learning_set` keeps it in a
folder the caller names (never the package), as one ``.npz`` file written to a
temporary name and renamed when complete, named by a digest of the options.
"""

from __future__ import annotations

import hashlib
import json
import zipfile
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from .._checks import check_integer, check_number, check_options, check_path
from .._cores import usable_cores
from .._io import atomic_open, make_folder
from ..errors import DatabaseCorruptError, DatabaseError, InvalidInputError
from ..models import GRID_LEVELS, JOINT_LIMITS_DEG, HandShape, natural_pose_set
from ..render import (
    DEFAULT_CELLS,
    CameraMount,
    HandVariation,
    MountVariation,
    VariedRasterizer,
    as_mount,
    coverage,
)
from ._executors import run_tasks

__all__ = ["MAX_LEARNING_HANDS", "LearningSet", "LearningSetOptions", "learning_poses",
           "learning_set", "learning_workers", "random_rest_posture", "render_learning_set",
           "render_mirror_set"]

_FORMAT = 1
#: Most hands a learning set may hold: 100,000 hands of 100 frames are about 14 GB of
#: coverage grids (the shipped perceptrons learnt from 16,000); more would fail for memory
#: after hours of rendering.
MAX_LEARNING_HANDS = 100_000
_LO, _HI = JOINT_LIMITS_DEG[:, 0], JOINT_LIMITS_DEG[:, 1]
# abduction of index, middle, ring, little in a fully fanned rest (deg toward the thumb)
_FAN_DEG = np.array([8.0, 1.0, -6.0, -12.0])


@dataclass(frozen=True)
class LearningSetOptions:
    """What a learning set holds.

    Parameters
    ----------
    hands : int
        Number of random hands.
    poses_per_hand : int
        Frames of each hand (besides its rest frame).
    mix : tuple of 3 float
        Shares of ``from_rest``, ``fingers`` and ``natural`` poses.
    hand_spread : float
        ``spread`` of :meth:`HandVariation.random`.
    segment_width_sd : float
        ``segment_width_sd`` of :meth:`HandVariation.random`: each segment's
        own breadth factor (0: a digit's segments share one).
    flesh_offset_sd_mm : float
        ``flesh_offset_sd_mm`` of :meth:`HandVariation.random`: where each
        segment's surface sits on its joints (0: as the model's).
    breadth_follows_scale : float
        ``breadth_follows_scale`` of :meth:`HandVariation.random`: the power
        of a hand's common length scale that its breadths take (0: breadths
        independent of the lengths).  1 read small hands resting near open
        better with the per-digit estimator (docs/camera_estimator.md, "Hands
        smaller and larger"); not the default.
    mount_variation : MountVariation
        How the device moves between wearers.
    edge_px : int
        Masks are grown or shrunk by up to this many pixels (uniform), so that
        the learner does not rely on the model's exact outline.
    cells : (int, int)
        Coverage grid.
    seed : int
    open_rest_share : float
        Share of hands whose rest posture is near open
        (:func:`random_rest_posture` with ``near_open``); the others rest
        relaxed.  A frame of the rest posture hardly tells a short finger
        from a slightly flexed one, so an estimator reads the rest about as
        the learning set's mean rest; with relaxed rests alone (share 0) a
        hand resting near open (every finger joint at 3-5 deg) was read worse
        than the constant open-hand answer on paper frames (four held-out
        model hands: skill -0.22).  Chosen on held-out model hands (seed 11,
        1.5 times the spread, poses seed 5, 200 frames per set and rest kind;
        per-digit estimator) by the rule: the best mean paper-frame flexion
        MAE over relaxed and near-open test rests, natural frames within 0.2
        deg of the best.  Share 0 / 0.5 / 0.75: paper 6.69 / 5.02 / 4.97,
        natural 11.12 / 10.55 / 10.37 deg.
    rest_slip : float
        How far the device moves on the wrist between a hand's rest frame
        and its other frames, as a multiple of ``mount_variation``'s s.d.s
        (one normal draw per hand; 0: never, the frames and the rest frame
        are seen from one place).  A user's strap slips after calibration:
        perceptrons learnt with slips of 0.5 read slipped frames far better
        and unmoved frames worse (0.9-2.8 deg on natural frames at 4,000
        hands, 0.2-0.3 deg at 16,000), which kept them out of the default
        ensemble (docs/camera_estimator.md, "The device slipping after calibration").
    rest_slip_share : float
        Share of hands whose device slips when `rest_slip` is not 0 (the
        others' frames are seen from where their rest frame was).
    """

    hands: int = 4000
    poses_per_hand: int = 100
    mix: tuple[float, float, float] = (0.4, 0.4, 0.2)
    hand_spread: float = 1.0
    segment_width_sd: float = 0.0
    flesh_offset_sd_mm: float = 0.0
    mount_variation: MountVariation = field(default_factory=MountVariation)
    edge_px: int = 4
    cells: tuple[int, int] = DEFAULT_CELLS
    seed: int = 0
    open_rest_share: float = 0.75
    rest_slip: float = 0.0
    rest_slip_share: float = 1.0
    breadth_follows_scale: float = 0.0

    def __post_init__(self) -> None:
        for name in ("hands", "poses_per_hand"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
                raise InvalidInputError(f"LearningSetOptions.{name} must be a positive integer, "
                                        f"got {v!r}")
        if self.hands > MAX_LEARNING_HANDS:
            raise InvalidInputError(f"LearningSetOptions.hands must be at most "
                                    f"{MAX_LEARNING_HANDS:,}, got {self.hands!r}")
        try:
            mix = tuple(float(m) for m in self.mix)
        except (TypeError, ValueError):
            mix = ()
        if len(mix) != 3 or min(mix) < 0 or not np.isclose(sum(mix), 1.0):
            raise InvalidInputError(f"LearningSetOptions.mix must be 3 shares summing to 1, "
                                    f"got {self.mix!r}")
        object.__setattr__(self, "mix", mix)
        for name, lo, hi in (("edge_px", 0, 20), ("seed", 0, None)):
            v = getattr(self, name)
            if (isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < lo
                    or (hi is not None and v > hi)):
                where = f"in [{lo}, {hi}]" if hi is not None else f">= {lo}"
                raise InvalidInputError(f"LearningSetOptions.{name} must be an integer {where}, "
                                        f"got {v!r}")
            object.__setattr__(self, name, int(v))
        spread = self.hand_spread
        check_number(spread, "LearningSetOptions.hand_spread", minimum=0)
        if not isinstance(self.mount_variation, MountVariation):  # which checks its s.d.s
            raise InvalidInputError("LearningSetOptions.mount_variation must be a MountVariation")
        cells = self.cells
        if (not isinstance(cells, (tuple, list)) or len(cells) != 2
                or any(isinstance(c, bool) or not isinstance(c, (int, np.integer)) or c < 1
                       for c in cells)):
            raise InvalidInputError(f"LearningSetOptions.cells must be (rows, cols), two positive "
                                    f"integers, got {cells!r}")
        object.__setattr__(self, "cells", tuple(int(c) for c in cells))
        for name, top in (("segment_width_sd", 1), ("flesh_offset_sd_mm", 10),
                          ("breadth_follows_scale", 2)):
            sd = getattr(self, name)
            if isinstance(sd, bool) or not isinstance(sd, (int, float)) or not 0 <= sd <= top:
                raise InvalidInputError(f"LearningSetOptions.{name} must be in [0, {top}], "
                                        f"got {sd!r}")
        slip = self.rest_slip
        if isinstance(slip, bool) or not isinstance(slip, (int, float)) or not 0 <= slip <= 5:
            raise InvalidInputError(f"LearningSetOptions.rest_slip must be in [0, 5], got {slip!r}")
        share = self.rest_slip_share
        if isinstance(share, bool) or not isinstance(share, (int, float)) or not 0 <= share <= 1:
            raise InvalidInputError(f"LearningSetOptions.rest_slip_share must be in [0, 1], "
                                    f"got {share!r}")
        share = self.open_rest_share
        if isinstance(share, bool) or not isinstance(share, (int, float)) or not 0 <= share <= 1:
            raise InvalidInputError(f"LearningSetOptions.open_rest_share must be in [0, 1], "
                                    f"got {share!r}")

    def digest(self) -> str:
        """A short digest of the options (names the cached file)."""
        d = asdict(self)
        for name in ("open_rest_share", "segment_width_sd", "flesh_offset_sd_mm", "rest_slip",
                     "breadth_follows_scale"):
            if not d[name]:
                del d[name]  # the sets made before the option keep their names
        if d["rest_slip_share"] == 1.0:
            del d["rest_slip_share"]
        d["format"] = _FORMAT
        return hashlib.sha256(json.dumps(d, sort_keys=True).encode()).hexdigest()[:16]


@dataclass(frozen=True, eq=False)
class LearningSet:
    """Coverage grids of randomised hands with their joint angles.

    Attributes
    ----------
    grids : ndarray, shape (N, rows * cols), uint8
        Coverage of each frame, 255 = fully covered.
    rest_grids : ndarray, shape (hands, rows * cols), uint8
        Coverage of each hand's rest frame.
    hand : ndarray, shape (N,), int32
        The hand (row of `rest_grids`) of each frame.
    angles : ndarray, shape (N, 20), float32
        Joint angles, degrees, canonical order.
    rest_angles : ndarray, shape (hands, 20), float32
    options : LearningSetOptions
    mount : CameraMount
        The nominal device (before each hand's variation).
    side : str
    """

    grids: np.ndarray
    rest_grids: np.ndarray
    hand: np.ndarray
    angles: np.ndarray
    rest_angles: np.ndarray
    options: LearningSetOptions
    mount: CameraMount
    side: str

    def __len__(self) -> int:
        return len(self.grids)


def random_rest_posture(rng: np.random.Generator, *, near_open: bool = False) -> np.ndarray:
    """A random relaxed posture for learning (degrees, (20,)).

    Finger MCP flexion uniform in [-5, 20], PIP in [0, 30], DIP in [0, 20]
    (with `near_open`, every finger flexion uniform in [-3, 8]: a hand held
    open but not flat); the fingers fanned by a common random share (-0.3 to
    1) of a full fan (index +8, middle +1, ring -6, little -12 deg) plus 3 deg
    each; the thumb anywhere in a band around its rest (CMC flexion -15 to 25,
    palmar abduction 0 to 40, MCP -5 to 25, IP -10 to 30 deg).

    Parameters
    ----------
    rng : numpy.random.Generator
        Draws the thumb's four angles first, then the fan share, then each
        finger's (index to little) MCP flexion, abduction, PIP and DIP.
    near_open : bool, keyword-only
        Draw every finger flexion (MCP, PIP, DIP) uniform in [-3, 8] deg
        instead of the relaxed ranges (as many draws, in the same order).

    Returns
    -------
    ndarray, shape (20,), float64
        Degrees, canonical order, clipped to
        :data:`~handsynth.models.JOINT_LIMITS_DEG`.
    """
    a = np.zeros(20)
    a[0] = rng.uniform(-15, 25)
    a[1] = rng.uniform(0, 40)
    a[2] = rng.uniform(-5, 25)
    a[3] = rng.uniform(-10, 30)
    fan = rng.uniform(-0.3, 1.0)
    mcp, pip, dip = ((-3, 8),) * 3 if near_open else ((-5, 20), (0, 30), (0, 20))
    for k in range(4):
        j = 4 + 4 * k
        a[j] = rng.uniform(*mcp)
        a[j + 1] = fan * _FAN_DEG[k] + rng.normal(0, 3)
        a[j + 2] = rng.uniform(*pip)
        a[j + 3] = rng.uniform(*dip)
    return np.clip(a, _LO, _HI)


def _dip(pip: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    return pip * rng.uniform(0.3, 1.0, np.shape(pip)) + rng.normal(0, 5, np.shape(pip))


def learning_poses(rest: np.ndarray, n: int, rng: np.random.Generator, *,
                   mix: tuple[float, float, float] = (0.4, 0.4, 0.2)) -> np.ndarray:
    """Poses of one hand for learning (module docstring), degrees, (n, 20).

    Parameters
    ----------
    rest : ndarray, shape (20,)
        The hand's rest posture.
    n : int
    rng : numpy.random.Generator
    mix : tuple of 3 float, keyword-only
        Shares of ``from_rest``, ``fingers`` and ``natural`` poses.
    """
    kinds = rng.choice(3, size=n, p=np.asarray(mix) / sum(mix))
    out = np.tile(rest, (n, 1))
    nat = natural_pose_set(max(int((kinds == 2).sum()), 1), seed=int(rng.integers(2**31)))
    k_nat = 0
    for i, kind in enumerate(kinds):
        a = out[i]
        if kind == 0:
            motion = int(rng.integers(9))
            if motion < 4:  # one finger flexes (MCP, PIP jointly over their ranges)
                j = 4 + 4 * motion
                a[j] = rng.uniform(_LO[j], _HI[j])
                a[j + 2] = rng.uniform(_LO[j + 2], _HI[j + 2])
                a[j + 3] = _dip(a[j + 2], rng)
            elif motion < 8:  # one finger's abduction
                j = 4 + 4 * (motion - 4)
                a[j + 1] = rng.uniform(_LO[j + 1], _HI[j + 1])
                a[j] = rng.uniform(0, 45)
            else:  # the thumb
                a[:4] = rng.uniform(_LO[:4], _HI[:4])
        elif kind == 1:
            for k in range(4):
                if rng.random() < 0.3:
                    continue
                j = 4 + 4 * k
                c = rng.random()
                a[j] = 100 * c - 10 + rng.normal(0, 15)
                a[j + 2] = 105 * np.clip(c + rng.normal(0, 0.3), 0, 1) - 5
                a[j + 3] = _dip(a[j + 2], rng)
                a[j + 1] = a[j + 1] * (1 - c) + rng.normal(0, 5) * (1 - c)
            if rng.random() < 0.6:
                a[:4] = rng.uniform(_LO[:4], _HI[:4])
        else:
            out[i] = nat[k_nat]
            k_nat += 1
    return np.clip(out, _LO, _HI)


def _random_shape(rng: np.random.Generator) -> HandShape:
    kw = {}
    for name, (lo, mid, hi) in GRID_LEVELS.items():
        kw[name] = rng.uniform(lo - (mid - lo), hi + (hi - mid))
    return HandShape(**kw)


def _edge(mask: np.ndarray, px: int) -> np.ndarray:
    import cv2

    if px == 0:
        return mask
    k = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * abs(px) + 1, 2 * abs(px) + 1))
    op = cv2.dilate if px > 0 else cv2.erode
    return op(mask.view(np.uint8), k).view(bool)


def _grid_bytes(mask: np.ndarray, mount: CameraMount, side: str, cells) -> np.ndarray:
    """The :func:`~handsynth.render.coverage` grid of `mask` as a learning set keeps it:
    uint8, 255 = covered, rounded."""
    return np.rint(coverage(mask, mount, side=side, cells=cells) * 255).astype(np.uint8)


def _hand_plan(rng: np.random.Generator, opts: LearningSetOptions, mount: CameraMount, *,
               forearm: bool = True):
    """The draws of one hand of a learning set: ``(shape key, variation, worn mount, edge_px, rest)``.

    `rng` is drawn in the order every learning set was made with; nothing is
    rendered, so the hands can be rendered apart (:func:`_render_plans`).
    """
    shape = _random_shape(rng)
    key = round(shape.length, 1), round(shape.width, 1), forearm
    variation = HandVariation.random(rng, spread=opts.hand_spread,
                                     segment_width_sd=opts.segment_width_sd,
                                     flesh_offset_sd_mm=opts.flesh_offset_sd_mm,
                                     breadth_follows_scale=opts.breadth_follows_scale)
    worn = opts.mount_variation.sample(mount, rng)
    edge = int(rng.integers(-opts.edge_px, opts.edge_px + 1))
    near_open = opts.open_rest_share > 0 and rng.uniform() < opts.open_rest_share
    rest = random_rest_posture(rng, near_open=bool(near_open))
    return key, variation, worn, edge, rest


def _rasteriser(shapes: dict, key: tuple, variation: HandVariation, worn: CameraMount,
                mount: CameraMount, side: str) -> VariedRasterizer:
    """The rasteriser of rounded shape `key` (length, width, forearm), varied and worn.

    Built once in `shapes` for the nominal `mount` (a few built hands; the variation
    does the rest), then given `variation` and moved to the `worn` mount.
    """
    if key not in shapes:
        shapes[key] = VariedRasterizer(HandShape(length=key[0], width=key[1]), mount,
                                       side=side, forearm=key[2])
    r = shapes[key]
    r.vary(variation)
    r.set_mount(worn)
    return r


def _draw_hand(rng: np.random.Generator, opts: LearningSetOptions, shapes: dict,
               mount: CameraMount, side: str, *, forearm: bool = True):
    """One hand of a learning set, worn and at rest: ``(rasteriser, worn mount, edge_px, rest)``.

    The rasteriser (of `shapes`, built once per rounded shape and `forearm`) is varied and
    moved to the worn mount; `rng` is drawn as :func:`_hand_plan` draws it.
    """
    key, variation, worn, edge, rest = _hand_plan(rng, opts, mount, forearm=forearm)
    return _rasteriser(shapes, key, variation, worn, mount, side), worn, edge, rest


#: Rasterisers a worker process of :func:`render_learning_set` keeps between its tasks,
#: by (shape key, mount, side).
_WORKER_RASTERISERS: dict = {}


def _render_plans(task, shapes: dict | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Render the hands of `task` ``(plans, mount, side, cells)``: rest grids and pose grids.

    Each plan is ``(shape key, variation, worn, edge_px, rest, poses, slip mount or None)``
    as :func:`render_learning_set` draws them.  `shapes` caches the rasterisers (a worker
    process keeps its own, :data:`_WORKER_RASTERISERS`).
    """
    plans, mount, side, cells = task
    if shapes is None:
        shapes = _WORKER_RASTERISERS.setdefault((mount, side), {})
    d = cells[0] * cells[1]
    rest_grids = np.empty((len(plans), d), np.uint8)
    grids = np.empty((sum(len(p[5]) for p in plans), d), np.uint8)
    row = 0
    for h, (key, variation, worn, edge, rest, poses, slip) in enumerate(plans):
        r = _rasteriser(shapes, key, variation, worn, mount, side)
        rest_grids[h] = _grid_bytes(_edge(r.mask(rest), edge), mount, side, cells).ravel()
        if slip is not None:
            r.set_mount(slip)
        for pose in poses:
            grids[row] = _grid_bytes(_edge(r.mask(pose), edge), mount, side, cells).ravel()
            row += 1
    return rest_grids, grids


def render_mirror_set(hands: int, *, seed: int = 0, forearm_share: float = 0.5,
                      options: LearningSetOptions | None = None,
                      mount: CameraMount | None = None,
                      side: str = "right") -> tuple[np.ndarray, np.ndarray]:
    """Rest frames of random hands as the device sees them and mirrored left to right.

    A camera or its driver set to mirror its image shows the device's view turned left to
    right; such a view of a hand at rest still looks like a hand to the estimators
    (docs/camera_estimator.md, "A mirrored camera image").  These pairs teach
    :class:`~handsynth.estimate.MirrorCheck` to tell the two apart.  Each hand is drawn as
    a learning set's hand (:class:`LearningSetOptions`: geometry, device placement, outline
    jitter, rest posture); its forearm stub is left out for a share of the hands, because
    a hand mesh or a real view may show no forearm behind the wrist, and the check must not
    lean on it.

    Parameters
    ----------
    hands : int
        How many hands, at least 1 and at most :data:`MAX_LEARNING_HANDS`.
    seed : int, keyword-only
        The generator's seed; the set is a pure function of the arguments, and its first
        hands do not depend on how many it holds.
    forearm_share : float, keyword-only
        Share of hands drawn with their forearm stub, in [0, 1].
    options : LearningSetOptions, keyword-only, optional
        Spreads of the hands and of the device's placement (its ``hands``,
        ``poses_per_hand``, ``mix`` and ``seed`` are not used).
    mount : CameraMount, keyword-only, optional
        The nominal device (the paper's by default); the grids' wrist cut is its.
    side : {"right", "left"}, keyword-only

    Returns
    -------
    seen, mirrored : ndarray, shape (hands, rows * cols), uint8
        :func:`~handsynth.render.coverage` grids (255 = covered) of each hand's rest frame
        and of that frame turned left to right.

    Raises
    ------
    InvalidInputError
        `hands` or `forearm_share` out of range, naming the value.
    """
    n = check_integer(hands, "hands", minimum=1, maximum=MAX_LEARNING_HANDS)
    share = check_number(forearm_share, "forearm_share", minimum=0, maximum=1)
    opts = check_options(options, LearningSetOptions)
    mount = as_mount(mount)
    rng = np.random.default_rng(check_integer(seed, "seed", minimum=0))
    d = opts.cells[0] * opts.cells[1]
    seen = np.empty((n, d), np.uint8)
    mirrored = np.empty((n, d), np.uint8)
    shapes: dict = {}
    for h in range(n):
        forearm = bool(rng.uniform() < share)
        r, _worn, edge, rest = _draw_hand(rng, opts, shapes, mount, side, forearm=forearm)
        m = _edge(r.mask(rest), edge)
        seen[h] = _grid_bytes(m, mount, side, opts.cells).ravel()
        mirrored[h] = _grid_bytes(np.ascontiguousarray(m[:, ::-1]), mount, side, opts.cells).ravel()
    return seen, mirrored


def render_learning_set(options: LearningSetOptions | None = None, *,
                        mount: CameraMount | None = None, side: str = "right",
                        progress=None, workers: int = 1) -> LearningSet:
    """Render a learning set (module docstring).

    Parameters
    ----------
    options : LearningSetOptions, optional
    mount : CameraMount, keyword-only, optional
        The nominal device (the paper's by default): every hand wears it
        moved by ``options.mount_variation``; the wrist cut of the coverage
        grids is the nominal device's.
    side : {"right", "left"}, keyword-only
    progress : callable, keyword-only, optional
        Called with (hands done, hands) after each chunk of hands rendered.
    workers : int, keyword-only
        Processes rendering the hands (default 1: this one).  The set is the
        same to the byte whatever their number: every random draw is made
        first, in order.  Worker processes are started afresh ("spawn"), so
        a script that asks for them keeps its work under
        ``if __name__ == "__main__":``.

    Returns
    -------
    LearningSet
    """
    opts = check_options(options, LearningSetOptions)
    mount = as_mount(mount)
    workers = check_integer(workers, "workers", minimum=1)
    rng = np.random.default_rng(opts.seed)
    n, per = opts.hands, opts.poses_per_hand
    d = opts.cells[0] * opts.cells[1]
    grids = np.empty((n * per, d), np.uint8)
    rest_grids = np.empty((n, d), np.uint8)
    angles = np.empty((n * per, 20), np.float32)
    rest_angles = np.empty((n, 20), np.float32)
    hand = np.repeat(np.arange(n, dtype=np.int32), per)
    plans = []
    for h in range(n):  # every draw first, in the order the sets were always drawn in
        key, variation, worn, edge, rest = _hand_plan(rng, opts, mount)
        poses = learning_poses(rest, per, rng, mix=opts.mix)
        slip = None
        # drawn only with a slip: the sets made before the option stay the same
        if opts.rest_slip and (opts.rest_slip_share == 1.0 or rng.uniform() < opts.rest_slip_share):
            slip = opts.mount_variation.scaled(opts.rest_slip).sample(worn, rng)
        plans.append((key, variation, worn, edge, rest, poses, slip))
        rest_angles[h] = rest
        angles[h * per:(h + 1) * per] = poses
    # then the rendering, in chunks of hands (a few per worker and progress line)
    size = max(1, min(_CHUNK_HANDS, -(-n // (4 * workers))))
    starts = range(0, n, size)
    tasks = [(plans[a:a + size], mount, side, opts.cells) for a in starts]
    done = 0
    shapes: dict = {}
    results = (run_tasks(_render_plans, tasks, workers=workers) if workers > 1
               else ((i, _render_plans(t, shapes)) for i, t in enumerate(tasks)))
    for i, (rg, g) in results:
        a = starts[i]
        rest_grids[a:a + len(rg)] = rg
        grids[a * per:a * per + len(g)] = g
        done += len(rg)
        if progress is not None:
            progress(done, n)
    return LearningSet(grids, rest_grids, hand, angles, rest_angles, opts, mount, side)


#: Hands per rendering task of :func:`render_learning_set` at most.
_CHUNK_HANDS = 100


def learning_workers(hands: int) -> int:
    """Processes the ``handsynth`` commands render learning sets with.

    `hands` is the largest set's hands (an ensemble's perceptrons learn from
    four times the hands of its base set:
    :func:`~handsynth.estimate.largest_learning_set`).  Every core this
    process may use (at most 8) for 400 hands or more; 1 below, where
    starting the workers takes longer than they save.
    """
    if hands < 400:
        return 1
    return min(usable_cores(), 8)


def learning_set(folder, options: LearningSetOptions | None = None, *,
                 mount: CameraMount | None = None, side: str = "right",
                 progress=None, workers: int = 1) -> LearningSet:
    """The learning set of `options`, read from `folder` or rendered and kept there.

    Parameters
    ----------
    folder : str or os.PathLike
        A folder the caller chose (created if missing).  The file is
        ``learning_<digest>.npz``; a file that does not read back complete is
        rendered again.
    options, mount, side, progress, workers
        As :func:`render_learning_set`.

    Raises
    ------
    InvalidInputError
        `folder` is not a folder name (None, a number, ``""``), or an option
        of the wrong type or value.
    DatabaseError
        The folder cannot be created or written (a file in the way, a
        read-only folder): refused before the set is rendered.
    """
    folder = check_path(folder, "folder", kind="folder")
    opts = check_options(options, LearningSetOptions)
    mount = as_mount(mount)
    key = hashlib.sha256(json.dumps([opts.digest(), mount.as_dict(), side],
                                    sort_keys=True).encode()).hexdigest()[:16]
    path = folder / f"learning_{key}.npz"
    if path.is_file():
        try:
            return _read(path, opts, mount, side)
        except DatabaseCorruptError:
            pass
    # checked before the rendering (minutes with the defaults), not after it
    make_folder(folder, what="learning-set folder", writable=True, error=DatabaseError)
    out = render_learning_set(opts, mount=mount, side=side, progress=progress, workers=workers)
    with atomic_open(path, "wb", what="learning set", error=DatabaseError) as f:
        np.savez(f, grids=out.grids, rest_grids=out.rest_grids, hand=out.hand,
                 angles=out.angles, rest_angles=out.rest_angles,
                 complete=np.array([len(out.grids)]))
    return out


def _read(path: Path, opts: LearningSetOptions, mount: CameraMount, side: str) -> LearningSet:
    try:
        with np.load(path) as z:
            arrays = {k: z[k] for k in ("grids", "rest_grids", "hand", "angles", "rest_angles",
                                        "complete")}
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as exc:
        raise DatabaseCorruptError(f"learning set {path} is unreadable: {exc}") from None
    n = opts.hands * opts.poses_per_hand
    if int(arrays["complete"][0]) != n or arrays["grids"].shape != (n, opts.cells[0] * opts.cells[1]):
        raise DatabaseCorruptError(f"learning set {path} is incomplete")
    return LearningSet(arrays["grids"], arrays["rest_grids"], arrays["hand"], arrays["angles"],
                       arrays["rest_angles"], opts, mount, side)
