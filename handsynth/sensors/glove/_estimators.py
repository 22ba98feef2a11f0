"""Estimators of the 20 joint angles from five glove readings, one interface.

Every estimator satisfies :class:`GloveEstimator` (checked at run time by
``isinstance`` and by a test): a ``name``, ``predict(sensors, *, motion=None)``
returning angles (N, 20) in degrees, and ``to_dict()`` for the calibration
file.  Rows of `sensors` with a NaN give rows of NaN; every other output is
clipped to the joint limits (:data:`handsynth.models.JOINT_LIMITS_DEG`),
since no hand can take an angle outside them.

The estimators of :func:`calibrate` carry the calibration's range of
readings (``reading_range``); their ``predict`` warns, as
:func:`check_reading_range` words it, when readings lie off it (the models
clamp such readings to the range, so the answer would hardly move without a
word).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from ...errors import EstimationError, InvalidInputError
from ...models import JOINT_LIMITS_DEG, JOINT_NAMES
from ._checks import check_reading_range
from ._fields import array_field, as_array, as_number, as_sensors, number_field
from ._mixing import MotionMixer
from ._models import GloveWarning, MotionModel
from ._sensors import SENSOR_NAMES, _check_kind, sensor_joints
from ._synergy import Synergies

__all__ = [
    "ConstantEstimator",
    "GatedEstimator",
    "GloveEstimator",
    "RangeNormalizer",
    "RegressionEstimator",
    "SynergyEstimator",
    "estimator_from_dict",
]


@runtime_checkable
class GloveEstimator(Protocol):
    """What every glove estimator provides."""

    @property
    def name(self) -> str:
        """Short name, the key of the estimator in a calibration file."""

    def predict(self, sensors: np.ndarray, *, motion: str | None = None) -> np.ndarray:
        """Joint angles (N, 20), deg, canonical order, from readings (N, 5), counts.

        `motion` names the representative motion when it is known; estimators
        that do not use motions ignore it.
        """

    def to_dict(self) -> dict:
        """JSON-serialisable form, read back by :func:`estimator_from_dict`."""


def _finish(s: np.ndarray, fn) -> np.ndarray:
    """Apply fn to the finite rows; NaN rows stay NaN; clip to the joint limits."""
    ok = ~np.isnan(s).any(axis=1)
    out = np.full((len(s), len(JOINT_NAMES)), np.nan)
    if ok.any():
        out[ok] = np.clip(fn(s[ok]), JOINT_LIMITS_DEG[:, 0], JOINT_LIMITS_DEG[:, 1])
    return out


def _reading_range(value, what: str) -> np.ndarray | None:
    """A reading range (2, 5): lowest and highest reading of each sensor, or None."""
    if value is None:
        return None
    r = as_array(value, what, (2, 5))
    turned = np.flatnonzero(r[0] > r[1])
    if turned.size:
        k = turned[0]
        raise InvalidInputError(f"{what}: the lowest {SENSOR_NAMES[k]} reading {r[0, k]:g} "
                                f"lies above the highest {r[1, k]:g}")
    return r


class _Estimator:
    """What the estimators below share: checks of the input, then ``_predict``."""

    name: str
    reading_range: np.ndarray | None

    def _check_common(self) -> None:
        """Check ``name`` and convert ``reading_range`` (from ``__post_init__``)."""
        cls = type(self).__name__
        if not isinstance(self.name, str) or not self.name:
            raise InvalidInputError(f"{cls}.name must be a non-empty string, "
                                    f"got {self.name!r}")
        object.__setattr__(self, "reading_range",
                           _reading_range(self.reading_range, f"{cls}.reading_range"))

    def predict(self, sensors, *, motion: str | None = None) -> np.ndarray:
        """Joint angles (N, 20), deg, canonical order, from readings (N, 5), counts.

        Parameters
        ----------
        sensors : array_like, shape (N, 5) or (5,), counts
            NaN marks a dropped sample (its row of angles is NaN).
        motion : str, keyword-only
            The representative motion, when known; estimators that do not
            use motions ignore it.

        Raises
        ------
        InvalidInputError
            `sensors` of another shape or with an infinite reading; a
            `motion` that was not calibrated (for an estimator with models
            of several motions).

        Warns
        -----
        GloveWarning
            Readings mostly off ``reading_range`` (:func:`check_reading_range`).
        """
        s = as_sensors(sensors)
        self._check_motion(motion)
        if self.reading_range is not None:
            check_reading_range(s, self.reading_range[0], self.reading_range[1],
                                where=self.name, stacklevel=3)
        return self._predict(s, motion)

    def _check_motion(self, motion: str | None) -> None:
        """Refuse a `motion` the estimator cannot use (most ignore it)."""

    def _predict(self, s: np.ndarray, motion: str | None) -> np.ndarray:
        """`predict` of checked readings (N, 5) and motion, without the check of the range."""
        raise NotImplementedError


def _predict_unchecked(est: GloveEstimator, s: np.ndarray, motion: str | None) -> np.ndarray:
    """`est`'s answer to readings its caller already checked (no second range warning)."""
    if isinstance(est, _Estimator):
        return est._predict(s, motion)
    return est.predict(s, motion=motion)


def _to_dict_range(est: _Estimator) -> list | None:
    return None if est.reading_range is None else est.reading_range.tolist()


def _range_field(d: dict) -> np.ndarray | None:
    """Field ``reading_range`` of an estimator entry (absent in older files: None)."""
    return None if d.get("reading_range") is None else array_field(d, "reading_range", (2, 5))


@dataclass(frozen=True, eq=False)
class ConstantEstimator(_Estimator):
    """The trivial baseline: always the mean posture of the calibration.

    Attributes
    ----------
    posture : ndarray, shape (20,), deg
    name : str
    reading_range : ndarray, shape (2, 5), counts, or None
        Lowest (row 0) and highest (row 1) reading of each sensor in the
        calibration; None: unknown, no check.

    Raises
    ------
    InvalidInputError
        A field of another type or shape, or not finite (named in the message).
    """

    posture: np.ndarray
    name: str = "constant"
    reading_range: np.ndarray | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "posture", as_array(self.posture, "ConstantEstimator.posture",
                                                     (len(JOINT_NAMES),)))
        self._check_common()

    def _predict(self, s: np.ndarray, motion: str | None) -> np.ndarray:
        return _finish(s, lambda x: np.tile(self.posture, (len(x), 1)))

    def to_dict(self) -> dict:
        return {"type": "constant", "name": self.name, "posture": self.posture.tolist(),
                "reading_range": _to_dict_range(self)}


@dataclass(frozen=True, eq=False)
class RegressionEstimator(_Estimator):
    """Per-motion regressions of seed 004, with likelihood mixing (eqs. 4-6).

    Attributes
    ----------
    name : str
    models : dict of str to MotionModel
        One fit per representative motion (one entry "pooled" for a fit on
        every motion at once).  With a single model, `motion` is ignored.
    mixer : MotionMixer or None
        Needed to predict without a motion when there is more than one model.
    reading_range : ndarray, shape (2, 5), counts, or None
        See :class:`ConstantEstimator`.

    Raises
    ------
    InvalidInputError
        No models, a model that is no :class:`MotionModel`, or a mixer that
        is no :class:`MotionMixer`.
    """

    name: str
    models: dict
    mixer: MotionMixer | None = None
    reading_range: np.ndarray | None = None

    def __post_init__(self) -> None:
        self._check_common()
        if not isinstance(self.models, dict) or not self.models:
            raise InvalidInputError(f"RegressionEstimator.models must map each calibrated "
                                    f"motion to its MotionModel, got {self.models!r:.40}")
        bad = [m for m, v in self.models.items() if not isinstance(v, MotionModel)]
        if bad:
            raise InvalidInputError(f"RegressionEstimator.models[{bad[0]!r}] must be a "
                                    f"MotionModel, got {type(self.models[bad[0]]).__name__}")
        if self.mixer is not None and not isinstance(self.mixer, MotionMixer):
            raise InvalidInputError(f"RegressionEstimator.mixer must be a MotionMixer or "
                                    f"None, got {type(self.mixer).__name__}")

    @property
    def motions(self) -> tuple[str, ...]:
        return tuple(self.models)

    def weights(self, sensors) -> np.ndarray:
        """Motion weights r_p (eq. 6), shape (N, P), in the order of `motions`."""
        s = as_sensors(sensors)
        if len(self.models) == 1:
            return np.ones((len(s), 1))
        if self.mixer is None:
            raise EstimationError(f"{self.name}: no motion mixer; give the motion")
        return self.mixer.weights(s)

    def _check_motion(self, motion: str | None) -> None:
        """A single model (such as the pooled one) answers whatever `motion` is.

        Raises
        ------
        InvalidInputError
            `motion` is not one of the calibrated motions (with several models).
        """
        if motion is not None and len(self.models) > 1 and motion not in self.models:
            raise InvalidInputError(f"motion {motion!r} was not calibrated; calibrated "
                                    f"motions: {', '.join(self.models)}")

    def _predict(self, s: np.ndarray, motion: str | None) -> np.ndarray:
        """Angles from the named motion's model, or mixed over all (eq. 6)."""
        if len(self.models) == 1:
            return _finish(s, next(iter(self.models.values())).predict)
        if motion is not None:
            return _finish(s, self.models[motion].predict)

        def mixed(x):
            r = self.weights(x)
            order = self.mixer.motions if self.mixer is not None else self.motions
            return sum(r[:, [p]] * self.models[m].predict(x) for p, m in enumerate(order))

        return _finish(s, mixed)

    def to_dict(self) -> dict:
        return {"type": "regression", "name": self.name,
                "models": {m: v.to_dict() for m, v in self.models.items()},
                "mixer": None if self.mixer is None else self.mixer.to_dict(),
                "reading_range": _to_dict_range(self)}


@dataclass(frozen=True, eq=False)
class SynergyEstimator(_Estimator):
    """Synergy-based reconstruction (Bianchi et al. 2013), the outside baseline.

    Each reading is first turned into the bend angle of its sensor (a cubic
    in the standardised reading, fitted on the calibration to the nominal
    bend of the reference angles, see :func:`sensor_joints`); the angles are
    then the minimum-variance estimate under the synergy prior
    (:meth:`Synergies.reconstruct`).

    Attributes
    ----------
    synergies : Synergies
    kind : str
        Glove design (fixes the sensors' joint weights).
    centre, scale : ndarray, shape (5,)
    bend_coef : ndarray, shape (5, 4)
        Intercept and z, z^2, z^3 coefficients per sensor.
    bend_variance : ndarray, shape (5,), deg^2
    name : str
    reading_range : ndarray, shape (2, 5), counts, or None
        See :class:`ConstantEstimator`.

    Raises
    ------
    InvalidInputError
        A field of another type or shape, not finite, an unknown kind, or a
        scale or bend variance that is not positive.
    """

    synergies: Synergies
    kind: str
    centre: np.ndarray
    scale: np.ndarray
    bend_coef: np.ndarray
    bend_variance: np.ndarray
    name: str = "synergy"
    reading_range: np.ndarray | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.synergies, Synergies):
            raise InvalidInputError(f"SynergyEstimator.synergies must be Synergies, "
                                    f"got {type(self.synergies).__name__}")
        _check_kind(self.kind)
        for name, shape in (("centre", (5,)), ("scale", (5,)), ("bend_coef", (5, 4)),
                            ("bend_variance", (5,))):
            object.__setattr__(self, name, as_array(getattr(self, name),
                                                    f"SynergyEstimator.{name}", shape))
        for name in ("scale", "bend_variance"):
            if (getattr(self, name) <= 0).any():
                raise InvalidInputError(f"SynergyEstimator.{name} must be positive, "
                                        f"got {getattr(self, name).tolist()}")
        self._check_common()

    def weight_matrix(self) -> np.ndarray:
        j = sensor_joints(self.kind)
        a = np.zeros((5, len(JOINT_NAMES)))
        for k in range(5):
            a[k, j["distal"][k]] += j["w_distal"][k]
            a[k, j["proximal"][k]] += j["w_proximal"][k]
        return a

    def bend(self, sensors) -> np.ndarray:
        z = (as_sensors(sensors) - self.centre) / self.scale
        c = self.bend_coef
        return c[:, 0] + c[:, 1] * z + c[:, 2] * z**2 + c[:, 3] * z**3

    def _predict(self, s: np.ndarray, motion: str | None) -> np.ndarray:
        return _finish(s, lambda x: self.synergies.reconstruct(
            self.bend(x), self.weight_matrix(), self.bend_variance))

    def to_dict(self) -> dict:
        return {"type": "synergy", "name": self.name, "kind": self.kind,
                "synergies": self.synergies.to_dict(), "centre": self.centre.tolist(),
                "scale": self.scale.tolist(), "bend_coef": self.bend_coef.tolist(),
                "bend_variance": self.bend_variance.tolist(),
                "reading_range": _to_dict_range(self)}


@dataclass(frozen=True, eq=False)
class GatedEstimator(_Estimator):
    """Mixing over the representative motions, handing over to a fallback off them.

    The mixing of seed 004 (eqs. 4-6) always answers with a blend of the
    representative motions, even for a reading that none of them explains.
    Here the smallest Mahalanobis distance d^2 = -2 max_p log L_p of a
    reading to the motion points (eqs. 4-5) is compared with the chi-square
    distribution of 5 degrees of freedom that it follows for a reading of a
    calibrated motion: below its 95 % quantile (11.07) the answer is the
    primary's, above its 99.9 % quantile (20.52) the fallback's, linear in
    between.  The quantiles are fixed by the distribution, not tuned on data.

    Attributes
    ----------
    primary : RegressionEstimator
        With a mixer (more than one motion).
    fallback : GloveEstimator
        Typically the synergy baseline.
    name : str
    lo, hi : float
        d^2 where the hand-over starts and where it is complete; finite,
        ``lo < hi``.
    reading_range : ndarray, shape (2, 5), counts, or None
        See :class:`ConstantEstimator`.

    Raises
    ------
    InvalidInputError
        A primary that is no :class:`RegressionEstimator`, a fallback that is
        no :class:`GloveEstimator`, or `lo` and `hi` not finite with lo < hi.
    """

    primary: RegressionEstimator
    fallback: GloveEstimator
    name: str = "model4+synergy"

    #: chi-square(5) quantiles 0.95 and 0.999 (scipy.stats.chi2.ppf); chosen here: fixed by
    #: the distribution, not fitted to any data (docs/glove.md, the `model4+synergy` gate)
    lo: float = 11.0705
    hi: float = 20.5150
    reading_range: np.ndarray | None = None

    def __post_init__(self) -> None:
        self._check_common()
        if not isinstance(self.primary, RegressionEstimator):
            raise InvalidInputError(f"GatedEstimator.primary must be a RegressionEstimator, "
                                    f"got {type(self.primary).__name__}")
        if not isinstance(self.fallback, GloveEstimator):
            raise InvalidInputError(f"GatedEstimator.fallback must be a GloveEstimator, "
                                    f"got {type(self.fallback).__name__}")
        lo = as_number(self.lo, "GatedEstimator.lo")
        hi = as_number(self.hi, "GatedEstimator.hi")
        if not lo < hi:
            raise InvalidInputError(f"GatedEstimator.lo must be below hi, got lo {lo:g} and "
                                    f"hi {hi:g}")
        object.__setattr__(self, "lo", lo)
        object.__setattr__(self, "hi", hi)

    def fallback_weight(self, sensors) -> np.ndarray:
        """Weight of the fallback per sample, shape (N,), in [0, 1]."""
        s = as_sensors(sensors)
        if self.primary.mixer is None:
            raise EstimationError(f"{self.name}: the primary estimator has no motion mixer")
        d2 = -2.0 * self.primary.mixer.log_likelihood(s).max(axis=1)
        return np.clip((d2 - self.lo) / (self.hi - self.lo), 0.0, 1.0)

    def _check_motion(self, motion: str | None) -> None:
        self.primary._check_motion(motion)

    def _predict(self, s: np.ndarray, motion: str | None) -> np.ndarray:
        def gated(x):
            f = self.fallback_weight(x)[:, None]
            return (1.0 - f) * _predict_unchecked(self.primary, x, motion) + \
                f * _predict_unchecked(self.fallback, x, None)

        return _finish(s, gated)

    def to_dict(self) -> dict:
        return {"type": "gated", "name": self.name, "primary": self.primary.to_dict(),
                "fallback": self.fallback.to_dict(), "lo": self.lo, "hi": self.hi,
                "reading_range": _to_dict_range(self)}


@dataclass(frozen=True, eq=False)
class RangeNormalizer:
    """Two-point map of a new wearing's readings onto the calibration's.

    A wearer holds the open hand and a fist for a few seconds after putting
    the glove on (what VR glove software asks for); each sensor is mapped
    linearly so that its open and fist readings land on those of the
    calibration session.  This removes gain and offset changes, not changes
    of nonlinearity, placement or grasp style.

    Attributes
    ----------
    source_open, source_fist : ndarray, shape (5,), counts
        Readings of the new wearing.
    target_open, target_fist : ndarray, shape (5,), counts
        Readings of the calibration session.
    """

    source_open: np.ndarray
    source_fist: np.ndarray
    target_open: np.ndarray
    target_fist: np.ndarray

    def __post_init__(self) -> None:
        for name in ("source_open", "source_fist", "target_open", "target_fist"):
            try:
                v = np.asarray(getattr(self, name), dtype=np.float64)
            except (TypeError, ValueError):
                v = np.full(0, np.nan)
            if v.shape != (5,) or not np.isfinite(v).all():
                raise EstimationError(f"range calibration: {name} must be 5 finite readings, "
                                      f"got {getattr(self, name)!r:.60}")
            object.__setattr__(self, name, v)
        span = np.asarray(self.source_fist) - np.asarray(self.source_open)
        flat = np.flatnonzero(np.abs(span) < 1.0)
        if flat.size == len(span) and (span != 0).any():
            # readings scaled to 0-1 (or volts) move by a fraction of a count: not five dead sensors
            raise EstimationError(
                "range calibration: every sensor moves by less than 1 count from the open hand "
                "to the fist (" + ", ".join(f"{SENSOR_NAMES[k]} {span[k]:+.3g}" for k in range(5))
                + "): are the readings scaled (0-1, volts) instead of the converter's counts?")
        if flat.size:
            raise EstimationError(
                f"range calibration: {SENSOR_NAMES[flat[0]]} reads the same for the open "
                f"hand and the fist ({self.source_open[flat[0]]:g} counts); is it dead?")
        target = np.asarray(self.target_fist) - np.asarray(self.target_open)
        turned = np.flatnonzero(np.sign(span) != np.sign(target))
        if turned.size >= 3:
            raise EstimationError(
                f"range calibration: {turned.size} of 5 sensors go the other way from the open "
                "hand to the fist than in the calibration: are the holds labelled "
                "range_open and range_fist the other way round?")
        if turned.size:
            warnings.warn(f"range calibration: {', '.join(SENSOR_NAMES[k] for k in turned)} "
                          "go(es) the other way from the open hand to the fist than in the "
                          "calibration (a sensor turned over, or another glove?)", GloveWarning,
                          stacklevel=2)

    def apply(self, sensors) -> np.ndarray:
        s = as_sensors(sensors)
        u = (s - self.source_open) / (self.source_fist - self.source_open)
        return self.target_open + u * (self.target_fist - self.target_open)


def _named(prefix: str, message: str) -> str:
    """`message` after `prefix`, unless it already starts with it (a nested entry's error
    was named once on its way up)."""
    return message if message.startswith(prefix) else prefix + message


def estimator_from_dict(d: dict) -> GloveEstimator:
    """Rebuild an estimator written by its ``to_dict``.

    Parameters
    ----------
    d : dict
        One estimator's ``to_dict`` (as read back from JSON); its ``"type"``
        (``"constant"``, ``"regression"``, ``"gated"`` or ``"synergy"``)
        chooses the class.  A gated estimator's ``"primary"`` and
        ``"fallback"`` are rebuilt by this function too.

    Returns
    -------
    GloveEstimator
        A :class:`ConstantEstimator`, :class:`RegressionEstimator`,
        :class:`GatedEstimator` or :class:`SynergyEstimator`.

    Raises
    ------
    InvalidInputError
        Unknown ``type``, a missing field, or a field of the wrong type or
        shape (named in the message).
    """
    if not isinstance(d, dict):
        raise InvalidInputError(f"an estimator entry must be an object, got {type(d).__name__}")
    try:
        t = d["type"]
        if t == "constant":
            return ConstantEstimator(posture=array_field(d, "posture", (len(JOINT_NAMES),)),
                                     name=str(d["name"]), reading_range=_range_field(d))
        if t == "regression":
            if not isinstance(d["models"], dict) or not d["models"]:
                raise InvalidInputError(f"estimator {d['name']!r}: field 'models' must map "
                                        f"each calibrated motion to its model, got "
                                        f"{type(d['models']).__name__} {len(d['models'])}")
            mixer = None if d["mixer"] is None else MotionMixer.from_dict(d["mixer"])
            if mixer is not None and set(mixer.motions) - set(d["models"]):
                raise InvalidInputError(f"estimator {d['name']!r}: its mixer weighs motions "
                                        f"without a model: "
                                        f"{', '.join(set(mixer.motions) - set(d['models']))}")
            return RegressionEstimator(
                name=str(d["name"]),
                models={m: MotionModel.from_dict(v) for m, v in d["models"].items()},
                mixer=mixer, reading_range=_range_field(d))
        if t == "gated":
            primary = estimator_from_dict(d["primary"])
            if not isinstance(primary, RegressionEstimator):
                raise InvalidInputError(f"estimator {d['name']!r}: its primary must be a "
                                        "regression estimator")
            return GatedEstimator(primary=primary, fallback=estimator_from_dict(d["fallback"]),
                                  name=str(d["name"]), lo=number_field(d, "lo"),
                                  hi=number_field(d, "hi"), reading_range=_range_field(d))
        if t == "synergy":
            return SynergyEstimator(
                synergies=Synergies.from_dict(d["synergies"]), kind=str(d["kind"]),
                centre=array_field(d, "centre", (5,)), scale=array_field(d, "scale", (5,)),
                bend_coef=array_field(d, "bend_coef", (5, 4)),
                bend_variance=array_field(d, "bend_variance", (5,)),
                name=str(d["name"]), reading_range=_range_field(d))
    except KeyError as exc:
        raise InvalidInputError(f"estimator entry lacks field {exc.args[0]!r}") from None
    except InvalidInputError as exc:
        name = d.get("name") if isinstance(d, dict) else None
        raise InvalidInputError(_named(f"estimator {name!r}: ", str(exc))) from None
    except (TypeError, ValueError, AttributeError, IndexError) as exc:
        raise InvalidInputError(f"estimator entry {d.get('name')!r} is malformed: {exc}") \
            from None
    raise InvalidInputError(f"unknown estimator type {t!r}; expected constant, regression, "
                            "synergy or gated")
