"""Calibration of every glove estimator from recordings of the motions; the file.

A calibration recording holds trials of the representative motions with
reference joint angles (seed 004 section 2.1: a many-sensor glove worn at
the same time).  Samples labelled ``range_open`` and ``range_fist`` are
static holds of the open hand and a fist for the range calibration of later
wearings (:class:`RangeNormalizer`) and are not used as a motion (the labels
differ from the motion names, so a recorded "fist" motion is no hold).
"""

from __future__ import annotations

import json
import warnings
from dataclasses import dataclass, replace
from functools import cache
from pathlib import Path

import numpy as np

from ..._checks import check_instance, check_integer, check_options
from ..._io import write_text
from ...errors import EstimationError, InvalidInputError, RecordingError
from ...models import JOINT_NAMES, natural_pose_set
from ._checks import check_sensors, off_scale_words, row_positions, scale_hint
from ._estimators import (
    ConstantEstimator,
    GatedEstimator,
    GloveEstimator,
    RegressionEstimator,
    SynergyEstimator,
    estimator_from_dict,
)
from ._fields import array_field, as_number
from ._mixing import fit_mixer
from ._models import MODELS, GloveWarning, finger_joints, fit_motion_model
from ._recording import RANGE_LABELS, GloveRecording
from ._sensors import GLOVE_KINDS, SENSOR_NAMES
from ._synergy import Synergies, fit_synergies

__all__ = [
    "RANGE_LABELS",
    "CalibrationOptions",
    "calibrate",
    "default_synergies",
    "load_calibration",
    "range_readings",
    "save_calibration",
]

#: The estimators that carry the calibration's range of readings.
_RANGED = (ConstantEstimator, RegressionEstimator, SynergyEstimator, GatedEstimator)
_FORMAT = "handsynth-glove-calibration"
_VERSION = 1

@dataclass(frozen=True)
class CalibrationOptions:
    """Options of :func:`calibrate`.

    Parameters
    ----------
    models : tuple of str
        Which of :data:`MODELS` to fit.
    t_threshold : float
        |t| below which models 3 and 4 drop a sensor (eq. 11: 2).
    n_points : int
        Points along each motion for the mixing likelihood (eq. 4), 1-200.
    ridge : float
        Added to each point covariance, standardised units squared.
    pooled : bool
        Also fit model 4 on every motion at once ("pooled_model4").
    synergy_k : int
        Synergies kept by the synergy baseline (0-20); 0 leaves it out.

    Raises
    ------
    InvalidInputError
        A field of the wrong type or out of its range (named in the message).
    """

    models: tuple[str, ...] = MODELS
    t_threshold: float = 2.0
    n_points: int = 20
    ridge: float = 0.01
    pooled: bool = True
    synergy_k: int = 2

    def __post_init__(self) -> None:
        if isinstance(self.models, str) or not isinstance(self.models, (tuple, list)):
            raise InvalidInputError(f"CalibrationOptions.models must be a tuple of model "
                                    f"names, got {self.models!r}")
        bad = [m for m in self.models if m not in MODELS]
        if bad:
            raise InvalidInputError(f"CalibrationOptions.models: unknown {bad[0]!r}; "
                                    f"expected some of {', '.join(MODELS)}")
        object.__setattr__(self, "models", tuple(self.models))
        if not as_number(self.t_threshold, "CalibrationOptions.t_threshold") >= 0:
            raise InvalidInputError(
                f"CalibrationOptions.t_threshold must be >= 0, got {self.t_threshold!r}")
        if not as_number(self.ridge, "CalibrationOptions.ridge") > 0:
            raise InvalidInputError(f"CalibrationOptions.ridge must be > 0, got {self.ridge!r}")
        if not isinstance(self.pooled, (bool, np.bool_)):
            raise InvalidInputError(f"CalibrationOptions.pooled must be True or False, "
                                    f"got {self.pooled!r}")
        # n_points: a point per 0.5 % of a motion is more than its samples can fill
        for name, lo, hi in (("n_points", 1, 200), ("synergy_k", 0, 20)):
            check_integer(getattr(self, name), f"CalibrationOptions.{name}", minimum=lo,
                          maximum=hi)


def default_synergies(k: int = 2) -> Synergies:
    """Synergies of the hand model's natural pose set (4,096 poses, seed 0).

    Fitted once per `k` and shared by every caller: the arrays are read-only.

    Parameters
    ----------
    k : int
        Number of components kept, 1 to 20.

    Returns
    -------
    Synergies
        Angles in degrees; the same object for every call with the same `k`.

    Raises
    ------
    InvalidInputError
        `k` not an integer in 1..20.
    """
    return _default_synergies(check_integer(k, "k", minimum=1, maximum=20))


@cache
def _default_synergies(k: int) -> Synergies:
    syn = fit_synergies(natural_pose_set(4096, seed=0), k=k,
                        source="handsynth natural pose set (4096, seed 0)")
    for a in (syn.mean, syn.components, syn.variances, syn.explained):
        a.setflags(write=False)
    return syn


def _clean(rec: GloveRecording, where: str) -> GloveRecording:
    """Drop rows with a NaN and rows with a saturated or out-of-range reading; refuse dead
    sensors and a recording with no row left (saying why each row went)."""
    if rec.angles is None:
        raise EstimationError(f"{where}: no reference joint angles; calibration needs them")
    chk = check_sensors(rec.sensors, adc_max=rec.adc_max, where=where, warn=False)
    if chk.dead:
        k = chk.dead[0]
        raise EstimationError(
            f"{where}: {SENSOR_NAMES[k]} is dead (it reads "
            f"{rec.sensors[~np.isnan(rec.sensors[:, k]), k][0]:g} counts in every row); "
            "fix the sensor before calibrating")
    n = rec.n_samples
    bad = np.isnan(rec.sensors).any(axis=1) | np.isnan(rec.angles).any(axis=1)
    if bad.any():
        warnings.warn(f"{where}: dropped {int(bad.sum())} of {n} rows with NaN "
                      f"({row_positions(np.flatnonzero(bad), rec.lines)})", GloveWarning,
                      stacklevel=3)
    off = chk.off_scale & ~bad[:, None]
    sat = off.any(axis=1)
    per = "; ".join(f"{SENSOR_NAMES[k]} "
                    + " and ".join(off_scale_words(rec.sensors, chk, k, adc_max=rec.adc_max,
                                                   rows=~bad, unit="row"))
                    for k in range(5) if off[:, k].any())
    what = " or ".join(w for w, hit in (("saturated", chk.saturated[~bad].any()),
                                         ("out-of-range", (chk.below | chk.above)[~bad].any()))
                       if hit)
    if sat.any() and not (bad | sat).all():
        warnings.warn(f"{where}: dropped {int(sat.sum())} of {n} rows with {_article(what)} "
                      f"{what} reading ({per}; "
                      f"{row_positions(np.flatnonzero(sat), rec.lines)})"
                      + ("; a saturated sensor says only 'at least this far'"
                         if chk.saturated[~bad].any() else "") + scale_hint(chk),
                      GloveWarning, stacklevel=3)
    if (bad | sat).all():
        why = []
        if bad.any():
            why.append(f"{int(bad.sum())} have a NaN reading or angle")
        if sat.any():
            why.append(f"{int(sat.sum())} have {_article(what)} {what} reading ({per})")
        raise EstimationError(f"{where}: no row is left to calibrate on: of the {n} rows, "
                              f"{' and '.join(why)}{scale_hint(chk)}")
    return rec.select(~bad & ~sat)


def _article(word: str) -> str:
    return "an" if word[:1] in "aeiou" else "a"


def _motion_rows(rec: GloveRecording) -> np.ndarray:
    """Rows labelled with a motion (not empty, not a range hold), shape (N,), bool."""
    return ~np.isin(rec.motion.astype(str), ("", *RANGE_LABELS))


def calibrate(rec: GloveRecording, *, options: CalibrationOptions | None = None,
              synergies: Synergies | None = None,
              where: str = "calibration") -> dict[str, GloveEstimator]:
    """Fit every estimator on a calibration recording.

    Parameters
    ----------
    rec : GloveRecording
        Trials of the representative motions with reference ``angles``;
        ``kind`` must be set for the synergy baseline.
    options : CalibrationOptions, keyword-only
    synergies : Synergies, keyword-only
        Prior of the synergy baseline; default :func:`default_synergies`.
    where : str, keyword-only
        Name of the data in messages.

    Returns
    -------
    dict of str to GloveEstimator
        ``"constant"``, the chosen models (``"model1"`` ...), ``"pooled_model4"``,
        ``"synergy"`` and ``"model4+synergy"`` (:class:`GatedEstimator`) as the
        options allow.  Each carries the range of the readings it was
        calibrated on (``reading_range``: lowest and highest reading of each
        sensor over the samples kept, range holds included), and its
        ``predict`` warns about readings mostly off it.

    Raises
    ------
    EstimationError
        No reference angles; no row left once rows with a NaN or a saturated
        or out-of-range reading are dropped (each sensor named with its count
        of rows); no motion rows, or none left; a dead sensor; or a regression
        that cannot be fitted (named in the message, after `where`).

    Warns
    -----
    GloveWarning
        Rows dropped for NaN, saturation or readings out of the converter's
        range (counted in rows, named by file line where ``rec.lines`` is
        set); too few samples for a regression (with the t-values); models 3
        and 4 keeping no sensor for a joint-3 fit (`t_threshold` too high).
    """
    opts = check_options(options, CalibrationOptions)
    check_instance(rec, GloveRecording, name="rec")
    n_motion_rows = int(_motion_rows(rec).sum())
    rec = _clean(rec, where)
    cal = rec.select(_motion_rows(rec))
    angles = cal.angles
    assert angles is not None  # _clean refused a recording without them
    motions = tuple(dict.fromkeys(cal.motion.tolist()))
    if not motions and n_motion_rows:
        raise EstimationError(f"{where}: every one of the {n_motion_rows} rows labelled with a "
                              "motion was dropped (NaN, saturated or out-of-range readings: "
                              "see the warning); only range holds are left")
    if not motions:
        raise EstimationError(f"{where}: no rows labelled with a motion (column 'motion')")
    _warn_drift(cal, where)
    reading_range = np.stack([rec.sensors.min(axis=0), rec.sensors.max(axis=0)])
    centre = cal.sensors.mean(axis=0)
    scale = cal.sensors.std(axis=0)
    flat = np.flatnonzero(scale == 0)
    if flat.size:
        raise EstimationError(f"{where}: {SENSOR_NAMES[flat[0]]} never changes during the "
                              "motions (a dead sensor)")
    out: dict[str, GloveEstimator] = {
        "constant": ConstantEstimator(posture=angles.mean(axis=0), reading_range=reading_range)}
    mixer = None
    try:
        if len(motions) > 1:
            mixer = fit_mixer(cal.sensors, cal.motion, cal.phase(), motions=motions,
                              centre=centre, scale=scale, n_points=opts.n_points,
                              ridge=opts.ridge)
        caught: list = []
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always", GloveWarning)
                for model in opts.models:
                    fits = {}
                    for m in motions:
                        sel = cal.motion == m
                        fits[m] = fit_motion_model(cal.sensors[sel], angles[sel], model=model,
                                                   motion=m, t_threshold=opts.t_threshold,
                                                   centre=centre, scale=scale)
                    out[model] = RegressionEstimator(name=model, models=fits, mixer=mixer,
                                                     reading_range=reading_range)
        finally:  # also when a fit fails: the warnings (too few samples) explain it
            _reemit(caught, where)
        if opts.pooled:
            out["pooled_model4"] = RegressionEstimator(
                name="pooled_model4",
                models={"pooled": fit_motion_model(cal.sensors, angles, model="model4",
                                                   motion="pooled",
                                                   t_threshold=opts.t_threshold,
                                                   centre=centre, scale=scale)},
                reading_range=reading_range)
    except EstimationError as exc:  # a fit that failed: name the recording
        raise EstimationError(f"{where}: {exc}") from None
    _warn_no_sensor_kept(out, opts.t_threshold, where)
    if opts.synergy_k:
        if rec.kind not in GLOVE_KINDS:
            raise EstimationError(f"{where}: the glove kind is unknown; give one of "
                                  f"{', '.join(GLOVE_KINDS)} for the synergy baseline")
        out["synergy"] = _fit_synergy(cal, synergies or default_synergies(opts.synergy_k),
                                      centre, scale, reading_range)
        primary = out.get("model4")
        if isinstance(primary, RegressionEstimator) and primary.mixer is not None:
            out["model4+synergy"] = GatedEstimator(primary=primary, fallback=out["synergy"],
                                                   reading_range=reading_range)
    return out


#: Creep of the open-hand reading over a calibration recording, as a share of the sensor's
#: range there, above which :func:`calibrate` warns of drift (simulated recordings without
#: drift reach 0.07 on the thumb, whose range is the smallest; 100 counts of drift 0.15-0.6).
DRIFT_SHARE = 0.15
#: ... and whose trend is at least this many standard errors from none.
DRIFT_T = 4.0


def _warn_drift(cal: GloveRecording, where: str) -> None:
    """Warn about sensors whose reading at the start of the trials creeps over the recording.

    Every trial of a representative motion starts from the open hand, so the
    start readings of a motion's trials are repeats of one posture; their trend
    over time (fitted within each motion) is drift of the sensor's offset, which
    the fits would otherwise take for a change of posture.
    """
    starts, times, groups = [], [], []
    for m, k in cal.trials():
        idx = np.flatnonzero((cal.motion == m) & (cal.trial == k))
        starts.append(np.median(cal.sensors[idx[:5]], axis=0))
        times.append(cal.time_s[idx[0]])
        groups.append(m)
    if len(starts) < 3:
        return
    s, t, g = np.array(starts), np.array(times), np.array(groups, dtype=object)
    for m in set(groups):  # within each motion: their start postures may differ
        sel = g == m
        s[sel] -= s[sel].mean(axis=0)
        t[sel] -= t[sel].mean()
    if not (t ** 2).sum() > 0:
        return
    slope = (t[:, None] * s).sum(axis=0) / (t ** 2).sum()       # counts per s
    dof = len(t) - len(set(groups)) - 1
    if dof < 1:
        return
    # a trend that the trials' own spread explains is no drift: a motion's trials packed
    # into a short stretch of a long recording give a slope of little weight
    resid = s - t[:, None] * slope
    se = np.sqrt((resid ** 2).sum(axis=0) / dof / (t ** 2).sum())
    duration = float(cal.time_s.max() - cal.time_s.min())
    span = cal.sensors.max(axis=0) - cal.sensors.min(axis=0)
    creep = slope * duration
    bad = np.flatnonzero((np.abs(creep) > DRIFT_SHARE * np.maximum(span, 1e-9))
                         & (np.abs(slope) > DRIFT_T * np.maximum(se, 1e-12)))
    if bad.size:
        words = ", ".join(f"{SENSOR_NAMES[k]} {creep[k]:+.0f} counts "
                          f"({100 * abs(creep[k]) / span[k]:.0f} % of its range)" for k in bad)
        warnings.warn(f"{where}: the open-hand reading at the start of the trials creeps over "
                      f"the {duration:.0f} s of the recording ({words}): does the sensor drift? "
                      "The fits take the drift for posture; record again after the glove has "
                      "warmed up, or in shorter pieces", GloveWarning, stacklevel=3)


def _warn_no_sensor_kept(estimators: dict, t_threshold: float, where: str) -> None:
    """Warn when models 3 or 4 keep no sensor for a joint-3 fit (|t| below the threshold
    for all five): that joint is then a constant, whatever the readings."""
    j3 = [f["j3"] for f in finger_joints()]
    for name, est in estimators.items():
        if not isinstance(est, RegressionEstimator) or name in ("model1", "model2"):
            continue
        empty = [f"{m} {JOINT_NAMES[j]}" for m, mm in est.models.items() for j in j3
                 if not mm.fits[j].terms]
        if empty:
            n = len(est.models) * len(j3)
            warnings.warn(f"{where}: {name} keeps no sensor (every |t| < {t_threshold:g}, "
                          f"the t threshold) in {len(empty)} of {n} joint-3 fits "
                          f"({', '.join(empty[:3])}{', ...' if len(empty) > 3 else ''}): "
                          "those joints are constants", GloveWarning, stacklevel=3)


def _reemit(caught, where: str) -> None:
    """Re-issue the recorded warnings, one "too few samples" per motion.

    Of the models' warnings about the same motion, the one of model 2 (all
    five sensors, the seed's Table 1 layout) is kept, else the first.
    """
    per_motion: dict[str, str] = {}
    for w in caught:
        msg = str(w.message)
        if not issubclass(w.category, GloveWarning) or "calibration samples" not in msg:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
            continue
        motion = msg.split(" (", 1)[0]
        if motion not in per_motion or "(model2)" in msg:
            per_motion[motion] = msg
    for msg in per_motion.values():
        warnings.warn(f"{where}: {msg}", GloveWarning, stacklevel=3)


def _fit_synergy(cal: GloveRecording, syn: Synergies, centre, scale,
                 reading_range: np.ndarray) -> SynergyEstimator:
    proto = SynergyEstimator(synergies=syn, kind=cal.kind, centre=centre, scale=scale,
                             bend_coef=np.zeros((5, 4)), bend_variance=np.ones(5))
    target = cal.angles @ proto.weight_matrix().T          # nominal bend, (N, 5)
    z = (cal.sensors - centre) / scale
    coef = np.zeros((5, 4))
    var = np.zeros(5)
    for k in range(5):
        x = np.column_stack([np.ones(len(z)), z[:, k], z[:, k] ** 2, z[:, k] ** 3])
        beta, *_ = np.linalg.lstsq(x, target[:, k], rcond=None)
        coef[k] = beta
        var[k] = max(float(np.mean((target[:, k] - x @ beta) ** 2)), 1e-3)
    return SynergyEstimator(synergies=syn, kind=cal.kind, centre=centre, scale=scale,
                            bend_coef=coef, bend_variance=var, reading_range=reading_range)


def range_readings(rec: GloveRecording, *, where: str = "recording"
                   ) -> tuple[np.ndarray, np.ndarray] | None:
    """Median readings (open, fist), each shape (5,), or None without both holds.

    Parameters
    ----------
    rec : GloveRecording
        A recording whose ``motion`` labels some samples ``"range_open"`` and
        ``"range_fist"`` (:data:`RANGE_LABELS`, compared exactly); its
        ``adc_max`` tells saturated readings.
    where : str, keyword-only
        What the recording is (a file name), for the message.

    Returns
    -------
    tuple of two ndarray, shape (5,), float64, counts; or None
        Per sensor (thumb to little), the median of the readings labelled
        ``"range_open"`` and of those labelled ``"range_fist"``, NaN samples
        left out; None when either label is missing.

    Raises
    ------
    RecordingError
        A sensor has no reading (only NaN) in one of the holds, or half or
        more of its readings in a hold are saturated or out of the
        converter's range (its median is then not the hold's reading); the
        message names the file (`where`), the hold, the sensor and the count.

    Warns
    -----
    GloveWarning
        Fewer than half of a sensor's readings in a hold are saturated or out
        of the converter's range (the median is still the hold's reading, but
        the hold is at the end of the range).
    """
    lab = rec.motion.astype(str)
    if not all((lab == r).any() for r in RANGE_LABELS):
        return None
    out = []
    for r in RANGE_LABELS:
        held = rec.sensors[lab == r]
        n = len(held)
        empty = np.flatnonzero(np.isnan(held).all(axis=0))
        if empty.size:
            raise RecordingError(f"{where}: {SENSOR_NAMES[empty[0]]} has no reading in the "
                                 f"{n} rows labelled {r}")
        chk = check_sensors(held, adc_max=rec.adc_max, where=where, warn=False)
        for k in range(5):
            valid = ~np.isnan(held[:, k])
            n_off = int(chk.off_scale[valid, k].sum())
            if not n_off:
                continue
            words = " and ".join(off_scale_words(held, chk, k, adc_max=rec.adc_max, rows=valid))
            text = (f"{where}: {SENSOR_NAMES[k]} is {words} of the {int(valid.sum())} rows "
                    f"labelled {r}")
            hint = scale_hint(chk) if chk.above[valid, k].any() else ""
            if 2 * n_off >= valid.sum():
                raise RecordingError(f"{text}: its reading in that hold is not known; record "
                                     f"the hold again with the sensor inside the range{hint}")
            warnings.warn(f"{text}; the hold's median is kept, but the hold reaches the end of "
                          f"the range{hint}", GloveWarning, stacklevel=2)
        out.append(np.nanmedian(held, axis=0))
    return out[0], out[1]


def save_calibration(path, estimators: dict, *, kind: str = "",
                     range_reference: tuple[np.ndarray, np.ndarray] | None = None,
                     meta: dict | None = None) -> Path:
    """Write estimators (and the range-hold readings) as JSON, atomically.

    Parameters
    ----------
    path : str or os.PathLike
        The file written; it appears only when complete.
    estimators : dict of str to GloveEstimator
        Written with each estimator's ``to_dict``, read back by
        :func:`load_calibration`.
    kind : str, keyword-only
        Glove design, one of :data:`GLOVE_KINDS` or ``""`` when unknown; written
        as given (not checked here; :func:`load_calibration` refuses others).
    range_reference : tuple of two ndarray, shape (5,), counts, keyword-only, optional
        Readings (open, fist) of the range holds, as :func:`range_readings`
        returns; None when there were none.
    meta : dict, keyword-only, optional
        Written as the ``"meta"`` field (``{}`` for None); must be
        JSON-serialisable.

    Returns
    -------
    Path
        `path`.

    Raises
    ------
    OutputError
        The file cannot be written.
    """
    payload = {
        "format": _FORMAT, "version": _VERSION, "kind": kind,
        "range_reference": None if range_reference is None
        else {"open": np.asarray(range_reference[0]).tolist(),
              "fist": np.asarray(range_reference[1]).tolist()},
        "meta": meta or {},
        "estimators": {k: v.to_dict() for k, v in estimators.items()},
    }
    return write_text(path, json.dumps(payload), what="glove calibration")


def load_calibration(path) -> dict:
    """Read a calibration file.

    Parameters
    ----------
    path : str or os.PathLike
        A JSON file written by :func:`save_calibration` (a UTF-8 byte-order
        mark is accepted).

    Returns
    -------
    dict with ``"kind"``, ``"range_reference"`` (None or (open, fist)
    arrays), ``"meta"`` and ``"estimators"`` (dict of str to GloveEstimator).
    An estimator written without its ``reading_range`` (an older file) takes
    the range of ``meta`` fields ``sensor_min`` and ``sensor_max`` where the
    file has them.

    Raises
    ------
    InvalidInputError
        No such file, not JSON, another format or version, or a malformed
        estimator; the message names the file.
    """
    path = Path(path)
    if not path.is_file():
        raise InvalidInputError(f"cannot read calibration {str(path)!r}: no such file")
    try:
        d = json.loads(path.read_bytes().decode("utf-8-sig"))  # an editor's byte-order mark
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise InvalidInputError(f"{path}: not a calibration file (JSON error: {exc})") from None
    except OSError as exc:
        raise InvalidInputError(f"cannot read calibration {str(path)!r}: "
                                f"{exc.strerror or exc}") from None
    if not isinstance(d, dict) or d.get("format") != _FORMAT:
        raise InvalidInputError(f"{path}: not a handsynth glove calibration file")
    if d.get("version") != _VERSION:
        raise InvalidInputError(f"{path}: calibration version {d.get('version')!r}, this "
                                f"handsynth reads version {_VERSION} (the number)")
    kind = d.get("kind", "")
    if kind not in ("", *GLOVE_KINDS):
        raise InvalidInputError(f"{path}: field 'kind' must be one of "
                                f"{', '.join(GLOVE_KINDS)} or '', got {kind!r}")
    entries = d.get("estimators")
    if not isinstance(entries, dict) or not entries:
        raise InvalidInputError(f"{path}: field 'estimators' must map names to estimators, "
                                f"got {entries!r:.40}")
    rr = d.get("range_reference")
    est = {}
    for name, entry in entries.items():
        try:
            est[name] = estimator_from_dict(entry)
        except KeyError as exc:
            raise InvalidInputError(f"{path}: estimator {name!r} lacks field {exc.args[0]!r}") \
                from None
        except InvalidInputError as exc:
            text = str(exc)
            if not text.startswith(f"estimator {name!r}: "):
                text = f"estimator {name!r}: {text}"
            raise InvalidInputError(f"{path}: {text}") from None
    try:
        if rr is not None:
            if not isinstance(rr, dict):
                raise InvalidInputError("field 'range_reference' must be an object with "
                                        f"'open' and 'fist', got {rr!r:.40}")
            rr = (array_field(rr, "open", (5,)), array_field(rr, "fist", (5,)))
            same = np.flatnonzero(np.abs(rr[1] - rr[0]) < 1.0)
            if same.size:  # every new wearing would be mapped onto one reading
                k = int(same[0])
                raise InvalidInputError(
                    f"field 'range_reference': {SENSOR_NAMES[k]} reads the same open "
                    f"({rr[0][k]:g}) and in the fist ({rr[1][k]:g}); the holds of a range "
                    "calibration differ by at least 1 count")
    except KeyError as exc:
        raise InvalidInputError(f"{path}: field 'range_reference' lacks {exc.args[0]!r}") \
            from None
    except InvalidInputError as exc:
        raise InvalidInputError(f"{path}: {exc}") from None
    meta = d.get("meta", {})
    meta = dict(meta) if isinstance(meta, dict) else {}
    try:
        for key in ("sensor_min", "sensor_max"):  # the calibration's range of readings
            if key in meta:
                meta[key] = array_field(meta, key, (5,))
    except InvalidInputError as exc:
        raise InvalidInputError(f"{path}: meta {exc}") from None
    if "sensor_min" in meta and "sensor_max" in meta:  # older files: the range in meta only
        try:
            low_high = np.stack([meta["sensor_min"], meta["sensor_max"]])
            est = {k: replace(v, reading_range=low_high) if isinstance(v, _RANGED)
                   and v.reading_range is None else v for k, v in est.items()}
        except InvalidInputError as exc:
            raise InvalidInputError(f"{path}: meta fields 'sensor_min', 'sensor_max': "
                                    f"{exc}") from None
    return {"kind": kind, "meta": meta, "estimators": est,
            "range_reference": rr}
