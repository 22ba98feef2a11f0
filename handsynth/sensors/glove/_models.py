"""Per-motion regression from five sensor readings to the 20 joint angles.

Seed 004 (SPEC.md section 4) numbers the joints of finger i from the tip:
joint 1 is the DIP (thumb: IP), joint 2 the PIP (thumb: MCP), joint 3 the
MCP (thumb: CMC flexion).  For one representative motion p:

* joint 2 is a cubic in the finger's own sensor S_i (eq. 2);
* joint 1 is 2/3 of joint 2 (eq. 1);
* joint 3 depends on the model:

  - model 1: a cubic in the own sensor (eq. 3),
  - model 2: multiple linear regression on all five sensors (eq. 7), by
    least squares (eq. 8),
  - model 3: model 2 refitted on the sensors whose coefficient has
    ``|t| >= 2``, t = C / S.E. (eqs. 9-11),
  - model 4: model 3's sensors with squared terms added (eq. 12).

The seed says nothing of the abduction angles (finger MCP abduction, thumb
CMC abduction); they get the same form as joint 3 here.  Readings enter the
polynomials standardised, z = (S - centre) / scale, which spans the same
functions as the raw readings and keeps the cubic well conditioned; the
t-values of model 2 do not change under that affine map.

The t-values treat the samples as independent, as the seed does; samples
of a motion recorded at 60 Hz are strongly autocorrelated, so they overstate
the evidence, and model 3 keeps more sensors than a test with the effective
sample size would.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from ...errors import EstimationError, InvalidInputError
from ...models import JOINT_NAMES
from ._fields import array_field, as_array, as_number, as_sensors, number_field
from ._sensors import SENSOR_NAMES

__all__ = [
    "DIP_PIP_RATIO",
    "MODELS",
    "GloveWarning",
    "JointFit",
    "MotionModel",
    "finger_joints",
    "fit_motion_model",
]

#: The seed's four estimation models for joint 3 (section 4.1).
MODELS: tuple[str, ...] = ("model1", "model2", "model3", "model4")

#: Joint 1 / joint 2 flexion, seed 004 eq. 1 (after Elkoura 2003).
DIP_PIP_RATIO = 2.0 / 3.0

#: Fewer samples than this per coefficient raise a :class:`GloveWarning`.
MIN_SAMPLES_PER_COEF = 10


class GloveWarning(UserWarning):
    """Glove data that can be used but deserve a look (named in the message)."""


def finger_joints() -> list[dict[str, int]]:
    """Canonical indices of joints 1-3 and the abduction of each finger.

    Returns
    -------
    list of 5 dicts with keys ``"j1"`` (DIP / thumb IP), ``"j2"`` (PIP /
    thumb MCP), ``"j3"`` (MCP flexion / thumb CMC flexion) and ``"abd"``
    (MCP abduction / thumb CMC abduction).
    """
    idx = JOINT_NAMES.index
    out = [{"j1": idx("thumb_ip_flex"), "j2": idx("thumb_mcp_flex"),
            "j3": idx("thumb_cmc_flex"), "abd": idx("thumb_cmc_abd")}]
    for f in ("index", "middle", "ring", "little"):
        out.append({"j1": idx(f"{f}_dip_flex"), "j2": idx(f"{f}_pip_flex"),
                    "j3": idx(f"{f}_mcp_flex"), "abd": idx(f"{f}_mcp_abd")})
    return out


@dataclass(frozen=True, eq=False)
class JointFit:
    """Fitted polynomial of one joint: ``angle = intercept + sum coef * z[s]**p``.

    Attributes
    ----------
    terms : tuple of (int, int)
        (sensor index 0-4, power 1-3) of each regressor.
    coef : ndarray, shape (len(terms),), deg
    intercept : float, deg
    r2 : float
        Coefficient of determination on the calibration samples.
    t_values : ndarray, shape (len(terms),)
        C / S.E. of each coefficient (eq. 9); NaN without residual freedom.
    n_samples : int
    """

    terms: tuple[tuple[int, int], ...]
    coef: np.ndarray
    intercept: float
    r2: float
    t_values: np.ndarray
    n_samples: int

    def predict(self, z: np.ndarray) -> np.ndarray:
        out = np.full(z.shape[0], self.intercept)
        for (s, p), c in zip(self.terms, self.coef):
            out += c * z[:, s] ** p
        return out

    def to_dict(self) -> dict:
        return {"terms": [list(t) for t in self.terms], "coef": self.coef.tolist(),
                "intercept": self.intercept, "r2": self.r2,
                "t_values": [None if not np.isfinite(t) else float(t) for t in self.t_values],
                "n_samples": self.n_samples}

    @classmethod
    def from_dict(cls, d: dict) -> JointFit:
        # no terms: an intercept alone (model 3 with every |t| < 2)
        terms = np.zeros((0, 2)) if d["terms"] == [] else array_field(d, "terms", (None, 2))
        if not np.all(np.isin(terms[:, 0], range(5)) & np.isin(terms[:, 1], (1, 2, 3))):
            raise InvalidInputError(f"field 'terms' must hold [sensor 0-4, power 1-3] pairs, "
                                    f"got {terms.astype(int).tolist()}")
        n = len(terms)
        t_values = dict(d, t_values=[np.nan if t is None else t for t in d["t_values"]])
        return cls(terms=tuple((int(s), int(p)) for s, p in terms),
                   coef=array_field(d, "coef", (n,)),
                   intercept=number_field(d, "intercept"), r2=float(d["r2"]),
                   t_values=array_field(t_values, "t_values", (n,), allow_nan=True),
                   n_samples=int(d["n_samples"]))


def _ols(z: np.ndarray, y: np.ndarray, terms, *, what: str) -> JointFit:
    """Least squares (eq. 8) with t-values (eq. 9)."""
    n = len(y)
    x = np.column_stack([np.ones(n)] + [z[:, s] ** p for s, p in terms])
    k = x.shape[1]
    if n <= k:
        raise EstimationError(
            f"{what}: {n} calibration samples cannot fit {k} coefficients; record more")
    xtx = x.T @ x
    d = np.sqrt(np.diag(xtx))
    xtx_n = xtx / np.outer(d, d)                  # unit diagonal: a scale-free rank test
    if np.linalg.cond(xtx_n) > 1e10:
        raise EstimationError(
            f"{what}: the regressors are collinear; a sensor may be dead or duplicated")
    inv = np.linalg.inv(xtx_n) / np.outer(d, d)
    beta = inv @ (x.T @ y)
    resid = y - x @ beta
    dof = n - k
    sigma2 = resid @ resid / dof
    cov = sigma2 * inv
    se = np.sqrt(np.clip(np.diag(cov)[1:], 0.0, None))
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(se > 0, beta[1:] / se,
                     np.where(beta[1:] == 0, 0.0, np.inf * np.sign(beta[1:])))
    sst = float(((y - y.mean()) ** 2).sum())
    r2 = 1.0 - float(resid @ resid) / sst if sst > 0 else 1.0
    return JointFit(terms=tuple(terms), coef=beta[1:].copy(), intercept=float(beta[0]),
                    r2=r2, t_values=np.asarray(t, dtype=np.float64), n_samples=n)


def _joint3_terms(model: str, i: int, z, y, *, t_threshold: float, what: str):
    if model == "model1":  # eq. 3
        return [(i, 1), (i, 2), (i, 3)]
    all_lin = [(f, 1) for f in range(5)]
    if model == "model2":  # eq. 7
        return all_lin
    full = _ols(z, y, all_lin, what=what)
    keep = [f for f in range(5) if abs(full.t_values[f]) >= t_threshold]  # eqs. 10-11
    if model == "model3":
        return [(f, 1) for f in keep]
    return [(f, p) for f in keep for p in (1, 2)]  # eq. 12


@dataclass(frozen=True, eq=False)
class MotionModel:
    """The fitted estimator of one representative motion (or of all pooled).

    Attributes
    ----------
    motion : str
    model : str
        One of :data:`MODELS`.
    centre, scale : ndarray, shape (5,), counts
        Standardisation of the readings.
    fits : dict of int to JointFit
        Fits of every joint except joints 1 (derived by eq. 1).
    z_range : ndarray, shape (2, 5) or None
        Lowest and highest standardised reading of the calibration; readings
        beyond are clamped to it before the polynomials are evaluated (a
        cubic fitted on one range runs away outside it; the seed does not
        say what it did there).  None: no clamping.
    """

    motion: str
    model: str
    centre: np.ndarray
    scale: np.ndarray
    fits: dict
    z_range: np.ndarray | None = None

    def predict(self, sensors: np.ndarray) -> np.ndarray:
        """Joint angles, shape (N, 20), deg, from readings (N, 5), counts.

        One reading (5,) is one row; a row with a NaN reading gives NaN angles.

        Raises
        ------
        InvalidInputError
            `sensors` of another shape or with an infinite reading.
        """
        z = (as_sensors(sensors) - self.centre) / self.scale
        if self.z_range is not None:
            z = np.clip(z, self.z_range[0], self.z_range[1])
        out = np.zeros((z.shape[0], len(JOINT_NAMES)))
        for j, fit in self.fits.items():
            out[:, j] = fit.predict(z)
        for fj in finger_joints():
            out[:, fj["j1"]] = DIP_PIP_RATIO * out[:, fj["j2"]]  # eq. 1
        return out

    def to_dict(self) -> dict:
        return {"motion": self.motion, "model": self.model, "centre": self.centre.tolist(),
                "scale": self.scale.tolist(),
                "z_range": None if self.z_range is None else self.z_range.tolist(),
                "fits": {JOINT_NAMES[j]: f.to_dict() for j, f in self.fits.items()}}

    @classmethod
    def from_dict(cls, d: dict) -> MotionModel:
        fits = d["fits"]
        derived = {JOINT_NAMES[fj["j1"]] for fj in finger_joints()}  # eq. 1
        needed = [j for j in JOINT_NAMES if j not in derived]
        if not isinstance(fits, dict) or sorted(fits) != sorted(needed):
            got = sorted(fits) if isinstance(fits, dict) else type(fits).__name__
            missing = [j for j in needed if not isinstance(fits, dict) or j not in fits]
            raise InvalidInputError(
                f"motion {d.get('motion')!r}: field 'fits' must hold a fit of each joint but "
                f"the DIPs and the thumb IP; " + (f"missing {', '.join(missing)}" if missing
                                                  else f"got {got}"))
        scale = array_field(d, "scale", (5,))
        if (scale <= 0).any():
            raise InvalidInputError(f"field 'scale' must be positive, got {scale.tolist()}")
        z_range = None if d.get("z_range") is None else array_field(d, "z_range", (2, 5))
        if z_range is not None and (z_range[0] > z_range[1]).any():
            k = int(np.flatnonzero(z_range[0] > z_range[1])[0])
            # np.clip would read every reading as the lower bound's other end: a constant
            raise InvalidInputError(f"motion {d.get('motion')!r}: field 'z_range' must hold "
                                    f"[lowest, highest] standardised readings, got lowest "
                                    f"{z_range[0, k]:g} above highest {z_range[1, k]:g} for "
                                    f"sensor {k}")
        return cls(motion=str(d["motion"]), model=str(d["model"]),
                   centre=array_field(d, "centre", (5,)), scale=scale, z_range=z_range,
                   fits={JOINT_NAMES.index(k): JointFit.from_dict(v) for k, v in fits.items()})


def fit_motion_model(sensors: np.ndarray, angles: np.ndarray, *, model: str,
                     motion: str = "", t_threshold: float = 2.0,
                     centre: np.ndarray | None = None,
                     scale: np.ndarray | None = None, clamp: bool = True) -> MotionModel:
    """Fit `model` to the calibration samples of one motion.

    Parameters
    ----------
    sensors : ndarray, shape (N, 5), float, counts
        Readings (drop saturated samples first); rows with a NaN here or in
        `angles` are dropped with a warning.
    angles : ndarray, shape (N, 20), float, deg
        Reference joint angles at the same instants.
    model : {"model1", "model2", "model3", "model4"}, keyword-only
    motion : str, keyword-only
        Name used in messages and stored with the fit.
    t_threshold : float, keyword-only
        |t| below which model 3 and 4 drop a sensor (2, eq. 11).
    centre, scale : ndarray, shape (5,), keyword-only
        Standardisation, finite (`scale` positive); default the mean and s.d.
        of `sensors`.
    clamp : bool, keyword-only
        Clamp readings to the calibration's range when predicting (see
        :class:`MotionModel`).

    Returns
    -------
    MotionModel

    Raises
    ------
    InvalidInputError
        `sensors`, `angles`, `centre` or `scale` of another shape, an
        infinite value, `sensors` and `angles` of different lengths, a scale
        that is not positive, a negative `t_threshold` or an unknown `model`
        (named in the message).
    EstimationError
        No more samples than coefficients, or collinear
        regressors (a dead sensor).

    Warns
    -----
    GloveWarning
        Rows dropped for a NaN; fewer than :data:`MIN_SAMPLES_PER_COEF`
        samples per coefficient (the message lists the t-values).
    """
    if model not in MODELS:
        raise InvalidInputError(f"model must be one of {', '.join(MODELS)}, got {model!r}")
    label = (f"motion {motion!r}" if motion else "calibration") + f" ({model})"
    s = as_array(sensors, "sensors", (None, 5), allow_nan=True)
    a = as_array(angles, "angles", (None, len(JOINT_NAMES)), allow_nan=True)
    if len(s) != len(a):
        raise InvalidInputError(f"sensors and angles must have the same number of rows, got "
                                f"{len(s)} and {len(a)}")
    if as_number(t_threshold, "t_threshold") < 0:
        raise InvalidInputError(f"t_threshold must be >= 0, got {t_threshold!r}")
    bad = np.isnan(s).any(axis=1) | np.isnan(a).any(axis=1)
    if bad.any():
        idx = np.flatnonzero(bad)
        at = "at row index" if idx.size == 1 else "first at row indices"
        warnings.warn(f"{label}: dropped {idx.size} of {len(s)} rows with NaN ({at} "
                      f"{', '.join(str(int(r)) for r in idx[:5])})", GloveWarning, stacklevel=2)
        s, a = s[~bad], a[~bad]
    if not len(s):
        raise EstimationError(f"{label}: no calibration samples with every reading and angle")
    centre = s.mean(axis=0) if centre is None else as_array(centre, "centre", (5,))
    if scale is not None:
        scale = as_array(scale, "scale", (5,))
        if (scale <= 0).any():
            raise InvalidInputError(f"scale must be positive, got {scale.tolist()}")
    else:
        scale = s.std(axis=0)
        dead = np.flatnonzero(scale == 0)
        if dead.size:
            raise EstimationError(
                f"motion {motion!r}: {SENSOR_NAMES[dead[0]]} reads a constant "
                f"{s[0, dead[0]]:g} counts over {len(s)} rows (a dead sensor)")
    z = (s - centre) / scale
    fits = {}
    for i, fj in enumerate(finger_joints()):
        own_cubic = [(i, 1), (i, 2), (i, 3)]
        fits[fj["j2"]] = _ols(z, a[:, fj["j2"]], own_cubic,  # eq. 2
                              what=f"{label}, {JOINT_NAMES[fj['j2']]}")
        for key in ("j3", "abd"):
            j = fj[key]
            what = f"{label}, {JOINT_NAMES[j]}"
            terms = _joint3_terms(model, i, z, a[:, j], t_threshold=t_threshold, what=what)
            fits[j] = _ols(z, a[:, j], terms, what=what)
    _warn_few_samples(fits, label)
    z_range = np.stack([z.min(axis=0), z.max(axis=0)]) if clamp else None
    return MotionModel(motion=motion, model=model, centre=centre, scale=scale, fits=fits,
                       z_range=z_range)


def _warn_few_samples(fits: dict, label: str) -> None:
    """One warning per motion when a fit has < MIN_SAMPLES_PER_COEF samples per coefficient.

    It lists the t-values (eq. 9) of the joint-3 regressions, the ones the
    seed's sensor selection (eq. 11) rests on.
    """
    thin = {j: f for j, f in fits.items()
            if f.n_samples < MIN_SAMPLES_PER_COEF * (len(f.terms) + 1)}
    if not thin:
        return
    n = next(iter(thin.values())).n_samples
    k = max(len(f.terms) + 1 for f in thin.values())
    j3 = [fj["j3"] for fj in finger_joints()]
    tv = "; ".join(
        f"{JOINT_NAMES[j]}: " + (", ".join(f"{SENSOR_NAMES[s]}^{p} t={t:.2f}" for (s, p), t
                                           in zip(fits[j].terms, fits[j].t_values))
                                 or "no sensor kept")
        for j in j3 if j in fits)
    warnings.warn(
        f"{label}: only {n} calibration samples for up to {k} coefficients (fewer than "
        f"{MIN_SAMPLES_PER_COEF} per coefficient in {len(thin)} of {len(fits)} joint fits); "
        f"t-values of the joint-3 regressions: {tv}", GloveWarning, stacklevel=3)
