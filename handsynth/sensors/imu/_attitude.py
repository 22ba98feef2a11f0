"""Initial attitude and compass azimuth alignment across sensors.

Initial attitude: gravity and the tilt-compensated compass over the static
start (seed 003 eqs. 2.9-2.11).  Azimuth alignment (section 4.2.5): every
sensor sees the same angular velocity during a common rotation; the vector
w_g = g x w_max (eq. 4.18), tilt-compensated, has a heading psi_wg (eq. 4.19)
with far less spread between sensors than the compass.  The per-sensor
difference psi_d = psi - psi_wg (eq. 4.20) is compared with its median over
the sensors, giving the correction psi_cor = median - psi_d (eq. 4.21) that
is added to each compass heading (eq. 4.22).

Sensors without a magnetometer (6-axis, ``rec.mag`` None) take their
headings from the common rotation alone: w_g of eq. 4.18 is one horizontal
direction for every sensor, and each sensor's heading is set so that it
points along the world's x axis (eq. 4.19 with w_g in the compass's place).
The world's x axis is then that direction, not magnetic north.  A single
6-axis sensor shares its heading with none: without a common rotation its
world x axis is its own x axis made horizontal (its y axis where x is
within 25 deg of the vertical).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from ..._checks import check_instance, is_number
from ...errors import EstimationError, InvalidInputError, RecordingError
from ._quat import quat_from_acc_mag
from ._recording import ImuRecording, check_recording, check_static

__all__ = ["StaticStart", "azimuth_correction", "check_run_input", "check_static_fits", "gyro_bias",
           "initial_attitude"]


#: Default common rotation (azimuth alignment), s.
_ALIGN = (2.0, 4.0)


@dataclass(frozen=True)
class StaticStart:
    """Where the static start and the common rotation are (seconds).

    Parameters
    ----------
    static_s : float
        Length of the still start, s (finite, > 0).
    align_start_s, align_end_s : float or None
        The common rotation for the azimuth alignment, s (finite, start >= 0,
        end after start).  None for either turns the alignment off (the other
        then None too, or left at its default); half a window, one bound None
        and the other set to another value, is refused.
    """

    static_s: float = 2.0
    align_start_s: float | None = _ALIGN[0]
    align_end_s: float | None = _ALIGN[1]

    def __post_init__(self) -> None:
        check_static(self.static_s, source="StaticStart")
        a, b = self.align_start_s, self.align_end_s
        if (a is None) != (b is None):
            # one bound None turns the alignment off; the other left at its default says
            # nothing more, one set to another value is half a window
            if (a, b) not in ((None, _ALIGN[1]), (_ALIGN[0], None)):
                raise InvalidInputError(
                    f"the common rotation needs both align_start_s and align_end_s, or None "
                    f"(no azimuth alignment), got align_start_s={a!r}, align_end_s={b!r}")
            object.__setattr__(self, "align_start_s", None)
            object.__setattr__(self, "align_end_s", None)
            a = b = None
        if a is not None and b is not None:
            if not all(is_number(v) for v in (a, b)):
                raise InvalidInputError(f"align_start_s and align_end_s must be numbers of "
                                        f"seconds, got {a!r} and {b!r}")
            if not (np.isfinite(a) and np.isfinite(b) and a >= 0):
                raise InvalidInputError(f"the common rotation (--align) must be finite seconds "
                                        f">= 0, got {a}-{b} s")
            if not b > a:
                raise InvalidInputError(f"the common rotation (--align START,END) {a:g}-{b:g} s "
                                        "is empty: END must be after START")


def check_run_input(rec, static) -> ImuRecording:
    """Refuse a recording an estimator cannot use; warn about a suspicious one.

    The one check of every estimator's ``run``: what :func:`check_recording`
    checks (its errors raised, its warnings issued with :func:`warnings.warn`
    unless it already returned them for this recording), and that the static
    start lies inside the recording.  Shapes, dtype and the rate are checked
    when the :class:`ImuRecording` is made; a common rotation cut by the
    recording's end is used as far as it goes, one wholly outside is refused
    by :func:`azimuth_correction`.

    Parameters
    ----------
    rec : ImuRecording
    static : StaticStart

    Returns
    -------
    ImuRecording
        `rec`.

    Raises
    ------
    RecordingError
        See :func:`check_recording`; a static start longer than the
        recording.
    InvalidInputError
        `rec` or `static` of the wrong type.
    """
    check_instance(rec, ImuRecording, name="rec")
    check_instance(static, StaticStart, name="static")
    check_static_fits(rec, static.static_s)
    before = rec.reported or frozenset()
    for w in check_recording(rec, static_s=static.static_s):
        if w not in before:
            warnings.warn(w, UserWarning, stacklevel=3)
    return rec


def check_static_fits(rec: ImuRecording, static_s: float, *, source: str = "") -> None:
    """Refuse a static start longer than the recording (by more than half a sample).

    The one test of every use of a static start: :func:`check_run_input` (the
    estimators), :func:`gyro_bias`, :func:`azimuth_correction` and
    :func:`initial_attitude`; the command line can share it.

    Parameters
    ----------
    rec : ImuRecording
    static_s : float
        Length of the static start, s (already checked to be finite and > 0).
    source : str, keyword-only
        Prefix of the message (a file name), none by default.

    Raises
    ------
    RecordingError
        ``round(static_s * rate_hz)`` beyond the recording's N samples: 2.0 s of
        200 samples at 100 Hz fit (half a sample's tolerance), 2.01 s do not.
    """
    end = (rec.n + 0.5) / rec.rate_hz
    if static_s > end:
        where = f"{source}: " if source else ""
        raise RecordingError(f"{where}the static start static_s={static_s:g} s is longer than "
                             f"the recording ({rec.n} samples, {rec.n / rec.rate_hz:.4g} s); "
                             "shorten the static start")


def _n(rec: ImuRecording, seconds: float) -> int:
    return max(1, min(rec.n, round(seconds * rec.rate_hz)))


def _static_samples(rec: ImuRecording, static: StaticStart) -> int:
    """Samples of the static start, after checking the two arguments' types and that the
    static start fits in the recording."""
    check_instance(rec, ImuRecording, name="rec")
    check_instance(static, StaticStart, name="static")
    check_static_fits(rec, static.static_s)
    return _n(rec, static.static_s)


def gyro_bias(rec: ImuRecording, static: StaticStart = StaticStart()) -> np.ndarray:
    """Mean gyro over the static start, rad/s, shape (S, 3) (seed 003 section 4.2.4).

    Parameters
    ----------
    rec : ImuRecording
    static : StaticStart
        Its ``static_s`` gives the samples averaged: ``round(static_s *
        rate_hz)``, at least 1 and at most the recording's N.

    Returns
    -------
    ndarray, shape (S, 3), float64, rad/s

    Raises
    ------
    InvalidInputError
        `rec` not an :class:`ImuRecording` or `static` not a :class:`StaticStart`.
    RecordingError
        A static start longer than the recording (:func:`check_static_fits`).
    """
    n0 = _static_samples(rec, static)
    return rec.gyr[:, :n0].mean(axis=1)


def azimuth_correction(rec: ImuRecording, static: StaticStart = StaticStart()) -> np.ndarray:
    """Per-sensor compass heading correction psi_cor, radians, shape (S,) (eqs. 4.18-4.21).

    Parameters
    ----------
    rec : ImuRecording
        All sensors must turn together during the common rotation.
    static : StaticStart
        The static start (mean accelerometer and magnetometer, and the gyro
        bias removed from the rotation) and the common rotation's window,
        s; a window cut by the recording's end is used as far as it goes.

    Returns
    -------
    ndarray, shape (S,), float64, rad
        Wrapped to (-pi, pi]; zeros when `static` has no common rotation
        (``align_start_s`` None).

    Raises
    ------
    InvalidInputError
        `rec` or `static` of the wrong type; a common rotation of fewer than
        2 samples inside the recording.
    RecordingError
        A static start longer than the recording (:func:`check_static_fits`).
    EstimationError
        If the common rotation is too slow (< 0.5 rad/s) or about the vertical
        (then g x w_max vanishes and fixes no heading).
    """
    n0 = _static_samples(rec, static)
    if static.align_start_s is None or static.align_end_s is None or rec.mag is None:
        return np.zeros(len(rec.sensors))  # 6-axis: no compass heading to correct
    g, wg = _common_rotation(rec, static, n0)
    mag = rec.mag[:, :n0].mean(axis=1)
    q_m = quat_from_acc_mag(g, mag)
    q_w = quat_from_acc_mag(g, wg)                                      # eq. 4.19
    psi = 2 * np.arctan2(q_m[:, 3], q_m[:, 0])
    psi_wg = 2 * np.arctan2(q_w[:, 3], q_w[:, 0])
    d = np.angle(np.exp(1j * (psi - psi_wg)))                           # eq. 4.20
    # median of the angles, unwrapped around the first sensor's
    dmean = d[0] + np.median(np.angle(np.exp(1j * (d - d[0]))))
    return np.angle(np.exp(1j * (dmean - d)))                           # eq. 4.21


def _common_rotation(rec: ImuRecording, static: StaticStart, n0: int
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Gravity over the static start and w_g = g x w_max of the common rotation (eq. 4.18),
    both in each sensor's frame, shape (S, 3); the checks of :func:`azimuth_correction`."""
    assert static.align_start_s is not None and static.align_end_s is not None
    a, b = _n(rec, static.align_start_s), _n(rec, static.align_end_s)
    if b - a < 2:
        raise InvalidInputError(f"the common rotation {static.align_start_s}-{static.align_end_s} s "
                                "is outside the recording")
    g = rec.acc[:, :n0].mean(axis=1)
    gyr = rec.gyr[:, a:b] - gyro_bias(rec, static)[:, None]
    # one common instant for every sensor (the fastest on average), so that
    # all take w_max with the same sign
    k = int(np.argmax(np.linalg.norm(gyr, axis=-1).mean(axis=0)))
    wmax = gyr[:, k]
    if np.any(np.linalg.norm(wmax, axis=-1) < 0.5):
        raise EstimationError(f"the common rotation {static.align_start_s:g}-"
                              f"{static.align_end_s:g} s (--align) is slower than 0.5 rad/s "
                              f"(its fastest sample: {float(np.linalg.norm(wmax, axis=-1).min()):.3g} "
                              "rad/s in the slowest sensor); cannot align compass azimuths")
    wg = np.cross(g, wmax)                                              # eq. 4.18
    if np.any(np.linalg.norm(wg, axis=-1) < 0.2 * np.linalg.norm(g, axis=-1)
              * np.linalg.norm(wmax, axis=-1)):
        raise EstimationError("the common rotation is about the vertical; "
                              "g x w_max fixes no heading")
    return g, wg


def initial_attitude(rec: ImuRecording, static: StaticStart = StaticStart(), *,
                     align: bool = True) -> np.ndarray:
    """Initial sensor-to-world quaternions, shape (S, 4) (eqs. 2.9-2.11, 4.22).

    Parameters
    ----------
    rec : ImuRecording
    static : StaticStart
        Accelerometer and magnetometer are averaged over its static start;
        its common rotation gives the azimuth correction.
    align : bool, keyword-only
        Add :func:`azimuth_correction` to each compass heading; False keeps
        the compass headings as they are.

    Returns
    -------
    ndarray, shape (S, 4), float64
        Unit quaternions (w, x, y, z), world frame z up, x magnetic north;
        for 6-axis sensors (``rec.mag`` None) x along the common rotation's
        w_g (module docstring), whatever `align`.

    Raises
    ------
    InvalidInputError, EstimationError
        As :func:`azimuth_correction` (with `align`, and always for 6-axis
        sensors); `rec` or `static` of the wrong type; two or more 6-axis
        sensors with no common rotation in `static` (nothing else gives them
        a common heading).
    RecordingError
        A static start longer than the recording (:func:`check_static_fits`).
    """
    n0 = _static_samples(rec, static)
    g = rec.acc[:, :n0].mean(axis=1)
    if rec.mag is None:
        if static.align_start_s is None and len(rec.sensors) == 1:
            up = g[0] / np.linalg.norm(g[0])
            axis = np.eye(3)[0 if abs(up[0]) < np.cos(np.radians(25.0)) else 1]
            return quat_from_acc_mag(g, axis[None])
        if static.align_start_s is None:
            raise EstimationError(
                "a recording of 6-axis sensors (no magnetometer) takes the sensors' headings "
                "from the common rotation, and it is off (--align none): give the common "
                "rotation's seconds (--align START,END)")
        return quat_from_acc_mag(*_common_rotation(rec, static, n0))   # eqs. 4.18-4.19
    mag = rec.mag[:, :n0].mean(axis=1)
    cor = azimuth_correction(rec, static) if align else 0.0
    return quat_from_acc_mag(g, mag, heading_offset_rad=cor)
