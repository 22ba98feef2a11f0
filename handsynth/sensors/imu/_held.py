"""Readings held by the logger: samples lost and the last one repeated in their place.

A wireless IMU whose packets are lost, or a logger that polls a stalled sensor, repeats
the sensor's last reading until the next one arrives.  A gyro held so through a motion
turns its segment by the held rate for as long as the hold lasts.  Measured on the
held-out configuration (15-s free motion, elbow fixed, Filter 4; docs/imu.md, "Readings
held by the logger"): one sensor held for 0.2 s put its segment 8-10 deg off at worst, for
0.5 s 18-44 deg and for 1 s 34-104 deg (as recorded 3.2 deg), and nothing said so.

A real sensor's noise moves its accelerometer and gyro between any two samples, so six
values equal bit for bit over :data:`HELD_MIN_S` are a held reading, not a still sensor.
In the real recordings of BROAD (Laidig, Caruso, Cereatti & Seel 2021; the 30 trials
present, 286 Hz, 1.6 million samples) a reading is repeated at most 9 times (31 ms);
magnetometers, which many sensors update more slowly than the accelerometer and gyro,
repeat routinely and are not looked at.  A noise-free simulation of a still hand also
repeats every value: a run is taken as held only when the gyro held is not exactly 0 (as
a noise-free still sensor's is) and it was turning (:data:`HELD_TURNING_RADPS`) or another
sensor's readings change during it.

:func:`~handsynth.sensors.imu.check_recording` refuses a recording with readings held;
:func:`bridge_held` fills them in by straight lines between the last reading before and
the first after.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..._checks import check_instance, check_number
from ...errors import RecordingError
from ._recording import ImuRecording

__all__ = ["HELD_MIN_S", "HELD_TURNING_RADPS", "MAX_BRIDGE_S", "HeldStretch", "bridge_held",
           "held_stretches"]

#: A reading repeated bit for bit (accelerometer and gyro, all six values) for this long,
#: s, is held.  BROAD's real recordings repeat for at most 31 ms; a hold of 50 ms moved
#: the held-out configuration's worst segment by 0.3 deg at most, one of 0.2 s by 7 deg.
HELD_MIN_S = 0.1
#: ... when the held gyro reads at least this, rad/s (about 3 deg/s: the segment was
#: turning), or another sensor's readings change during the hold.
HELD_TURNING_RADPS = 0.05
#: Longest hold :func:`bridge_held` fills in, s.  Chosen on the tuning configuration
#: (``scripts/study_imu_held.py``; worst segment 0.75 deg as recorded): bridged holds of
#: 0.2 s read 1.49 deg (held 4.88), of 0.3 s 2.47 deg (held 6.85), of 0.5 s 11.2 deg
#: (held 29.3): a straight line across half a second is no estimate of a finger's motion.
MAX_BRIDGE_S = 0.25


@dataclass(frozen=True)
class HeldStretch:
    """Samples of one sensor that repeat the reading before them.

    Attributes
    ----------
    sensor : str
    first : int
        The first repeated sample (the reading repeated is sample ``first - 1``).
    count : int
        How many samples repeat it.
    time_s : float
        Time of sample `first` in the recording's own time, s.
    duration_s : float
        ``count / rate``, s.
    turned_deg : float
        What the held gyro turns the sensor by over the hold, deg.
    """

    sensor: str
    first: int
    count: int
    time_s: float
    duration_s: float
    turned_deg: float

    def describe(self) -> str:
        """One line: sensor, how long, from when, and what the held gyro turns."""
        return (f"sensor {self.sensor!r} repeats its accelerometer and gyro readings bit for "
                f"bit for {self.duration_s:.3g} s ({self.count} samples) from t="
                f"{self.time_s:.4g} s (sample {self.first}), its gyro turning "
                f"{self.turned_deg:.3g} deg meanwhile")


def _runs(same: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Starts and lengths of the runs of True in 1-D `same`."""
    d = np.diff(np.r_[0, same.astype(np.int8), 0])
    starts = np.nonzero(d == 1)[0]
    return starts, np.nonzero(d == -1)[0] - starts


def held_stretches(rec: ImuRecording, *, min_s: float = HELD_MIN_S) -> list[HeldStretch]:
    """Every stretch in which a sensor's accelerometer and gyro repeat a reading.

    Parameters
    ----------
    rec : ImuRecording
    min_s : float, keyword-only
        Shortest hold reported, s (:data:`HELD_MIN_S`); at least two samples.

    Returns
    -------
    list of HeldStretch
        In the order of the sensors, then of time; only holds in which the held gyro
        is not exactly 0 and reads :data:`HELD_TURNING_RADPS` or more, or another
        sensor's readings change in half or more of the steps.

    Raises
    ------
    RecordingError
        `rec` not an :class:`ImuRecording`; `min_s` not a finite number > 0.
    """
    check_instance(rec, ImuRecording, name="rec", error=RecordingError)
    min_s = check_number(min_s, "min_s", above=0.0, error=RecordingError)
    if rec.n < 3:
        return []
    six = np.concatenate([rec.acc, rec.gyr], axis=2)  # (S, N, 6)
    same = np.all(six[:, 1:] == six[:, :-1], axis=2)  # (S, N - 1): sample i + 1 repeats i
    shortest = max(2, math.ceil(min_s * rec.rate_hz - 1e-9))
    out = []
    for k in np.nonzero(same.sum(axis=1) >= shortest)[0]:
        starts, lengths = _runs(same[k])
        others = np.delete(~same, k, axis=0)
        for i, n in zip(starts, lengths):
            if n < shortest:
                continue
            rate = float(np.linalg.norm(rec.gyr[k, i]))
            moving = others[:, i:i + n].mean(axis=1).max() >= 0.5 if len(others) else False
            if rate == 0.0 or (rate < HELD_TURNING_RADPS and not moving):
                continue  # a gyro at exactly 0: a noise-free simulation's still sensor
            out.append(HeldStretch(rec.sensors[k], int(i) + 1, int(n),
                                   rec.start_s + (int(i) + 1) / rec.rate_hz, n / rec.rate_hz,
                                   math.degrees(rate * n / rec.rate_hz)))
    return out


def bridge_held(rec: ImuRecording, *, max_s: float = MAX_BRIDGE_S, min_s: float = HELD_MIN_S,
                source: str = "recording") -> tuple[ImuRecording, list[HeldStretch]]:
    """The recording with held readings replaced by straight lines across each hold.

    Each repeated sample of accelerometer, gyro and magnetometer is interpolated
    linearly between the reading held (the sample before the hold) and the first new
    one after it.  On the held-out configuration a sensor held 0.2 s put the worst
    segment at 4.68 deg (up to 9.7), bridged 3.17 (as recorded 3.15); longer holds are
    bridged less well (0.3 s: 7.51 against 13.76) and are refused (docs/imu.md).

    Parameters
    ----------
    rec : ImuRecording
    max_s : float, keyword-only
        Longest hold filled in, s (:data:`MAX_BRIDGE_S`).
    min_s : float, keyword-only
        As :func:`held_stretches`.
    source : str, keyword-only
        The file, for messages.

    Returns
    -------
    recording : ImuRecording
        A new recording (its truth, segments and start kept), or `rec` itself when
        nothing is held.
    bridged : list of HeldStretch
        The holds filled in.

    Raises
    ------
    RecordingError
        A hold longer than `max_s`, or one that lasts to the recording's end (no
        reading after it to draw the line to), naming the sensor and the time; bad
        arguments.
    """
    max_s = check_number(max_s, "max_s", above=0.0, error=RecordingError)
    found = held_stretches(rec, min_s=min_s)
    if not found:
        return rec, []
    arrays = {name: getattr(rec, name).copy() for name in ("acc", "gyr", "mag")}
    for h in found:
        stop = h.first + h.count
        if stop >= rec.n:
            raise RecordingError(f"{source}: {h.describe()}, to the end of the recording: nothing after "
                                 "it to bridge to; cut the recording before it")
        if h.duration_s > max_s:
            raise RecordingError(f"{source}: {h.describe()}: longer than the {max_s:g} s bridged; cut "
                                 "the recording there")
        k = rec.index(h.sensor)
        w = (np.arange(1, h.count + 1) / (h.count + 1))[:, None]
        for a in arrays.values():
            a[k, h.first:stop] = (1 - w) * a[k, h.first - 1] + w * a[k, stop]
    return dataclasses.replace(rec, **arrays), found
