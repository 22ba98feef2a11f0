"""Pose from the camera's fixed frame, learnt from randomised model hands (beyond the paper).

The paper's lookup crops the silhouette to its bounding box and compares it
with one hand shape's entries, each one finger moving from the exact open
hand.  Issue 15 measured what that gives on hands the databases were not made
from, resting a few degrees from zero: no better than always answering the
open hand.  This estimator changes three things:

1. **The camera's frame is kept** (:func:`~handsynth.render.coverage`): the
   camera is fixed to the wrist, so a cell's place means something and one
   finger's motion changes only the cells it crosses.
2. **It learns from many hands** (:func:`~handsynth.db.learning_set`): random
   segment lengths and breadths, palm length, MCP places, rest postures and
   device offsets, with fingers moving alone and together.
3. **It can read the user's rest frame** (:meth:`LearnedEstimator.calibrated`):
   the input is the frame's coverage and its difference from the coverage of
   a frame of the same hand at rest, and the learning set pairs every frame
   with its hand's rest frame, so the estimator learns what in a frame is the
   hand's own shape and what is motion.  The rest frame need not be the open
   hand: any relaxed posture.

Three regressors share that input (:class:`LearnedOptions` ``kind``):

``"fingers"`` (default)
    The pose space factorises: each digit is read from its own cells.  A
    cell belongs to a digit when its coverage correlates with one of the
    digit's angles over the learning set (|r| > 0.1), weighted by that
    correlation; per digit, the principal components of those cells (of the
    frame and of its difference from the rest frame) and, among the ``k``
    nearest learning frames (weights ``1 / (d + d_1)``, ``d_1`` the nearest
    distance; faiss inverted file), a weighted ridge regression of the
    digit's angles on their codes read at the frame's code
    (:func:`local_linear`; ``local="mean"``: their weighted mean).  Other
    fingers moving no longer disturb a digit's match.
``"knn"``
    The same nearest-neighbour mean on the principal components of the whole
    frame.
``"mlp"``
    A two-hidden-layer perceptron (ReLU) on the principal components (one
    common scale), trained with Adam on the squared error of standardised
    angles (numpy only; :func:`fit_mlp`).

Chosen on model hands of random geometry (docs/camera_estimator.md, "Camera estimator for
unseen hands"): ``"fingers"`` with ``k = 128`` and the local linear fit on a
400,000-frame learning set (4,000 hands), alone or averaged with ``"mlp"``
(:class:`~handsynth.estimate.EnsembleEstimator`).

Each kind learns how unlike the learning frames a frame may be before it is
flagged ``low_confidence`` (a *novelty limit*, stored as ``novelty_limit``):
``"fingers"``, the 99th percentile of the distance of learning frames to the
nearest frame of another hand; ``"mlp"`` and ``"knn"``, the 99th percentile,
over the learning frames, of the norm of the part of a frame's input that its
principal components leave out (:func:`_left_out_norms`).  A frame that shows
no hand, or a hand the device does not see as it was learnt (shifted by a
slipped mount, upside down), leaves far more out than any learning frame.

Everything learnt is kept in a folder the caller names
(:func:`learned_estimator`), as one ``.npz`` written to a temporary name and
renamed when complete; the default ensemble's perceptrons are shipped with
handsynth and read from the package when that folder lacks them
(:mod:`handsynth.estimate._shipped`).
"""

from __future__ import annotations

import copy
import hashlib
import itertools
import json
import zipfile
import zlib
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from numba import njit

from .._checks import (
    check_array,
    check_instance,
    check_integer,
    check_number,
    check_options,
    check_path,
    check_side,
    short_repr,
)
from .._io import atomic_open, make_folder, os_error_reason
from ..db import LearningSet, LearningSetOptions, learning_set
from ..errors import (
    DatabaseCorruptError,
    DatabaseError,
    DatabaseMismatchError,
    EstimationError,
    InvalidInputError,
)
from ..models import JOINT_LIMITS_DEG
from ..render import (
    CameraMount,
    SkinColour,
    as_mount,
    brightness_overlap,
    coverage,
    fit_skin_colour,
    skin_mask,
)
from ._hand import MIN_HAND_COVERAGE
from ._lookup import PoseEstimate, check_frame_ratio
from ._moved import MoveCheck
from ._shipped import shipped_path

__all__ = ["LearnedEstimator", "LearnedOptions", "fit_mlp", "learned_estimator",
           "local_linear", "train_learned"]

_FORMAT = 2  # 2: novelty_limit
#: ``segment="auto"`` tells the hand by colour when Otsu's mask and the skin's colour mask
#: of the rest frame overlap less than this (intersection over union): 0.92-0.94 on a dark
#: background, 0.01-0.86 over photographs (docs/camera_estimator.md, "Telling the hand from
#: an ordinary background");
#: chosen before those were measured.
AUTO_OVERLAP = 0.8


@dataclass(frozen=True)
class LearnedOptions:
    """How a :class:`LearnedEstimator` is learnt.

    Parameters
    ----------
    kind : {"mlp", "knn", "fingers"}
        ``"fingers"``: a kNN per digit on the cells that digit changes
        (module docstring).
    use_rest : bool
        Give the regressor the difference from the rest frame (a calibrated
        estimator); without it the frame alone.
    target : {"delta", "angles"}
        With `use_rest`: ``"angles"`` (default) learns the angles directly;
        ``"delta"`` learns the change from the hand's rest posture (zero
        where the frame equals the rest frame) and adds the rest posture read
        from the rest frame by a second regressor of the same kind.  On model
        hands ``"delta"`` was worse (the rest posture read from one frame
        adds its own error), so it is kept only to be measured.
    components : int
        Principal components of the input kept.
    hidden : tuple of int
        Widths of the perceptron's hidden layers.
    epochs, batch : int
        Perceptron training: passes over the set, frames per step.
    learning_rate : float
        Adam's step size at the start (cosine decay to 5 % of it).
    loss : {"squared", "absolute"}
        What the perceptron's training minimises over standardised angles:
        the squared error (its answer tends to the mean angle of frames that
        look alike) or the absolute error (their median).  Measured on
        held-out model hands with perceptrons of 4,000 hands (docs/camera_estimator.md, "The
        perceptron's loss"): the absolute error reads moving joints as
        nearer their rest and natural poses worse, so ``"squared"`` stays.
    weight_decay : float
        L2 penalty on the perceptron's weights.
    k : int
        Neighbours of ``"knn"`` and ``"fingers"``.
    local : {"linear", "mean"}
        How the neighbours' angles become the answer: ``"linear"``
        (default) a weighted ridge regression on their codes read at the
        query (:func:`local_linear`), ``"mean"`` their weighted mean.  The
        linear fit needs more neighbours than code dimensions; with fewer it
        falls back to the mean.  On model hands of random geometry it lowered
        the natural-pose flexion MAE from 11.3 to 10.5 deg and the paper-frame
        MAE from 5.6 to 5.5 deg (docs/camera_estimator.md).
    ridge : float
        Shrinkage of the local fit's slopes (:func:`local_linear`).
    lists, probes : int
        The nearest-neighbour search is faiss's inverted-file index
        (`lists` k-means cells, the `probes` nearest of them searched;
        trained when the estimator is learnt, 4-6 s per index of 400,000
        codes on one core, and stored with it, so reading it back takes 0.1
        s):
        0.12 ms instead of 0.93 ms for 64 neighbours among 100,000 codes of
        64 dimensions.  ``lists=0``: exact search.  Eight of 512 cells
        (1.6 % of the codes) find 92 % of the 128 nearest neighbours of
        glTF-hand frames among 400,000 codes per digit (8 of 256: 96 %; 16
        of 256: 98-99 %), and the default ensemble reads a frame 10-14 %
        faster than with 8 of 256 for the same flexion error on held-out
        model hands.  Chosen there by rules fixed before the runs
        (docs/camera_estimator.md, "Speed"): through the ensemble, the
        fewest probes within 0.05 deg of four times as many on paper frames
        and 0.1 deg on natural ones, at both rests; and 512 cells over 256
        where no further than that from 256 cells' error.
    quantize : bool
        The inverted file holds the codes quantised to 8 bits per dimension
        (faiss's ``IndexIVFScalarQuantizer``, ``QT_8bit``) instead of as
        float32 (``IndexIVFFlat``): a quarter of the memory read per search,
        which halves its time (1.35 ms instead of 2.98 ms for the five
        digits' searches, 128 neighbours among 400,000 codes; 99 % of the
        neighbours the same).  The neighbours found are re-measured on
        their float32 codes either way, so only which are found can differ.
        Read when frames are read (not part of what is learnt).
    seed : int

    Raises
    ------
    InvalidInputError
        A field of the wrong type or range, naming it and the value
        received: a choice not among its values; a count that is not an
        integer in range; `learning_rate` or `weight_decay` or `ridge` that is not
        a finite number (``"0.01"``, ``inf``, ``True``: a flag is not a
        number) above 0 (`learning_rate`) or at least 0; `hidden` that is not
        a tuple of positive integers; `use_rest` or `quantize` that is not
        True or False.
    """

    kind: str = "fingers"
    use_rest: bool = True
    target: str = "angles"
    components: int = 192
    hidden: tuple[int, ...] = (384, 384)
    epochs: int = 15
    batch: int = 256
    learning_rate: float = 1e-3
    loss: str = "squared"
    weight_decay: float = 1e-5
    k: int = 128
    local: str = "linear"
    ridge: float = 3.0
    lists: int = 512
    probes: int = 8
    quantize: bool = True
    seed: int = 0

    def __post_init__(self) -> None:
        if self.target not in ("delta", "angles"):
            raise InvalidInputError(f"LearnedOptions.target must be 'delta' or 'angles', "
                                    f"got {self.target!r}")
        if self.loss not in ("squared", "absolute"):
            raise InvalidInputError(f"LearnedOptions.loss must be 'squared' or 'absolute', "
                                    f"got {self.loss!r}")
        if self.local not in ("linear", "mean"):
            raise InvalidInputError(f"LearnedOptions.local must be 'linear' or 'mean', "
                                    f"got {self.local!r}")
        for name in ("use_rest", "quantize"):
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise InvalidInputError(f"LearnedOptions.{name} must be True or False, "
                                        f"got {getattr(self, name)!r}")
        check_number(self.ridge, "LearnedOptions.ridge", minimum=0)
        if self.kind not in ("mlp", "knn", "fingers"):
            raise InvalidInputError(f"LearnedOptions.kind must be 'mlp', 'knn' or 'fingers', "
                                    f"got {self.kind!r}")
        for name in ("lists", "probes", "seed"):
            check_integer(getattr(self, name), f"LearnedOptions.{name}", minimum=0)
        for name in ("components", "epochs", "batch", "k"):
            check_integer(getattr(self, name), f"LearnedOptions.{name}", minimum=1)
        hidden = self.hidden
        if not isinstance(hidden, (tuple, list)) or not hidden:
            raise InvalidInputError(
                f"LearnedOptions.hidden must be a tuple of positive integers (the widths of the "
                f"hidden layers), got {type(hidden).__name__} {short_repr(hidden)}")
        for i, width in enumerate(hidden):
            check_integer(width, f"LearnedOptions.hidden[{i}]", minimum=1)
        object.__setattr__(self, "hidden", tuple(int(h) for h in hidden))
        check_number(self.learning_rate, "LearnedOptions.learning_rate", above=0)
        check_number(self.weight_decay, "LearnedOptions.weight_decay", minimum=0)

    def digest(self) -> str:
        """Hash of the options that shape what is learnt (the cache's name).

        The options used only when frames are read (:data:`_READING_OPTIONS`)
        are left out: changing them reads the same learnt arrays.
        """
        learnt = {k: v for k, v in asdict(self).items() if k not in _READING_OPTIONS}
        if learnt["loss"] == "squared":
            del learnt["loss"]  # estimators learnt before the option keep their names
        if self.kind == "mlp":
            # a perceptron searches nothing: hashed with the search options earlier
            # releases had, so that changing them keeps its cache (7 min to learn)
            learnt.update(_SEARCH_OPTIONS_OF_PERCEPTRONS)
        return hashlib.sha256(json.dumps(learnt, sort_keys=True).encode()).hexdigest()[:16]


#: :class:`LearnedOptions` fields used only when an estimator reads frames
#: (how many neighbours, how their angles become the answer, how the codes are
#: stored for the search), not when it learns.  ``lists`` and ``probes`` are
#: not among them: the novelty limit is learnt through the same search, which
#: they shape; ``quantize`` changes only which neighbours are found, each
#: measured on its float code either way.
_READING_OPTIONS = ("k", "local", "ridge", "quantize")

#: The search options a perceptron's cache name is hashed with, whatever they
#: are (:meth:`LearnedOptions.digest`): the defaults when perceptrons were
#: first cached.
_SEARCH_OPTIONS_OF_PERCEPTRONS = {"lists": 256, "probes": 16}


# ---------------------------------------------------------------------------
# inputs
# ---------------------------------------------------------------------------
def _inputs(grids: np.ndarray, rest: np.ndarray | None) -> np.ndarray:
    """(N, D) or (N, 2D) float32 input of the regressors from uint8 coverage rows."""
    x = grids.astype(np.float32) * (1.0 / 255.0)
    if rest is None:
        return x
    r = rest.astype(np.float32) * (1.0 / 255.0)
    return np.hstack([x, x - r])


class _Rows:
    """The regressors' inputs of a learning set, made on demand a block of rows at a time.

    The float inputs of every frame (:func:`_inputs`: the frame's coverage
    and its difference from its hand's rest frame) take 8 bytes per cell and
    frame; made all at once they outgrew the memory of ordinary machines
    beyond a few thousand hands.  This keeps the uint8 grids and makes the
    inputs of the rows asked for.

    Parameters
    ----------
    grids : ndarray, shape (N, D) uint8
    rest : ndarray, shape (H, D) uint8, optional
        Rest grid of each hand; row ``i`` is paired with ``rest[hand[i]]``.
    hand : ndarray, shape (N,) int, optional
    """

    def __init__(self, grids: np.ndarray, rest: np.ndarray | None = None,
                 hand: np.ndarray | None = None) -> None:
        if (rest is None) != (hand is None):
            raise ValueError("rest and hand are given together or not at all")
        self.grids, self.rest, self.hand = grids, rest, hand
        self.width = grids.shape[1] * (1 if rest is None else 2)

    def __len__(self) -> int:
        return len(self.grids)

    def take(self, rows) -> np.ndarray:
        """Inputs (n, width) float32 of `rows` (a slice or an index array)."""
        rest = None
        if self.rest is not None and self.hand is not None:
            rest = self.rest[self.hand[rows]]
        return _inputs(self.grids[rows], rest)

    def blocks(self, rows: int = 20000):
        """(slice, inputs) of consecutive blocks of at most `rows` rows."""
        for start in range(0, len(self), rows):
            sl = slice(start, min(start + rows, len(self)))
            yield sl, self.take(sl)


#: The share of learning frames a frame must be more novel than to be flagged
#: ``low_confidence`` (every kind's novelty limit is this quantile).
_NOVELTY_QUANTILE = 0.99


def _left_out_norms(centred: np.ndarray, codes: np.ndarray) -> np.ndarray:
    """Norm (N,) of the part of inputs that their principal components leave out.

    ``sqrt(|x - mean|^2 - |codes|^2)`` with ``centred = x - mean`` (N, D) and
    ``codes = centred @ components`` (N, k): the distance from each input to
    the subspace the components span through the mean (the components are
    orthonormal columns, :func:`_pca`).
    """
    return np.sqrt(np.maximum(np.einsum("ij,ij->i", centred, centred)
                              - np.einsum("ij,ij->i", codes, codes), 0.0))


def _pca(z: _Rows, k: int, rng: np.random.Generator, sample: int = 20000, *,
         cols: np.ndarray | None = None, weight: np.ndarray | None = None
         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mean (D,), components (D, k) and their s.d. (k,) of a sample of `sample` rows of `z`.

    With `cols` (and `weight`), of those input columns (times `weight`).
    """
    idx = rng.choice(len(z), size=min(sample, len(z)), replace=False)
    s = z.take(idx)
    if cols is not None:
        s = s[:, cols] * weight
    s = s.astype(np.float64)
    mean = s.mean(axis=0)
    s -= mean
    if len(s) > s.shape[1]:
        w, v = np.linalg.eigh(s.T @ s / max(len(s) - 1, 1))
        order = np.argsort(w)[::-1][:k]
        v, w = v[:, order], w[order]
    else:  # fewer rows than dimensions: the thin SVD of the rows is cheaper
        _, sv, vt = np.linalg.svd(s, full_matrices=False)
        v, w = vt[:k].T, sv[:k] ** 2 / max(len(s) - 1, 1)
    return (mean.astype(np.float32), np.ascontiguousarray(v, np.float32),
            np.sqrt(np.maximum(w, 1e-12)).astype(np.float32))


# ---------------------------------------------------------------------------
# the perceptron
# ---------------------------------------------------------------------------
def _flush_subnormals(arrays: dict, *, skip: tuple[str, ...] = ()) -> dict:
    """`arrays` with every subnormal float (0 < |x| < the dtype's smallest normal) set to 0.

    Weight decay leaves the weights of hidden units that learnt nothing at
    1e-45 to 1e-38 (float32 subnormals: 2,300-6,100 of the 147,456 weights
    of each shipped perceptron's second layer).  Many processors take a
    microcode path for every product with one (no flush-to-zero in NumPy):
    on an Intel Xeon here that layer's matrix-vector product took 131 us
    instead of 8 us.  Each of them adds less than 1e-37 to sums of order 1,
    so the answers do not change (tested).  Arrays holding none are kept,
    others are copied (the caller's are not changed).

    Parameters
    ----------
    arrays : dict of str to ndarray (or other values, kept)
    skip : tuple of str, keyword-only
        Keys ending so are kept as they are, unread (the learning frames'
        codes and angles: 512 MB a per-digit estimator, no weights, half a
        second to read through at every start).

    Returns
    -------
    dict
    """
    out = dict(arrays)
    for k, v in arrays.items():
        if (isinstance(v, np.ndarray) and v.dtype.kind == "f" and v.size
                and not k.endswith(skip)):
            sub = _subnormal(v)
            if sub.any():
                out[k] = np.where(sub, v.dtype.type(0), v)
    return out


def _subnormal(a: np.ndarray) -> np.ndarray:
    """Where float array `a` is subnormal (0 < |a| < its dtype's smallest normal number)."""
    return (np.abs(a) < np.finfo(a.dtype).tiny) & (a != 0)


def _relu_forward(x, weights, biases):
    acts = [x]
    for i, (w, b) in enumerate(zip(weights, biases)):
        x = x @ w + b
        if i < len(weights) - 1:
            x = np.maximum(x, 0.0)
        acts.append(x)
    return acts


def fit_mlp(x: np.ndarray, y: np.ndarray, *, hidden=(384, 384), epochs: int = 40,
            batch: int = 256, learning_rate: float = 1e-3, weight_decay: float = 1e-5,
            loss: str = "squared", seed: int = 0,
            progress=None) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Fit a ReLU perceptron to the squared or absolute error, with Adam.

    Parameters
    ----------
    x : ndarray, shape (N, D), float32
    y : ndarray, shape (N, K), float32
    hidden : tuple of int, keyword-only
    epochs, batch : int, keyword-only
    learning_rate, weight_decay : float, keyword-only
        Adam step (cosine decay to 5 %) and L2 penalty on weights.
    loss : {"squared", "absolute"}, keyword-only
        The mean squared or the mean absolute error of the outputs.
    seed : int, keyword-only
    progress : callable, keyword-only, optional
        Called with (epoch, mean training loss).

    Returns
    -------
    weights, biases : lists of ndarray
        Layer ``i`` maps ``a @ weights[i] + biases[i]``.

    Notes
    -----
    Weight decay drives the weights of hidden units that stop learning toward
    0, down to subnormal floats, and many processors take a slow path for
    every product with one (on an Intel Xeon here a training step with the
    shipped perceptrons' weights took 66 ms instead of 7 ms).  Every 16 steps
    the weights and Adam's moments that are subnormal are set to 0
    (:func:`_flush_in_place`; the returned weights hold none); a subnormal
    weight adds less than 1e-37 to sums of order 1.
    """
    if loss not in ("squared", "absolute"):
        raise InvalidInputError(f"fit_mlp: loss must be 'squared' or 'absolute', got {loss!r}")
    absolute = loss == "absolute"
    rng = np.random.default_rng(seed)
    sizes = [x.shape[1], *hidden, y.shape[1]]
    weights = [(rng.normal(0, np.sqrt(2.0 / a), (a, b))).astype(np.float32)
               for a, b in itertools.pairwise(sizes)]
    biases = [np.zeros(b, np.float32) for b in sizes[1:]]
    params = weights + biases
    m1 = [np.zeros_like(p) for p in params]
    m2 = [np.zeros_like(p) for p in params]
    b1, b2, eps = 0.9, 0.999, 1e-8
    n = len(x)
    steps = epochs * max(1, n // batch)
    t = 0
    for ep in range(epochs):
        order = rng.permutation(n)
        total = 0.0
        for s in range(0, n - batch + 1, batch):
            idx = order[s:s + batch]
            acts = _relu_forward(x[idx], weights, biases)
            diff = acts[-1] - y[idx]
            if absolute:
                total += float(np.mean(np.abs(diff))) * len(idx)
                g = np.sign(diff) * np.float32(1.0 / diff.size)
            else:
                total += float(np.mean(diff * diff)) * len(idx)
                g = (2.0 / diff.size) * diff
            gw: list = [None] * len(weights)
            gb: list = [None] * len(weights)
            for i in range(len(weights) - 1, -1, -1):
                gw[i] = acts[i].T @ g + weight_decay * weights[i]
                gb[i] = g.sum(axis=0)
                if i:
                    g = (g @ weights[i].T) * (acts[i] > 0)
            t += 1
            lr = learning_rate * (0.05 + 0.95 * 0.5 * (1 + np.cos(np.pi * min(t / steps, 1.0))))
            for p, gp, a, bb in zip(params, gw + gb, m1, m2):
                a *= b1
                a += (1 - b1) * gp
                bb *= b2
                bb += (1 - b2) * gp * gp
                p -= lr * (a / (1 - b1 ** t)) / (np.sqrt(bb / (1 - b2 ** t)) + eps)
            if t % _FLUSH_EVERY == 0:
                _flush_in_place(params + m1 + m2)
        if progress is not None:
            progress(ep + 1, total / max(n, 1))
    _flush_in_place(params)
    return weights, biases


#: :func:`fit_mlp` reads the weights and Adam's moments that have decayed to
#: subnormal floats as 0 every this many steps (:func:`_flush_in_place`).
_FLUSH_EVERY = 16


def _flush_in_place(arrays) -> None:
    """Set the subnormal values of each float array in `arrays` to 0, in place."""
    for a in arrays:
        np.copyto(a, 0, where=_subnormal(a))


def local_linear(x: np.ndarray, y: np.ndarray, w: np.ndarray, *, ridge: float) -> np.ndarray:
    """Weighted ridge regression of `y` on `x` among neighbours, read at ``x = 0``.

    The weighted mean of the neighbours' angles is pulled toward where the
    learning set is dense (the hand at rest): a finger flexed far is read as
    flexed less.  Fitting ``y ~ b0 + x @ b`` among the neighbours and
    reading ``b0`` (the fit at the query, placed at ``x = 0``) removes that
    pull to first order (locally weighted regression, Cleveland & Devlin
    1988, J. Am. Stat. Assoc. 83:596).  The slopes are shrunk by
    ``ridge * trace(Xᵀ W X) / D``, so the fit degrades to the weighted mean
    as `ridge` grows.

    Parameters
    ----------
    x : ndarray, shape (k, D)
        Neighbours' codes less the query's.
    y : ndarray, shape (k, J)
        Their angles, degrees.
    w : ndarray, shape (k,)
        Their weights (> 0).
    ridge : float, keyword-only
        Shrinkage of the slopes (0: none).

    Returns
    -------
    ndarray, shape (J,), float64

    Raises
    ------
    InvalidInputError
        `x`, `y` or `w` not finite real arrays of those shapes with one
        `k` >= 1, a weight <= 0, or `ridge` not a finite number >= 0 (naming
        it).
    """
    x = check_array(x, "x", (None, None), rows="neighbours")
    y = check_array(y, "y", (len(x), None), rows="neighbours")
    w = check_array(w, "w", (len(x),), rows="neighbours")
    if (w <= 0).any():
        raise InvalidInputError(f"w must be weights > 0, got {float(w.min())!r} at "
                                f"neighbour {int(np.argmin(w))}")
    return _local_linear(x, y, w, ridge=check_number(ridge, "ridge", minimum=0))


def _local_linear(x: np.ndarray, y: np.ndarray, w: np.ndarray, *, ridge: float) -> np.ndarray:
    """:func:`local_linear` without its checks (the estimators' inner loop)."""
    x = np.asarray(x, np.float64)
    w = np.asarray(w, np.float64) / np.sum(w)
    design = np.hstack([np.ones((len(x), 1)), x])
    wd = design * w[:, None]
    gram = design.T @ wd
    penalty = ridge * np.trace(gram[1:, 1:]) / max(x.shape[1], 1)
    gram[np.arange(1, len(gram)), np.arange(1, len(gram))] += max(penalty, 1e-12)
    beta = np.linalg.solve(gram, wd.T @ np.asarray(y, np.float64))
    return beta[0]


def _local_linear_stack(x: np.ndarray, y: np.ndarray, w: np.ndarray, *,
                        ridge: float) -> np.ndarray:
    """:func:`_local_linear` of B fits at once (one frame's digits): the same answers.

    Parameters
    ----------
    x : ndarray, shape (B, k, D)
    y : ndarray, shape (B, k, J)
    w : ndarray, shape (B, k)
    ridge : float, keyword-only

    Returns
    -------
    ndarray, shape (B, J), float64
        Row ``b`` is ``_local_linear(x[b], y[b], w[b], ridge=ridge)`` to
        rounding (tested): one call of each NumPy step instead of B, the
        normal equations built from their blocks (the intercept's row is
        the weighted mean of the codes), and solved by Cholesky
        (:func:`_solve_spd`; NumPy's LU took 60 us per 65x65 system).
    """
    x = np.asarray(x, np.float64)
    y = np.asarray(y, np.float64)
    w = np.asarray(w, np.float64)
    w = w / np.sum(w, axis=1, keepdims=True)
    b, _, dim = x.shape
    xw = x * w[:, :, None]
    gram = np.empty((b, dim + 1, dim + 1))
    gram[:, 0, 0] = 1.0  # the weights sum to 1
    gram[:, 0, 1:] = gram[:, 1:, 0] = xw.sum(axis=1)
    np.matmul(x.transpose(0, 2, 1), xw, out=gram[:, 1:, 1:])
    penalty = ridge * np.trace(gram[:, 1:, 1:], axis1=1, axis2=2) / max(dim, 1)
    at = np.arange(1, dim + 1)
    gram[:, at, at] += np.maximum(penalty, 1e-12)[:, None]
    rhs = np.empty((b, dim + 1, y.shape[2]))
    rhs[:, 0] = np.einsum("bk,bkj->bj", w, y)
    np.matmul(xw.transpose(0, 2, 1), y, out=rhs[:, 1:])
    beta, ok = _solve_spd(gram, rhs)
    if not ok.all():  # not positive definite to rounding (ridge 0, neighbours in a plane)
        beta[~ok] = np.linalg.solve(gram[~ok], rhs[~ok])
    return beta[:, 0]


@njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _solve_spd(a, b):  # pragma: no cover - compiled (tested through _local_linear_stack)
    """Solve ``a[s] @ x[s] = b[s]`` for symmetric positive definite `a` (S, m, m) by Cholesky.

    Returns `x` (S, m, r) and `ok` (S,) bool: False where a pivot was not
    positive (that system's `x` is left undefined for the caller to solve
    otherwise).  Only the lower triangle of each ``a[s]`` is read.
    """
    n, m, _ = a.shape
    r = b.shape[2]
    x = np.empty_like(b)
    ok = np.ones(n, np.bool_)
    lower = np.zeros((m, m))
    y = np.empty(m)
    for s in range(n):
        for j in range(m):
            d = a[s, j, j]
            for k in range(j):
                d -= lower[j, k] * lower[j, k]
            if not d > 0.0:
                ok[s] = False
                break
            d = np.sqrt(d)
            lower[j, j] = d
            for i in range(j + 1, m):
                v = a[s, i, j]
                for k in range(j):
                    v -= lower[i, k] * lower[j, k]
                lower[i, j] = v / d
        if not ok[s]:
            continue
        for c in range(r):
            for i in range(m):
                v = b[s, i, c]
                for k in range(i):
                    v -= lower[i, k] * y[k]
                y[i] = v / lower[i, i]
            for i in range(m - 1, -1, -1):
                v = y[i]
                for k in range(i + 1, m):
                    v -= lower[k, i] * x[s, k, c]
                x[s, i, c] = v / lower[i, i]
    return x, ok


# ---------------------------------------------------------------------------
# the nearest-neighbour search
# ---------------------------------------------------------------------------
def _faiss():
    """faiss, imported when an estimator of kind ``"fingers"`` or ``"knn"`` is made."""
    import faiss  # this module's one import of faiss

    return faiss


#: Names of the inverted files :meth:`LearnedEstimator.save` stores end with
#: these (codes quantised to 8 bits, or float32: :class:`LearnedOptions` ``quantize``).
_INDEX_SUFFIXES = ("ivf_sq8", "ivf_flat")


def _index_name(prefix: str, options: LearnedOptions) -> str:
    """Name under which the inverted file of the codes ``prefix + "codes"`` is stored."""
    return prefix + _INDEX_SUFFIXES[0 if options.quantize else 1]


def _search_index(codes: np.ndarray, options: LearnedOptions, *, stored: np.ndarray | None = None):
    """The faiss index searched for the nearest of `codes` (N, D) float32.

    An inverted file (:class:`LearnedOptions` ``lists``, ``probes``,
    ``quantize``), or an exact index when `lists` is 0 or there are too few
    codes to train its cells.  `stored` (uint8, as ``faiss.serialize_index``
    writes it) is read instead of training the cells and filing the codes
    (4-6 s per index of 400,000 codes on one core, 0.1 s read) when it holds
    these codes in cells of these options; otherwise the index is trained
    (faiss's k-means has a fixed seed, so it trains to the stored one).
    """
    faiss = _faiss()
    codes = np.ascontiguousarray(codes)
    n, dim = codes.shape
    if not options.lists or n < 39 * options.lists:
        index = faiss.IndexFlatL2(dim)
        index.add(codes)
        return index
    kind = faiss.IndexIVFScalarQuantizer if options.quantize else faiss.IndexIVFFlat
    if stored is not None:
        try:
            index = faiss.deserialize_index(np.ascontiguousarray(stored, np.uint8))
        except RuntimeError:  # not an index faiss can read: train it instead
            index = None
        if (isinstance(index, kind) and index.ntotal == n and index.d == dim
                and index.nlist == options.lists):
            index.nprobe = min(options.probes or 1, options.lists)
            return index
    quantizer = faiss.IndexFlatL2(dim)
    index = (kind(quantizer, dim, options.lists, faiss.ScalarQuantizer.QT_8bit)
             if options.quantize else kind(quantizer, dim, options.lists))
    index.train(codes)
    index.nprobe = min(options.probes or 1, options.lists)
    index.add(codes)  # faiss's wrapper keeps `quantizer` alive with the index
    return index


# ---------------------------------------------------------------------------
# the estimator
# ---------------------------------------------------------------------------
_NOT_CALIBRATED = "this estimator reads the user's rest frame: call calibrated(rest_frame) first"


class LearnedEstimator:
    """Hand pose from one frame of the whole camera view (module docstring).

    Made by :func:`train_learned` or :func:`learned_estimator`; an estimator
    with ``options.use_rest`` must be :meth:`calibrated` to a frame of the
    user's hand at rest before :meth:`estimate`.

    Implements :class:`~handsynth.estimate.PoseEstimator`.  :meth:`estimate`
    keeps state between frames: a calibrated estimator's move check
    (:class:`~handsynth.estimate.MoveCheck`) remembers the grids of the last
    frames, and ``smoothing`` the previous answer.  So use one instance per
    camera stream (frames of two streams through one instance mix their
    ``moved`` flags), and do not share one between threads.  Each call of
    :meth:`calibrated` returns a new instance with its own state that
    shares the learnt arrays (no copy of them): calibrate once per stream.

    Attributes
    ----------
    options : LearnedOptions
    mount : CameraMount
    side : str
    cells : (int, int)
    smoothing : float
        Exponential smoothing of successive answers: 0 (default) none;
        ``a`` reports ``a * previous + (1 - a) * new``.  Settable, checked
        (:attr:`smoothing`).
    """

    def __init__(self, arrays: dict, *, options: LearnedOptions, mount: CameraMount, side: str,
                 cells: tuple[int, int]) -> None:
        self.options = options
        self.mount = mount
        self.side = side
        # what the arrays were learnt from; mirrored() reads the other hand's frames upside down
        self._learnt_view = (mount, side)
        self._mirror = False
        self.cells: tuple[int, int] = (int(cells[0]), int(cells[1]))
        arrays = dict(arrays)
        # inverted files stored by save(): read below instead of trained, not learnt arrays
        stored = {k: arrays.pop(k) for k in list(arrays) if k.endswith(_INDEX_SUFFIXES)}
        arrays = _flush_subnormals(arrays, skip=("codes", "angles"))
        self._a = arrays
        for v in arrays.values():
            if isinstance(v, np.ndarray):
                v.setflags(write=False)
        self._rest: np.ndarray | None = None
        self._skin: SkinColour | None = None
        self.segment = "brightness"
        self._move_check: MoveCheck | None = None
        self._smoothing = 0.0
        self._previous: np.ndarray | None = None
        self._index: dict = {}
        if options.kind in ("knn", "fingers"):
            for prefix in ("", "abs_", *(f"d{d}_" for d in range(5))):
                if prefix + "codes" in arrays:
                    self._index[prefix] = _search_index(
                        arrays[prefix + "codes"], options,
                        stored=stored.get(_index_name(prefix, options)))
        self._rest_angles: np.ndarray | None = None
        self._fold: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self._lo = JOINT_LIMITS_DEG[:, 0]
        self._hi = JOINT_LIMITS_DEG[:, 1]

    @property
    def smoothing(self) -> float:
        """Exponential smoothing of successive answers, in [0, 1).

        0 (default): none; ``a`` reports ``a * previous + (1 - a) * new``
        (1 would never move from the first answer).

        Raises
        ------
        InvalidInputError
            On setting anything but a finite number in [0, 1) (a string, a
            bool, NaN, 1, a negative number), named with the value received.
        """
        return self._smoothing

    @smoothing.setter
    def smoothing(self, value: float) -> None:
        self._smoothing = check_number(value, "smoothing", minimum=0, below=1)

    @property
    def view_key(self) -> tuple:
        """What makes a frame's grid: estimators of one key read the same grid of a frame.

        The device and hand the arrays were learnt for, whether frames are
        turned over first (:meth:`mirrored`), and the cells.
        """
        return (*self._learnt_view, self._mirror, self.cells)

    @property
    def skin(self) -> SkinColour | None:
        """The skin's colour the frames are told by (:meth:`calibrated`), or None."""
        return self._skin

    def mirrored(self) -> LearnedEstimator:
        """This estimator reading the other hand's frames.

        A left hand is the mirror image of the right with the same joint
        senses, and its frame through a device is the right hand's frame
        through the mirrored device (:meth:`CameraMount.mirrored`) turned
        upside down, pixel for pixel.  So the mirrored estimator turns each
        frame upside down and reads it as learnt: no learning set of the
        other hand, the same figures.

        Returns
        -------
        LearnedEstimator
            A copy (calibration kept, turned with it) whose ``side`` is the
            other hand and whose ``mount`` is the mirrored device;
            ``mirrored().mirrored()`` reads as this one.
        """
        out = copy.copy(self)
        out._mirror = not self._mirror
        out.side = "left" if self.side == "right" else "right"
        out.mount = self.mount.mirrored()
        if self._move_check is not None:  # its own frames, not the original's
            out._move_check = self._move_check.fresh()
        return out

    def check_ready(self) -> None:
        """Raise if this estimator cannot read any frame as it is.

        A frame it refuses says something about that frame; this says the
        estimator is not set up, so that a live run stops at once
        (:func:`handsynth.live.run_live`) instead of refusing every frame.

        Raises
        ------
        EstimationError
            It reads the user's rest frame (``options.use_rest``) and was not
            :meth:`calibrated`.
        """
        if self.options.use_rest and self._rest is None:
            raise EstimationError(_NOT_CALIBRATED)

    # -- calibration -----------------------------------------------------------
    def calibrated(self, rest_frame: np.ndarray, *, check_moved: bool = True,
                   segment: str | SkinColour = "auto") -> LearnedEstimator:
        """A copy of this estimator calibrated to a frame of the user's hand at rest.

        Parameters
        ----------
        rest_frame : ndarray, shape (H, W) or (H, W, 3)
            The user's hand relaxed (not necessarily open or flat) through
            the device, a mask or a camera frame as :meth:`estimate` takes.
        check_moved : bool, keyword-only
            Check each frame for a device moved since `rest_frame`
            (:class:`~handsynth.estimate.MoveCheck`; False: ``moved`` is never
            set, as for an ensemble member whose grid another member checks).
        segment : {"auto", "brightness", "colour"} or SkinColour, keyword-only
            How camera frames are told into hand and background (masks are
            read as they are): ``"brightness"`` by Otsu's threshold
            (:func:`~handsynth.render.binarize`: a hand brighter than a dark
            background); ``"colour"`` by the colour of the skin on the back of
            the hand in `rest_frame` (:func:`~handsynth.render.skin_mask`: the
            hand need not be the brightest thing in view; colour frames);
            ``"auto"`` (default) brightness unless `rest_frame` is a colour
            frame on which the two disagree (their masks' intersection over
            union under :data:`AUTO_OVERLAP`: the background is not dark) and
            whose skin can be told from grey by colour
            (:attr:`~handsynth.render.SkinColour.tells_grey`; not a pale or
            overexposed skin).  A :class:`~handsynth.render.SkinColour`
            already fitted to this rest frame (another estimator's
            :attr:`skin`) is used as it is.  The choice is kept as the
            attribute ``segment``, the skin as :attr:`skin`.

        Raises
        ------
        InvalidInputError
            The frame shows no hand, or is not an image; ``"colour"`` with a
            rest frame that is not a colour frame; an unknown `segment`;
            `check_moved` that is not a bool (``"no"``, 0, None), before the
            frame is read.
        """
        check_instance(check_moved, bool, name="check_moved")
        if not isinstance(segment, SkinColour) and segment not in ("auto", "brightness", "colour"):
            raise InvalidInputError(f"segment must be 'auto', 'brightness' or 'colour', "
                                    f"got {segment!r}")
        out = copy.copy(self)
        out._skin = None
        view = np.asarray(rest_frame)[::-1] if self._mirror else rest_frame
        mount, side = self._learnt_view
        if isinstance(segment, SkinColour):
            out._skin = segment
        elif segment == "colour":
            out._skin = fit_skin_colour(view, mount, side=side)
        elif segment == "auto" and _is_colour(view):
            try:
                skin = fit_skin_colour(view, mount, side=side)
            except InvalidInputError:  # no lit skin where the hand always is: brightness decides
                skin = None
            if skin is not None and skin.tells_grey and brightness_overlap(view, skin) < AUTO_OVERLAP:
                out._skin = skin
        out.segment = "colour" if out._skin is not None else "brightness"
        g = out.grid(rest_frame)
        if g.mean() < MIN_HAND_COVERAGE * 255:
            raise InvalidInputError(
                f"rest_frame shows no hand: what stands out covers {g.mean() / 2.55:.2f} % of the "
                f"view, a hand at least {100 * MIN_HAND_COVERAGE:g} % (MIN_HAND_COVERAGE)")
        out._rest = g.ravel()
        out._fold = (self._folded_projection(out._rest)
                     if self.options.kind == "mlp" and self.options.use_rest else None)
        out._move_check = MoveCheck(g, mount, side=side) if check_moved else None
        out._previous = None
        if "abs_mean" in self._a:
            z = _inputs(out._rest[None], None) - self._a["abs_mean"]
            out._rest_angles = self._predict("abs_", z @ self._a["abs_components"])[0]
        return out

    def _folded_projection(self, rest: np.ndarray):
        """A perceptron's principal-component projection with the rest frame folded in.

        Its input is the frame ``x`` and ``x - rest`` (:func:`_inputs`), so
        ``(z - mean) @ C == x @ (C1 + C2) - (rest @ C2 + mean @ C)``, ``C1``
        and ``C2`` the halves of ``C``: half the matrix to read per frame,
        less the cells that no component weighs (the wrist cut's, about 200
        of 1,350).  The codes agree with the plain product to float32
        rounding (tested).

        Returns
        -------
        keep : ndarray (K,) int
            The frame's cells read.
        projection : ndarray (K, k) float32
        offset : ndarray (k,) float32
        """
        c = self._a["components"]
        n = len(rest)
        both = c[:n] + c[n:]
        keep = np.flatnonzero(np.any(both != 0, axis=1))
        r = _inputs(rest[None], None)[0]
        offset = r @ c[n:] + self._a["mean"] @ c
        return keep, np.ascontiguousarray(both[keep]), offset

    def _digit_code(self, d: int, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Digit `d`'s codes (N, k) of inputs `z` and the squared norm (N,) they leave out."""
        a = self._a
        p = f"d{d}_"
        x = z[:, a[p + "cols"]] * a[p + "w"] - a[p + "mean"]
        c = x @ a[p + "components"]
        return c, np.maximum(np.einsum("ij,ij->i", x, x) - np.einsum("ij,ij->i", c, c), 0.0)

    def _predict_digits(self, z: np.ndarray) -> tuple[np.ndarray, float]:
        """Each digit's angles from its own cells (kind ``"fingers"``), and the novelty.

        The novelty is the mean over the digits of the distance to the
        nearest learning frame, counting the part of the frame's input its
        principal components leave out (which no learning frame shows).
        """
        angles = np.empty(20)
        novelty = 0.0
        near = []
        for d in range(len(_DIGIT_JOINTS)):
            c, left_out = self._digit_code(d, z)
            x, y, w, e = self._neighbours(f"d{d}_", c)
            near.append((x, y, w))
            novelty += float(np.sqrt(e * e + left_out[0])) / 5
        if (self.options.local == "linear" and len({(x.shape, y.shape) for x, y, _ in near}) == 1
                and len(near[0][0]) > near[0][0].shape[1] + 1):
            # the usual case: every digit found k neighbours, fitted together (same answers)
            got = list(_local_linear_stack(*(np.stack(part) for part in zip(*near)),
                                           ridge=self.options.ridge))
        else:
            got = [self._answer(x, y, w) for x, y, w in near]
        for joints, g in zip(_DIGIT_JOINTS, got, strict=True):
            angles[list(joints)] = g
        return angles, novelty

    def _novelty_limit(self, z: np.ndarray, rows: np.ndarray, hand: np.ndarray, *,
                       quantile: float = 0.99) -> float:
        """The `quantile` of the novelty of learning frames `rows` (inputs `z`) among other hands.

        `hand` is the hand of every learning frame.

        A user's hand is not in the learning set: each frame is searched for
        as a new hand's would be, its own hand's frames left out (the
        nearest neighbour of another hand among 256), so the limit says how
        novel frames of hands never learnt usually are.
        """
        a = self._a
        total = np.zeros(len(z))
        at = np.arange(len(z))
        for d in range(5):
            p = f"d{d}_"
            c, left_out = self._digit_code(d, z)
            c32 = np.ascontiguousarray(c, np.float32)
            _, idx = self._index[p].search(c32, min(256, len(a[p + "codes"])))
            other = (idx >= 0) & (hand[np.maximum(idx, 0)] != hand[rows][:, None])
            first = np.argmax(other, axis=1)
            # re-measured on the float codes (`quantize`), as estimate() does
            pick = np.maximum(np.where(other[at, first], idx[at, first], idx[:, -1]), 0)
            x = a[p + "codes"][pick] - c32
            near = np.einsum("ij,ij->i", x, x)
            total += np.sqrt(near + left_out) / 5
        return float(np.quantile(total, quantile))

    def _neighbours(self, prefix: str, c: np.ndarray):
        """Regressor `prefix`'s nearest learning frames to codes `c` (1, k).

        Returns their codes less `c` (n, k), angles (n, J) and weights (n,),
        and the nearest one's distance.
        """
        c32 = np.ascontiguousarray(c, np.float32)
        _, idx = self._index[prefix].search(c32, self.options.k)
        idx = idx[0][idx[0] >= 0]  # the inverted file may hold fewer than k in the cells searched
        x = self._a[prefix + "codes"][idx] - c32  # re-measured on the float codes (`quantize`)
        d = np.sqrt(np.einsum("ij,ij->i", x, x))
        d1 = float(d.min())
        w = 1.0 / (d + d1 + 1e-6)
        return x, self._a[prefix + "angles"][idx], w, d1

    def _answer(self, x: np.ndarray, y: np.ndarray, w: np.ndarray) -> np.ndarray:
        """The angles read from neighbours (:meth:`_neighbours`) by ``options.local``."""
        if self.options.local == "linear" and len(x) > x.shape[1] + 1:
            return _local_linear(x, y, w, ridge=self.options.ridge)
        return (w @ y / w.sum()).astype(np.float64)

    def _knn(self, prefix: str, c: np.ndarray) -> tuple[np.ndarray, float]:
        x, y, w, d1 = self._neighbours(prefix, c)
        return self._answer(x, y, w), d1

    def _predict(self, prefix: str, c: np.ndarray) -> tuple[np.ndarray, float]:
        """Regressor `prefix` on codes `c` (1, k): angles (20,) and the nearest distance."""
        a = self._a
        if self.options.kind == "mlp":
            h = c / a[prefix + "scale"]
            n_layers = int(a[prefix + "layers"])
            for i in range(n_layers):
                h = h @ a[f"{prefix}w{i}"] + a[f"{prefix}b{i}"]
                if i < n_layers - 1:
                    np.maximum(h, 0.0, out=h)
            return (h[0] * a[prefix + "y_sd"] + a[prefix + "y_mean"]).astype(np.float64), 0.0
        return self._knn(prefix, c)

    def grid(self, frame: np.ndarray) -> np.ndarray:
        """The frame's coverage grid as the learning set holds it ((rows, cols) uint8).

        Raises
        ------
        InvalidInputError
            A frame whose width-to-height ratio is not the device's (the grid's
            cells would fall on other parts of the view), or not an image
            (:func:`~handsynth.estimate._lookup.check_frame_ratio`).
        """
        frame = check_frame_ratio(frame, self.mount, view="this estimator learnt")
        if self._mirror:
            frame = frame[::-1]
        mount, side = self._learnt_view
        if self._skin is not None and frame.ndim == 3 and frame.dtype == np.uint8:
            frame = skin_mask(frame, self._skin)
        c = coverage(frame, mount, side=side, cells=self.cells)
        return np.rint(c * 255).astype(np.uint8)

    # -- estimation ---------------------------------------------------------------
    def code(self, frame: np.ndarray) -> np.ndarray:
        """The principal-component code (k,) of a frame (after calibration if used)."""
        g = self.grid(frame).reshape(1, -1)
        if self.options.use_rest and self._rest is None:
            raise InvalidInputError(_NOT_CALIBRATED)
        z = _inputs(g, self._rest[None] if self._rest is not None and self.options.use_rest
                    else None)
        return self._project(z)[0]

    def _project(self, z: np.ndarray) -> np.ndarray:
        """Principal-component codes (1, k) of inputs `z` (1, D); takes the mean off `z` in place.

        A calibrated perceptron reads the projection with its rest frame
        folded in (:meth:`_folded_projection`).
        """
        if self._fold is not None:
            keep, projection, offset = self._fold
            c = z[:, keep] @ projection - offset
            z -= self._a["mean"]
            return c
        z -= self._a["mean"]
        return z @ self._a["components"]

    def estimate(self, frame: np.ndarray) -> PoseEstimate:
        """Pose of the hand in one frame.

        Parameters
        ----------
        frame : ndarray, shape (H, W) or (H, W, 3)
            A bool mask or uint8 frame of the device's whole view.

        Returns
        -------
        PoseEstimate
            ``keypoints`` are NaN (this estimator reports angles only;
            :class:`~handsynth.estimate.KeypointEstimator` adds those of a model
            hand posed by them);
            ``entry`` is -1; ``confidence`` is a heuristic, low for frames
            unlike any learnt (``"fingers"``: ``1 / (1 + error)``, ``error``
            the mean over the digits of the nearest learning frame's
            distance; otherwise the share of the frame's variance its code
            explains, and ``error`` for ``"mlp"`` the norm of the part of
            its input the code leaves out, ``"knn"`` the nearest learning
            frame's distance); ``low_confidence`` when the frame is more
            novel than 99 % of learning frames (the novelty limit, module
            docstring; ``"fingers"``: learning frames among other hands),
            e.g. a frame of no hand, a cluttered background, a slipped
            device (an estimator stored without a limit flags nothing);
            ``no_hand`` when the frame shows no hand (what stands out covers
            less than :data:`MIN_HAND_COVERAGE` of the view); ``moved`` when the
            device seems to have moved on the wrist since the rest frame
            (:class:`~handsynth.estimate.MoveCheck`, calibrated estimators).
        """
        return self.estimate_grid(self.grid(frame))

    def estimate_grid(self, grid: np.ndarray) -> PoseEstimate:
        """Pose from a frame's coverage grid, as :meth:`grid` makes it.

        :meth:`estimate` is ``estimate_grid(grid(frame))``; estimators of the
        same :attr:`view_key` read the same grid, so an
        :class:`~handsynth.estimate.EnsembleEstimator` makes it once.

        Parameters
        ----------
        grid : ndarray, shape (rows, cols) uint8
        """
        g = np.asarray(grid)
        if g.dtype != np.uint8 or g.shape != self.cells:
            raise InvalidInputError(f"grid must be a {self.cells[0]}x{self.cells[1]} uint8 "
                                    f"coverage grid, got {g.dtype} of shape {g.shape}")
        g = g.reshape(1, -1)
        if g.mean() < MIN_HAND_COVERAGE * 255:  # nothing, or too little to be a hand
            return PoseEstimate(angles=np.full(20, np.nan), keypoints=np.full((21, 3), np.nan,
                                np.float32), confidence=0.0, entry=-1, error=float("inf"),
                                low_confidence=True, no_hand=True)
        if self.options.use_rest and self._rest is None:
            raise InvalidInputError(_NOT_CALIBRATED)
        z = _inputs(g, self._rest[None] if self._rest is not None and self.options.use_rest
                    else None)
        low = False
        if self.options.kind == "fingers":
            angles, error = self._predict_digits(z)
            conf = 1.0 / (1.0 + error)
            if "novelty_limit" in self._a:
                low = bool(error > float(self._a["novelty_limit"]))
        else:
            c = self._project(z)
            angles, error = self._predict("", c)
            total, kept = float(np.sum(z * z)), float(np.sum(c * c))
            conf = kept / total if total > 0 else 0.0
            left_out = float(np.sqrt(max(total - kept, 0.0)))
            if self.options.kind == "mlp":
                error = left_out
            if "novelty_limit" in self._a:
                low = left_out > float(self._a["novelty_limit"])
        if self._rest_angles is not None:
            angles = angles + self._rest_angles
        angles = np.clip(angles, self._lo, self._hi)
        if self.smoothing > 0 and self._previous is not None:
            angles = self.smoothing * self._previous + (1 - self.smoothing) * angles
        self._previous = angles if self.smoothing > 0 else None
        moved = self._move_check is not None and self._move_check.update(g)
        return PoseEstimate(angles=angles, keypoints=np.full((21, 3), np.nan, np.float32),
                            confidence=min(max(conf, 0.0), 1.0), entry=-1, error=error,
                            low_confidence=low, no_hand=False, moved=moved)

    # -- storage -------------------------------------------------------------------
    def save(self, path) -> None:
        """Write the learnt arrays to `path` (``.npz``), complete or not at all.

        A :meth:`mirrored` estimator writes the one it mirrors (the file says
        what was learnt); :meth:`load` it and mirror it again.
        """
        path = Path(path)
        mount, side = self._learnt_view
        meta = {"format": _FORMAT, "options": asdict(self.options), "mount": mount.as_dict(),
                "side": side, "cells": list(self.cells)}
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise DatabaseError(f"cannot write the learnt estimator to {path}: "
                                f"{os_error_reason(exc)}") from None
        # the inverted files too, so that reading the file skips training them
        indices = {_index_name(prefix, self.options): _faiss().serialize_index(index)
                   for prefix, index in self._index.items() if hasattr(index, "nlist")}
        with atomic_open(path, "wb", what="learnt estimator", error=DatabaseError) as f:
            np.savez(f, meta=np.array(json.dumps(meta)), **self._a, **indices)

    @classmethod
    def load(cls, path, *, options: LearnedOptions | None = None) -> LearnedEstimator:
        """Read an estimator written by :meth:`save`.

        Parameters
        ----------
        path : str or os.PathLike
        options : LearnedOptions, keyword-only, optional
            Read with these options (their reading options, such as ``k`` or
            ``ridge``, may differ from the file's; what is learnt may not).
            Default: the options it was learnt with.

        Raises
        ------
        DatabaseError
            The file does not exist, or is a folder.
        DatabaseCorruptError
            The file is unreadable, incomplete (a meta key or an array its
            options need is missing, naming it) or of another format.
        DatabaseMismatchError
            `options` differ from the file's in what is learnt.
        """
        path = Path(path)
        if not path.exists():
            raise DatabaseError(f"learnt estimator {path} does not exist")
        if path.is_dir():
            raise DatabaseError(f"learnt estimator {path} is a folder, not a file")
        try:
            with np.load(path) as z:
                meta = json.loads(str(z["meta"]))
                arrays = {k: z[k] for k in z.files if k != "meta"}
        except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile, zlib.error) as exc:
            raise DatabaseCorruptError(f"learnt estimator {path} is unreadable: {exc}") from None
        if not isinstance(meta, dict) or meta.get("format") != _FORMAT:
            got = meta.get("format") if isinstance(meta, dict) else type(meta).__name__
            raise DatabaseCorruptError(f"learnt estimator {path} has format {got}, "
                                       f"expected {_FORMAT}")
        stored, mount, side, cells = _stored_description(path, meta)
        _check_stored_arrays(path, arrays, stored)
        if options is not None and options.digest() != stored.digest():
            differ = [k for k, v in asdict(options).items()
                      if k not in _READING_OPTIONS and v != getattr(stored, k)]
            raise DatabaseMismatchError(f"learnt estimator {path} was learnt with other options "
                                        f"({', '.join(f'{k}={getattr(stored, k)!r}' for k in differ)})")
        return cls(arrays, options=options or stored, mount=mount, side=side, cells=cells)


def _stored_description(path: Path, meta: dict):
    """The options, mount, side and cells in a stored estimator's `meta`.

    Raises
    ------
    DatabaseCorruptError
        A key is missing or holds an unusable value (naming the key and the file).
    """
    for key in ("options", "mount", "side", "cells"):
        if key not in meta:
            raise DatabaseCorruptError(f"learnt estimator {path}: its meta has no {key!r}")
    key = "options"
    try:
        o = dict(meta["options"])
        o["hidden"] = tuple(o["hidden"])
        stored = LearnedOptions(**o)
        key = "mount"
        mount = CameraMount(**meta["mount"])
        key = "side"
        side = meta["side"]
        if side not in ("right", "left"):
            raise ValueError(f"side {side!r}")
        key = "cells"
        cells = tuple(int(c) for c in meta["cells"])
        if len(cells) != 2 or min(cells) < 1:
            raise ValueError(f"cells {meta['cells']!r}")
    except (TypeError, ValueError, KeyError) as exc:  # InvalidInputError is a ValueError
        raise DatabaseCorruptError(
            f"learnt estimator {path}: meta {key!r} is unusable ({exc})") from None
    return stored, mount, side, cells


def _check_stored_arrays(path: Path, arrays: dict, options: LearnedOptions) -> None:
    """Refuse a stored estimator that lacks an array its options need, or holds NaN.

    Raises
    ------
    DatabaseCorruptError
        Naming the first missing array and the file; or the first array of
        floating-point values holding NaN or infinity (a weight, a mean, a
        novelty limit: every answer would be NaN, or every frame flagged).
    """
    for name, arr in arrays.items():
        if isinstance(arr, np.ndarray) and arr.dtype.kind == "f" and not np.isfinite(arr).all():
            raise DatabaseCorruptError(
                f"learnt estimator {path} is damaged: array {name!r} holds "
                f"{int(np.size(arr) - np.isfinite(arr).sum())} NaN or infinite values")
    if options.kind == "fingers":
        need = [f"d{d}_{k}" for d in range(5)
                for k in ("cols", "w", "mean", "components", "codes", "angles")]
    else:
        prefixes = ["", "abs_"] if options.use_rest and options.target == "delta" else [""]
        need = []
        for p in prefixes:
            need += [p + "mean", p + "components", p + "scale"]
            if options.kind == "knn":
                need += [p + "codes", p + "angles"]
                continue
            need += [p + "y_mean", p + "y_sd", p + "layers"]
            layers = arrays.get(p + "layers")
            if layers is not None:
                try:
                    n_layers = int(layers)
                except (TypeError, ValueError):
                    raise DatabaseCorruptError(
                        f"learnt estimator {path}: array {p + 'layers'!r} is not a number of "
                        f"layers, got shape {np.shape(layers)}") from None
                need += [f"{p}{w}{i}" for i in range(n_layers) for w in ("w", "b")]
    missing = [k for k in need if k not in arrays]
    if missing:
        raise DatabaseCorruptError(
            f"learnt estimator {path} is incomplete: it has no array {missing[0]!r}"
            + (f" (and {len(missing) - 1} more)" if len(missing) > 1 else ""))


def train_learned(data: LearningSet, options: LearnedOptions | None = None, *,
                  progress=None) -> LearnedEstimator:
    """Learn an estimator from a learning set (module docstring).

    Parameters
    ----------
    data : LearningSet
    options : LearnedOptions, optional
    progress : callable, keyword-only, optional
        Called with (epoch, loss) while a perceptron is fitted.

    Returns
    -------
    LearnedEstimator
    """
    opts = check_options(options, LearnedOptions)
    check_instance(data, LearningSet, name="data")
    rng = np.random.default_rng(opts.seed)
    y = data.angles.astype(np.float32)
    rows = _Rows(data.grids, data.rest_grids, data.hand) if opts.use_rest else _Rows(data.grids)
    if opts.kind == "fingers":
        arrays = _fit_digits(rows, y, opts, rng)
        est = LearnedEstimator(arrays, options=opts, mount=data.mount, side=data.side,
                               cells=data.options.cells)
        pick = np.sort(rng.choice(len(y), size=min(1000, len(y)), replace=False))
        limit = np.array(est._novelty_limit(rows.take(pick), pick, data.hand,
                                            quantile=_NOVELTY_QUANTILE), np.float32)
        limit.setflags(write=False)
        est._a["novelty_limit"] = limit
        return est
    arrays = _fit(rows, y - data.rest_angles[data.hand] if opts.target == "delta" and opts.use_rest
                  else y, opts, rng, "", progress)
    if opts.use_rest and opts.target == "delta":
        both = _Rows(np.vstack([data.grids, data.rest_grids]))
        y_abs = np.vstack([y, data.rest_angles.astype(np.float32)])
        arrays.update(_fit(both, y_abs, opts, rng, "abs_", progress))
    return LearnedEstimator(arrays, options=opts, mount=data.mount, side=data.side,
                            cells=data.options.cells)


_DIGIT_JOINTS = ((0, 1, 2, 3), *(tuple(range(4 + 4 * k, 8 + 4 * k)) for k in range(4)))
#: A cell belongs to a digit's region when its coverage correlates with one of
#: the digit's angles by more than this over the learning set (or by four
#: standard errors of a zero correlation, ``4 / sqrt(N)``, if larger).
_REGION_CORR = 0.1


def _correlations(z: _Rows, y: np.ndarray, n_cells: int, block: int) -> np.ndarray:
    """|Pearson correlation| (n_cells, 20) of each cell's coverage with each angle.

    Accumulated over blocks of rows (float64 sums), so that the inputs of
    the whole set are never held at once; a cell or angle that never varies
    correlates 0.
    """
    n = len(z)
    sx = np.zeros(n_cells)
    sxx = np.zeros(n_cells)
    sxy = np.zeros((n_cells, y.shape[1]))
    for sl, x in z.blocks(block):
        x = x[:, :n_cells].astype(np.float64)
        sx += x.sum(axis=0)
        sxx += np.einsum("ij,ij->j", x, x)
        sxy += x.T @ y[sl].astype(np.float64)
    yd = y.astype(np.float64)
    mx, my = sx / n, yd.mean(axis=0)
    sdx = np.maximum(np.sqrt(np.maximum(sxx / n - mx * mx, 0.0)), 1e-6)
    sdy = np.maximum(yd.std(axis=0), 1e-6)
    return np.abs(sxy / n - np.outer(mx, my)) / np.outer(sdx, sdy)


def _fit_digits(z: _Rows, y: np.ndarray, opts: LearnedOptions, rng: np.random.Generator, *,
                block: int = 20000) -> dict:
    """Per digit: the cells whose coverage follows its angles, their components and a kNN.

    `block`: rows of inputs made at a time (the result does not depend on it).
    """
    n_cells = z.grids.shape[1]
    corr = _correlations(z, y, n_cells, block)
    arrays: dict = {}
    blocks = z.width // n_cells
    digits = []
    for d, joints in enumerate(_DIGIT_JOINTS):
        w = corr[:, list(joints)].max(axis=1)
        cells = np.nonzero(w > max(_REGION_CORR, 4.0 / np.sqrt(len(z))))[0]
        cols = np.concatenate([cells + b * n_cells for b in range(blocks)])
        weight = np.tile(w[cells], blocks).astype(np.float32)
        mean, comps, _ = _pca(z, min(opts.components, 64, len(cols)), rng, cols=cols,
                              weight=weight)
        p = f"d{d}_"
        arrays.update({p + "cols": cols, p + "w": weight, p + "mean": mean, p + "components": comps,
                       p + "codes": np.empty((len(z), comps.shape[1]), np.float32),
                       p + "angles": np.ascontiguousarray(y[:, list(joints)], np.float32)})
        digits.append(p)
    for sl, x in z.blocks(block):
        for p in digits:
            arrays[p + "codes"][sl] = (x[:, arrays[p + "cols"]] * arrays[p + "w"]
                                       - arrays[p + "mean"]) @ arrays[p + "components"]
    return arrays


def _fit(z: _Rows, y: np.ndarray, opts: LearnedOptions, rng: np.random.Generator,
         prefix: str, progress, *, block: int = 20000) -> dict:
    """Principal components of inputs `z` and a regressor of `y` on them, as named arrays."""
    k = min(opts.components, z.width)
    mean, comps, sd = _pca(z, k, rng)
    # one scale for every component (the first one's s.d.): whitening each
    # component gave the perceptron the noise of the small ones at full weight
    # (model hands, paper frames: flexion skill 0.17 whitened, 0.38 not)
    scale = np.full_like(sd, sd[0])
    codes = np.empty((len(z), comps.shape[1]), np.float32)
    left_out = np.empty(len(z), np.float32)
    for sl, x in z.blocks(block):
        centred = x - mean
        codes[sl] = centred @ comps
        left_out[sl] = _left_out_norms(centred, codes[sl])
    y = np.asarray(y, np.float32)
    arrays: dict = {"mean": mean, "components": comps, "scale": scale,
                    "novelty_limit": np.array(np.quantile(left_out, _NOVELTY_QUANTILE), np.float32)}
    if opts.kind == "knn":
        arrays["codes"] = codes
        arrays["angles"] = y
    else:
        y_mean, y_sd = y.mean(axis=0), np.maximum(y.std(axis=0), 1e-3)
        weights, biases = fit_mlp(codes / scale, (y - y_mean) / y_sd, hidden=opts.hidden,
                                  epochs=opts.epochs, batch=opts.batch,
                                  learning_rate=opts.learning_rate,
                                  weight_decay=opts.weight_decay, loss=opts.loss,
                                  seed=opts.seed,
                                  progress=progress)
        arrays.update({"y_mean": y_mean, "y_sd": y_sd, "layers": np.array(len(weights))})
        for i, (w, b) in enumerate(zip(weights, biases)):
            arrays[f"w{i}"], arrays[f"b{i}"] = w, b
    return {prefix + k: v for k, v in arrays.items()}


def _is_colour(frame) -> bool:
    """A uint8 (H, W, 3) frame whose channels are not all equal."""
    f = np.asarray(frame)
    if f.ndim != 3 or f.dtype != np.uint8 or f.shape[2] != 3:
        return False
    s = f[::8, ::8]
    return bool((s[..., 0] != s[..., 1]).any() or (s[..., 1] != s[..., 2]).any())


def learned_estimator(folder, options: LearnedOptions | None = None, *,
                      data: LearningSetOptions | None = None, mount: CameraMount | None = None,
                      side: str = "right", progress=None, shipped: bool = True,
                      workers: int = 1) -> LearnedEstimator:
    """The estimator learnt with `options` from the learning set `data`, cached in `folder`.

    Renders the learning set (:func:`~handsynth.db.learning_set`) and learns
    the estimator when `folder` holds neither; both stay in `folder` (a
    folder the caller chose, created if missing).  The default ensemble's
    perceptrons are shipped with handsynth (:mod:`._shipped`) and read from
    there when `folder` lacks them.

    Parameters
    ----------
    folder : str or os.PathLike
    options : LearnedOptions, optional
    data : LearningSetOptions, keyword-only, optional
    mount : CameraMount, keyword-only, optional
        The device (the paper's by default).
    side : {"right", "left"}, keyword-only
        The hand wearing the device.  A left hand's estimator is the right
        hand's :meth:`~LearnedEstimator.mirrored` (learnt, or shipped, for
        the mirrored device), so both hands share one learning set and the
        shipped perceptrons.
    progress : callable, keyword-only, optional
        Called with a line of text at each stage, and after each chunk of
        learning hands rendered (minutes in all on a first run).
    shipped : bool, keyword-only
        Read a shipped estimator of these options when there is one (default)
        instead of learning it.
    workers : int, keyword-only
        Processes rendering a learning set that is not in `folder`
        (:func:`~handsynth.db.render_learning_set`: the same set whatever
        their number; default 1).  Worker processes are started afresh, so
        a script that asks for them keeps its work under
        ``if __name__ == "__main__":``.

    Raises
    ------
    InvalidInputError
        `folder` is not a folder name (None, a number, ``""``), or an option
        of the wrong type or value.
    DatabaseError
        The estimator has to be learnt and `folder` cannot be created or
        written into (a file in the way, a read-only folder): refused before
        the learning set is rendered.
    """
    folder = check_path(folder, "folder", kind="folder")
    opts = check_options(options, LearnedOptions)
    data = check_options(data, LearningSetOptions, name="data")
    mount = as_mount(mount)
    check_side(side)
    if side == "left":
        return learned_estimator(folder, opts, data=data, mount=mount.mirrored(), side="right",
                                 progress=progress, shipped=shipped, workers=workers).mirrored()
    path = folder / learned_file_name(opts, data, mount, side)
    say = progress or (lambda _line: None)
    if path.is_file():
        try:
            return LearnedEstimator.load(path, options=opts)
        except DatabaseCorruptError:
            pass
    source = shipped_path(path.name) if shipped else None  # hashed only when needed
    if source is not None:
        try:
            est = LearnedEstimator.load(source, options=opts)
        except DatabaseCorruptError:
            pass
        else:
            say(f"{opts.kind} ({path.name}): shipped with handsynth")
            return est
    # checked before minutes of rendering and learning, not when the result is saved
    make_folder(folder, what="learnt-estimator folder", writable=True, error=DatabaseError)
    say(f"learning set: {data.hands} hands x {data.poses_per_hand} frames")
    ls = learning_set(folder, data, mount=mount, side=side, workers=workers,
                      progress=lambda done, n: say(f"learning set: {done} of {n} hands rendered"))
    say(f"learning {opts.kind}")
    est = train_learned(ls, opts, progress=lambda e, loss: say(f"epoch {e}: loss {loss:.4f}"))
    est.save(path)
    return est


def learned_file_name(options: LearnedOptions, data: LearningSetOptions, mount: CameraMount,
                      side: str) -> str:
    """The name of the file :func:`learned_estimator` keeps these options' estimator in."""
    key = hashlib.sha256(json.dumps([options.digest(), data.digest(), mount.as_dict(), side],
                                    sort_keys=True).encode()).hexdigest()[:16]
    return f"learned_{options.kind}_{key}.npz"
