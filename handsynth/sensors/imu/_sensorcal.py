"""Per-sensor accelerometer and gyro calibration from static poses.

A MEMS accelerometer reads ``a_m = M a + b`` with a scale/cross-axis matrix M
near the identity and a bias b (the MPU-9250 datasheet allows +/-3 %
sensitivity and +/-2 % cross-axis error for both the accelerometer and the
gyro, PS-MPU-9250A-01 rev 1.1 Tables 1-2).  Held still in K different
orientations the accelerometer reads gravity only, so the corrected readings
``C (a_m - b)`` must all have the length of gravity.  The symmetric C (6
unknowns) and b (3) follow from the K means by least squares on
``|C (a_m,k - b)| - g`` (the "multi-position" or ellipsoid fit: Skog &
Haendel, "Calibration of a MEMS inertial measurement unit", XVII IMEKO World
Congress 2006; Frosio, Pedersini & Borghese, "Autocalibration of MEMS
accelerometers", IEEE Trans. Instrum. Meas. 58:2034-2041, 2009).  The
antisymmetric part of M (a small rotation) cannot be told from a mounting
rotation by gravity; it is left to the link frames.

The gyro's scale/cross-axis matrix G (``w = G (w_m - b_w)``) follows from the
moves between the poses (Tedaldi, Pretto & Menegatti, "A robust and easy to
implement method for IMU calibration without external equipments", IEEE ICRA
2014): the gyro integrated over a move must turn the calibrated gravity
direction of one pose into that of the next.  Each move fixes two of G's
nine entries' combinations; a weak prior (`prior`) keeps the combinations
that no move excites at the identity.  The gyro bias is the mean over the
pose before each move.

The magnetometer reads ``m_m = M B_s + h`` with the sensor-frame field B_s,
a hard-iron offset h and a matrix M holding soft iron and the rotation of
the magnetometer's axes against the accelerometer's (the between-sensor
azimuth spread of seed 003 Table 4.2).  In every still pose the corrected
reading ``D (m_m - h)`` has the same length and the same angle to gravity
(the local field does not turn with the hand); D (a full 3x3 matrix) and h
follow by least squares on both (the dot-product invariant of Li & Li,
"Calibration of a MEMS magnetometer using the dot product invariant", IEEE
Sensors J. 11:3000-3006, 2011, fitted here without a separate
accelerometer step since the accelerometer is already calibrated).  A
rotation of D about the sensor's z axis changes the angle to gravity only
in poses where that axis is tilted, so the poses must tilt the hand.

Poses come from :func:`calibration_motion` with ``acc_poses=True``: the
static start and stretches labelled ``acc_pose_<k>``, nine or more.
"""

from __future__ import annotations

import dataclasses
import warnings
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from ...errors import EstimationError, InvalidInputError
from ._filters import integrate_gyro
from ._model import GRAVITY_MPS2
from ._quat import quat_to_mat
from ._recording import ImuRecording

__all__ = ["SensorCalibration", "fit_sensor_calibration"]

#: Label prefix of the static poses in a calibration recording.
POSE_PREFIX = "acc_pose_"

_IU = np.triu_indices(3)

#: Fields of one sensor in a calibration file and their shapes; the
#: magnetometer's (`_MAG`) are optional (files before version 4).
_SHAPES = {"acc_matrix": (3, 3), "acc_bias_mps2": (3,), "gyr_matrix": (3, 3),
           "acc_residual_mps2": (), "gyr_residual": (), "mag_matrix": (3, 3),
           "mag_bias_ut": (3,), "mag_residual": ()}
_MAG = ("mag_matrix", "mag_bias_ut", "mag_residual")



@dataclass(frozen=True)
class SensorCalibration:
    """Corrections ``a = C (a_m - b)``, ``w = G w_m``, ``m = D (m_m - h)`` of every sensor.

    Attributes
    ----------
    sensors : tuple of str
    acc_matrix : ndarray, shape (S, 3, 3), float64
        Symmetric accelerometer correction C, dimensionless.
    acc_bias_mps2 : ndarray, shape (S, 3), float64
        Accelerometer bias b, m/s^2.
    gyr_matrix : ndarray, shape (S, 3, 3), float64
        Gyro correction G, dimensionless (the gyro bias drifts and is taken
        from each recording's own static start, not from here).
    acc_residual_mps2 : ndarray, shape (S,), float64
        RMS of ``|C (a_m,k - b)| - g`` over the poses.
    gyr_residual : ndarray, shape (S,), float64
        RMS misfit of the unit gravity direction after each move.
    mag_matrix : ndarray, shape (S, 3, 3), float64 or None
        Magnetometer correction D, dimensionless (the corrected field keeps
        the raw readings' median length).  None: the magnetometers are left
        as read (calibration files before version 4).
    mag_bias_ut : ndarray, shape (S, 3), float64 or None
        Hard iron h, microtesla.
    mag_residual : ndarray, shape (S,), float64 or None
        RMS over the poses of the corrected field's length and
        gravity-angle-cosine misfits, relative to the field's length.
    """

    sensors: tuple
    acc_matrix: np.ndarray
    acc_bias_mps2: np.ndarray
    gyr_matrix: np.ndarray
    acc_residual_mps2: np.ndarray
    gyr_residual: np.ndarray
    mag_matrix: np.ndarray | None = None
    mag_bias_ut: np.ndarray | None = None
    mag_residual: np.ndarray | None = None

    def apply(self, rec: ImuRecording, *, gyro: bool = True) -> ImuRecording:
        """`rec` with corrected accelerometer, magnetometer (and gyro) readings.

        Sensors are matched by name.

        Any recording of the same physical sensors can be corrected, the
        calibration recording or a later one; the gyro bias is left in (the
        estimators take it from each recording's static start).

        Raises
        ------
        InvalidInputError
            A sensor of `rec` that the calibration does not hold.
        """
        missing = [s for s in rec.sensors if s not in self.sensors]
        if missing:
            raise InvalidInputError(
                f"sensor calibration has no sensor {missing[0]!r}; it holds "
                f"{', '.join(self.sensors)}")
        idx = [self.sensors.index(s) for s in rec.sensors]
        acc = np.einsum("sij,snj->sni", self.acc_matrix[idx],
                        rec.acc - self.acc_bias_mps2[idx][:, None, :])
        gyr = np.einsum("sij,snj->sni", self.gyr_matrix[idx], rec.gyr) if gyro else rec.gyr
        mag = rec.mag
        if mag is not None and self.mag_matrix is not None and self.mag_bias_ut is not None:
            mag = np.einsum("sij,snj->sni", self.mag_matrix[idx],
                            mag - self.mag_bias_ut[idx][:, None, :])
        return dataclasses.replace(rec, acc=acc, gyr=gyr, mag=mag)


    def to_dict(self) -> dict:
        """JSON-ready ``{sensor: {field: list}}``."""
        out = {}
        for k, s in enumerate(self.sensors):
            out[s] = {key: getattr(self, key)[k].tolist() for key in _SHAPES
                      if getattr(self, key) is not None}
        return out

    @classmethod
    def from_dict(cls, d: dict, *, source: str = "sensor calibration") -> SensorCalibration:
        """Inverse of :meth:`to_dict`; `source` names the origin in errors.

        The magnetometer fields are optional (files before version 4 lack
        them), but all three or none.

        Raises
        ------
        InvalidInputError
            A missing field, a wrong shape or a non-finite value (named).
        """
        if not isinstance(d, dict) or not d:
            raise InvalidInputError(f"{source}: expected an object of sensor: fields")
        out: dict[str, list] = {k: [] for k in _SHAPES}
        for sensor, fields in d.items():
            if not isinstance(fields, dict):
                raise InvalidInputError(f"{source}: sensor {sensor!r}: expected an object, "
                                        f"got {fields!r}")
            keys = [k for k in _SHAPES if k not in _MAG or any(m in fields for m in _MAG)]
            for key in keys:
                if key not in fields:
                    raise InvalidInputError(f"{source}: sensor {sensor!r} lacks {key!r}")
                try:
                    v = np.array(fields[key], float)
                except (TypeError, ValueError):
                    raise InvalidInputError(f"{source}: sensor {sensor!r} {key!r} is not "
                                            f"numeric: {fields[key]!r}") from None
                if v.shape != _SHAPES[key] or not np.all(np.isfinite(v)):
                    raise InvalidInputError(f"{source}: sensor {sensor!r} {key!r} must be "
                                            f"finite with shape {_SHAPES[key]}, got "
                                            f"{fields[key]!r}")
                out[key].append(v)
        with_mag = {len(out[k]) for k in _MAG}
        if with_mag != {0} and with_mag != {len(d)}:
            raise InvalidInputError(f"{source}: the magnetometer fields ({', '.join(_MAG)}) "
                                    "are given for some sensors only")
        mag = {k: np.array(out[k]) for k in _MAG if out[k]}
        return cls(tuple(d), *(np.array(out[k]) for k in _SHAPES if k not in _MAG), **mag)


def _poses(rec: ImuRecording) -> list[tuple[int, int]]:
    stretches = [(a, b) for name, a, b in rec.labelled()
                 if name == "static" or name.startswith(POSE_PREFIX)]
    if len(stretches) < 9:
        raise InvalidInputError(
            f"sensor calibration needs >= 9 static poses (stretches 'static' and "
            f"'{POSE_PREFIX}<k>'), the recording has {len(stretches)}")
    return sorted(stretches)


def _fit_acc(means: np.ndarray, g: float, prior: float) -> tuple[np.ndarray, np.ndarray, float]:
    def unpack(x):
        c = np.zeros((3, 3))
        c[_IU] = x[:6]
        return c + np.triu(c, 1).T, x[6:]

    x0 = np.r_[1.0, 0, 0, 1.0, 0, 1.0, 0, 0, 0]

    def residual(x):
        c, b = unpack(x)
        return np.linalg.norm((means - b) @ c.T, axis=1) - g

    sol = least_squares(lambda x: np.r_[residual(x), prior * (x - x0)], x0, method="lm")
    c, b = unpack(sol.x)
    return c, b, float(np.sqrt(np.mean(residual(sol.x) ** 2)))


def _fit_mag(mag: np.ndarray, up: np.ndarray, prior: float
             ) -> tuple[np.ndarray, np.ndarray, float]:
    """D and h from the pose means `mag` (K, 3) and unit up directions `up` (K, 3)."""
    scale = float(np.median(np.linalg.norm(mag, axis=1)))
    m = mag / scale
    x0 = np.r_[np.eye(3).ravel(), 0.0, 0.0, 0.0, np.mean(np.sum(m * up, axis=1))]

    def residual(x):
        f = (m - x[9:12]) @ x[:9].reshape(3, 3).T
        return np.r_[np.linalg.norm(f, axis=1) - 1.0, np.sum(f * up, axis=1) - x[12]]

    sol = least_squares(lambda x: np.r_[residual(x), prior * (x[:12] - x0[:12])], x0,
                        method="lm")
    return (sol.x[:9].reshape(3, 3), sol.x[9:12] * scale,
            float(np.sqrt(np.mean(residual(sol.x) ** 2))))


def _mag_axes_hint(mag: np.ndarray, up: np.ndarray) -> str | None:
    """The magnetometer's axes in the accelerometer's, as "y, x, -z", where a signed
    permutation of them, and not the identity, keeps the field's angle to gravity the same
    in every pose (the dot-product invariant); None otherwise.

    `mag` (K, 3): the poses' mean fields; `up` (K, 3): their unit up directions.
    """
    import itertools

    unit = mag / np.linalg.norm(mag, axis=1, keepdims=True)
    spread = {}
    for perm in itertools.permutations(range(3)):
        for signs in itertools.product((1.0, -1.0), repeat=3):
            dots = np.sum(unit[:, perm] * np.array(signs) * up, axis=1)
            spread[(perm, signs)] = float(np.std(dots))
    best = min(spread, key=spread.__getitem__)
    identity = ((0, 1, 2), (1.0, 1.0, 1.0))
    if best == identity or not spread[best] * 5.0 < spread[identity]:
        return None
    perm, signs = best
    return ", ".join(("-" if sg < 0 else "") + "xyz"[i] for i, sg in zip(perm, signs))


def _fit_gyr(moves: np.ndarray, u0: np.ndarray, u1: np.ndarray, rate_hz: float,
             prior: float) -> tuple[np.ndarray, float]:
    q0 = np.tile([1.0, 0.0, 0.0, 0.0], (len(moves), 1))

    def misfit(x):
        g = np.eye(3) + x.reshape(3, 3)
        r = quat_to_mat(integrate_gyro(q0, moves @ g.T, rate_hz)[:, -1])   # S0 <- S1
        return (np.einsum("mji,mj->mi", r, u0) - u1).ravel()

    sol = least_squares(lambda x: np.r_[misfit(x), prior * x], np.zeros(9), method="lm")
    return np.eye(3) + sol.x.reshape(3, 3), float(np.sqrt(np.mean(misfit(sol.x) ** 2)))


def fit_sensor_calibration(rec: ImuRecording, *, skip_s: float = 0.3, prior: float = 0.01,
                           acc_prior: float = 0.03, mag_prior: float = 0.01,
                           max_correction: float = 0.15, mag_max_correction: float = 0.4,
                           mag_warn: float = 0.02) -> SensorCalibration:
    """Fit accelerometer, gyro and magnetometer corrections from still poses.

    A recording of 6-axis sensors (``rec.mag`` None) gets the accelerometer
    and gyro corrections only (the magnetometer fields None).

    Parameters
    ----------
    rec : ImuRecording
        A calibration recording with labelled static poses (see module).
    skip_s : float, keyword-only
        Time dropped at the start of every pose (the motion settling), s.
    prior : float, keyword-only
        Weight of the gyro matrix's pull toward the identity (per unit of
        unit-vector misfit).
    acc_prior : float, keyword-only
        Weight of the accelerometer matrix's and bias's pull toward the
        identity and zero (m/s^2 of misfit per unit).  The forearm plate's
        poses leave one combination of bias and scale nearly unseen; without
        the pull it follows the noise (chosen on the datasheet noise).
    mag_prior : float, keyword-only
        Weight of the magnetometer matrix's and hard iron's pull toward the
        identity and zero (per unit of relative misfit; hard iron in units
        of the field's length).
    max_correction : float, keyword-only
        Largest accepted deviation of C or G from the identity (any
        element); a larger one means the poses were not still or not varied.
    mag_max_correction : float, keyword-only
        The same for D (soft iron and the magnetometer's axis rotation are
        larger than the accelerometer's errors).
    mag_warn : float, keyword-only
        A sensor whose poses still disagree by more than this share of the
        field's length after the fit is warned about (a magnetic disturbance
        during the poses; simulated sensors leave 0.1-0.2 %).

    Returns
    -------
    SensorCalibration

    Raises
    ------
    InvalidInputError
        Fewer than nine poses.
    EstimationError
        A sensor whose fit deviates more than `max_correction` from the
        identity (named in the message).

    Warns
    -----
    UserWarning
        Sensors whose magnetometer residual exceeds `mag_warn` (named).
    """
    poses = _poses(rec)
    skip = int(round(skip_s * rec.rate_hz))
    for first, end in poses:
        if end - first <= skip + 2:
            raise InvalidInputError(f"static pose at samples {first}-{end} is shorter than "
                                    f"skip_s={skip_s} s plus 3 samples")
    spans = [(first + skip, end) for first, end in poses]
    means = np.stack([rec.acc[:, i:j].mean(axis=1) for i, j in spans], axis=1)   # (S, K, 3)
    wbias = np.stack([rec.gyr[:, i:j].mean(axis=1) for i, j in spans], axis=1)
    mags = rec.mag  # None: 6-axis sensors, no magnetometer to calibrate
    mmeans = (None if mags is None else
              np.stack([mags[:, i:j].mean(axis=1) for i, j in spans], axis=1))
    length = max(b1 - (b0 - 1) for (_, b0), (_, b1) in zip(poses[:-1], spans[1:]))
    out: dict[str, list] = {k: [] for k in _SHAPES}
    for k, name in enumerate(rec.sensors):
        c, b, rc = _fit_acc(means[k], GRAVITY_MPS2, acc_prior)
        up = (means[k] - b) @ c.T
        up /= np.linalg.norm(up, axis=1, keepdims=True)
        moves = np.zeros((len(poses) - 1, length, 3))
        for m, ((_, b0), (a1, _)) in enumerate(zip(poses[:-1], spans[1:])):
            w = rec.gyr[k, b0 - 1:a1] - wbias[k, m]
            moves[m, :len(w)] = w                       # zero-padded: no rotation after
        g, rg = _fit_gyr(moves, up[:-1], up[1:], rec.rate_hz, prior)
        d, h, rm = (np.eye(3), np.zeros(3), 0.0) if mmeans is None else \
            _fit_mag(mmeans[k], up, mag_prior)
        for label, mat, most in (("accelerometer", c, max_correction),
                                 ("gyro", g, max_correction),
                                 ("magnetometer", d, mag_max_correction)):
            dev = float(np.abs(mat - np.eye(3)).max())
            if not np.isfinite(dev) or dev > most:
                axes = (_mag_axes_hint(mmeans[k], up) if label == "magnetometer"
                        and mmeans is not None else None)
                raise EstimationError(
                    f"sensor {name!r}: {label} calibration deviates {dev:.3g} from the identity "
                    f"(limit {most}); " + (
                        "poses not still or not varied" if axes is None else
                        f"the magnetometer's axes are not the accelerometer's: its field keeps "
                        f"one angle to gravity in every pose read as ({axes}), as the "
                        "MPU-9250's AK8963 is mounted ((y, x, -z)); turn its columns into the "
                        "accelerometer's axes first"))
        for key, v in zip(_SHAPES, (c, b, g, rc, rg, d, h, rm)):
            out[key].append(v)
    bad = [f"{name} {r:.1%}" for name, r in zip(rec.sensors, out["mag_residual"]) if r > mag_warn]
    if bad:
        warnings.warn(f"magnetometer poses disagree after the calibration ({', '.join(bad)} of "
                      f"the field's length; limit {mag_warn:.0%}): a magnetic disturbance during "
                      "the poses? Those sensors' headings will be off; calibrate away from iron",
                      UserWarning, stacklevel=2)
    fitted = {k: np.array(v) for k, v in out.items() if mmeans is not None or k not in _MAG}
    return SensorCalibration(tuple(rec.sensors), **fitted)
