"""Bend sensors of a five-sensor data glove as functions of the joint angles.

Two glove designs of seed 004 (SPEC.md section 4):

``"dg5"``
    DG5-VHand-like: one sensor per finger over the PIP joint only (the
    thumb's over its MCP joint), so MCP flexion moves the reading only
    through the sensor's slip onto the knuckle (`crosstalk`).
``"5dt"``
    5DT-Data-Glove-5-Ultra-like: one sensor per finger spanning the MCP and
    PIP joints.  Its manual (5DT Data Glove Ultra Series User's Manual,
    v1.3, 2011, Appendix A) says the sensor "measures average of knuckle
    and first joint", with a 12-bit A/D converter per sensor and a minimum
    dynamic range of 8 bits, sampled at >= 60 Hz.

A reading is built in this order (vectorised over the five sensors)::

    b      = w_proximal * theta_proximal + w_distal * theta_distal   # deg of bend
    b_h    = play(b, hysteresis_deg)          # backlash: the sensor lags reversals
    r      = b_h + nonlinearity * b_h**2 / 100
    counts = clip(round(offset + gain * r + noise), 0, adc_max)

Numbers that are assumptions (no datasheet gives them) are marked as such
in :class:`SensorParams`; resistive flex sensors are known to be nonlinear
and to show hysteresis (Saggio et al., "Resistive flex sensors: a survey",
Smart Mater. Struct. 25:013001, 2016), which is why both are modelled.  A
stock resistive flex sensor's datasheet (Spectra Symbol, *Flex Sensor
FS*, v.2014 Rev A, "Electrical specifications") gives only a flat
resistance of 10 kOhm +/-30 % and a bend resistance at least twice the flat
one at a 180 deg pinch bend: no hysteresis, noise or linearity figure.  The
5DT manual describes its sensors as fibre-optic ("proprietary fiber optic
based flexor technology", Appendix A); the same reading model, with the
same assumed figures, is used for both designs.

Which figures are sourced and which are assumptions is listed in
docs/glove.md, "The simulation (what the figures rest on)".
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from typing import Any

import numpy as np

from ...errors import InvalidInputError
from ...models import FINGERS, JOINT_NAMES
from ._fields import as_array

__all__ = [
    "GLOVE_KINDS",
    "SENSOR_NAMES",
    "SensorParams",
    "bend_angle_deg",
    "play_operator",
    "play_operator_reference",
    "sensor_joints",
    "simulate_sensors",
]

#: The glove designs this module simulates.
GLOVE_KINDS: tuple[str, ...] = ("dg5", "5dt")

#: Column names of the five sensors, thumb to little finger.
SENSOR_NAMES: tuple[str, ...] = tuple(f"sensor_{f}" for f in FINGERS)

# Joint under each sensor: "proximal" is the joint a 5DT sensor also spans,
# "distal" the one both designs cover.  For the thumb the sensor lies over the
# MCP and IP joints (the CMC joint is inside the palm, out of a glove
# sensor's reach).
_PROXIMAL = ("thumb_mcp_flex", *(f"{f}_mcp_flex" for f in FINGERS[1:]))
_DISTAL_DG5 = ("thumb_mcp_flex", *(f"{f}_pip_flex" for f in FINGERS[1:]))
_DISTAL_5DT = ("thumb_ip_flex", *(f"{f}_pip_flex" for f in FINGERS[1:]))


def sensor_joints(kind: str) -> dict[str, np.ndarray]:
    """Nominal joint weights of each sensor of glove `kind`.

    Parameters
    ----------
    kind : {"dg5", "5dt"}
        Glove design, one of :data:`GLOVE_KINDS`.

    Returns
    -------
    dict with keys ``"proximal"``, ``"distal"`` (int arrays, shape (5,): the
    canonical joint indices) and ``"w_proximal"``, ``"w_distal"`` (float
    arrays, shape (5,): the nominal weights before a user's placement error).
    DG5: bend = PIP (thumb: MCP); 5DT: bend = (MCP + PIP) / 2 (thumb: (MCP +
    IP) / 2), the "average of knuckle and first joint" of the 5DT manual.

    Raises
    ------
    InvalidInputError
        If `kind` is not one of :data:`GLOVE_KINDS`.
    """
    _check_kind(kind)
    prox = np.array([JOINT_NAMES.index(j) for j in _PROXIMAL])
    if kind == "dg5":
        dist = np.array([JOINT_NAMES.index(j) for j in _DISTAL_DG5])
        return {"proximal": prox, "distal": dist,
                "w_proximal": np.zeros(5), "w_distal": np.ones(5)}
    dist = np.array([JOINT_NAMES.index(j) for j in _DISTAL_5DT])
    return {"proximal": prox, "distal": dist,
            "w_proximal": np.full(5, 0.5), "w_distal": np.full(5, 0.5)}


def _check_kind(kind) -> None:
    if kind not in GLOVE_KINDS:
        raise InvalidInputError(
            f"glove kind must be one of {', '.join(GLOVE_KINDS)}, got {kind!r}")


def _vec5(value, name: str) -> np.ndarray:
    arr = np.broadcast_to(np.asarray(value, dtype=np.float64), (5,)).copy()
    if not np.all(np.isfinite(arr)):
        raise InvalidInputError(f"SensorParams.{name} must be finite, got {value!r}")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True)
class SensorParams:
    """Per-sensor parameters of one glove on one hand (one donning).

    Every array field takes a scalar (same for all five sensors) or five
    values, thumb to little finger.

    Parameters
    ----------
    kind : {"dg5", "5dt"}
        Glove design (see :func:`sensor_joints`).
    gain : float or (5,), counts/deg
        Slope of the reading.  Default 4.0 counts/deg: an assumption, bounded
        below by a source: a 100 deg PIP bend spans 400 of 4096 counts, above
        the 5DT manual's minimum dynamic range of 8 bits (256 counts;
        Appendix A).  No datasheet gives counts per degree, which depend on
        the glove's circuit.
    offset : float or (5,), counts
        Reading of the straight sensor.  Default 1500: an assumption (a
        straight sensor reads inside the 12-bit range, clear of either end).
        A straight reading that differs from sensor to sensor is in line
        with the flex-sensor datasheet's flat-resistance tolerance of +/-30 %
        (Spectra Symbol, v.2014 Rev A), which does not give the spread in
        counts: that is an assumption
        (:func:`~handsynth.sensors.glove.don_glove`).
    nonlinearity : float or (5,), 1/deg * 100
        Coefficient of the quadratic term; 0.1 makes a 100 deg bend read 10 %
        high.  Default 0.1: an assumption (Saggio et al. 2016 report
        nonlinear resistive sensors without a figure this model could take).
    hysteresis_deg : float or (5,), deg
        Width of the play (backlash) band.  Default 3 deg: an assumption
        (Saggio et al. 2016 document hysteresis without a figure this model
        could take; the flex-sensor datasheet gives none).
    noise_counts : float or (5,), counts
        White-noise s.d. before quantisation.  Default 2 counts: an
        assumption (about 0.5 deg at the default gain; neither the 5DT
        manual's specifications nor the flex-sensor datasheet gives a noise
        figure).
    crosstalk : float or (5,)
        Extra weight of the proximal joint (MCP; thumb CMC for DG5 is not
        modelled) from the sensor slipping toward the knuckle; 0 for a sensor
        exactly on its joint.  Default 0; the spread a donning draws is an
        assumption (:func:`~handsynth.sensors.glove.don_glove`).
    distal_weight_error : float or (5,)
        Relative error of the distal joint's weight (placement).  Default 0;
        the spread a donning draws is an assumption.
    adc_max : int
        Full scale: 4095 for a 12-bit converter (5DT manual, Appendix A:
        "12 bit A/D for each sensor").

    Raises
    ------
    InvalidInputError
        Unknown kind, non-finite values, a gain of zero or a negative noise,
        hysteresis or full scale.
    """

    kind: str = "dg5"
    # Any: a scalar or five values in, always a read-only (5,) array after __post_init__
    gain: Any = 4.0
    offset: Any = 1500.0
    nonlinearity: Any = 0.1
    hysteresis_deg: Any = 3.0
    noise_counts: Any = 2.0
    crosstalk: Any = 0.0
    distal_weight_error: Any = 0.0
    adc_max: int = 4095

    def __post_init__(self) -> None:
        _check_kind(self.kind)
        for f in fields(self):
            if f.name in ("kind", "adc_max"):
                continue
            object.__setattr__(self, f.name, _vec5(getattr(self, f.name), f.name))
        if np.any(self.gain == 0):
            raise InvalidInputError(f"SensorParams.gain must be non-zero, got {self.gain}")
        for name in ("hysteresis_deg", "noise_counts"):
            if np.any(getattr(self, name) < 0):
                raise InvalidInputError(
                    f"SensorParams.{name} must be >= 0, got {getattr(self, name)}")
        if isinstance(self.adc_max, bool) or not isinstance(self.adc_max, (int, np.integer)) \
                or self.adc_max < 1:
            raise InvalidInputError(
                f"SensorParams.adc_max must be a positive integer, got {self.adc_max!r}")

    def replace(self, **changes) -> SensorParams:
        """A copy with `changes` (a misspelt field raises TypeError)."""
        return replace(self, **changes)


def bend_angle_deg(angles: np.ndarray, params: SensorParams) -> np.ndarray:
    """Bend seen by each sensor before hysteresis and nonlinearity.

    Parameters
    ----------
    angles : ndarray, shape (N, 20), float, deg
        Joint angles, canonical order.
    params : SensorParams

    Returns
    -------
    ndarray, shape (N, 5), float64, deg

    Raises
    ------
    InvalidInputError
        `angles` not of shape (N, 20) or not finite, or `params`
        not :class:`SensorParams`.
    """
    a = _as_angles(angles)
    if not isinstance(params, SensorParams):
        raise InvalidInputError(f"params must be SensorParams, got {type(params).__name__}")
    j = sensor_joints(params.kind)
    w_prox = j["w_proximal"] + params.crosstalk
    w_dist = j["w_distal"] * (1.0 + params.distal_weight_error)
    # the DG5 thumb sensor's "proximal" and "distal" joints are the same MCP
    prox = np.where(j["proximal"] == j["distal"], 0.0, w_prox)
    return prox * a[:, j["proximal"]] + w_dist * a[:, j["distal"]]


def _as_angles(angles) -> np.ndarray:
    """Joint angles as a finite float array (N, 20) (a NaN would stick in the play
    operator's state and spoil every later reading)."""
    return as_array(angles, "angles", (None, len(JOINT_NAMES)))


def play_operator_reference(x: np.ndarray, width: np.ndarray) -> np.ndarray:
    """Plain per-sample loop of :func:`play_operator` (the reference version).

    Parameters
    ----------
    x : ndarray, shape (N, K), float
        Inputs in time order, one column per channel; N >= 1 (an empty `x`
        raises ``IndexError``, where :func:`play_operator` returns it empty).
    width : array_like, shape (K,), same unit as `x`
        Full width of each column's band.

    Returns
    -------
    ndarray, shape (N, K), float64
    """
    x = np.asarray(x, dtype=np.float64)
    out = np.empty_like(x)
    half = np.asarray(width, dtype=np.float64) / 2.0
    for k in range(x.shape[1]):
        y = x[0, k]
        for i in range(x.shape[0]):
            if x[i, k] > y + half[k]:
                y = x[i, k] - half[k]
            elif x[i, k] < y - half[k]:
                y = x[i, k] + half[k]
            out[i, k] = y
    return out


def play_operator(x: np.ndarray, width: np.ndarray) -> np.ndarray:
    """Backlash (play) hysteresis of band `width`, column by column.

    The output follows the input only once it has moved half the band
    away; on reversal it stays put until the input crosses the band.  It
    starts at the first input.

    Parameters
    ----------
    x : ndarray, shape (N, K), float
    width : array_like, shape (K,), same unit as `x`

    Returns
    -------
    ndarray, shape (N, K), float64
    """
    x = np.asarray(x, dtype=np.float64)
    half = np.asarray(width, dtype=np.float64) / 2.0
    out = np.empty_like(x)
    if x.shape[0] == 0:
        return out
    y = x[0].copy()
    lo, hi = x - half, x + half
    for i in range(x.shape[0]):  # vectorised over the K columns
        np.clip(y, lo[i], hi[i], out=y)
        out[i] = y
    return out


def simulate_sensors(angles: np.ndarray, params: SensorParams, *,
                     rng: np.random.Generator | None = None) -> np.ndarray:
    """Raw readings of the five sensors for a joint-angle trajectory.

    Parameters
    ----------
    angles : ndarray, shape (N, 20), float, deg
        Joint angles in time order (hysteresis depends on the order).
    params : SensorParams
    rng : numpy.random.Generator, keyword-only
        Source of the sensor noise; None means no noise.

    Returns
    -------
    ndarray, shape (N, 5), float64, counts
        Integer-valued readings clipped to ``[0, params.adc_max]`` (a reading
        at either end is saturated).

    Raises
    ------
    InvalidInputError
        As :func:`bend_angle_deg`.
    """
    b = bend_angle_deg(angles, params)
    b = play_operator(b, params.hysteresis_deg)
    r = b + params.nonlinearity * b**2 / 100.0
    counts = params.offset + params.gain * r
    if rng is not None:
        counts = counts + rng.normal(0.0, 1.0, counts.shape) * params.noise_counts
    return np.clip(np.rint(counts), 0, params.adc_max)
