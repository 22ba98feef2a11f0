"""Samples lost by the logger: held (the last reading repeated), zeros or empty cells.

A wireless IMU whose packets are lost, or a logger that polls a stalled sensor, repeats
the sensor's last reading until the next one arrives; other loggers write zeros, or
leave the cells empty (NaN).  A gyro held so through a motion turns its segment by the
held rate for as long as the hold lasts.  Measured on the
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

Zeros on every accelerometer and gyro axis are no reading either: an accelerometer at
rest reads gravity and one in free fall its noise and bias, never 0 to the bit on all
three axes with its gyro.  Zeros for 0.3 s in a free motion read as a magnetic
disturbance before (the magnetometer's zeros), while the filters took the sensor for
still and in free fall.

:func:`~handsynth.sensors.imu.check_recording` refuses a recording with samples lost;
:func:`bridge_lost` fills them in from the other sensors' readings.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..._checks import check_instance, check_number
from ...errors import RecordingError
from ._recording import ImuRecording

__all__ = ["HELD_MIN_S", "HELD_TURNING_RADPS", "MAX_BRIDGE_S", "LostStretch", "bridge_lost",
           "lost_stretches"]

#: A reading repeated bit for bit (accelerometer and gyro, all six values) for this long,
#: s, is held.  BROAD's real recordings repeat for at most 31 ms; a hold of 50 ms moved
#: the held-out configuration's worst segment by 0.3 deg at most, one of 0.2 s by 7 deg.
HELD_MIN_S = 0.1
#: ... when the held gyro reads at least this, rad/s (about 3 deg/s: the segment was
#: turning), or another sensor's readings change during the hold.
HELD_TURNING_RADPS = 0.05
#: Longest hold :func:`bridge_lost` fills in, s.  Chosen on the tuning configuration
#: (``scripts/study_imu_held.py``; worst segment 0.75 deg as recorded): holds bridged
#: from the other sensors read 1.13 deg at 0.3 s, 2.12 at 0.5 s and 10.3 at 1 s (within
#: 1.5 deg of the recording on average up to 0.5 s); with Filter 4 loosening the filled
#: samples' attitude (:attr:`ChainEKFOptions.filled_rate`) 0.76, 1.21 and 3.04 deg, by
#: the same rule the same limit.
MAX_BRIDGE_S = 0.5
#: Most samples the prediction of a held sensor is fitted on (evenly spread), for speed.
_MAX_FIT_ROWS = 50_000


@dataclass(frozen=True)
class LostStretch:
    """Samples of one sensor that hold no reading of their own.

    Attributes
    ----------
    sensor : str
    first : int
        The first sample lost (for a hold, the reading repeated is sample
        ``first - 1``).
    count : int
        How many samples are lost.
    time_s : float
        Time of sample `first` in the recording's own time, s.
    duration_s : float
        ``count / rate``, s.
    turned_deg : float
        What the held gyro turns the sensor by over a hold, deg (0 for the others).
    kind : {"held", "zeros", "missing"}
        The last reading repeated, zeros on every accelerometer and gyro axis, or a
        value that is not a finite number (an empty cell, NaN).
    """

    sensor: str
    first: int
    count: int
    time_s: float
    duration_s: float
    turned_deg: float = 0.0
    kind: str = "held"

    def describe(self) -> str:
        """One line: sensor, what, how long and from when (and what a held gyro turns)."""
        what = {"held": "repeats its accelerometer and gyro readings bit for bit",
                "zeros": "reads exactly 0 on every accelerometer and gyro axis",
                "missing": "has values that are not finite numbers (empty cells, NaN)"}[self.kind]
        turn = (f", its gyro turning {self.turned_deg:.3g} deg meanwhile"
                if self.kind == "held" else "")
        return (f"sensor {self.sensor!r} {what} for {self.duration_s:.3g} s ({self.count} "
                f"samples) from t={self.time_s:.4g} s (sample {self.first}){turn}")


def _runs(same: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Starts and lengths of the runs of True in 1-D `same`."""
    d = np.diff(np.r_[0, same.astype(np.int8), 0])
    starts = np.nonzero(d == 1)[0]
    return starts, np.nonzero(d == -1)[0] - starts


def lost_stretches(rec: ImuRecording, *, min_s: float = HELD_MIN_S) -> list[LostStretch]:
    """Every stretch of samples a sensor has no reading of its own for.

    Parameters
    ----------
    rec : ImuRecording
    min_s : float, keyword-only
        Shortest hold reported, s (:data:`HELD_MIN_S`); at least two samples.  Zeros
        and values that are not finite are reported from one sample on.

    Returns
    -------
    list of LostStretch
        In the order of the sensors, then of time: values that are not finite
        (``"missing"``), zeros on all six accelerometer and gyro axes (``"zeros"``) and
        holds (``"held"``) in which the held gyro is not exactly 0 and reads
        :data:`HELD_TURNING_RADPS` or more, or another sensor's readings change in half
        or more of the steps.

    Raises
    ------
    RecordingError
        `rec` not an :class:`ImuRecording`; `min_s` not a finite number > 0.
    """
    check_instance(rec, ImuRecording, name="rec", error=RecordingError)
    min_s = check_number(min_s, "min_s", above=0.0, error=RecordingError)
    six = np.concatenate([rec.acc, rec.gyr], axis=2)  # (S, N, 6)
    out = []
    nine = six if rec.mag is None else np.concatenate([six, rec.mag], axis=2)
    bad = ~np.isfinite(nine).all(axis=2)
    zeros = ~six.any(axis=2)
    for kind, flags in (("missing", bad), ("zeros", zeros & ~bad)):
        for k in np.nonzero(flags.any(axis=1))[0]:
            for i, n in zip(*_runs(flags[k])):
                out.append(LostStretch(rec.sensors[k], int(i), int(n),
                                       rec.start_s + int(i) / rec.rate_hz, n / rec.rate_hz,
                                       kind=kind))
    if rec.n < 3:
        return sorted(out, key=lambda h: (rec.index(h.sensor), h.first))
    same = np.all(six[:, 1:] == six[:, :-1], axis=2)  # (S, N - 1): sample i + 1 repeats i
    shortest = max(2, math.ceil(min_s * rec.rate_hz - 1e-9))
    for k in np.nonzero(same.sum(axis=1) >= shortest)[0]:
        starts, lengths = _runs(same[k])
        others = np.delete(~same, k, axis=0)
        for i, n in zip(starts, lengths):
            if n < shortest:
                continue
            rate = float(np.linalg.norm(rec.gyr[k, i]))
            moving = others[:, i:i + n].mean(axis=1).max() >= 0.5 if len(others) else False
            if rate == 0.0 or not math.isfinite(rate) or \
                    (rate < HELD_TURNING_RADPS and not moving):
                continue  # a gyro at exactly 0: a noise-free simulation's still sensor (or zeros)
            out.append(LostStretch(rec.sensors[k], int(i) + 1, int(n),
                                   rec.start_s + (int(i) + 1) / rec.rate_hz, n / rec.rate_hz,
                                   math.degrees(rate * n / rec.rate_hz)))
    return sorted(out, key=lambda h: (rec.index(h.sensor), h.first))


def _predicted(arrays: dict, k: int, ok: np.ndarray) -> dict:
    """Sensor `k`'s accelerometer and gyro as least-squares combinations of the others'.

    Fitted on the samples `ok` (at most :data:`_MAX_FIT_ROWS` of them, evenly spread):
    each of its six values from the same channel's three values of every other sensor
    and a constant (:func:`prediction_coefficients`).  With no other sensor, the constant
    alone (its mean).
    """
    rows = np.nonzero(ok)[0]
    rows = rows[:: max(1, rows.size // _MAX_FIT_ROWS)]
    coef = prediction_coefficients(arrays, k, rows)
    return {name: prediction_regressors(arrays[name], k) @ c for name, c in coef.items()}


def prediction_regressors(a: np.ndarray, k: int) -> np.ndarray:
    """What sensor `k`'s channel is predicted from: the same channel's three values of every
    other sensor and a constant, shape (N, 3 (S - 1) + 1), from `a` (S, N, 3)."""
    n = a.shape[1]
    return np.concatenate([np.delete(a, k, axis=0).transpose(1, 0, 2).reshape(n, -1),
                           np.ones((n, 1))], axis=1)


def prediction_coefficients(arrays: dict, k: int, rows) -> dict:
    """Least-squares coefficients that predict sensor `k`'s ``acc`` and ``gyr`` from
    :func:`prediction_regressors`, fitted on the samples `rows` of `arrays` (name ->
    (S, N, 3)); name -> (3 (S - 1) + 1, 3)."""
    out = {}
    for name in ("acc", "gyr"):
        a = arrays[name]
        coef, *_ = np.linalg.lstsq(prediction_regressors(a, k)[rows], a[k, rows], rcond=None)
        out[name] = coef
    return out


def bridge_lost(rec: ImuRecording, *, max_s: float = MAX_BRIDGE_S, min_s: float = HELD_MIN_S,
                predict: bool = True, source: str = "recording"
                ) -> tuple[ImuRecording, list[LostStretch]]:
    """The recording with held readings filled in across each hold.

    With `predict` (the default), a held sensor's accelerometer and gyro are
    predicted from the other sensors' readings at the same instants (each value a
    least-squares combination of the same channel of every other sensor and a
    constant, fitted on the recording's samples in which no reading is held: the
    hand's own motion, and the fingers' coupling, are seen by them), and what the
    prediction misses is drawn as a straight line between its values at the reading
    held (the sample before the hold) and at the first new one; the magnetometer, and
    every channel without `predict`, is drawn as a straight line between those two
    readings.  The samples filled in are marked (``filled`` of the recording
    returned), and Filter 4 loosens the sensor's attitude over them.  On the held-out
    configuration (seed 1) a sensor held 0.3 s put the worst segment at 13.76 deg,
    bridged 3.16 (straight lines alone 3.55; as recorded 3.15); held 0.5 s 24.66,
    bridged 3.53 (docs/imu.md, "Readings held by the logger").

    Parameters
    ----------
    rec : ImuRecording
    max_s : float, keyword-only
        Longest hold filled in, s (:data:`MAX_BRIDGE_S`).
    min_s : float, keyword-only
        As :func:`lost_stretches`.
    predict : bool, keyword-only
        Predict the held sensor from the others (above); False: straight lines only.
    source : str, keyword-only
        The file, for messages.

    Returns
    -------
    recording : ImuRecording
        A new recording (its truth, segments and start kept), or `rec` itself when
        nothing is held.
    bridged : list of LostStretch
        The holds filled in.

    Raises
    ------
    RecordingError
        A hold longer than `max_s`, or one that lasts to the recording's end (no
        reading after it to bridge to), naming the sensor and the time; bad
        arguments.
    """
    max_s = check_number(max_s, "max_s", above=0.0, error=RecordingError)
    if not isinstance(predict, bool):
        raise RecordingError(f"predict must be True or False, got {predict!r}")
    found = lost_stretches(rec, min_s=min_s)
    if not found:
        return rec, []
    arrays = {name: getattr(rec, name).copy() for name in ("acc", "gyr", "mag")
              if getattr(rec, name) is not None}
    lost = np.zeros((len(rec.sensors), rec.n), bool)
    for h in found:
        stop = h.first + h.count
        if h.first == 0:
            raise RecordingError(f"{source}: {h.describe()}, from the start of the recording: "
                                 "nothing before it to bridge from; cut the recording after it")
        if stop >= rec.n:
            raise RecordingError(f"{source}: {h.describe()}, to the end of the recording: "
                                 "nothing after it to bridge to; cut the recording before it")
        if h.duration_s > max_s:
            raise RecordingError(f"{source}: {h.describe()}: longer than the {max_s:g} s "
                                 "bridged (--bridge-max; library: max_s); cut the recording "
                                 "there")
        k = rec.index(h.sensor)
        lost[k, h.first:stop] = True
        # straight lines first: what a prediction of another lost sensor reads meanwhile
        for a in arrays.values():
            a[k, h.first:stop] = _between(a[k, h.first - 1], a[k, stop], h.count)
    if predict:
        ok = np.logical_not(lost.any(axis=0))
        for k in map(int, np.nonzero(lost.any(axis=1))[0]):
            pred = _predicted(arrays, k, ok)
            for h in (h for h in found if h.sensor == rec.sensors[k]):
                first, stop = h.first, h.first + h.count
                for name, p in pred.items():
                    a = arrays[name]  # the readings themselves at first - 1 and stop
                    a[k, first:stop] = p[first:stop] + _between(
                        a[k, first - 1] - p[first - 1], a[k, stop] - p[stop], h.count)
    filled = lost if rec.filled is None else rec.filled | lost
    return dataclasses.replace(rec, **arrays, filled=filled), found


def _between(before: np.ndarray, after: np.ndarray, count: int) -> np.ndarray:
    """`count` points (count, 3) evenly on the straight line from `before` to `after`,
    both ends left out."""
    w = (np.arange(1, count + 1) / (count + 1))[:, None]
    return (1 - w) * before + w * after
