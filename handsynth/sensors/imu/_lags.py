"""Sensors whose clocks disagree: one stream late against its neighbours on the finger.

Across a hinge (a finger's PIP or DIP, the thumb's IP) the two phalanges turn alike but for
the joint's own rotation about its axis, so the part of each gyro's rate perpendicular to
that axis has the same magnitude in both sensors at every instant: a rotation about the
axis keeps the perpendicular part's length.  A sensor whose stream is late (a wireless
logger's latency or buffering) shows as a shift between the two series, found by their
cross-correlation.  The axis in each sensor's frame is its link frame's x axis (the flexion
axis the calibration rotations gave, :func:`~handsynth.sensors.imu.link_frames`).  The
forearm plate's sensors share one rigid segment: the lengths of their whole rates agree.
So, nearly, do the hand's two sensors: the ring and little fingers' CM joint between them
turns little (palm cupping), and their rates compared whole put them 8.7 ms apart at most
on the 21 simulated recordings of ``python scripts/study_imu_lag.py`` as recorded (either
of them 20 ms late was named on 40 of 42).  The thumb's metacarpal sensor lies across the
thumb's MCP hinge from its proximal phalanx, but its link frame holds the CMC's flexion
axis, not the MCP's: the MCP's axis (the proximal sensor's link-frame x) is turned into the
metacarpal sensor's frame by the two sensors' relative attitude over the still start, from
the gravity and the magnetic field each reads (TRIAD); a recording without magnetometers,
or whose two sensors read the field at angles to gravity :data:`_FIELD_ANGLE_DEG` apart,
leaves that pair out.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..._checks import check_integer
from ...errors import InvalidInputError

__all__ = ["CARRIED", "HINGES", "LATE_S", "RIGID", "delayed", "late_offsets", "late_sensors",
           "realign_late", "sensor_lags"]

#: The sensor pairs either side of a one-axis joint (proximal, distal).
HINGES: tuple[tuple[str, str], ...] = (
    *((f"{f}_proximal", f"{f}_middle") for f in ("index", "middle", "ring", "little")),
    *((f"{f}_middle", f"{f}_distal") for f in ("index", "middle", "ring", "little")),
    ("thumb_proximal", "thumb_distal"),
)
#: Sensor pairs on one rigid segment (the forearm plate), or nearly (the hand's two parts):
#: their whole rates have the same length at every instant, whatever the axes.
RIGID: tuple[tuple[str, str], ...] = (("forearm_1", "forearm_2"), ("forearm_1", "forearm_3"),
                                      ("hand_radial", "hand_ulnar"))
#: Sensor pairs either side of a one-axis joint whose axis only the distal sensor's link
#: frame holds (proximal, distal): the proximal sensor's is carried over by the still start.
CARRIED: tuple[tuple[str, str], ...] = (("thumb_metacarpal", "thumb_proximal"),)
#: A lag warned about, s: 20 ms late put the worst joint at 2.4-3.1 deg against 1.65-2.06
#: as recorded (``python scripts/study_imu_lag.py``).
LATE_S = 0.015
#: Largest lag searched, s; least peak correlation for a pair to be judged (the hand's own
#: turning must show in both series).  At 0.8 two grasp recordings in step were warned of
#: (the middle finger's DIP pair read 19-20 ms late at 0.82-0.87); at 0.9 none of 42, and
#: 397-399 of 420 sensors 20 ms late were named (``python scripts/study_imu_lag.py``).
_MAX_LAG_S = 0.2
_MIN_CORRELATION = 0.9
#: Largest difference of the field's angle to gravity, deg, between the two sensors of a
#: :data:`CARRIED` pair for the still start to carry the axis.  Uncorrected, a field offset of
#: 30 uT on one sensor (a magnet) turned the axis enough to read a recording in step 19 ms
#: late; with the sensor calibration the two sensors read the angle within 0.2-3.5 deg on the
#: tuning configuration's and six held-out draws' free motions (1.6-13.6 deg uncorrected), and
#: offsets of 5-60 uT that passed read within 12 ms (``docs/imu.md``).
_FIELD_ANGLE_DEG = 5.0


def sensor_lags(rec, frames: dict, *, static_n: int, still=None) -> dict:
    """How late each hinge's distal sensor reads against its proximal one, each forearm
    plate sensor against ``forearm_1`` and ``hand_ulnar`` against ``hand_radial``.

    Parameters
    ----------
    rec : ImuRecording
    frames : dict
        Sensor -> (3, 3) rotation from sensor frame to link frame (a calibration's
        ``frames``).
    static_n : int, keyword-only
        Samples of the still start (the gyros' bias).
    still : ImuRecording, keyword-only, optional
        The still start's readings (of `rec`'s sensors, at least) where `rec` does not begin
        with them (a later stretch of a stream): the gyros' bias and the carried axis are
        read from its first `static_n` samples instead of `rec`'s.

    Returns
    -------
    dict
        ``(proximal, distal)`` -> ``(lag_s, correlation)`` for every pair of :data:`HINGES`
        both of whose sensors `rec` and `frames` hold, of :data:`CARRIED` whose sensors `rec`
        holds with magnetometers and whose distal one `frames` holds, and of :data:`RIGID`
        both of whose sensors `rec` holds (their whole rates compared): the shift, s, of the distal sensor's
        series that best matches the proximal one's (positive: the distal sensor late; to a
        fraction of a sample, by a parabola through the peak) and the peak's correlation.
    """
    n = rec.n
    base = rec if still is None else still
    max_lag = max(1, int(round(_MAX_LAG_S * rec.rate_hz)))
    out: dict[tuple[str, str], tuple[float, float]] = {}
    if n < 4 * max_lag:
        return out

    def speed(name: str, axis: np.ndarray | None) -> np.ndarray:
        """The length of the sensor's rate, less its part about `axis` (its own frame),
        centred."""
        k = rec.sensors.index(name)
        w = rec.gyr[k] - base.gyr[base.sensors.index(name), :max(1, static_n)].mean(axis=0)
        if axis is not None:
            w = w - np.outer(w @ axis, axis)
        v = np.linalg.norm(w, axis=1)
        return v - v.mean()

    series = []  # (proximal, distal, proximal's series, distal's series)
    for prox, dist in HINGES + CARRIED:
        if not {prox, dist} <= set(rec.sensors) or dist not in frames:
            continue
        axis = np.asarray(frames[dist], float)[0]  # the link frame's x: the flexion axis
        if (prox, dist) in CARRIED:
            turn = _still_turn(base, prox, dist, static_n)
            if turn is None:
                continue
            prox_axis = turn @ axis
        elif prox in frames:
            prox_axis = np.asarray(frames[prox], float)[0]
        else:
            continue
        series.append((prox, dist, speed(prox, prox_axis), speed(dist, axis)))
    for prox, dist in RIGID:
        if {prox, dist} <= set(rec.sensors):
            series.append((prox, dist, speed(prox, None), speed(dist, None)))
    for prox, dist, a, b in series:
        cor = np.empty(2 * max_lag + 1)
        for i, lag in enumerate(range(-max_lag, max_lag + 1)):
            x, y = (a[:n - lag], b[lag:]) if lag >= 0 else (a[-lag:], b[:n + lag])
            cor[i] = x @ y / max(np.sqrt((x @ x) * (y @ y)), 1e-300)
        i = int(np.argmax(cor))
        shift = 0.0
        if 0 < i < len(cor) - 1:
            den = cor[i - 1] - 2 * cor[i] + cor[i + 1]
            shift = 0.5 * (cor[i - 1] - cor[i + 1]) / den if den < 0 else 0.0
        out[(prox, dist)] = ((i - max_lag + shift) / rec.rate_hz, float(cor[i]))
    return out


def _still_turn(rec, a: str, b: str, static_n: int) -> np.ndarray | None:
    """Rotation from sensor `b`'s frame to sensor `a`'s over the still start, from gravity and
    the magnetic field each reads (TRIAD), or None: without magnetometers, where the two
    vectors nearly align, or where the two sensors do not read one field (its angle to
    gravity :data:`_FIELD_ANGLE_DEG` apart: a magnet or an iron part near one of them, which
    would turn the carried axis)."""
    if rec.mag is None:
        return None
    n = max(1, static_n)
    read = []
    for k in (rec.sensors.index(a), rec.sensors.index(b)):
        g, m = rec.acc[k, :n].mean(axis=0), rec.mag[k, :n].mean(axis=0)
        c = np.cross(g, m)
        if not np.linalg.norm(c) > 0.1 * np.linalg.norm(g) * np.linalg.norm(m):
            return None
        t1, t2 = g / np.linalg.norm(g), c / np.linalg.norm(c)
        dip = np.degrees(np.arccos(np.clip(t1 @ m / np.linalg.norm(m), -1.0, 1.0)))
        read.append((np.column_stack([t1, t2, np.cross(t1, t2)]), dip))
    (ta, dip_a), (tb, dip_b) = read
    return None if abs(dip_a - dip_b) > _FIELD_ANGLE_DEG else ta @ tb.T


def late_sensors(rec, frames: dict, *, static_n: int, still=None) -> str | None:
    """A warning naming the sensors whose streams are late or early, or None.

    `rec`, `frames`, `static_n` and `still` are :func:`sensor_lags`'.
    Pairs whose correlation peaks under 0.9 are not judged (the hand did not turn enough);
    a lag of :data:`LATE_S` or more is named.  A sensor in two such pairs (a middle
    phalanx, between its PIP and DIP) is named as the one off.
    """
    lags = sensor_lags(rec, frames, static_n=static_n, still=still)
    off = {pair: lag for pair, (lag, cor) in lags.items()
           if cor >= _MIN_CORRELATION and abs(lag) >= LATE_S}
    if not off:
        return None
    count: dict[str, int] = {}
    for pair in off:
        for s in pair:
            count[s] = count.get(s, 0) + 1
    parts = []
    for (prox, dist), lag in off.items():
        late, early = (dist, prox) if lag > 0 else (prox, dist)
        parts.append(f"{late} {abs(lag) * 1e3:.0f} ms behind {early}")
    shared = sorted(s for s, c in count.items() if c > 1)
    which = f" ({', '.join(shared)} in two pairs: that sensor's clock)" if shared else ""
    return (f"sensor streams out of step: {'; '.join(parts)}{which}, judged by the turn of the "
            "phalanges either side of a finger's hinge joint (of the forearm plate's sensors and "
            "the hand's two, by their common turn); a late stream reads its joints "
            "several degrees off (20 ms: 2-3 deg, 100 ms: 9-13 deg at the joint): keep the "
            "sensors' clocks within about 15 ms of each other. A recording made so can be read "
            "realigned by the lags found: imu track --realign-late (library: track(..., "
            "realign_late=True); not the hand's two sensors against each other)")


def late_offsets(rec, frames: dict, *, static_n: int) -> tuple[dict[str, float], list]:
    """How late each sensor's stream is, s, where the pairs :func:`sensor_lags` judges tell it.

    The pairs join the sensors into chains (a finger's phalanges, the thumb's metacarpal and
    phalanges, the forearm plate about ``forearm_1``, the hand's two sensors); a lag says
    only how much later one sensor of a pair reads than the other, so each chain's times are
    read as the fewest sensors off: with each sensor of the chain in turn taken as on time,
    the lags of the others follow along the chain, and the assignment that puts the fewest
    of them :data:`LATE_S` or more off is kept, where it is the only one so (a middle
    phalanx late reads late against both neighbours: it alone is off; a proximal phalanx
    late reads early against the middle one and the middle and distal ones agree: it alone
    is off).  A chain of two sensors whose lag is off (the hand's two, or a finger of which
    one pair was judged) has two such readings and is left as it is.

    Parameters
    ----------
    rec, frames, static_n
        As :func:`sensor_lags`'.

    Returns
    -------
    offsets : dict
        Sensor -> how late its stream reads, s (positive: late), for the sensors read as
        off.
    undecided : list of tuple of str
        The chains with a lag off that could not be assigned to one reading.
    """
    lags = {pair: lag for pair, (lag, cor) in sensor_lags(rec, frames, static_n=static_n).items()
            if cor >= _MIN_CORRELATION}
    links: dict[str, list[tuple[str, float]]] = {}
    for (prox, dist), lag in lags.items():   # lag: how much later `dist` reads than `prox`
        links.setdefault(prox, []).append((dist, lag))
        links.setdefault(dist, []).append((prox, -lag))
    offsets: dict[str, float] = {}
    undecided: list = []
    seen: set = set()
    for start in sorted(links, key=rec.index):
        if start in seen:
            continue
        chain = _reach(links, start)
        seen |= set(chain)
        if all(abs(lag) < LATE_S for (a, _), lag in lags.items() if a in chain):
            continue
        readings: dict[frozenset, list[dict]] = {}
        for ref in chain:       # `ref` on time: the others' lags along the chain
            late = {s: t for s, t in _reach(links, ref).items() if abs(t) >= LATE_S}
            readings.setdefault(frozenset(late), []).append(late)
        fewest = min(len(off) for off in readings)
        best = [off for off in readings if len(off) == fewest]
        if len(best) == 1:    # (the lags as the references that read so read them, averaged)
            offsets.update({s: float(np.mean([r[s] for r in readings[best[0]]])) for s in best[0]})
        else:
            undecided.append(tuple(sorted(chain, key=rec.index)))
    return offsets, undecided


def _reach(links: dict, start: str) -> dict[str, float]:
    """Every sensor `links` joins to `start`, with its lag against `start` (0 for `start`)."""
    out = {start: 0.0}
    todo = [start]
    while todo:
        a = todo.pop()
        for b, lag in links.get(a, ()):
            if b not in out:
                out[b] = out[a] + lag
                todo.append(b)
    return out


def realign_late(rec, offsets: dict):
    """`rec` with the streams of `offsets` read earlier by their lags (:func:`late_offsets`).

    Each sensor's accelerometer, gyro and magnetometer readings are read `offset` seconds
    later in its stream (linearly between samples); where that runs past the recording's
    end (or, for a stream early, before its start) the stream is read back from the end
    (the start) as in a mirror, not held (a reading held for 0.1 s reads as samples lost),
    and those samples are marked filled (:attr:`ImuRecording.filled`: Filter 4 loosens the
    sensor's attitude over them).

    Parameters
    ----------
    rec : ImuRecording
    offsets : dict
        Sensor -> how late its stream reads, s (negative: early).

    Returns
    -------
    ImuRecording
        A copy (unchecked, as a copy made with :func:`dataclasses.replace` is).
    """
    n = rec.n
    t = np.arange(n, dtype=float)
    out = {name: getattr(rec, name).copy() for name in ("acc", "gyr", "mag")
           if getattr(rec, name) is not None}
    filled = np.zeros((len(rec.sensors), n), bool) if rec.filled is None else rec.filled.copy()
    for sensor, lag_s in offsets.items():
        k = rec.index(sensor)
        src = t + float(lag_s) * rec.rate_hz
        beyond = (src > n - 1) | (src < 0)
        src = np.abs(src)
        src = np.where(src > n - 1, 2 * (n - 1) - src, src)
        for name, a in out.items():
            old = getattr(rec, name)[k]
            a[k] = np.column_stack([np.interp(src, t, old[:, c]) for c in range(3)])
        filled[k] |= beyond
    return dataclasses.replace(rec, **out, filled=filled if filled.any() else rec.filled)


def delayed(rec, sensor: str, samples: int):
    """`rec` with one sensor's stream `samples` late, as a wireless logger may deliver it.

    For trying :func:`late_sensors` and measuring what a lag costs.  The sensor's first
    `samples` readings are the ones that follow them (in a recording's still start, readings
    alike but not repeated bit for bit, which would read as samples lost).

    Parameters
    ----------
    rec : ImuRecording
    sensor : str
        One of ``rec.sensors``.
    samples : int
        The delay, samples, from 1 to half the recording.

    Returns
    -------
    ImuRecording
        A new recording (truth kept: it is the motion's, which the delay does not change).

    Raises
    ------
    InvalidInputError
        A sensor `rec` does not hold; `samples` out of range.
    """
    if sensor not in rec.sensors:
        raise InvalidInputError(f"sensor {sensor!r} is not in the recording "
                                f"({', '.join(rec.sensors)})")
    lag = check_integer(samples, "samples", minimum=1, maximum=max(1, rec.n // 2))
    k = rec.sensors.index(sensor)
    out = {}
    for name in ("acc", "gyr", "mag"):
        a = getattr(rec, name)
        if a is None:
            continue
        b = a.copy()
        b[k, lag:] = a[k, :-lag]
        b[k, :lag] = a[k, lag:2 * lag]
        out[name] = b
    return dataclasses.replace(rec, **out)
