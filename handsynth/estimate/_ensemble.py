"""The mean of several estimators' answers (beyond the paper).

Learnt estimators of different kinds err differently: the per-digit
nearest neighbours of :class:`~handsynth.estimate.LearnedEstimator`
(``kind="fingers"``) average what similar learning frames did, the
perceptron (``kind="mlp"``) interpolates between them.  Their mean is more
accurate than either on the model hands of the evaluation protocol
(docs/camera_estimator.md); :func:`learned_ensemble` makes
the default one (:data:`LEARNED_ENSEMBLE`).
"""

from __future__ import annotations

from dataclasses import fields, replace
from types import MappingProxyType

import numpy as np

from .._checks import check_options
from ..db import LearningSetOptions
from ..errors import InvalidInputError
from ..render import CameraMount, SkinColour
from ._learned import LearnedEstimator, LearnedOptions, learned_estimator, learned_file_name
from ._lookup import PoseEstimate
from ._shipped import shipped_path

__all__ = ["LEARNED_ENSEMBLE", "LEARNED_ENSEMBLES", "LEARNED_PERCEPTRONS", "SHIPPED_LEARNING_SETS",
           "EnsembleEstimator", "largest_learning_set", "learned_ensemble", "member_learning_set",
           "shipped_members", "shipped_perceptrons"]

#: The default learnt estimator's members: each member's options, its weight
#: and what its learning set changes from the one given to
#: :func:`learned_ensemble` (``(field, value)`` pairs of
#: :class:`~handsynth.db.LearningSetOptions`, or ``("hands_factor", f)``:
#: ``f`` times that set's hands; none: that set).  The per-digit estimator at
#: 0.3; at 0.7 / 3 each, perceptrons started from seeds 0 and 1, learnt from
#: four times the hands of that set (16,000 by default), and the seed-0 perceptron
#: of as many hands that all rest relaxed (``open_rest_share`` 0; the default
#: set rests three hands in four near open).  The default perceptrons are
#: shipped with handsynth (:mod:`._shipped`), so a first run renders only the
#: 4,000 hands the per-digit estimator needs.  Chosen on held-out model hands
#: by rules fixed before the runs (docs/camera_estimator.md, "Perceptrons of 16,000 hands and
#: their weight", "A perceptron of relaxed learning rests" and "Ensemble
#: members").
#: A mean of perceptrons errs by no more than their mean error on any frame
#: (the triangle inequality), and one
#: perceptron's error on unseen hands depends on its start and its learning
#: set: on the glTF hands' relaxed paper frames starts 0, 1 and 2 erred by 5.1,
#: 7.3 and 6.8 deg (docs/camera_estimator.md, "The learning set's draw").
LEARNED_ENSEMBLE: tuple[tuple[LearnedOptions, float, tuple], ...] = (
    (LearnedOptions(kind="fingers"), 0.3, ()),
    (LearnedOptions(kind="mlp", seed=0), 0.7 / 3, (("hands_factor", 4),)),
    (LearnedOptions(kind="mlp", seed=1), 0.7 / 3, (("hands_factor", 4),)),
    (LearnedOptions(kind="mlp", seed=0), 0.7 / 3, (("hands_factor", 4), ("open_rest_share", 0.0))),
)

#: The perceptrons of :data:`LEARNED_ENSEMBLE` alone, at equal weights: what
#: ``handsynth estimate --learned --learned-kind perceptrons`` reads.  For the
#: default learning set, the paper's mount and the right hand they are shipped
#: with handsynth, so :func:`learned_ensemble` with these members renders and
#: learns nothing (ready in about a second on a first run, where the full
#: ensemble's per-digit member takes about 5 min), and a frame costs about a
#: third as much.  Measured beside the full ensemble in docs/camera_estimator.md ("The
#: perceptrons alone").
_PERCEPTRON_MEMBERS = [m for m in LEARNED_ENSEMBLE if m[0].kind == "mlp"]
LEARNED_PERCEPTRONS: tuple[tuple[LearnedOptions, float, tuple], ...] = tuple(
    (opts, 1.0 / len(_PERCEPTRON_MEMBERS), changes) for opts, _w, changes in _PERCEPTRON_MEMBERS)

#: The ensembles by the name the CLI, the protocol and the benchmark give them
#: (``--learned-kind``, ``--conditions``, ``--kind``): their members.
LEARNED_ENSEMBLES = MappingProxyType({"ensemble": LEARNED_ENSEMBLE,
                                      "perceptrons": LEARNED_PERCEPTRONS})

#: The learning sets, as given to :func:`learned_ensemble`, whose perceptron
#: members (of :data:`LEARNED_ENSEMBLE`) are shipped with handsynth
#: (:mod:`._shipped`, :func:`shipped_perceptrons`): the default one, and the
#: one whose hands all rest relaxed (``handsynth estimate --learned-rest
#: relaxed``).
SHIPPED_LEARNING_SETS: tuple[LearningSetOptions, ...] = (
    LearningSetOptions(), LearningSetOptions(open_rest_share=0.0))


class EnsembleEstimator:
    """Reports the (weighted) mean of its members' angles.

    Implements :class:`~handsynth.estimate.PoseEstimator`.

    Parameters
    ----------
    members : sequence of PoseEstimator
        At least one.  Members with a ``calibrated(rest_frame)`` method are
        calibrated together by :meth:`calibrated`.
    weights : sequence of float, keyword-only, optional
        Non-negative, one per member (equal by default).

    Raises
    ------
    InvalidInputError
        No members, or weights that do not match them.
    """

    def __init__(self, members, *, weights=None) -> None:
        self.members = list(members)
        if not self.members:
            raise InvalidInputError("an EnsembleEstimator needs at least one member")
        for m in self.members:
            if not callable(getattr(m, "estimate", None)):
                raise InvalidInputError(f"ensemble member {m!r} has no estimate(frame) method")
        w = np.ones(len(self.members)) if weights is None else np.asarray(weights, float)
        if w.shape != (len(self.members),) or not np.all(np.isfinite(w)) or np.any(w < 0) \
                or w.sum() <= 0:
            raise InvalidInputError(f"weights must be {len(self.members)} non-negative numbers "
                                    f"with a positive sum, got {weights!r}")
        self.weights = w / w.sum()
        #: how the calibrated members tell the hand in camera frames (LearnedEstimator.calibrated)
        self.segment = next((m.segment for m in self.members if isinstance(m, LearnedEstimator)),
                            "brightness")

    def calibrated(self, rest_frame: np.ndarray, *,
                   segment: str | SkinColour = "auto") -> EnsembleEstimator:
        """A copy whose members are calibrated to `rest_frame` (those that calibrate).

        `segment` is passed to the learnt members
        (:meth:`LearnedEstimator.calibrated`); the first of a
        :attr:`~LearnedEstimator.view_key` decides it, and those after it take
        its decision and skin.
        """
        members = []
        told: dict = {}  # learnt members reading one grid: told once, checked once for a move
        for m in self.members:
            if isinstance(m, LearnedEstimator):
                key = m.view_key
                first = told.get(key)
                how = segment if first is None else (first.skin or "brightness")
                members.append(m.calibrated(rest_frame, check_moved=first is None, segment=how))
                told.setdefault(key, members[-1])
            else:
                members.append(m.calibrated(rest_frame)
                               if callable(getattr(m, "calibrated", None)) else m)
        return EnsembleEstimator(members, weights=self.weights)

    def check_ready(self) -> None:
        """Raise if a member cannot read any frame as it is (its own ``check_ready()``).

        Raises
        ------
        EstimationError
            A member is not set up, e.g. a learnt member that reads the rest
            frame and was not :meth:`calibrated`.
        """
        for m in self.members:
            ready = getattr(m, "check_ready", None)
            if callable(ready):
                ready()

    def estimate(self, frame: np.ndarray) -> PoseEstimate:
        """Every member's estimate of `frame`, averaged.

        Returns
        -------
        PoseEstimate
            ``angles``: the weighted mean of the members' (NaN when any finds
            no hand); ``keypoints`` the mean of those given (NaN if none, as
            for learnt members: :class:`~handsynth.estimate.KeypointEstimator`
            adds a model hand's);
            ``confidence`` the weighted mean; ``entry`` -1; ``low_confidence``
            and ``moved`` when any member's is.  Learnt members
            of the same :attr:`~LearnedEstimator.view_key` share one coverage
            grid of the frame (:meth:`LearnedEstimator.estimate_grid`).
        """
        grids: dict = {}  # learnt members of one view read one grid
        got = []
        for m in self.members:
            if isinstance(m, LearnedEstimator):
                key = m.view_key
                if key not in grids:
                    grids[key] = m.grid(frame)
                got.append(m.estimate_grid(grids[key]))
            else:
                got.append(m.estimate(frame))
        if any(e.no_hand for e in got):
            return PoseEstimate(angles=np.full(20, np.nan), keypoints=np.full((21, 3), np.nan,
                                np.float32), confidence=0.0, entry=-1, error=float("inf"),
                                low_confidence=True, no_hand=True)
        angles = self.weights @ np.stack([e.angles for e in got])
        kps = [e.keypoints for e in got if np.isfinite(e.keypoints).all()]
        keypoints = (np.mean(kps, axis=0).astype(np.float32) if kps
                     else np.full((21, 3), np.nan, np.float32))
        return PoseEstimate(angles=angles, keypoints=keypoints,
                            confidence=float(self.weights @ [e.confidence for e in got]),
                            entry=-1, error=float(self.weights @ [e.error for e in got]),
                            low_confidence=any(e.low_confidence for e in got), no_hand=False,
                            moved=any(e.moved for e in got))


def _member(member) -> tuple:
    """An ensemble member as (options, weight, changes); raises InvalidInputError if not one."""
    if not isinstance(member, (tuple, list)) or len(member) not in (2, 3):
        raise InvalidInputError(f"an ensemble member is (LearnedOptions, weight) or "
                                f"(LearnedOptions, weight, changes), got {member!r}")
    return (*member, ()) if len(member) == 2 else tuple(member)


def member_learning_set(data: LearningSetOptions, changes) -> LearningSetOptions:
    """The learning set of an ensemble member: `data` with `changes` made.

    Parameters
    ----------
    data : LearningSetOptions
    changes : sequence of (str, value)
        Fields of :class:`~handsynth.db.LearningSetOptions` and their
        values, or ``("hands_factor", f)``: ``f`` (> 0) times the hands of
        `data`, rounded (at least one).

    Raises
    ------
    InvalidInputError
        A change naming no option, or a factor that is not a positive number.
    """
    changes = dict(changes)
    unknown = sorted(set(changes) - {f.name for f in fields(LearningSetOptions)} - {"hands_factor"})
    if unknown:
        raise InvalidInputError(f"an ensemble member's learning-set changes name no option "
                                f"of LearningSetOptions: {', '.join(unknown)}")
    if "hands_factor" in changes:
        factor = changes.pop("hands_factor")
        if isinstance(factor, bool) or not isinstance(factor, (int, float)) or not factor > 0:
            raise InvalidInputError(f"an ensemble member's hands_factor must be a positive "
                                    f"number, got {factor!r}")
        changes["hands"] = max(1, round(data.hands * factor))
    return replace(data, **changes)


def largest_learning_set(data: LearningSetOptions, members=LEARNED_ENSEMBLE) -> int:
    """Hands in the largest of the learning sets `members` learn from.

    What a command that may render the sets judges its worker processes by
    (:func:`~handsynth.db.learning_workers`): the default ensemble's
    perceptrons learn from four times the hands of `data`.

    Parameters
    ----------
    data : LearningSetOptions
        The learning set given to :func:`learned_ensemble`.
    members : sequence of (LearnedOptions, float, changes)
        As :data:`LEARNED_ENSEMBLE`.
    """
    return max([data.hands] + [member_learning_set(data, changes).hands
                               for _options, _weight, changes in members])


def shipped_perceptrons(*, members=LEARNED_ENSEMBLE, bases=SHIPPED_LEARNING_SETS
                        ) -> list[tuple[LearnedOptions, LearningSetOptions]]:
    """The perceptrons shipped with handsynth: what ``scripts/ship_perceptrons.py`` learns.

    Parameters
    ----------
    members : sequence, keyword-only
        Ensemble members, as :func:`learned_ensemble` takes them.
    bases : sequence of LearningSetOptions, keyword-only
        Learning sets as given to :func:`learned_ensemble`.

    Returns
    -------
    list of (LearnedOptions, LearningSetOptions)
        Each perceptron member's options with the learning set it learns
        from (:func:`member_learning_set`) given each of `bases` in turn;
        each pair once, in that order.
    """
    out: list[tuple[LearnedOptions, LearningSetOptions]] = []
    for base in bases:
        for member in members:
            opts, _weight, changes = _member(member)
            pair = (opts, member_learning_set(base, changes))
            if opts.kind == "mlp" and pair not in out:
                out.append(pair)
    return out


def shipped_members(*, members=LEARNED_ENSEMBLE) -> list[LearnedEstimator]:
    """The members of `members` shipped with handsynth, read from the package.

    Its perceptrons learnt from the default learning set (with each member's
    changes; :func:`shipped_perceptrons`), for the paper's mount and the
    right hand, whose shipped file is intact (:mod:`._shipped`); the others
    are left out.  Reads nothing else and learns nothing.

    Parameters
    ----------
    members : sequence, keyword-only
        Ensemble members as :func:`learned_ensemble` takes them:
        ``(LearnedOptions, weight)`` or ``(LearnedOptions, weight, changes)``
        (:data:`LEARNED_ENSEMBLE` by default).  Only perceptrons
        (``kind="mlp"``) are looked for; the weights are not used.

    Returns
    -------
    list of LearnedEstimator
        In the order of `members`, each once.

    Raises
    ------
    InvalidInputError
        As :func:`learned_ensemble`, for a member or changes it cannot read.
    """
    mount = CameraMount.paper()
    out = []
    for opts, data in shipped_perceptrons(members=members, bases=(LearningSetOptions(),)):
        path = shipped_path(learned_file_name(opts, data, mount, "right"))
        if path is not None:
            out.append(LearnedEstimator.load(path, options=opts))
    return out


def learned_ensemble(folder, *, members=LEARNED_ENSEMBLE, data=None, mount=None,
                     side: str = "right", progress=None, learnt=(),
                     shipped: bool = True, workers: int = 1) -> EnsembleEstimator:
    """The weighted mean of learnt estimators, each read from `folder` or learnt there first.

    Parameters
    ----------
    folder : str or os.PathLike
        As :func:`~handsynth.estimate.learned_estimator`'s.
    members : sequence of (LearnedOptions, float) or (LearnedOptions, float, changes), keyword-only
        Each member's options and weight, and optionally what its learning
        set changes from `data` (:func:`member_learning_set`; default
        :data:`LEARNED_ENSEMBLE`).
    data, mount, side, progress, shipped, workers
        As :func:`~handsynth.estimate.learned_estimator`'s, for every member.
    learnt : sequence of LearnedEstimator, keyword-only
        Estimators already read (of the learning set `data`, mount and
        side), used for the members with their options and no learning-set
        changes instead of reading them again.

    Returns
    -------
    EnsembleEstimator

    Raises
    ------
    InvalidInputError
        A member that is not options and a weight (and changes), or changes
        naming no field of the learning set's options.
    """
    data = check_options(data, LearningSetOptions, name="data")
    have = {e.options: e for e in learnt}
    ests, weights = [], []
    for member in members:
        opts, weight, changes = _member(member)
        est = None if changes else have.get(opts)
        if est is None:
            est = learned_estimator(folder, opts, data=member_learning_set(data, changes),
                                    mount=mount, side=side, progress=progress, shipped=shipped,
                                    workers=workers)
        ests.append(est)
        weights.append(weight)
    return EnsembleEstimator(ests, weights=weights)
