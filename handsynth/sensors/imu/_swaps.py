"""Sensors exchanged or turned since the calibration, told by the centres of their joints
(and, for a turned phalanx, by its hinges).

Sensors taken off and put back on the wrong phalanges (or two channels exchanged in a
recording) are read by the calibration of the places they left: where the joints stay
within their ranges nothing looked wrong.  Measured on the held-out configuration (15-s
trial, elbow fixed; Filter 4): the index and middle fingers' proximal sensors exchanged
gave joint angles of 4.75 deg RMSE against 0.85 deg (fingertips 12.7 mm against 7.8), the
middle and ring fingers' middle phalanges 4.89 deg, the hand's two sensors 4.33 deg, and
no warning (docs/imu.md, "Sensors exchanged since the calibration").

Each joint's centre moves with both segments it joins, so the specific force at the
centre seen from either of its two sensors has one magnitude (Seel, Schauer & Raisch,
IEEE CCA 2012; :func:`~handsynth.sensors.imu.seel_joint_positions`):

    r(t) = |a1 + G1 o1| - |a2 + G2 o2|,   G o = w x (w x o) + dw x o,

o the vector from the sensor to the joint's centre in its frame, from the calibration's
link model (:class:`~handsynth.sensors.imu.ChainModel`: ``o = link - own`` for the
proximal sensor, ``-own`` for the distal one).  r is taken about its median (two
sensors' scale errors make it a constant, not the motion).  For two sensors A and B, the
RMS of r over the joints either of them measures is compared with the same with A's and
B's readings exchanged: a pair whose exchange makes its joints agree better by more than
:data:`SWAP_RATIO` reads as exchanged.  Comparing the two assignments of the same
readings leaves out how well the joints agree at all (skin motion, noise, the link
model's own errors), which varies from joint to joint by a factor of six.

``python scripts/study_imu_swaps.py`` (41 recordings: the tuning configuration and 18 draws
of the held-out one, free motions with the elbow fixed and moving, grasp reaches, a still
hold; 8 random pairs exchanged in each): no recording as labelled was warned of; of the
320 exchanges in recordings that move 318 were, 308 named first (the still hold's 8 are
not, as meant).

A sensor turned on its segment (:data:`TURNS`) is told the same way, its readings turned
back instead of exchanged (:func:`turn_ratios`, :func:`turned_sensors`); a phalanx's
sensor also by its hinges (:data:`HINGE_TURN_RATIO`), which tell too a turn by any angle up
to 60 deg about the phalanx's long axis (a strap slipped round the finger).  ``python
scripts/study_imu_turns.py`` (the same 41 recordings, 8 random turns each): no recording as
labelled warned of; of 320 turns in recordings that move 311 told, each named with the turn
made, and of 136 slips round the finger of 10-40 deg every one, the angle to 1.1 deg
(docs/imu.md, "Sensors turned on their segments since the calibration").
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from itertools import combinations

import numpy as np

from ._lags import HINGES
from ._layout import LINKS
from ._recording import ImuRecording
from ._vectors import ChainModel, _child, smoothed_motion

__all__ = [
    "HINGE_FLOOR_RADPS",
    "HINGE_TURN_RATIO",
    "MAX_PUT_BACK",
    "SWAP_FLOOR_MPS2",
    "SWAP_RATIO",
    "TURNS",
    "Misplaced",
    "find_misplaced",
    "misplaced_sensors",
    "put_back",
    "swap_ratios",
    "swapped_sensors",
    "turn_ratios",
    "turned_sensors",
    "undo_misplaced",
]

#: A pair reads as exchanged when, with its two sensors' readings exchanged, its joints'
#: residual is less than this share of the residual as labelled: the exchange must fit 1.5
#: times better.  The geometric middle of a first look at the tuning configuration's two
#: 15-s trials (four pairs exchanged: shares at most 0.14; as labelled every pair 3.15 or
#: more); the same look showed the held-out configuration's seed 1 (as labelled 1.7 or
#: more, exchanged at most 0.53), the other draws of ``scripts/study_imu_swaps.py`` came
#: after.  Every pair of the tuning configuration exchanged in turn: shares at most 0.32.
SWAP_RATIO = 0.66
#: ... and when its joints' residual as labelled is at least this, m/s^2 (mean over its
#: joints, RMS about the median): on a still hold every assignment agrees to the noise,
#: whose ratio says nothing.  The tuning configuration's joints reach 0.03 as labelled, a
#: held-out still hold 0.04.
SWAP_FLOOR_MPS2 = 0.05


def _turn(axis: int, quarters: int) -> np.ndarray:
    c, s = ((1, 0), (0, 1), (-1, 0), (0, -1))[quarters % 4]
    i, j = [k for k in range(3) if k != axis]
    m = np.eye(3)
    m[i, i], m[i, j], m[j, i], m[j, j] = c, -s, s, c
    return m


#: A hinge's sensor reads as turned (by a turn of :data:`TURNS`, or by an angle about its
#: segment's long axis) when its hinges agree better with its flexion axis turned so by more
#: than this share (1 / 4).  The rates of the two phalanges either side of a hinge differ
#: only about its axis (the module :mod:`._lags`): with a sensor turned its calibrated axis
#: is another, and the parts of the rates off the axis part ways.  A first look at the
#: recordings of ``python scripts/study_imu_turns.py`` (the tuning configuration and
#: held-out seeds 1-3, free motions and grasp reaches): as labelled no quarter turn fit
#: better than 27 times worse; a sensor turned a quarter turn fit 25 times better or more
#: turned back (a share of 0.04 at most), and a neighbour of the turned sensor on its finger
#: 0.26 at least (not named after it).  Turns about the long axis, a scratch look before the
#: search was written (four sensors turned 10, 20 and 30 deg on held-out seeds 1-2): turned
#: back by the angle found, a share of 0.02-0.09, the angle found to the degree; as labelled
#: the best angle 0 deg on every sensor.
HINGE_TURN_RATIO = 0.25
#: ... and when its hinges' residual as labelled is at least this, rad/s (mean per hinge, RMS
#: about the median): as calibrated the hinges of the first look agreed to 0.03 rad/s or
#: better, a still hold to the noise; a ring proximal sensor turned a quarter turn read 0.54
#: (``tests/sensors/imu/test_swaps.py``).
HINGE_FLOOR_RADPS = 0.05

#: The turns of a sensor on its segment that are told: name -> the rotation of the sensor's
#: frame (its columns are the turned sensor's axes in its calibrated frame; its readings of a
#: vector v are then R^T v).  Clipped on back to front (half a turn about z, out of the
#: segment's back), upside down (half a turn about x or y), or a square housing put on a
#: quarter turn round (about z, counter-clockwise seen from +z, or clockwise).
TURNS: dict[str, np.ndarray] = {
    "half a turn about its z axis": _turn(2, 2),
    "half a turn about its x axis": _turn(0, 2),
    "half a turn about its y axis": _turn(1, 2),
    "a quarter turn about its z axis (counter-clockwise seen from +z)": _turn(2, 1),
    "a quarter turn about its z axis (clockwise seen from +z)": _turn(2, -1),
}


def _joints(model: ChainModel, sensors) -> list[tuple[str, str, np.ndarray, np.ndarray]]:
    """(proximal sensor, distal sensor, o_proximal, o_distal) of every joint both measure."""
    out = []
    for s1, j1, j2 in LINKS:
        s2 = _child(s1, j2)
        if j2.endswith("_tip") or s1 not in sensors or s2 not in sensors:
            continue
        out.append((s1, s2, model.links[(s1, j1, j2)] - model.own[s1], -model.own[s2]))
    return out


class _JointResiduals:
    """The joints' residuals r(t) of a recording (module docstring), with any sensor's
    readings read as another's or turned."""

    def __init__(self, rec: ImuRecording, model: ChainModel) -> None:
        self.joints = _joints(model, rec.sensors)
        self.sensors = {x for j in self.joints for x in j[:2]}
        self.motion = {s: smoothed_motion(rec, rec.index(s)) for s in self.sensors}
        self.turns = dict(TURNS)    # name -> rotation; others may be added
        self._norms: dict = {}

    def norm(self, n: int, end: int, sensor: str, turn: str | None = None) -> np.ndarray:
        """|a + G o| at joint `n`'s centre from `sensor`'s readings (turned by
        ``self.turns[turn]``), with the vector `o` of the joint's proximal (`end` 0) or
        distal (1) sensor."""
        key = (n, end, sensor, turn)
        if key not in self._norms:
            w, dw, a = self.motion[sensor]
            o = self.joints[n][3] if end else self.joints[n][2]
            if turn is not None:
                # readings turned by R read with o are the readings read with R^T o (the
                # norm does not see a rotation)
                o = self.turns[turn].T @ o
            self._norms[key] = np.linalg.norm(a + np.cross(w, np.cross(w, o)) + np.cross(dw, o),
                                              axis=1)
        return self._norms[key]

    def residual(self, of: dict, among: set, turn: dict | None = None) -> tuple[float, int]:
        """Summed RMS residual of the joints of the sensors `among` and their count, each
        sensor read as ``of.get(s, s)``'s readings, turned by ``turn.get(s)``."""
        turn = turn or {}
        total, count = 0.0, 0
        for n, (s1, s2, _, _) in enumerate(self.joints):
            if s1 in among or s2 in among:
                r = (self.norm(n, 0, of.get(s1, s1), turn.get(s1))
                     - self.norm(n, 1, of.get(s2, s2), turn.get(s2)))
                r = r - np.median(r)  # a constant: two sensors' scale errors, not the motion
                total += float(np.sqrt(np.mean(r * r)))
                count += 1
        return total, count


#: Turns of a phalanx's sensor about its segment's long axis (the link frame's y axis) that
#: its hinges are searched for, deg (the best refined by a parabola through its neighbours).
_ROLLS_DEG = np.arange(-60.0, 61.0, 5.0)


@dataclass(frozen=True)
class _HingeFit:
    """What a hinge sensor's hinges say (:func:`_hinge_fits`): ``shares``, turn name -> the
    share of their residual left with the sensor turned so (every turn of :data:`TURNS`, and
    `roll` by `roll_deg` about its segment's long axis, the best of :data:`_ROLLS_DEG`);
    ``residual`` as labelled, rad/s (mean per hinge)."""

    shares: dict
    roll: str
    roll_turn: np.ndarray
    residual: float


def _hinge_fits(res: _JointResiduals, frames: dict) -> dict[str, _HingeFit]:
    """Each hinge sensor's :class:`_HingeFit`, from the rates `res` smoothed.

    Across a hinge (:data:`HINGES`) the parts of the two phalanges' rates off its axis have
    one length (:mod:`._lags`): r(t) = |w1 - (w1.x1) x1| - |w2 - (w2.x2) x2|, x the link
    frame's x axis (the calibration's flexion axis) in each sensor's frame, about its
    median; its RMS over the sensor's hinges, with the sensor's axis turned as a turn of
    the sensor would turn it, is compared with that as labelled.  Turns that move the axis
    alike (the two quarter turns about z, when the axis lies near the sensor's x) are told
    apart by the joints' centres (:func:`_turns`).
    """
    pairs = [(p, d) for p, d in HINGES if {p, d} <= res.sensors and {p, d} <= set(frames)]
    rates = {s: res.motion[s][0] for pair in pairs for s in pair}

    def off_axis(sensor: str, turn: np.ndarray | None = None) -> np.ndarray:
        w, axis = rates[sensor], np.asarray(frames[sensor], float)[0]
        if turn is not None:
            axis = turn.T @ axis
        return np.linalg.norm(w - np.outer(w @ axis, axis), axis=1)

    labelled_off = {s: off_axis(s) for s in rates}

    def residual(sensor: str, turn: np.ndarray | None) -> float:
        mine = labelled_off[sensor] if turn is None else off_axis(sensor, turn)
        total = 0.0
        for p, d in (pair for pair in pairs if sensor in pair):
            r = (mine - labelled_off[d]) if p == sensor else (labelled_off[p] - mine)
            r = r - np.median(r)
            total += float(np.sqrt(np.mean(r * r)))
        return total

    out = {}
    for s in sorted({x for pair in pairs for x in pair}):
        labelled = residual(s, None)
        long_axis = np.asarray(frames[s], float)[1]
        rolls = np.array([residual(s, _about(long_axis, deg)) if deg else labelled
                          for deg in _ROLLS_DEG])
        k = int(np.argmin(rolls))
        deg = float(_ROLLS_DEG[k])
        if 0 < k < len(rolls) - 1:
            den = rolls[k - 1] - 2 * rolls[k] + rolls[k + 1]
            if den > 0:
                deg += 2.5 * (rolls[k - 1] - rolls[k + 1]) / den
        way = "counter-clockwise" if deg > 0 else "clockwise"
        roll = f"{abs(deg):.0f} deg about its phalanx's long axis ({way} seen from the fingertip)"
        scale = 1.0 / labelled if labelled > 0 else 0.0   # (0: under the floor, never named)
        shares = {name: residual(s, m) * scale for name, m in TURNS.items()}
        shares[roll] = float(rolls[k]) * scale
        n = sum(s in pair for pair in pairs)
        out[s] = _HingeFit(shares, roll, _about(long_axis, deg), labelled / n)
    return out


def _about(axis: np.ndarray, deg: float) -> np.ndarray:
    """The rotation by `deg` about the unit `axis` (Rodrigues)."""
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    a = np.radians(deg)
    return np.eye(3) + np.sin(a) * k + (1.0 - np.cos(a)) * (k @ k)


def _measured(res: _JointResiduals, rec: ImuRecording) -> list[str]:
    """The sensors judged: those a joint joins, the forearm plate's left out."""
    return sorted((s for s in res.sensors if not s.startswith("forearm")), key=rec.index)


def swap_ratios(rec: ImuRecording, model: ChainModel) -> dict[tuple[str, str], tuple[float, float]]:
    """How much better each pair's joints agree with the pair's readings exchanged.

    Parameters
    ----------
    rec : ImuRecording
        A recording of the calibrated sensors (corrected by the sensor calibration, if
        one was made), with some motion.
    model : ChainModel
        The calibration's link model.

    Returns
    -------
    dict
        ``(sensor_a, sensor_b) -> (share, residual)`` for every pair of the recording's
        sensors that a joint of the model joins to another (the forearm plate's left
        out: its three sensors are one rigid body): the RMS residual of their joints with
        the two exchanged over that as labelled, and the latter as the mean per joint,
        m/s^2 (module docstring).
    """
    return _swap_shares(_JointResiduals(rec, model), rec)


def turn_ratios(rec: ImuRecording, model: ChainModel) -> dict[str, dict[str, tuple[float, float]]]:
    """How much better each sensor's joints agree with its readings turned back.

    Parameters
    ----------
    rec, model
        As :func:`swap_ratios`'s.

    Returns
    -------
    dict
        ``sensor -> {turn: (share, residual)}`` for every sensor :func:`swap_ratios`
        judges and every turn of :data:`TURNS`: the RMS residual of its joints with its
        readings turned back (as though the sensor, turned so on its segment since the
        calibration, were put back) over that as labelled, and the latter as the mean per
        joint, m/s^2.
    """
    return _turn_shares(_JointResiduals(rec, model), rec)


def _swap_shares(res: _JointResiduals, rec: ImuRecording) -> dict:
    out = {}
    for a, b in combinations(_measured(res, rec), 2):
        labelled, count = res.residual({}, {a, b})
        exchanged, _ = res.residual({a: b, b: a}, {a, b})
        out[(a, b)] = (exchanged / labelled if labelled > 0 else 1.0, labelled / max(count, 1))
    return out


def _turn_shares(res: _JointResiduals, rec: ImuRecording) -> dict:
    out: dict = {}
    for s in _measured(res, rec):
        labelled, count = res.residual({}, {s})
        out[s] = {name: ((res.residual({}, {s}, {s: name})[0] / labelled) if labelled > 0
                         else 1.0, labelled / max(count, 1)) for name in TURNS}
    return out


def swapped_sensors(rec: ImuRecording, model: ChainModel, *, ratio: float = SWAP_RATIO,
                    floor_mps2: float = SWAP_FLOOR_MPS2) -> str | None:
    """A warning naming the pairs of sensors that read as exchanged, or None.

    Parameters
    ----------
    rec, model
        As :func:`swap_ratios`'s.
    ratio : float, keyword-only
        :data:`SWAP_RATIO`.
    floor_mps2 : float, keyword-only
        :data:`SWAP_FLOOR_MPS2`.

    Returns
    -------
    str or None
        The pairs whose share is below `ratio` and whose residual as labelled is at
        least `floor_mps2`, the most telling first (at most three), with what each
        measured; None when there is none.
    """
    return _exchanges_said(_exchanges(swap_ratios(rec, model), ratio, floor_mps2))


def turned_sensors(rec: ImuRecording, model: ChainModel, frames: dict | None = None, *,
                   ratio: float = SWAP_RATIO, floor_mps2: float = SWAP_FLOOR_MPS2) -> str | None:
    """A warning naming the sensors that read as turned on their segments, or None.

    A sensor reads as turned by one of :data:`TURNS` when its joints agree better with its
    readings turned back by more than `ratio` allows (the exchanges' rule,
    :data:`SWAP_RATIO`) and agree as labelled no better than `floor_mps2`; with `frames`, a
    finger's or the thumb's phalanx also when its hinges agree better with its flexion
    axis turned a quarter turn about z by more than :data:`HINGE_TURN_RATIO` allows
    (:data:`HINGE_FLOOR_RADPS`), the way it turned read from its joints.

    Parameters
    ----------
    rec, model
        As :func:`swap_ratios`'s.
    frames : dict, optional
        The calibration's link frames (``ImuCalibration.frames``), for the hinges.
    ratio, floor_mps2 : float, keyword-only
        As :func:`swapped_sensors`'.

    Returns
    -------
    str or None
        Each such sensor with the turn that fits best and what it measured, the most
        telling first (at most three); None when there is none.
    """
    res = _JointResiduals(rec, model)
    hinges = {} if frames is None else _hinge_fits(res, frames)
    return _turns_said(_turns(res, rec, hinges, ratio, floor_mps2, ()))


@dataclass(frozen=True)
class Misplaced:
    """Sensors a recording reads as misplaced since the calibration (:func:`find_misplaced`).

    Attributes
    ----------
    exchanged : tuple of (str, str)
        Pairs read as exchanged, no sensor in two pairs, the one whose exchange leaves the
        joints' centres agreeing best over every joint first (the warning names them by
        their own joints' share).
    turned : tuple of (str, str, ndarray of shape (3, 3))
        Sensors read as turned on their segments: the sensor, the turn in words (as the
        warning names it) and its rotation (columns: the turned sensor's axes in its
        calibrated frame, as :data:`TURNS`'), the most telling first.
    warnings : tuple of str
        What :func:`misplaced_sensors` says (none, one or both of the exchanges' and the
        turns' warnings).
    """

    exchanged: tuple = ()
    turned: tuple = ()
    warnings: tuple = ()

    def __bool__(self) -> bool:
        return bool(self.exchanged or self.turned)

    def __add__(self, other: Misplaced) -> Misplaced:
        return Misplaced(self.exchanged + other.exchanged, self.turned + other.turned,
                         self.warnings + other.warnings)

    def describe(self) -> str:
        """What :func:`undo_misplaced` undoes, in words (empty when nothing)."""
        said = [f"{a} and {b} exchanged back" for a, b in self.exchanged]
        said += [f"{sensor} turned back by {name}" for sensor, name, _ in self.turned]
        return "; ".join(said)


def find_misplaced(rec: ImuRecording, model: ChainModel, frames: dict | None = None) -> Misplaced:
    """The sensors :func:`swapped_sensors` and :func:`turned_sensors` read as misplaced (what
    ``track`` checks), the joints' motion read once; a sensor named as exchanged is not named
    as turned.

    Parameters
    ----------
    rec, model, frames
        As :func:`turned_sensors`'.

    Returns
    -------
    Misplaced
        The pairs and turns found, and the warnings that name them.
    """
    return _read(rec, model, frames)[0]


def _read(rec: ImuRecording, model: ChainModel, frames: dict | None) -> tuple[Misplaced, list]:
    """:func:`find_misplaced`'s answer, and every single put back it allows (each pair found,
    each sensor found turned, its exchanged ones too) as a :class:`Misplaced` with the summed
    residual of every joint left once it is put back, the least first."""
    res = _JointResiduals(rec, model)
    exchanges = _exchanges(_swap_shares(res, rec), SWAP_RATIO, SWAP_FLOOR_MPS2)
    named = {s for _, _, pair in exchanges for s in pair}
    hinges = {} if frames is None else _hinge_fits(res, frames)
    shares = _turn_shares(res, rec)
    every_turn = _turns(res, rec, hinges, SWAP_RATIO, SWAP_FLOOR_MPS2, (), shares)
    turns = (_turns(res, rec, hinges, SWAP_RATIO, SWAP_FLOOR_MPS2, named, shares) if named
             else every_turn)
    every = set(res.sensors)
    singles = [(res.residual({a: b, b: a}, every)[0], Misplaced(exchanged=((a, b),)))
               for _, _, (a, b) in exchanges]
    for k in every_turn:
        # the turn named, and every other its joints' centres or its hinges allow (a half
        # turn about z hardly moves a flexion axis near the sensor's x: its hinges may
        # allow a slip instead, and the centres tell)
        sensor, fit = k[1], hinges.get(k[1])
        options = {k[2]: k[5], **{name: TURNS[name] for name, (share, _) in
                                  shares.get(sensor, {}).items() if share < SWAP_RATIO}}
        if fit is not None:
            options.update({name: fit.roll_turn if name == fit.roll else TURNS[name]
                            for name, share in fit.shares.items() if share < HINGE_TURN_RATIO})
        for name, rotation in options.items():
            key = f"{sensor} put back {name}"
            res.turns[key] = rotation
            singles.append((res.residual({}, every, {sensor: key})[0],
                            Misplaced(turned=((sensor, name, rotation),))))
    singles.sort(key=lambda c: c[0])
    pairs: list = []
    for _, one in singles:      # a sensor in one pair at most
        if one.exchanged and not any(set(one.exchanged[0]) & set(p) for p in pairs):
            pairs.append(one.exchanged[0])
    said = tuple(m for m in (_exchanges_said(exchanges), _turns_said(turns)) if m is not None)
    return Misplaced(tuple(pairs), tuple((k[1], k[2], k[5]) for k in turns), said), singles


def misplaced_sensors(rec: ImuRecording, model: ChainModel, frames: dict | None = None) -> list[str]:
    """:func:`find_misplaced`'s warnings as a list (what ``track`` warns of): none, one or
    both of :func:`swapped_sensors`' and :func:`turned_sensors`'."""
    return list(find_misplaced(rec, model, frames).warnings)


def undo_misplaced(rec: ImuRecording, found: Misplaced) -> ImuRecording:
    """`rec` with the sensors `found` misplaced put back: each pair's readings exchanged back,
    each turned sensor's readings turned back into its calibrated frame.

    A sensor's own calibration (biases, scales, the magnetometer's iron) travels with the
    sensor, not with its place: give `rec` corrected by the sensor calibration (as
    ``track(..., undo_misplaced=True)`` does).  Where a logger's columns, not the sensors,
    were exchanged, each column wants the other sensor's calibration: exchange the raw
    readings first, then correct them (``track`` tells the two cases apart by the
    magnetometers' field strength).

    Parameters
    ----------
    rec : ImuRecording
    found : Misplaced
        What :func:`find_misplaced` read of `rec`.

    Returns
    -------
    ImuRecording
        A copy (its ``filled`` samples exchanged with their readings; unchecked, as a copy
        made with :func:`dataclasses.replace` is).
    """
    order = list(range(len(rec.sensors)))
    for a, b in found.exchanged:
        i, j = rec.index(a), rec.index(b)
        order[i], order[j] = order[j], order[i]
    acc, gyr = rec.acc[order], rec.gyr[order]
    mag = None if rec.mag is None else rec.mag[order]
    for sensor, _, rotation in found.turned:
        k = rec.index(sensor)
        for c in (acc, gyr, mag):
            if c is not None:
                c[k] = c[k] @ np.asarray(rotation).T   # it read r = R^T v: v = R r
    filled = None if rec.filled is None else rec.filled[order]
    return replace(rec, acc=acc, gyr=gyr, mag=mag, filled=filled)


_PUT_BACK_HINT = ("A recording made so can be read as though they were put back: imu track "
                  "--undo-misplaced (library: track(..., undo_misplaced=True), put_back).")

#: Most misplacements :func:`put_back` undoes in one recording (one at a time).
MAX_PUT_BACK = 4


def put_back(rec: ImuRecording, model: ChainModel, frames: dict | None = None, *,
             rounds: int = MAX_PUT_BACK) -> tuple[ImuRecording, Misplaced, Misplaced]:
    """`rec` with its misplaced sensors put back, one at a time, the one that fits best first.

    Each round reads the recording as put back so far (:func:`find_misplaced`) and undoes
    one of its findings alone: of the pairs found exchanged and the sensors found turned
    (those in a pair too; each by the turn named, or any other its joints' centres or its
    hinges allow), the one that leaves the joints' centres agreeing best over every joint
    (the residual of the module docstring, summed), never the one just put back undone
    again.  A pair exchanged makes its
    neighbours' joints agree worse too, so a pair beside it may be named (on a held-out draw,
    the thumb's distal and the index finger's middle sensors exchanged also named the two
    proximal ones), even first by its own joints' share (on one recording, 8 of the 136
    pairs of phalanx and hand sensors exchanged: a distal pair named before the middle
    pair exchanged), and a sensor turned may read as exchanged with a neighbour (the hand's
    radial sensor turned half a turn about z, with the thumb's metacarpal); the next round,
    with the one that fits best put back, no longer names them.

    Parameters
    ----------
    rec : ImuRecording
        Corrected by the sensor calibration, as :func:`undo_misplaced` wants it.
    model, frames
        As :func:`turned_sensors`'.
    rounds : int, keyword-only
        At most this many put back (:data:`MAX_PUT_BACK`).

    Returns
    -------
    recording : ImuRecording
        `rec` put back (`rec` itself when nothing was found).
    undone : Misplaced
        What was put back, in order (no warnings).
    left : Misplaced
        What the recording as put back still reads as misplaced (after `rounds`), with
        its warnings: empty unless `rounds` ran out.
    """
    undone = last = Misplaced()
    found, singles = _read(rec, model, frames)
    for _ in range(rounds):
        # never the one just put back undone again (two readings that each prefer the other)
        one = next((c for _, c in singles if not _reverses(c, last)), None)
        if one is None:
            break
        rec, undone, last = undo_misplaced(rec, one), undone + one, one
        found, singles = _read(rec, model, frames)
    return rec, undone, found


def _reverses(one: Misplaced, last: Misplaced) -> bool:
    """Whether putting back `one` undoes `last` (one finding each)."""
    if one.exchanged and last.exchanged:
        return set(one.exchanged[0]) == set(last.exchanged[0])
    if one.turned and last.turned:
        (s1, _, r1), (s2, _, r2) = one.turned[0], last.turned[0]
        return s1 == s2 and bool(np.allclose(np.asarray(r1) @ np.asarray(r2), np.eye(3),
                                             atol=1e-6))
    return False


def _exchanges(shares: dict, ratio: float, floor_mps2: float) -> list:
    return sorted((share, resid, pair) for pair, (share, resid) in shares.items()
                  if share < ratio and resid >= floor_mps2)


def _exchanges_said(found: list) -> str | None:
    if not found:
        return None
    said = "; ".join(f"{a} and {b} (their joints agree {1 / share:.1f} times better exchanged: "
                     f"{resid * share:.2f} against {resid:.2f} m/s^2 as labelled)"
                     for share, resid, (a, b) in found[:3])
    more = f"; {len(found) - 3} pair(s) more" if len(found) > 3 else ""
    return (f"sensors read as exchanged since the calibration: {said}{more}. Is each sensor on "
            "the segment it was calibrated on, and each column of the recording its own? "
            f"{_PUT_BACK_HINT}")


def _turns(res: _JointResiduals, rec: ImuRecording, hinges: dict, ratio: float,
           floor_mps2: float, exclude, shares: dict | None = None) -> list:
    """(share, sensor, turn, words, by its hinges, rotation) of the sensors read as turned, the most
    telling first; a hinge neighbour of a sensor its hinges tell is not told by its own.

    Where a sensor's hinges allow turns (a share under :data:`HINGE_TURN_RATIO`), its
    joints' centres choose among them; elsewhere the centres' own rule decides."""
    found = []
    for sensor, turns in (_turn_shares(res, rec) if shares is None else shares).items():
        if sensor in exclude:
            continue
        fit = hinges.get(sensor)
        allowed = [] if fit is None or fit.residual < HINGE_FLOOR_RADPS else \
            [name for name, share in fit.shares.items() if share < HINGE_TURN_RATIO]
        if fit is not None and allowed:
            if fit.roll in allowed:
                key = f"{sensor}: {fit.roll}"
                res.turns[key] = fit.roll_turn
                labelled = res.residual({}, {sensor})[0]
                centre = res.residual({}, {sensor}, {sensor: key})[0] / max(labelled, 1e-300)
                turns = {**turns, fit.roll: (centre, 0.0)}
            name = min(allowed, key=lambda t: turns[t][0])
            share = fit.shares[name]
            found.append((share, sensor, name, f"its hinges agree {1 / share:.0f} times better "
                          f"turned back so: {fit.residual * share:.3f} against "
                          f"{fit.residual:.3f} rad/s as it is", True,
                          fit.roll_turn if name == fit.roll else TURNS[name]))
            continue
        name, (share, resid) = min(turns.items(), key=lambda kv: kv[1][0])
        if share < ratio and resid >= floor_mps2:
            found.append((share, sensor, name, f"its joints agree {1 / share:.1f} times better "
                          f"turned back: {resid * share:.2f} against {resid:.2f} m/s^2 as it is",
                          False, TURNS[name]))
    kept: list = []
    for k in sorted(found, key=lambda k: k[:2]):
        sensor, by_hinge = k[1], k[4]
        if by_hinge and any(o[4] and ((sensor, o[1]) in HINGES or (o[1], sensor) in HINGES)
                            for o in kept):
            continue
        kept.append(k)
    return kept


def _turns_said(found: list) -> str | None:
    if not found:
        return None
    said = "; ".join(f"{sensor} {name} ({words})" for _, sensor, name, words, *_ in found[:3])
    more = f"; {len(found) - 3} sensor(s) more" if len(found) > 3 else ""
    return (f"sensors read as turned on their segments since the calibration: {said}{more}. "
            f"Put each back as it was when calibrated (or calibrate again). {_PUT_BACK_HINT}")
