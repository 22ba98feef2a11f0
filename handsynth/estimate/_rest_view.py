"""Is the rest frame seen as the device sees it, or turned?  Read from the rest frame.

Three mistakes of wearing or wiring turn every frame the learnt estimators read:

* the device on the other hand than the estimator's: the view turned top to bottom;
* the camera mounted turned half a turn: the view turned both ways;
* a camera, or its driver, set to mirror its image (as many webcams are for a video
  call): the view turned left to right.

The first two read as no hand learnt (every frame ``low_confidence``); the estimator
calibrated to the rest frame turned back reads that as a hand.  A mirrored view does not
read so: the fingers point into the wrist cut and what is left looks enough like a hand
at rest that the estimators read it, with no skill and seldom flagged (the default
ensemble on three glTF hands and six held-out model hands, 30 natural frames per rest:
finger flexion MAE 27.5-39.6° against 7.0-13.1° as the camera sees them, the open-hand
constant 34.0-49.5°; docs/camera_estimator.md, "A mirrored camera image").
:func:`read_rest_frame` says which turn, if any, explains a rest frame.

:class:`MirrorCheck` tells a rest frame as the device sees it from its mirror image.
A small perceptron learnt from the rest frames of random model hands, as seen and
mirrored (:func:`~handsynth.db.render_mirror_set`; half of them without their forearm
stub, so that it does not lean on a forearm behind the wrist), scores a coverage grid
near 1 for a view as the device sees it and near 0 for a mirrored one.  A rest frame
reads mirrored when its mirror image scores higher than the frame itself by more than
``MirrorCheckOptions.margin``.  Comparing the two views of one frame, instead of the
score of one, leaves out what the hand's own geometry does to the score.

The check learnt with the default options for the paper's device is shipped
(``shipped/mirror_check.npz``, :func:`mirror_check`), with the first two hands of the set
it learnt from: a test renders them again and says to learn it again when the hand
generator or the rasteriser has changed (``python scripts/ship_mirror_check.py``).
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from .._checks import check_integer, check_number, check_options
from .._io import atomic_open
from ..db import LearningSetOptions, render_mirror_set
from ..errors import DatabaseCorruptError, DatabaseError, InvalidInputError
from ..render import CameraMount, SkinColour, as_mount
from ._learned import LearnedEstimator, _flush_subnormals, _relu_forward, fit_mlp

__all__ = ["TURNS", "MirrorCheck", "MirrorCheckOptions", "MirrorReading", "RestFrameReading",
           "mirror_check", "read_rest_frame"]

_FORMAT = 1
#: Hands of the learning set kept in the file as its fingerprint.
_FINGERPRINT_HANDS = 2
_SHIPPED = Path(__file__).parent / "shipped" / "mirror_check.npz"


@dataclass(frozen=True)
class MirrorCheckOptions:
    """How :class:`MirrorCheck` is learnt and when it calls a view mirrored.

    Parameters
    ----------
    hands : int
        Random model hands it learns from (:func:`~handsynth.db.render_mirror_set`), each
        seen and mirrored.  With 4,000 hands (the default perceptron) 4 of 90 held-out
        rest frames scored their mirror image higher; with 12,000, 1 (by 0.03).
    seed : int
        Seed of the hands and of the perceptron's start.
    forearm_share : float
        Share of the hands drawn with their forearm stub.  With every hand's forearm
        shown, the mirror image of a glTF hand (which has none) scored as high as the
        hand itself.
    components : int
        Principal components of the grids the perceptron reads.
    hidden : tuple of int
        Its hidden layers.
    epochs : int
        Passes over the learning set.
    margin : float
        A view reads mirrored when its mirror image scores higher than the view itself
        by more than this.  Chosen on model hands only: the smallest lead of a view as
        the device sees it over its mirror image was 0.26 (0.1 % quantile over 1,000
        learning-like hands of another seed) and -0.03 over six held-out model hands
        and the three glTF hands, worn as the paper's device and beyond the learning
        set's spread (40 mm higher, 30 mm lower, tilted or rolled 15°).

    Raises
    ------
    InvalidInputError
        A value out of range, naming the field and the value; an unknown keyword
        raises ``TypeError``.
    """

    hands: int = 12000
    seed: int = 0
    forearm_share: float = 0.5
    components: int = 64
    hidden: tuple[int, ...] = (64,)
    epochs: int = 30
    margin: float = 0.3

    def __post_init__(self) -> None:
        check_integer(self.hands, "MirrorCheckOptions.hands", minimum=2)
        check_integer(self.seed, "MirrorCheckOptions.seed", minimum=0)
        check_number(self.forearm_share, "MirrorCheckOptions.forearm_share", minimum=0,
                     maximum=1)
        check_integer(self.components, "MirrorCheckOptions.components", minimum=1)
        if not isinstance(self.hidden, tuple) or not self.hidden:
            raise InvalidInputError(f"MirrorCheckOptions.hidden must be a non-empty tuple of "
                                    f"layer sizes, got {self.hidden!r}")
        for size in self.hidden:
            check_integer(size, "MirrorCheckOptions.hidden", minimum=1)
        check_integer(self.epochs, "MirrorCheckOptions.epochs", minimum=1)
        check_number(self.margin, "MirrorCheckOptions.margin", minimum=0)


@dataclass(frozen=True)
class MirrorReading:
    """What :meth:`MirrorCheck.read` found in a rest frame.

    Attributes
    ----------
    seen : float
        Score of the frame as given (near 1: a view as the device sees it).
    turned : float
        Score of the frame turned left to right.
    mirrored : bool
        The frame reads mirrored: ``turned - seen`` exceeds the check's margin.
    """

    seen: float
    turned: float
    mirrored: bool


class MirrorCheck:
    """Tells a rest frame as the device sees it from its mirror image (module docstring).

    Made by :meth:`learn` or :meth:`load`, or :func:`mirror_check` for the shipped one.

    Attributes
    ----------
    options : MirrorCheckOptions
    mount : CameraMount
        The device whose view it learnt.
    side : str
        The hand it learnt.
    cells : (int, int)
        The coverage grid it reads.
    """

    def __init__(self, arrays: dict, *, options: MirrorCheckOptions, mount: CameraMount,
                 side: str, cells: tuple[int, int]) -> None:
        self.options = options
        self.mount = mount
        self.side = side
        self.cells = (int(cells[0]), int(cells[1]))
        self._a = _flush_subnormals(arrays)  # (see there: speed, same answers)
        layers = int(self._a["layers"])
        self._weights = [self._a[f"w{i}"] for i in range(layers)]
        self._biases = [self._a[f"b{i}"] for i in range(layers)]

    # -- learning ------------------------------------------------------------------
    @classmethod
    def learn(cls, options: MirrorCheckOptions | None = None, *,
              mount: CameraMount | None = None, side: str = "right") -> MirrorCheck:
        """Learn the check from random model hands (about 45 s for 12,000 hands on one core).

        Parameters
        ----------
        options : MirrorCheckOptions, optional
        mount : CameraMount, keyword-only, optional
            The nominal device (the paper's by default).
        side : {"right", "left"}, keyword-only

        Returns
        -------
        MirrorCheck
        """
        opts = check_options(options, MirrorCheckOptions)
        mount = as_mount(mount)
        data = LearningSetOptions()
        seen, turned = render_mirror_set(opts.hands, seed=opts.seed,
                                         forearm_share=opts.forearm_share, mount=mount,
                                         side=side)
        x = np.vstack([seen, turned]).astype(np.float32) * np.float32(1 / 255)
        y = np.concatenate([np.ones(len(seen)), np.zeros(len(turned))]).astype(np.float32)
        mean = x.mean(axis=0)
        k = min(opts.components, x.shape[1])
        # principal directions from every fourth row: the same directions, a quarter the time
        vt = np.linalg.svd(x[::4] - mean, full_matrices=False)[2]
        components = np.ascontiguousarray(vt[:k].T, dtype=np.float32)
        codes = (x - mean) @ components
        scale = np.float32(codes.std())
        weights, biases = fit_mlp(codes / scale, y[:, None], hidden=opts.hidden,
                                  epochs=opts.epochs, batch=128, learning_rate=2e-3,
                                  seed=opts.seed)
        arrays: dict = {"mean": mean, "components": components, "scale": np.array(scale),
                        "layers": np.array(len(weights)),
                        "fingerprint_seen": seen[:_FINGERPRINT_HANDS],
                        "fingerprint_turned": turned[:_FINGERPRINT_HANDS]}
        for i, (w, b) in enumerate(zip(weights, biases)):
            arrays[f"w{i}"], arrays[f"b{i}"] = w, b
        return cls(arrays, options=opts, mount=mount, side=side, cells=data.cells)

    # -- reading -------------------------------------------------------------------
    def score(self, grid: np.ndarray) -> float:
        """How much a coverage grid looks like a rest frame as the device sees it.

        Parameters
        ----------
        grid : ndarray, shape cells, uint8
            A :func:`~handsynth.render.coverage` grid (255 = covered), as
            :meth:`LearnedEstimator.grid` makes it.

        Returns
        -------
        float
            Near 1 for a view as the device sees it, near 0 for a mirrored one.

        Raises
        ------
        InvalidInputError
            A grid of another shape or dtype, naming both.
        """
        g = np.asarray(grid)
        if g.dtype != np.uint8 or g.shape != self.cells:
            raise InvalidInputError(f"grid must be a {self.cells[0]}x{self.cells[1]} uint8 "
                                    f"coverage grid, got {g.dtype} of shape {g.shape}")
        x = g.reshape(1, -1).astype(np.float32) * np.float32(1 / 255) - self._a["mean"]
        codes = (x @ self._a["components"]) / self._a["scale"]
        return float(_relu_forward(codes, self._weights, self._biases)[-1][0, 0])

    def read(self, estimator, rest_frame: np.ndarray, *,
             segment: str | SkinColour = "auto") -> MirrorReading:
        """Does `rest_frame` read mirrored left to right?

        The frame and its mirror image are each told into hand and background as
        `estimator` calibrated to that image tells it (over an ordinary background, by
        the colour of the skin where the back of the hand is in that image), and each
        grid is scored.

        Parameters
        ----------
        estimator : LearnedEstimator or EnsembleEstimator
            The estimator that will read the frames, calibrated or not (it makes the
            grids: its hand, its wrist cut).  An ensemble's first learnt member is used.
        rest_frame : ndarray, shape (H, W) or (H, W, 3)
            The frame of the hand at rest, as the estimator takes it.
        segment : {"auto", "brightness", "colour"} or SkinColour, keyword-only
            As :meth:`LearnedEstimator.calibrated`'s; a fitted ``SkinColour`` is used
            for both images.

        Returns
        -------
        MirrorReading

        Raises
        ------
        InvalidInputError
            An estimator with no learnt member, or one learnt for another device or
            grid than the check; a frame the estimator refuses (naming it).
        """
        est = _learnt_member(estimator)
        mount, _side, _turned_over, cells = est.view_key
        if mount != self.mount or cells != self.cells:
            raise InvalidInputError(
                f"the estimator learnt the view of {mount} in {cells[0]}x{cells[1]} cells, "
                f"the mirror check that of {self.mount} in {self.cells[0]}x{self.cells[1]}: "
                "learn a MirrorCheck for its device")
        frame = np.asarray(rest_frame)
        scores = []
        for view in (frame, np.ascontiguousarray(frame[:, ::-1])):
            told = est.calibrated(view, check_moved=False, segment=segment)
            scores.append(self.score(told.grid(view)))
        seen, turned = scores
        return MirrorReading(seen=seen, turned=turned,
                             mirrored=turned - seen > self.options.margin)

    # -- storage -------------------------------------------------------------------
    def save(self, path) -> None:
        """Write the check to `path` (``.npz``), complete or not at all."""
        meta = {"format": _FORMAT, "options": asdict(self.options),
                "mount": self.mount.as_dict(), "side": self.side, "cells": list(self.cells)}
        with atomic_open(Path(path), "wb", what="mirror check", error=DatabaseError) as f:
            np.savez(f, meta=np.array(json.dumps(meta)), **self._a)

    @classmethod
    def load(cls, path) -> MirrorCheck:
        """Read a check written by :meth:`save`.

        Raises
        ------
        DatabaseError
            The file does not exist.
        DatabaseCorruptError
            A file that is not such a check (damaged, truncated, another format, an array
            missing), naming the file and what is wrong.
        """
        path = Path(path)
        if not path.is_file():
            raise DatabaseError(f"mirror check {path} does not exist")
        try:
            with np.load(path, allow_pickle=False) as z:
                arrays = {k: z[k] for k in z.files}
            meta = json.loads(str(arrays.pop("meta")))
            if meta.get("format") != _FORMAT:
                raise ValueError(f"format {meta.get('format')!r}, expected {_FORMAT}")
            options = MirrorCheckOptions(**{**meta["options"],
                                            "hidden": tuple(meta["options"]["hidden"])})
            layers = int(arrays["layers"])
            missing = [k for k in ("mean", "components", "scale", "fingerprint_seen",
                                   "fingerprint_turned",
                                   *(f"{p}{i}" for i in range(layers) for p in "wb"))
                       if k not in arrays]
            if missing:
                raise ValueError(f"missing array(s) {', '.join(missing)}")
            return cls(arrays, options=options, mount=CameraMount(**meta["mount"]),
                       side=meta["side"], cells=tuple(meta["cells"]))
        except Exception as exc:  # damaged in any of the ways numpy, zipfile and json fail
            raise DatabaseCorruptError(f"mirror check {path} is unreadable: {exc}") from None

    def fingerprint_matches(self) -> bool:
        """Whether the first hands of its learning set render as they did when it learnt."""
        opts = self.options
        seen, turned = render_mirror_set(_FINGERPRINT_HANDS, seed=opts.seed,
                                         forearm_share=opts.forearm_share, mount=self.mount,
                                         side=self.side)
        return bool(np.array_equal(seen, self._a["fingerprint_seen"])
                    and np.array_equal(turned, self._a["fingerprint_turned"]))


def _learnt_member(estimator) -> LearnedEstimator:
    if isinstance(estimator, LearnedEstimator):
        return estimator
    for m in getattr(estimator, "members", ()):
        if isinstance(m, LearnedEstimator):
            return m
    raise InvalidInputError(f"estimator must be a LearnedEstimator or an ensemble with one, "
                            f"got {type(estimator).__name__}")


@lru_cache(maxsize=1)
def _shipped() -> MirrorCheck:
    return MirrorCheck.load(_SHIPPED)


def mirror_check(options: MirrorCheckOptions | None = None, *,
                 mount: CameraMount | None = None, side: str = "right") -> MirrorCheck:
    """The mirror check of `options` for `mount`: the shipped one, or learnt now.

    Parameters as :meth:`MirrorCheck.learn`'s; `side` is the hand the estimators learnt (a
    left-hand estimator made by :meth:`LearnedEstimator.mirrored` reads its frames as the
    right hand's).

    Returns
    -------
    MirrorCheck
        The shipped check when it was learnt with these arguments (read at once);
        otherwise one learnt now (about 45 s for 12,000 hands).
    """
    opts = check_options(options, MirrorCheckOptions)
    mount = as_mount(mount)
    if _SHIPPED.is_file():
        shipped = _shipped()
        if (shipped.options, shipped.mount, shipped.side) == (opts, mount, side):
            return shipped
    return MirrorCheck.learn(opts, mount=mount, side=side)


#: The turns of a rest frame :func:`read_rest_frame` tries, and what each says.
TURNS = {"top to bottom": "the view of the other hand than the estimator's",
         "half a turn": "the camera mounted turned half a turn",
         "left to right": "a camera set to mirror its image"}


@dataclass(frozen=True)
class RestFrameReading:
    """What :func:`read_rest_frame` found.

    Attributes
    ----------
    low_confidence : bool
        The estimator calibrated to the frame reads the frame itself as unlike any
        hand learnt.
    turn : str or None
        The turn of the frame that reads as a hand where the frame does not, one of
        :data:`TURNS` (``"top to bottom"``: the other hand's view; ``"half a turn"``: the
        camera upside down; ``"left to right"``: a mirrored image); None when no turn
        explains the frame better than it is.
    mirror : MirrorReading or None
        The mirror check's reading, when it was asked (not when a turn top to bottom or
        half a turn explained the frame, nor for an estimator of another device than the
        shipped check's with no `check` given).
    """

    low_confidence: bool
    turn: str | None
    mirror: MirrorReading | None


def read_rest_frame(estimator, rest_frame: np.ndarray, *, segment: str | SkinColour = "auto",
                    check: MirrorCheck | None = None) -> RestFrameReading:
    """Which turn of `rest_frame`, if any, is the view the estimator learnt (module docstring).

    A frame that reads as unlike any hand learnt is read turned top to bottom and turned
    half a turn, each by the estimator calibrated to it; of those that read as a hand the
    one it finds least novel (its ``error``) is the turn (measured with the shipped
    perceptrons on three model hands of other geometry: the right turn's ``error`` 2.0-2.5,
    the other's 3.5-4.5, novelty limit about 4.9).  Otherwise the mirror check says
    whether the frame reads mirrored left to right.

    Parameters
    ----------
    estimator : LearnedEstimator or EnsembleEstimator
        The estimator that will read the frames (calibrated or not).
    rest_frame : ndarray, shape (H, W) or (H, W, 3)
        The frame of the hand at rest, as the estimator takes it.
    segment : {"auto", "brightness", "colour"} or SkinColour, keyword-only
        As :meth:`LearnedEstimator.calibrated`'s.
    check : MirrorCheck, keyword-only, optional
        The mirror check; the shipped one (:func:`mirror_check`) when the estimator
        learnt the paper's device, else none is asked unless given.

    Returns
    -------
    RestFrameReading

    Raises
    ------
    InvalidInputError
        A frame the estimator refuses (no hand, another width-to-height ratio), naming
        it; an estimator of another device than `check`'s.
    """
    frame = np.asarray(rest_frame)
    low = estimator.calibrated(frame, segment=segment).estimate(frame).low_confidence
    if low:
        best = None
        for turn, view in (("top to bottom", frame[::-1]), ("half a turn", frame[::-1, ::-1])):
            view = np.ascontiguousarray(view)
            got = estimator.calibrated(view, segment=segment).estimate(view)
            if not got.low_confidence and (best is None or got.error < best[0]):
                best = (got.error, turn)
        if best is not None:
            return RestFrameReading(low_confidence=True, turn=best[1], mirror=None)
    if check is None:
        shipped = mirror_check()
        if _learnt_member(estimator).view_key[0] == shipped.mount:
            check = shipped
    reading = None if check is None else check.read(estimator, frame, segment=segment)
    mirrored = reading is not None and reading.mirrored
    return RestFrameReading(low_confidence=low, turn="left to right" if mirrored else None,
                            mirror=reading)
