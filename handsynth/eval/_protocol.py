"""An evaluation of camera estimators that cannot flatter them (issue 15).

The paper's experiment (:func:`~handsynth.eval.evaluate`) draws its test
poses from the same generator as the databases: one joint moving from the
exact open hand.  A lookup in such a database then looks accurate while a
hand whose other fingers rest a few degrees elsewhere is read as the open
hand.  This protocol changes what was not modelled:

* **Test poses** come from :mod:`handsynth.eval._testposes`, a generator no
  estimator is built from: a relaxed rest posture per hand, then the paper's
  motions from it (``paper``) or natural grasps (``natural``).
* **Test hands**: model hands whose geometry goes beyond the four ratios
  (:func:`model_test_hands`: a random shape over and beyond the grid and a
  :class:`~handsynth.render.HandVariation` of every segment and the palm),
  and the realistic glTF hands of :mod:`handsynth.testhands`
  (:func:`mesh_test_hands`) -- those stand for users' hands: constants are
  chosen on model hands only.
* **Calibration**: an estimator that calibrates gets one frame of the test
  hand at its own rest posture, not at the database's zero.  With
  ``ProtocolOptions.slip`` the device then moves on the wrist before the
  other frames, as a strap slips after calibration.
* **Baseline**: every figure stands beside the constant estimator that
  always answers the open hand (all angles 0) on the same frames, and the
  skill ``1 - MAE / MAE_constant`` (0: no better than the constant; 1:
  perfect).  Per joint: MAE, mean +- s.d. of the signed error, the MAE on
  frames where the joint truly moves (more than 20 deg from the hand's rest
  posture) and the correlation of estimate and truth.

Joint groups: ``finger_flexion`` is the 12 MCP, PIP and DIP flexions of index
to little; ``abduction`` the 4 finger MCP abductions; ``thumb`` its 4 angles;
``all`` the 20.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._checks import check_integer, check_number, check_options
from ..errors import InvalidInputError
from ..models import JOINT_NAMES, HandShape
from ..render import (
    CameraMount,
    HandVariation,
    MountVariation,
    VariedRasterizer,
    as_mount,
)
from ._options import MAX_FRAMES, MAX_HANDS
from ._testposes import REST_POSTURES, natural_test_poses, paper_protocol_poses

__all__ = [
    "JOINT_GROUPS",
    "MOVING_DEG",
    "ProtocolOptions",
    "TestHand",
    "condition_stats",
    "mesh_test_hands",
    "model_test_hands",
    "run_protocol",
]

#: A joint "truly moves" in a frame when it is this far from the hand's rest posture.
MOVING_DEG = 20.0

JOINT_GROUPS: dict[str, tuple[int, ...]] = {
    "finger_flexion": tuple(4 + 4 * k + o for k in range(4) for o in (0, 2, 3)),
    "abduction": tuple(5 + 4 * k for k in range(4)),
    "thumb": (0, 1, 2, 3),
    "all": tuple(range(20)),
}


@dataclass(frozen=True)
class ProtocolOptions:
    """Options of :func:`run_protocol`.

    Parameters
    ----------
    frames : int
        Frames per hand and pose set, 2 to :data:`~handsynth.eval.MAX_FRAMES` (every
        frame of a hand is held in memory).
    pose_sets : tuple of str
        ``"paper"`` and/or ``"natural"``, each once.
    seed : int
        Seed of the test poses and rest postures, >= 0 (independent of any
        estimator's seeds: it is mixed with a constant of this module).
    rest : {"relaxed", "open"}
        The test hands' rest postures (:data:`REST_POSTURES`).
    slip : float
        After the rest frame the device moves on the wrist by one normal
        draw per hand of `slip` times the s.d.s of
        :class:`~handsynth.render.MountVariation` (height 10 mm, shifts 6
        and 8 mm, tilt and roll 4 deg), seeded by `seed` and the hand's
        name; 0 (default): every frame is seen from where the rest frame
        was.
    """

    frames: int = 200
    pose_sets: tuple[str, ...] = ("paper", "natural")
    seed: int = 0
    rest: str = "relaxed"
    slip: float = 0.0

    def __post_init__(self) -> None:
        check_integer(self.frames, "ProtocolOptions.frames", minimum=2, maximum=MAX_FRAMES)
        check_integer(self.seed, "ProtocolOptions.seed", minimum=0)
        sets = self.pose_sets
        if isinstance(sets, str) or not isinstance(sets, (list, tuple)) or not sets \
                or any(p not in ("paper", "natural") for p in sets) or len(set(sets)) < len(sets):
            raise InvalidInputError(f"ProtocolOptions.pose_sets must name 'paper' and/or "
                                    f"'natural', each once, got {sets!r}")
        check_number(self.slip, "ProtocolOptions.slip", minimum=0, maximum=5)
        if not isinstance(self.rest, str) or self.rest not in REST_POSTURES:
            raise InvalidInputError(f"ProtocolOptions.rest must be one of "
                                    f"{', '.join(REST_POSTURES)}, got {self.rest!r}")


@dataclass
class TestHand:
    """A hand of the protocol: its name and a maker of its masks at the device's frame size.

    Attributes
    ----------
    name : str
    kind : {"model", "mesh"}
    make : callable
        ``make()`` returns a :class:`~handsynth.render.MaskMaker` (with
        ``mask(angles)``) of this hand through its own device, ``make(at)``
        through the :class:`~handsynth.render.CameraMount` `at`.
    info : dict
        What the hand is (JSON-ready).
    measurements : HandMeasurements or None
        What a photo of the hand would give (for the paper's selection).
    """

    __test__ = False  # not a pytest class

    name: str
    kind: str
    make: Callable
    info: dict = field(default_factory=dict)
    measurements: object = None
    mount: CameraMount = field(default_factory=CameraMount.paper)


def model_test_hands(n: int, *, seed: int = 0, mount: CameraMount | None = None,
                     spread: float = 1.0, segment_width_sd: float = 0.0,
                     flesh_offset_sd_mm: float = 0.0,
                     breadth_follows_scale: float = 0.0) -> list[TestHand]:
    """`n` model hands with random geometry beyond the four ratios.

    Each hand is a random :class:`HandShape` (each ratio uniform over the
    grid's range and one grid step beyond it on either side) varied by
    :meth:`HandVariation.random` at `spread`, seen through `mount` (the
    paper's device by default) at 720x480, each segment with its own
    breadth when `segment_width_sd` is not 0 and its flesh moved on its
    joints when `flesh_offset_sd_mm` is not 0 (the hands are otherwise those
    of the same seed without them).  Seeds are mixed with a constant of this
    module, so they never repeat a learning set's hands.

    Parameters
    ----------
    n : int
        How many hands, at most :data:`~handsynth.eval.MAX_HANDS`; 0 gives none (a run of
        glTF hands only).
    seed : int, keyword-only
        Seed of the hands (>= 0).
    mount : CameraMount, keyword-only, optional
        The paper's device by default.
    spread : float, keyword-only
        Multiplies every s.d. of :meth:`HandVariation.random` (0: each hand
        its random :class:`HandShape` unvaried).
    segment_width_sd, flesh_offset_sd_mm : float, keyword-only
        As :meth:`HandVariation.with_random_surface` takes them.
    breadth_follows_scale : float, keyword-only
        As :meth:`HandVariation.random` takes it: the power of each hand's
        common length scale that its breadths take (0: independent of it;
        the hands' lengths are those of the same seed whatever its value).

    Returns
    -------
    list of TestHand
        Named ``model0``, ``model1``, ...

    Raises
    ------
    InvalidInputError
        `n` not an integer >= 0, `seed` not an integer >= 0, `spread` not a
        finite number >= 0, `breadth_follows_scale` not in [0, 2] (each named
        with the value received); a `mount`
        that is not a :class:`CameraMount` (:class:`InvalidCameraError`); an
        s.d. out of range (:class:`InvalidShapeError`).
    """
    from ..models import GRID_LEVELS

    n = check_integer(n, "n", minimum=0, maximum=MAX_HANDS)
    seed = check_integer(seed, "seed", minimum=0)
    spread = check_number(spread, "spread", minimum=0)
    breadth_follows_scale = check_number(breadth_follows_scale, "breadth_follows_scale",
                                         minimum=0, maximum=2)
    mount = as_mount(mount)
    rng = np.random.default_rng(np.random.SeedSequence([seed, 0x7E57]))
    surface_rng = np.random.default_rng(np.random.SeedSequence([seed, 0x7E57, 0x5E6]))
    out = []
    for i in range(n):
        ratios = {k: float(rng.uniform(lo - (mid - lo), hi + (hi - mid)))
                  for k, (lo, mid, hi) in GRID_LEVELS.items()}
        shape = HandShape(**ratios)
        var = HandVariation.random(rng, spread=spread,
                                   breadth_follows_scale=breadth_follows_scale).with_random_surface(
            surface_rng, spread=spread, segment_width_sd=segment_width_sd,
            flesh_offset_sd_mm=flesh_offset_sd_mm)

        def make(at=None, shape=shape, var=var):
            r = VariedRasterizer(shape, at or mount)
            r.vary(var)
            return r

        out.append(TestHand(f"model{i}", "model", make,
                            info={"shape": shape.as_dict(), "variation": {
                                k: (list(v) if isinstance(v, tuple) else v)
                                for k, v in var.__dict__.items()}}, mount=mount))
    return out


def mesh_test_hands(names=None, *, mount: CameraMount | None = None,
                    scale: float = 1.0) -> list[TestHand]:
    """Rigged glTF hands as test hands: shipped ones by name, or any file.

    Parameters
    ----------
    names : sequence of str or os.PathLike, optional
        Each a key of :data:`handsynth.testhands.TEST_HANDS` (the hands
        shipped in :mod:`handsynth.testhands`; by default
        :data:`~handsynth.testhands.PROTOCOL_HANDS`) or the
        path of a ``.gltf`` / ``.glb`` file of a hand rigged with OpenXR,
        WebXR, Mixamo, Unity or VRM humanoid or MANO joint names
        (:func:`handsynth.testhands.load_mesh_rig`), named by its file's stem.
    mount : CameraMount, keyword-only, optional
        The paper's by default.
    scale : float, keyword-only
        Every hand made larger or smaller about its wrist joint by this
        factor (:meth:`handsynth.testhands.MeshRig.scaled`); 1 by default.

    Returns
    -------
    list of TestHand
        Each with its :attr:`TestHand.measurements` (taken on the mesh here,
        which also checks it).

    Raises
    ------
    InvalidInputError
        A name that is neither a shipped hand nor a glTF file, a file that
        does not load as a rigged hand or whose mesh cannot be measured (a
        damaged file: the loader's message, naming the file), two hands of
        one name, or a `scale` outside [0.5, 2].
    """
    from ..testhands import (
        PROTOCOL_HANDS,
        TEST_HANDS,
        MeshHandRenderer,
        load_mesh_rig,
        shipped_hand_path,
    )

    mount = as_mount(mount)
    out: list[TestHand] = []
    entries = list(names or PROTOCOL_HANDS)
    for entry in entries:
        if str(entry) in TEST_HANDS:
            name, path = str(entry), shipped_hand_path(str(entry))
        elif Path(entry).suffix.lower() in (".gltf", ".glb"):
            path = Path(entry)
            if not path.is_file():
                raise InvalidInputError(f"test hand file {str(path)!r} does not exist")
            name = path.stem
        else:
            raise InvalidInputError(f"a test hand is one of {sorted(TEST_HANDS)} or a .gltf/.glb "
                                    f"file, got {str(entry)!r}")

        if name in (h.name for h in out):
            raise InvalidInputError(f"two test hands named {name!r} (the results are keyed by "
                                    f"the name), got {', '.join(str(e) for e in entries)}")
        # a file that is no rigged hand, a damaged mesh or a bad scale fails here, not after
        # hours of learning: the rig is loaded, scaled, put in a scene and measured
        try:
            rig = load_mesh_rig(path)
        except InvalidInputError as exc:
            raise _naming(exc, path) from None
        rig.scaled(scale)

        def make(at=None, path=path):
            return MeshHandRenderer(at or mount, path=path, scale=scale)

        renderer = make()
        try:
            measurements = renderer.measurements()
        except InvalidInputError as exc:
            raise _naming(exc, path) from None
        finally:
            renderer.close()
        info = {"file": path.name, **({"scale": float(scale)} if scale != 1.0 else {})}
        out.append(TestHand(name, "mesh", make, info=info, measurements=measurements,
                            mount=mount))
    return out


def _naming(exc: InvalidInputError, path: Path) -> InvalidInputError:
    """`exc` with the test hand file named, unless its message names it already."""
    if str(path) not in str(exc) and len(exc.args) == 1:
        exc.args = (f"{exc.args[0]} (test hand file {str(path)!r})",)
    return exc


def _seed(seed: int, hand: str, pose_set: str) -> np.random.SeedSequence:
    return np.random.SeedSequence([seed, 0x51A7E, *hand.encode(), *pose_set.encode()])


def _stats(est: np.ndarray, truth: np.ndarray, rest: np.ndarray) -> dict:
    """Per-joint and per-group figures of one method on one set of frames."""
    err = est - truth
    ok = ~np.isnan(err).any(axis=1)
    err, e_t, e_r = err[ok], truth[ok], rest[ok]
    e_est = est[ok]
    moving = np.abs(e_t - e_r) > MOVING_DEG
    joints = {}
    for j, name in enumerate(JOINT_NAMES):
        m = moving[:, j]
        sd_t, sd_e = np.std(e_t[:, j]), np.std(e_est[:, j])
        corr = float(np.corrcoef(e_t[:, j], e_est[:, j])[0, 1]) if sd_t > 1e-9 and sd_e > 1e-9 \
            else float("nan")
        joints[name] = {
            "mae_deg": _r(np.mean(np.abs(err[:, j]))),
            "mean_deg": _r(np.mean(err[:, j])),
            "sd_deg": _r(np.std(err[:, j], ddof=1)) if len(err) > 1 else None,
            "moving_frames": int(m.sum()),
            "moving_mae_deg": _r(np.mean(np.abs(err[m, j]))) if m.any() else None,
            "moving_mean_deg": _r(np.mean(err[m, j])) if m.any() else None,
            "corr": _r(corr),
        }
    groups = {g: _r(np.mean(np.abs(err[:, list(ix)]))) for g, ix in JOINT_GROUPS.items()}
    return {"frames": int(ok.sum()), "no_hand": int((~ok).sum()), "groups_mae_deg": groups,
            "joints": joints}


def _r(v) -> float | None:
    v = float(v)
    return None if not math.isfinite(v) else round(v, 4)


def condition_stats(estimates: np.ndarray, truth: np.ndarray, rest: np.ndarray) -> dict:
    """Figures of one method beside the constant open-hand estimator on the same frames.

    Parameters
    ----------
    estimates, truth : ndarray, shape (N, 20)
        Degrees; rows of `estimates` with NaN (no hand found) are left out of
        the method's figures and counted.
    rest : ndarray, shape (20,) or (N, 20)
        The hand's rest posture (a joint moves when it is more than
        :data:`MOVING_DEG` from it).

    Returns
    -------
    dict
        ``method`` and ``constant`` (the figures of :func:`_stats`) and
        ``skill`` per joint group: ``1 - MAE / MAE_constant``.

    Raises
    ------
    InvalidInputError
        `estimates` and `truth` not both (N, 20) with the same N, or `rest`
        neither (20,) nor of their shape.
    """
    truth = np.asarray(truth, float)
    estimates = np.asarray(estimates, float)
    if truth.ndim != 2 or truth.shape[1] != 20 or estimates.shape != truth.shape:
        raise InvalidInputError(f"estimates and truth must both have shape (N, 20), got "
                                f"{estimates.shape} and {truth.shape}")
    rest = np.asarray(rest, float)
    if rest.shape not in ((20,), truth.shape):
        raise InvalidInputError(f"rest must have shape (20,) or {truth.shape}, got {rest.shape}")
    rest = np.broadcast_to(rest, truth.shape)
    method = _stats(estimates, truth, rest)
    constant = _stats(np.zeros_like(truth), truth, rest)
    skill = {}
    for g in JOINT_GROUPS:
        a, b = method["groups_mae_deg"][g], constant["groups_mae_deg"][g]
        skill[g] = _r(1.0 - a / b) if a is not None and b else None
    return {"method": method, "constant": constant, "skill": skill}


def run_protocol(methods: dict, hands: list[TestHand], options: ProtocolOptions | None = None,
                 *, progress=None) -> dict:
    """Render every test hand's frames and score every method on them.

    Parameters
    ----------
    methods : dict of str to callable
        ``make(rest_frame, hand)`` returns an object with ``estimate(frame)``
        (a :class:`~handsynth.estimate.PoseEstimator`) for one test hand, or
        None where the method does not apply to the hand;
        `rest_frame` is the hand at its rest posture (720x480 bool mask),
        `hand` the :class:`TestHand` (for methods that need its measurements).
    hands : list of TestHand
    options : ProtocolOptions, optional
    progress : callable, keyword-only, optional
        Called with a line of text after each hand, pose set and method.

    Returns
    -------
    dict
        ``{"options", "hands": {name: {"info", "rest_deg", "<pose set>":
        {method: condition_stats + "seconds_per_frame" + "moved_frames"}}}}``;
        ``moved_frames`` counts the frames whose estimate said the device had
        moved since the rest frame (:attr:`PoseEstimate.moved`).

    Raises
    ------
    InvalidInputError
        No methods, or two test hands of one name (the result is keyed by it).
    """
    opts = check_options(options, ProtocolOptions)
    if not methods:
        raise InvalidInputError("run_protocol needs at least one method")
    names = [h.name for h in hands]
    if len(set(names)) < len(names):
        twice = sorted({n for n in names if names.count(n) > 1})
        raise InvalidInputError(f"test hands must have distinct names, got {', '.join(twice)} twice")
    out: dict = {"options": {"frames": opts.frames, "pose_sets": list(opts.pose_sets),
                             "seed": opts.seed, "rest": opts.rest, "moving_deg": MOVING_DEG},
                 "hands": {}}
    if opts.slip:
        out["options"]["slip"] = opts.slip
    for hand in hands:
        rng = np.random.default_rng(_seed(opts.seed, hand.name, "rest"))
        rest = REST_POSTURES[opts.rest](rng)
        makers = [hand.make()]
        try:
            rest_frame = makers[0].mask(rest)
            if hand.measurements is None and callable(getattr(makers[0], "measurements", None)):
                hand.measurements = makers[0].measurements()
            made = {name: est for name, make in methods.items()
                    if (est := make(rest_frame, hand)) is not None}
            rec: dict = {"info": hand.info, "kind": hand.kind,
                         "rest_deg": [round(float(v), 3) for v in rest]}
            if opts.slip:  # the strap slips after calibration
                srng = np.random.default_rng(_seed(opts.seed, hand.name, "slip"))
                slipped = MountVariation().scaled(opts.slip).sample(hand.mount, srng)
                rec["slipped_mount"] = {k: round(float(v), 3) for k, v in slipped.as_dict().items()}
                makers.append(hand.make(slipped))
            for ps in opts.pose_sets:
                prng = np.random.default_rng(_seed(opts.seed, hand.name, ps))
                gen = paper_protocol_poses if ps == "paper" else natural_test_poses
                poses, _ = gen(rest, opts.frames, prng)
                frames = makers[-1].masks(poses)
                rec[ps] = {}
                for name, est in made.items():
                    t0 = time.perf_counter()
                    read = [est.estimate(f) for f in frames]
                    dt = (time.perf_counter() - t0) / len(frames)
                    stats = condition_stats(np.stack([e.angles for e in read]), poses, rest)
                    stats["seconds_per_frame"] = round(dt, 6)
                    stats["moved_frames"] = sum(bool(getattr(e, "moved", False)) for e in read)
                    rec[ps][name] = stats
                    if progress is not None:
                        mae, const = (stats[k]["groups_mae_deg"] for k in ("method", "constant"))
                        progress(f"{hand.name} {ps} {name}: flexion MAE {mae['finger_flexion']} "
                                 f"(constant {const['finger_flexion']}, skill "
                                 f"{stats['skill']['finger_flexion']}), all {mae['all']} "
                                 f"(skill {stats['skill']['all']})")
        finally:
            for maker in makers:
                close = getattr(maker, "close", None)
                if close is not None:
                    close()
        out["hands"][hand.name] = rec
    return out
