"""Filter 4 on a live stream: readings in as they come, joint angles out one sample later.

:meth:`ImuCalibration.track` reads a whole recording.  A live user (a robot hand
teleoperated, an avatar in VR) has the readings one sample, or one packet, at a time.
:class:`ImuStream` runs the same filter on them: it gathers the static start (and the
common rotation, if one is set), takes from it what the filter takes (gyro biases,
initial attitudes, the compass's static field; :meth:`ChainEKF.prepare`), then filters
every sample as soon as the next one has come, since the gyro's derivative at a sample
is the central difference of its neighbours, as in :func:`numpy.gradient`.  The answers
equal :meth:`ImuCalibration.track`'s on the same readings (tested to 1e-7 deg); the last
sample, which has no next one, is finished by :meth:`ImuStream.close` with the one-sided
difference, as :func:`numpy.gradient` does at a recording's end.

The checks :meth:`ImuCalibration.track` makes of a whole recording (sensors exchanged or
turned since the calibration, streams out of step, joint angles beyond the hand's range in
a share of the samples) are made of each stretch of `check_s` seconds of the stream as soon as it
has been read, and what they find is warned of once, with the stretch's times.  What a
whole recording allows and a stream does not: the check of the axes' conventions (it
needs turns about every axis, which one stretch may lack; run ``imu track`` on one
recording of the logger) and the bridging of lost samples from both sides.  The static
start is checked as :func:`check_recording` checks a recording;
afterwards a reading that is not finite (a lost packet) is filled in from the other
sensors' readings (`max_hold_s`) and marked (Filter 4 loosens that sensor's attitude
meanwhile, as for a bridged gap); a longer loss stops the stream with an error naming the
sensor.
"""

from __future__ import annotations

import dataclasses
import re
import warnings
from dataclasses import dataclass, field

import numpy as np

from ..._checks import check_instance, check_number, check_options
from ..._csv import column_index, row_numbers, stream_rows
from ...errors import HandsynthError, RecordingError
from ._attitude import StaticStart, check_static_fits
from ._calibration import ImuCalibration
from ._ekf import ChainEKF, ChainEKFOptions, FilterStart, fast_turns, observed_field
from ._kinematics import angles_beyond_range
from ._lags import late_sensors
from ._lost import prediction_coefficients, prediction_regressors
from ._recording import UNITS, ImuRecording, check_rate, check_recording, check_units
from ._recording import _columns as _csv_columns
from ._swaps import misplaced_sensors

__all__ = ["ImuStream", "StreamState", "TrackedSamples", "stream_csv"]

#: Seconds of readings (every sensor read) a lost sensor's prediction is fitted on, and the
#: fewest samples it is fitted on (below, the reading is held): three per coefficient of
#: 20 sensors' regression (58).
_HISTORY_S = 10.0
_MIN_FIT_SAMPLES = 174
#: The shortest stretch checked, s (``check_s``; at the end of a stream, what is left).
_MIN_CHECK_S = 5.0
#: Time steps a streamed CSV's rate is judged on, and the largest share its median step may
#: differ by from the period of the rate given (a logger's jitter and millisecond stamps
#: stay well within it; a rate given as half or double the logger's does not).
_RATE_STEPS = 20
_RATE_TOLERANCE = 0.1


@dataclass(frozen=True, eq=False)
class TrackedSamples:
    """The samples an :class:`ImuStream` has finished.

    Attributes
    ----------
    t_s : ndarray, shape (M,), float64
        Each sample's time, s (``start_s + i / rate_hz``).
    quat : ndarray, shape (S, M, 4), float64
        Sensor-to-world quaternions (w, x, y, z), the calibration's sensors in its order.
    angles_deg : ndarray, shape (M, 20), float64
        Joint angles, canonical order (:data:`~handsynth.models.JOINT_NAMES`).
    tips_m : dict
        Finger -> (M, 3) fingertip positions from the elbow, metres (eq. 3.12).
    held : ndarray, shape (S, M), bool
        The sensors whose readings were lost at that sample and filled in (predicted from
        the other sensors', or held), on which the answers there rest.
    """

    t_s: np.ndarray
    quat: np.ndarray
    angles_deg: np.ndarray
    tips_m: dict
    held: np.ndarray

    def __len__(self) -> int:
        return len(self.t_s)


@dataclass(eq=False)
class StreamState:
    """The running state of an :class:`ImuStream` (its options stay in the stream).

    Attributes
    ----------
    six_axis : bool or None
        Whether the pushes carry no magnetometer (None before the first).
    warmup : list of tuple
        The raw (acc, gyr, mag) blocks of the static start, until it is read.
    start : FilterStart or None
        What the filter took from the static start, once read.
    filter : tuple
        The filter's state after the last sample finished: attitudes (S, 4), covariance
        (3S + 3, 3S + 3), learnt gyro biases (S, 3).
    done : int
        Samples finished.
    tail : dict
        ``acc``, ``gyr`` (bias removed), ``mag``, ``filled``: the samples from the last
        finished one on, corrected.
    last_raw : tuple of ndarray
        Each sensor's last reading that was finite (acc, gyr[, mag]), shape (S, 3) each.
    held_run : ndarray, shape (S,), int
        Readings held in a row now, per sensor.
    held_count : ndarray, shape (S,), int
        Readings held since the start, per sensor.
    warned : set of str
        Warnings given once already (the plate fusion's, the stretches' checks').
    history : dict
        ``acc``, ``gyr`` (S, H, 3): the last H samples in which every sensor read (a ring,
        ``next`` the count written), which a lost sensor's readings are predicted from.
    models : dict
        Lost sensor -> its prediction's coefficients and what they missed at its last
        reading, while it is lost.
    still : ImuRecording or None
        The static start's readings, corrected, once read (the checks' gyro biases).
    stretch : dict
        The stretch being gathered for the checks: ``first`` (its first sample's index),
        ``acc``, ``gyr`` (lists of (S, n, 3) blocks, corrected) and ``angles`` (the answers
        given of it so far, (n, 20) blocks).
    read : int
        Samples read since the start.
    closed : bool
    """

    held_run: np.ndarray
    held_count: np.ndarray
    six_axis: bool | None = None
    warmup: list = field(default_factory=list)
    start: FilterStart | None = None
    filter: tuple = ()
    done: int = 0
    tail: dict = field(default_factory=dict)
    last_raw: tuple = ()
    warned: set = field(default_factory=set)
    history: dict = field(default_factory=dict)
    models: dict = field(default_factory=dict)
    still: ImuRecording | None = None
    stretch: dict = field(default_factory=lambda: {"first": 0, "acc": [], "gyr": [], "angles": []})
    read: int = 0
    closed: bool = False


class ImuStream:
    """Filter 4 (:meth:`ImuCalibration.track`) on readings as they come.

    Parameters
    ----------
    calibration : ImuCalibration
    rate_hz : float, keyword-only
        The sensors' sampling rate, Hz.
    static : StaticStart, keyword-only, optional
        The still start (default 2 s) and the common rotation, as for ``track``: no
        answer comes before both have been read.
    options : ChainEKFOptions, keyword-only, optional
        Filter 4's options (the thesis' filter by default).
    sensor_calibration : bool, keyword-only
        Correct the readings by the calibration's sensor calibration (if it holds one).
    plate_fusion : bool, keyword-only
        Fuse the forearm plate's attitudes (:meth:`ImuCalibration.fuse`).
    start_s : float, keyword-only
        Time of the first sample, s.
    max_hold_s : float, keyword-only
        Longest run of readings of one sensor that are not finite which the stream fills
        in, s (default 0.5, as :func:`bridge_lost`'s): its accelerometer and gyro predicted
        from the other sensors' readings of the last 10 s by :func:`bridge_lost`'s
        regression, plus what the prediction missed at its last reading; its magnetometer
        (and, before 174 samples were read, everything) held at its last reading.  On the
        held-out configuration (``python scripts/study_imu_stream.py``: 15-s free motions,
        one sensor lost at a random time, 12 losses of each length) the worst joint's RMSE
        over the trial was 1.88 deg as recorded, 1.88 with 0.1 or 0.2 s lost, 1.93 with 0.3 s,
        2.33 with 0.5 s (up to 4.76) and 2.46 with 1 s; bridging the whole recording
        afterwards (both sides of the gap) 1.88-2.35.  Holding the last reading instead
        read 1.97 with 0.2 s, 2.63 with 0.3 s and 6.40 with 0.5 s (up to 25.1).
    check_s : float or None, keyword-only
        Length of the stretches checked as ``track`` checks a recording, s (default 20;
        at least 5; None: not checked).  The push that completes a stretch checks it
        (about 0.3 s for 20 sensors over 20 s, two thirds of it the exchanged sensors' check),
        and :meth:`close` what is left of the last one if it spans 5 s or more; each
        finding is warned of once for the stream.

    Warns
    -----
    UserWarning
        What the checks of :meth:`ImuCalibration.track` find in a stretch of `check_s`
        seconds: sensors exchanged (:func:`swapped_sensors`) or turned on their segments
        (:func:`turned_sensors`), streams out of step (:func:`late_sensors`), joint angles
        beyond the hand's range (:func:`angles_beyond_range`); the static start's findings
        (:func:`check_recording`); a plate sensor straying from the others.

    Examples
    --------
    >>> stream = ImuStream(calibration, rate_hz=100.0)        # doctest: +SKIP
    >>> for acc, gyr, mag in packets:                           # doctest: +SKIP
    ...     done = stream.push(acc, gyr, mag)                   # (S, n, 3) each
    ...     send(done.angles_deg)                               # (M, 20), M may be 0
    >>> send(stream.close().angles_deg)                         # doctest: +SKIP
    """

    def __init__(self, calibration: ImuCalibration, *, rate_hz: float,
                 static: StaticStart | None = None, options: ChainEKFOptions | None = None,
                 sensor_calibration: bool = True, plate_fusion: bool = True,
                 start_s: float = 0.0, max_hold_s: float = 0.5,
                 check_s: float | None = 20.0) -> None:
        check_instance(calibration, ImuCalibration, name="calibration")
        self.calibration = calibration
        self.rate_hz = check_rate(rate_hz, source="ImuStream")
        self._filter = ChainEKF(calibration.model, options=check_options(options, ChainEKFOptions),
                                static=check_options(static, StaticStart, name="static"))
        self.sensor_calibration = bool(sensor_calibration)
        self.plate_fusion = bool(plate_fusion)
        self.start_s = check_number(start_s, "start_s")
        self.max_hold = max(1, int(round(check_number(max_hold_s, "max_hold_s", above=0)
                                         * self.rate_hz)))
        self.check_n = None if check_s is None else int(round(
            check_number(check_s, "check_s", minimum=_MIN_CHECK_S) * self.rate_hz))
        static = self._filter.static
        ends = [static.static_s] + ([] if static.align_end_s is None else [static.align_end_s])
        #: samples read before the filter starts: the static start and the common rotation
        #: (as many as :func:`gyro_bias` and :func:`azimuth_correction` read), and one more
        self.warmup_n = max(max(1, round(t * self.rate_hz)) for t in ends) + 1
        s = len(calibration.sensors)
        h = max(1, round(_HISTORY_S * self.rate_hz))
        self.state = StreamState(held_run=np.zeros(s, int), held_count=np.zeros(s, int),
                                 history={"acc": np.zeros((s, h, 3)), "gyr": np.zeros((s, h, 3)),
                                          "next": 0})

    @property
    def sensors(self) -> tuple:
        """The sensors' names, the order of the rows of every array in and out."""
        return self.calibration.sensors

    @property
    def tracking(self) -> bool:
        """Whether the static start has been read and the filter runs."""
        return self.state.start is not None

    # -- input -----------------------------------------------------------------------

    def _as_block(self, name: str, value, n: int | None) -> np.ndarray:
        given = np.asarray(value, dtype=np.float64)
        a = given[:, None, :] if given.ndim == 2 else given
        s = len(self.sensors)
        if a.ndim != 3 or a.shape[0] != s or a.shape[2] != 3 or (n is not None and a.shape[1] != n):
            want = f"({s}, 3) or ({s}, n, 3)" + ("" if n is None else f" with n = {n}")
            raise RecordingError(f"{name} has shape {given.shape}, expected {want}: one row per "
                                 f"sensor of the calibration, in its order ({self.sensors[0]}, "
                                 f"{self.sensors[1]}, ...)")
        return a

    def push(self, acc, gyr, mag=None) -> TrackedSamples:
        """Read one or more samples; return those that could be finished.

        Parameters
        ----------
        acc : array_like, shape (S, 3) or (S, n, 3)
            Accelerometer, m/s^2, one row per sensor in :attr:`sensors`' order.
        gyr : array_like, the same shape
            Gyro, rad/s.
        mag : array_like, the same shape, or None
            Magnetometer, uT; None for 6-axis sensors (then in every push).

        Returns
        -------
        TrackedSamples
            The samples finished by this push, in order: none during the static start,
            then every sample but the last one read.

        Raises
        ------
        RecordingError
            Arrays of the wrong shape; a magnetometer given in some pushes and not in
            others; the static start refused by :func:`check_recording` (raised by the push
            that completes it); a sensor's readings not finite for longer than
            `max_hold_s`; a push after :meth:`close` or after an error other than the
            arrays' shapes (which closes the stream).
        EstimationError
            The static start gives no attitudes (6-axis sensors without a common
            rotation; :func:`initial_attitude`).
        """
        if self.state.closed:
            raise RecordingError("the stream is closed (by close(), or by the error that "
                                 "stopped it): make a new ImuStream")
        acc = self._as_block("acc", acc, None)
        n = acc.shape[1]
        gyr = self._as_block("gyr", gyr, n)
        six = mag is None
        if self.state.six_axis is None:
            self.state.six_axis = six
        elif six != self.state.six_axis:
            raise RecordingError("mag given in some pushes and not in others: give every "
                                 "sensor's magnetometer in every push, or never (6-axis)")
        mag = None if six else self._as_block("mag", mag, n)
        if n == 0:
            return self._empty()
        try:
            return self._read(acc, gyr, mag, n)
        except HandsynthError:
            self.state.closed = True         # its state is part-way through a sample
            raise

    def _read(self, acc, gyr, mag, n: int) -> TrackedSamples:
        if self.state.start is not None:
            return self._advance(self._correct(*self._hold(acc, gyr, mag)))
        # the warm-up's samples; any after them in this push go on as later pushes' would
        need = self.warmup_n - sum(a.shape[1] for a, _, _ in self.state.warmup)
        self.state.warmup.append((acc[:, :need], gyr[:, :need],
                                  None if mag is None else mag[:, :need]))
        if n < need:
            return self._empty()
        first = self._begin()
        if n == need:
            return first
        later = self._hold(acc[:, need:], gyr[:, need:], None if mag is None else mag[:, need:])
        return _join(first, self._advance(self._correct(*later)))

    def close(self) -> TrackedSamples:
        """Finish the last sample read (its gyro derivative one-sided) and close the stream.

        What is left of the last stretch is checked if it spans 5 s or more (`check_s`).

        Raises
        ------
        RecordingError
            The stream ended before its static start (and common rotation) were read.
        """
        if self.state.closed:
            return self._empty()
        self.state.closed = True
        if self.state.start is None:
            got = sum(a.shape[1] for a, _, _ in self.state.warmup)
            raise RecordingError(
                f"the stream ended after {got} samples, before its static start and common "
                f"rotation ({self.warmup_n} samples at {self.rate_hz:g} Hz) were read")
        return self._advance(None)

    # -- the filter --------------------------------------------------------------------

    def _empty(self) -> TrackedSamples:
        s = len(self.sensors)
        return TrackedSamples(np.empty(0), np.empty((s, 0, 4)), np.empty((0, 20)), {},
                              np.zeros((s, 0), bool))

    def _correct(self, block: ImuRecording, filled: np.ndarray | None) -> ImuRecording:
        rec = self.calibration.correct(block, sensor_calibration=self.sensor_calibration)
        return dataclasses.replace(rec, filled=filled)

    def _hold(self, acc, gyr, mag) -> tuple[ImuRecording, np.ndarray]:
        """Readings that are not finite filled in: the sensor's accelerometer and gyro
        predicted from the other sensors' readings (:meth:`_fill`), its magnetometer held."""
        chans = [acc, gyr] + ([] if mag is None else [mag])
        bad = np.zeros(acc.shape[:2], bool)
        for c in chans:
            bad |= ~np.isfinite(c).all(axis=-1)
        st = self.state
        if bad.any():
            chans = [c.copy() for c in chans]
            for i in range(acc.shape[1]):
                for k in np.flatnonzero(bad[:, i]):
                    st.held_run[k] += 1
                    if st.held_run[k] > self.max_hold:
                        index = st.done - 1 + st.tail["gyr"].shape[1] + i
                        t = self.start_s + index / self.rate_hz
                        raise RecordingError(
                            f"sensor {self.sensors[k]}: readings not finite for more than "
                            f"{self.max_hold / self.rate_hz:g} s (max_hold_s), at t = {t:.3f} s: "
                            "a sensor lost; the stream stops")
                    for c, last in zip(chans, st.last_raw):
                        c[k, i] = last[k]
                if bad[:, i].any():
                    self._fill(chans, i, bad[:, i])
                else:
                    self._remember(chans, i)
                for k in np.flatnonzero(~bad[:, i]):
                    st.held_run[k] = 0
                    st.models.pop(int(k), None)
                st.last_raw = tuple(c[:, i].copy() for c in chans)
            st.held_count += bad.sum(axis=1)
        else:
            st.held_run[:] = 0
            st.models.clear()
            for i in range(max(0, acc.shape[1] - st.history["acc"].shape[1]), acc.shape[1]):
                self._remember(chans, i)
            st.last_raw = tuple(c[:, -1].copy() for c in chans)
        rec = ImuRecording(self.rate_hz, self.sensors, chans[0], chans[1],
                           None if mag is None else chans[2])
        return rec, bad

    def _remember(self, chans, i: int) -> None:
        """Sample `i` of the readings (every sensor read) kept for the predictions."""
        h = self.state.history
        j = h["next"] % h["acc"].shape[1]
        h["acc"][:, j], h["gyr"][:, j] = chans[0][:, i], chans[1][:, i]
        h["next"] += 1

    def _fill(self, chans, i: int, bad: np.ndarray) -> None:
        """Sample `i` of the lost sensors `bad` predicted from the others (the regression of
        :func:`bridge_lost`, fitted on the last :data:`_HISTORY_S` seconds in which every
        sensor read, when there are enough of them), plus what the prediction missed at
        the sensor's last reading; else held (as filled in by the caller)."""
        st, h = self.state, self.state.history
        n = min(h["next"], h["acc"].shape[1])
        arrays = {"acc": h["acc"][:, :n], "gyr": h["gyr"][:, :n]}
        for k in map(int, np.flatnonzero(bad)):
            if k not in st.models:
                if n < _MIN_FIT_SAMPLES:
                    continue                 # too little seen yet: the reading held
                coef = prediction_coefficients(arrays, k, slice(None))
                # what the prediction misses at the last reading, carried on
                miss = {c: st.last_raw[m][k] - prediction_regressors(
                    st.last_raw[m][:, None], k)[0] @ coef[c]
                    for m, c in enumerate(("acc", "gyr"))}
                st.models[k] = (coef, miss)
            coef, miss = st.models[k]
            for m, c in enumerate(("acc", "gyr")):
                x = prediction_regressors(chans[m][:, i:i + 1], k)[0]
                chans[m][k, i] = x @ coef[c] + miss[c]

    def _begin(self) -> TrackedSamples:
        """The warm-up read: check it, prepare the filter, filter it but its last sample."""
        blocks, self.state.warmup = self.state.warmup, []
        acc = np.concatenate([a for a, _, _ in blocks], axis=1)
        gyr = np.concatenate([g for _, g, _ in blocks], axis=1)
        mag = None if self.state.six_axis else np.concatenate([m for _, _, m in blocks], axis=1)
        raw = ImuRecording(self.rate_hz, self.sensors, acc, gyr, mag, start_s=self.start_s)
        rec = self._correct(raw, None)
        static_s = self._filter.static.static_s
        check_static_fits(rec, static_s)
        # the axes are judged on whole recordings (imu calibrate, imu track): a static start
        # and one common rotation turn about one axis, which leaves the others unseen
        for w in check_recording(rec, static_s=static_s, axes=False, source="stream"):
            warnings.warn(w, UserWarning, stacklevel=3)
        self.state.last_raw = (acc[:, -1].copy(), gyr[:, -1].copy()) + (
            () if mag is None else (mag[:, -1].copy(),))
        for i in range(max(0, acc.shape[1] - self.state.history["acc"].shape[1]), acc.shape[1]):
            self._remember((acc, gyr), i)
        n = max(1, round(static_s * self.rate_hz))
        self.state.still = ImuRecording(self.rate_hz, self.sensors, rec.acc[:, :n], rec.gyr[:, :n],
                                        None if rec.mag is None else rec.mag[:, :n])
        start = self._filter.prepare(rec)
        self.state.start = start
        self.state.filter = (start.q0, start.covariance, np.zeros((len(self.sensors), 3)))
        first = self._outputs(start.q0[:, None], 0, np.zeros((len(self.sensors), 1), bool))
        # sample 0 is the first finished one (its attitude q0), the last of an empty tail
        s = len(self.sensors)
        self.state.tail = {"acc": np.empty((s, 0, 3)), "gyr": np.empty((s, 0, 3)),
                           "mag": np.empty((s, 0, 3)), "filled": np.empty((s, 0), bool)}
        self.state.done = 1
        return _join(first, self._advance(rec))

    def _advance(self, rec: ImuRecording | None) -> TrackedSamples:
        """Append `rec` (None: the end) and filter every sample whose next one is read."""
        from ._ekf_numba import run_fast

        tail, start, o = self.state.tail, self.state.start, self._filter.options
        assert start is not None  # push and close call this once the warm-up is read
        if rec is not None:
            self.state.read += rec.n
            if self.check_n is not None:
                self.state.stretch["acc"].append(rec.acc)
                self.state.stretch["gyr"].append(rec.gyr)
            tail["acc"] = np.concatenate([tail["acc"], rec.acc], axis=1)
            filled = np.zeros(rec.gyr.shape[:2], bool) if rec.filled is None else rec.filled
            gyr = rec.gyr - start.gyro_bias[:, None]
            tail["gyr"] = np.concatenate([tail["gyr"], gyr], axis=1)
            tail["mag"] = np.concatenate([tail["mag"], observed_field(rec)], axis=1)
            tail["filled"] = np.concatenate([tail["filled"], filled], axis=1)
        g = tail["gyr"]
        n = g.shape[1]                       # sample 0: the last finished one
        m = n - 1 if rec is None else n - 2  # samples finished now
        if m <= 0:
            return self._empty()
        dt = 1.0 / self.rate_hz
        # the gyro's derivative as numpy.gradient takes it over a whole recording: central
        # differences, one-sided at the recording's end; sample 0's is not read
        dg = np.zeros_like(g[:, : m + 1])
        c = min(m, n - 2)                    # samples whose next one is read
        dg[:, 1:c + 1] = (g[:, 2:c + 2] - g[:, 0:c]) / (2.0 * dt)
        if rec is None:
            dg[:, m] = (g[:, m] - g[:, m - 1]) / dt
        q, p, bias = self.state.filter
        out, (p, bias) = run_fast(start.tree, q, (p, bias), g[:, : m + 1], dg,
                                  tail["acc"][:, : m + 1], tail["mag"][:, : m + 1], dt, start.mh,
                                  start.fnorm0, start.rz, fast_turns(g[:, : m + 1], o),
                                  tail["filled"][:, : m + 1], o)
        self.state.filter = (out[:, -1], p, bias)
        held = tail["filled"][:, 1:m + 1]
        for k in tail:
            tail[k] = tail[k][:, m:]
        done = self._outputs(out[:, 1:], self.state.done, held)
        self.state.done += m
        if self.check_n is not None:
            self.state.stretch["angles"].append(done.angles_deg)
            left = self.state.read - self.state.stretch["first"]
            # a stretch is checked once read; at the end, what is left if it is long enough
            if left >= self.check_n or (rec is None and left >= _MIN_CHECK_S * self.rate_hz):
                self._check()
        return done

    def _check(self) -> None:
        """The checks of :meth:`ImuCalibration.track` on the stretch read since the last;
        each finding warned of once for the stream."""
        st, cal = self.state, self.calibration
        stretch, first = st.stretch, st.stretch["first"]
        st.stretch = {"first": st.read, "acc": [], "gyr": [], "angles": []}
        rec = ImuRecording(self.rate_hz, self.sensors, np.concatenate(stretch["acc"], axis=1),
                           np.concatenate(stretch["gyr"], axis=1), None)
        assert st.still is not None  # the warm-up is read before any stretch
        said = (angles_beyond_range(np.concatenate(stretch["angles"])),
                *misplaced_sensors(rec, cal.model, cal.frames),
                late_sensors(rec, cal.frames, static_n=st.still.n, still=st.still))
        t0, t1 = (self.start_s + i / self.rate_hz for i in (first, st.read))
        for message in filter(None, said):
            # one finding, whatever the figures it measured in each stretch
            self._say_once(re.sub(r"(?<![\w.])[-+]?\d[\d.]*", "#", message),
                           f"the stream's {t0:.1f}-{t1:.1f} s: {message}")

    def _say_once(self, key: str, message: str) -> None:
        """Warn of `message` unless a message of the same `key` was warned of already."""
        if key not in self.state.warned:
            self.state.warned.add(key)
            warnings.warn(f"{message} (said once for this stream)", UserWarning, stacklevel=5)

    def _outputs(self, q: np.ndarray, first: int, held: np.ndarray) -> TrackedSamples:
        """Fused attitudes, joint angles and fingertips of samples ``first ..``."""
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            out = self.calibration.read_attitudes(q, self.sensors, plate_fusion=self.plate_fusion)
        for w in caught:                     # a plate sensor straying: said once a stream
            self._say_once(str(w.message).split("(")[0], str(w.message))
        t = self.start_s + (first + np.arange(q.shape[1])) / self.rate_hz
        return TrackedSamples(t, out["quat"], out["angles"], out["tips"], held)


def _join(a: TrackedSamples, b: TrackedSamples) -> TrackedSamples:
    if not len(a) or not len(b):
        return b if len(b) else a
    return TrackedSamples(np.concatenate([a.t_s, b.t_s]), np.concatenate([a.quat, b.quat], axis=1),
                          np.concatenate([a.angles_deg, b.angles_deg]),
                          {f: np.concatenate([a.tips_m[f], b.tips_m[f]]) for f in a.tips_m},
                          np.concatenate([a.held, b.held], axis=1))


def stream_csv(lines, calibration: ImuCalibration, *, rate_hz: float, acc_units: str = "m/s2",
               gyr_units: str = "rad/s", mag_units: str = "uT", source: str = "stream",
               **options):
    """Track CSV lines as they come: a header, then one sample a line.

    The columns are :func:`read_imu_csv`'s (``<sensor>_acc_x`` .. ``_mag_z`` of every
    sensor of the calibration, in any order; other columns are passed over), separated by
    commas, or as the header is: by semicolons (decimal commas then read as points) or tabs;
    quotes around a cell are dropped.  Samples are
    taken to come at `rate_hz`; with a time column (``time_s`` or ``time_ms``) the first
    stamp is the stream's ``start_s``, a step of more than half a period over the
    sampling period is samples lost, filled in as :class:`ImuStream` fills a sensor's
    lost readings (all sensors' here), and the median of the first 20 steps must be within
    10 % of the period (a rate given wrong is refused before any answer).  An empty cell is
    a reading lost.

    Parameters
    ----------
    lines : iterable of str
        The header first (lines starting with ``#`` and blank lines are passed over).
    calibration : ImuCalibration
    rate_hz : float, keyword-only
    acc_units, gyr_units, mag_units : str, keyword-only
        One of :data:`UNITS` for each channel.
    source : str, keyword-only
        The input's name, for messages.
    **options
        Passed to :class:`ImuStream` (``static``, ``options``, ``sensor_calibration``,
        ``max_hold_s``, ...).

    Yields
    ------
    TrackedSamples
        What each line (and, at the end, :meth:`ImuStream.close`) finished.

    Raises
    ------
    RecordingError
        Unknown units; a header without a calibrated sensor's columns; a line whose
        number of cells is not the header's, or a cell that is no number (naming the line
        and the column); time stamps that go back or repeat, or that leave out more than
        `max_hold_s`; time stamps that step by under half the period of `rate_hz`, or whose
        first 20 steps' median is more than 10 % off it; what :class:`ImuStream` raises.
    """
    units = {"acc": acc_units, "gyr": gyr_units, "mag": mag_units}
    check_units(**units)
    stream: ImuStream | None = None
    header: list[str] | None = None
    idx: dict = {}
    time_col: int | None = None
    last_t, scale = 0.0, 1.0
    steps: list[float] = []
    for number, cells in stream_rows(lines):
        if header is None:
            header = cells
            col = column_index(header, path=source, line=number)
            col, sensors, time_name, _, _ = _csv_columns(header, col, source)
            missing = [s for s in calibration.sensors if s not in sensors]
            if missing:
                raise RecordingError(f"{source}, line {number}: no columns of the calibration's "
                                     f"sensor(s) {', '.join(missing[:4])} ({missing[0]}_acc_x ..)")
            six = not any(f"{s}_mag_x" in col for s in sensors)
            idx = {ch: np.array([[col[f"{s}_{ch}_{a}"] for a in "xyz"] for s in calibration.sensors])
                   for ch in (("acc", "gyr") if six else ("acc", "gyr", "mag"))}
            time_col = None if time_name is None else col[time_name]
            scale = 1e-3 if time_name == "time_ms" else 1.0
            continue
        if len(cells) != len(header):
            raise RecordingError(f"{source}, line {number}: {len(cells)} values but "
                                 f"{len(header)} columns")
        got = {ch: row_numbers(cells, where, header, source=source, line=number)
               * UNITS[ch][units[ch]]
               for ch, where in idx.items()}
        t, stamp = None, ""
        if time_col is not None:
            t = float(row_numbers(cells, time_col, header, source=source, line=number)) * scale
            stamp = f"{header[time_col]} {cells[time_col]} after {last_t / scale:.6g}"
            if not np.isfinite(t):
                raise RecordingError(f"{source}, line {number}: {header[time_col]} is "
                                     f"{cells[time_col]!r:.40}, not a time")
        if stream is None:
            if t is not None and "start_s" not in options:
                options["start_s"] = float(t)
            stream = ImuStream(calibration, rate_hz=rate_hz, **options)
        elif t is not None:
            step = (t - last_t) * rate_hz
            if step < 0.5 and t > last_t:
                raise RecordingError(
                    f"{source}, line {number}: time stamps step by {(t - last_t):.6g} s ({stamp}), "
                    f"under half the period of the {rate_hz:g} Hz given (--rate): is that the "
                    "logger's rate?")
            if step < 0.5:
                raise RecordingError(f"{source}, line {number}: time stamps do not increase "
                                     f"({stamp})")
            if len(steps) < _RATE_STEPS:       # the first steps only, judged once
                steps.append(t - last_t)
                # a rate given wrong (a half or a double) reads every step as a half sample or
                # as one lost: judged within the static start (2 s by default), before any
                # answer
                median = float(np.median(steps))
                if len(steps) == _RATE_STEPS and abs(median * rate_hz - 1.0) > _RATE_TOLERANCE:
                    raise RecordingError(
                        f"{source}, line {number}: the time stamps step by {median:.6g} s (the "
                        f"median of the first {_RATE_STEPS} steps), {1.0 / median:.5g} Hz, not the "
                        f"{rate_hz:g} Hz given (--rate): give the logger's rate")
            lost = int(round(step)) - 1
            if lost > stream.max_hold:
                raise RecordingError(
                    f"{source}, line {number}: {lost} samples missing before this line "
                    f"({stamp}, at {rate_hz:g} Hz): more than max_hold_s fills in; the stream "
                    "stops")
            if lost > 0:
                gap = np.full((len(calibration.sensors), lost, 3), np.nan)
                yield stream.push(gap, gap, None if "mag" not in got else gap)
        if t is not None:
            last_t = float(t)
        yield stream.push(got["acc"], got["gyr"], got.get("mag"))
    if header is None:
        raise RecordingError(f"{source}: no header line (time_s, <sensor>_acc_x .. _mag_z)")
    if stream is None:
        raise RecordingError(f"{source}: no sample after the header")
    yield stream.close()
