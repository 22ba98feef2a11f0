"""Simulated glove sessions: a user, a donning of the glove, trials of motions.

Everything a real calibration would not see is varied here, so that test
data never share the generator of the data an estimator was fitted on:

* the **user** (:class:`GloveUser`): hand length, rest posture, grasp style
  (per-joint scale and offset of each grasp posture), how the MCP leads or
  lags the PIP during a grasp, and the DIP/PIP ratio (the estimators assume
  2/3, seed 004 eq. 1; users here draw 0.55-0.80);
* the **donning** (:func:`don_glove`): sensor gain, offset, nonlinearity,
  hysteresis, noise and slip of each sensor toward the knuckle, which grows
  on a shorter hand (a glove of one size sits farther down its fingers);
* each **trial**: grasp posture jitter, speed, per-finger onset delays.

The reference angles of a session are the truth plus the error of a
many-sensor glove worn under it (1.5 deg s.d. by default, inside the
1-2.4 deg RMSE range of many-sensor gloves quoted in issue 19: SenGlove,
Bioengineering 10:324, 2023, 0.99-2.38 deg).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..._checks import check_options
from ...errors import InvalidInputError
from ...models import JOINT_LIMITS_DEG, JOINT_NAMES, NAMED_POSES
from ._fields import as_array, as_number
from ._motions import MOTIONS, grasp_posture
from ._recording import RANGE_LABELS, GloveRecording
from ._sensors import SensorParams, simulate_sensors

__all__ = ["GLOVE_HELDOUT", "GLOVE_TUNING", "GloveConfig", "GloveUser", "don_glove", "make_user",
           "simulate_poses", "simulate_range_holds", "simulate_session"]

_MCP = np.array([JOINT_NAMES.index(n) for n in JOINT_NAMES if n.endswith("mcp_flex")
                 or n == "thumb_cmc_flex"])
#: Hand lengths (ratio to the standard hand) a user may have: a hand half or twice the
#: standard's length is no hand a glove of the standard's size fits.
HAND_LENGTH_RANGE = (0.5, 2.0)


@dataclass(frozen=True)
class GloveConfig:
    """The spreads users, a glove and its donnings are drawn from, frozen.

    Every figure is an assumption (no datasheet or survey gives them; see
    :func:`make_user`, :func:`don_glove`).
    :data:`GLOVE_TUNING` is the configuration every estimator's options were chosen on;
    :data:`GLOVE_HELDOUT` sets other figures for each, so that no estimator is scored on
    the spreads it was tuned with.

    Parameters
    ----------
    label : str
    gain_counts_per_deg : (float, float)
        Range of each sensor's nominal gain (the glove).
    gain_donning_sd : float
        S.d. of the gain's change at each donning, a fraction.
    offset_counts : (float, float)
        Range of each sensor's offset at each donning.
    nonlinearity : (float, float)
        Range of the quadratic term (:class:`SensorParams`, 1/deg * 100).
    hysteresis_deg : (float, float)
        Range of the play.
    noise_counts : (float, float)
        Range of the noise s.d.
    slip : (float, float)
        Range of the extra MCP weight at each donning (the sensor slipping onto the
        knuckle), plus `slip_per_short` per unit of hand length below 1.
    slip_per_short : float
    distal_weight_sd : float
        S.d. of the placement error of the distal joint's weight.
    rest_sd_deg : float
        S.d. of a user's rest posture at every joint (:func:`make_user`).
    style_scale_sd, style_offset_sd_deg : float
        S.d. of a user's grasp style: posture scale and offset, per joint.
    mcp_lead, other_lead : (float, float)
        Ranges of the exponents of the MCPs' and the other joints' progress along a motion.
    dip_ratio : (float, float)
        Range of a user's DIP/PIP ratio per finger.

    Raises
    ------
    InvalidInputError
        A range that is not two finite numbers, low before high, or a spread below 0
        (naming the field).
    """

    label: str = "tuning"
    gain_counts_per_deg: tuple[float, float] = (3.0, 5.0)
    gain_donning_sd: float = 0.05
    offset_counts: tuple[float, float] = (1200.0, 1800.0)
    nonlinearity: tuple[float, float] = (0.0, 0.2)
    hysteresis_deg: tuple[float, float] = (2.0, 5.0)
    noise_counts: tuple[float, float] = (1.5, 3.0)
    slip: tuple[float, float] = (0.02, 0.10)
    slip_per_short: float = 0.8
    distal_weight_sd: float = 0.05
    rest_sd_deg: float = 3.0
    style_scale_sd: float = 0.08
    style_offset_sd_deg: float = 4.0
    mcp_lead: tuple[float, float] = (0.6, 1.0)
    other_lead: tuple[float, float] = (0.9, 1.5)
    dip_ratio: tuple[float, float] = (0.55, 0.80)

    def __post_init__(self) -> None:
        for name in ("gain_counts_per_deg", "offset_counts", "nonlinearity", "hysteresis_deg",
                     "noise_counts", "slip", "mcp_lead", "other_lead", "dip_ratio"):
            v = getattr(self, name)
            try:
                lo, hi = (as_number(x, f"GloveConfig.{name}") for x in v)
            except (TypeError, ValueError):
                raise InvalidInputError(f"GloveConfig.{name} must be two numbers (low, high), "
                                        f"got {v!r}") from None
            if not 0 <= lo <= hi:
                raise InvalidInputError(f"GloveConfig.{name} must be a range 0 <= low <= high, "
                                        f"got {v!r}")
            object.__setattr__(self, name, (lo, hi))
        for name in ("gain_donning_sd", "slip_per_short", "distal_weight_sd", "rest_sd_deg",
                     "style_scale_sd", "style_offset_sd_deg"):
            v = as_number(getattr(self, name), f"GloveConfig.{name}")
            if v < 0:
                raise InvalidInputError(f"GloveConfig.{name} must be >= 0, got {v!r}")
            object.__setattr__(self, name, v)
        for name in ("gain_counts_per_deg", "mcp_lead", "other_lead", "dip_ratio"):
            if getattr(self, name)[0] <= 0:
                raise InvalidInputError(f"GloveConfig.{name} must be above 0, got "
                                        f"{getattr(self, name)!r}")


#: The configuration the estimators' options were chosen on.
GLOVE_TUNING = GloveConfig()
#: Other figures for every spread (assumptions too, chosen before any figure was measured
#: on them): gains over a wider range and changing by 10 % at each donning, offsets over a
#: wider range, more nonlinearity (0.1-0.35), play (4-8 deg) and noise (3-6 counts), more
#: slip and a distal placement error of 10 %; users whose rest postures and grasp styles
#: spread half as far again, who lead and lag over wider ranges, and whose DIP/PIP ratios
#: span 0.45-0.85.
GLOVE_HELDOUT = GloveConfig("heldout", gain_counts_per_deg=(2.0, 6.0), gain_donning_sd=0.10,
                            offset_counts=(1000.0, 2200.0), nonlinearity=(0.1, 0.35),
                            hysteresis_deg=(4.0, 8.0), noise_counts=(3.0, 6.0),
                            slip=(0.05, 0.15), slip_per_short=0.8, distal_weight_sd=0.10,
                            rest_sd_deg=4.5, style_scale_sd=0.12, style_offset_sd_deg=6.0,
                            mcp_lead=(0.5, 1.0), other_lead=(0.8, 1.7), dip_ratio=(0.45, 0.85))


@dataclass(frozen=True, eq=False)
class GloveUser:
    """One simulated wearer.

    Parameters
    ----------
    name : str
    hand_length : float
        Ratio to the standard hand (1.0); shifts the sensors (see
        :func:`don_glove`).
    rest_deg : ndarray, shape (20,), deg
        The user's relaxed "open hand".
    style_scale, style_offset_deg : ndarray, shape (20,)
        A grasp posture of this user is ``scale * posture + offset``.
    lead : ndarray, shape (20,)
        Exponent of each joint's progress along the motion phase u in [0, 1]
        (progress = u**lead): below 1 the joint moves early.
    dip_ratio : ndarray, shape (5,)
        Distal joint / middle joint flexion (thumb IP / MCP, DIP / PIP).

    Raises
    ------
    InvalidInputError
        A hand length outside :data:`HAND_LENGTH_RANGE`, or an array field of
        another shape or not finite (named in the message).
    """

    name: str
    hand_length: float
    rest_deg: np.ndarray
    style_scale: np.ndarray
    style_offset_deg: np.ndarray
    lead: np.ndarray
    dip_ratio: np.ndarray

    def __post_init__(self) -> None:
        if not isinstance(self.name, str):
            raise InvalidInputError(f"GloveUser.name must be a string, got {self.name!r}")
        hand = as_number(self.hand_length, "hand_length")
        lo, hi = HAND_LENGTH_RANGE
        if not lo <= hand <= hi:
            raise InvalidInputError(f"hand_length (ratio to the standard hand) must lie in "
                                    f"[{lo:g}, {hi:g}], got {self.hand_length!r}")
        object.__setattr__(self, "hand_length", hand)
        for name, n in (("rest_deg", len(JOINT_NAMES)), ("style_scale", len(JOINT_NAMES)),
                        ("style_offset_deg", len(JOINT_NAMES)), ("lead", len(JOINT_NAMES)),
                        ("dip_ratio", 5)):
            object.__setattr__(self, name, as_array(getattr(self, name), f"GloveUser.{name}",
                                                    (n,)))

    def replace(self, **changes) -> GloveUser:
        return replace(self, **changes)


def make_user(seed: int, *, name: str | None = None, hand_length: float | None = None,
              config: GloveConfig | None = None) -> GloveUser:
    """A random wearer drawn from `seed`.

    Style spreads (assumptions, chosen so two users differ by several
    degrees at every joint; not taken from a source): posture scale s.d.
    0.08, offset s.d. 4 deg, rest posture s.d. 3 deg around 5 deg MCP
    flexion, MCP lead exponent 0.6-1.0 and PIP 0.9-1.5, DIP/PIP ratio
    0.55-0.80 (around the 2/3 of seed 004 eq. 1 that the estimators
    assume).  Hand length 0.92-1.08 of the standard hand: an assumption
    that spans the mean hand lengths of men and women in the 1988 US Army
    survey (Gordon et al. 1989: 193.8 and 180.4 mm, 1.04 and 0.96 of the
    standard hand's 187 mm; :mod:`handsynth.models`), not the survey's
    spread.

    Parameters
    ----------
    seed : int
        Non-negative; the same seed gives the same user.
    name : str, keyword-only, optional
        The user's name; ``f"user{seed}"`` for None (or ``""``).
    hand_length : float, keyword-only, optional
        Ratio to the standard hand; None draws it from 0.92-1.08.  Giving it
        skips that draw, so the style scale, style offset and DIP/PIP ratios
        drawn after it differ from those of ``make_user(seed)`` (the rest
        posture and lead exponents, drawn before, do not).
    config : GloveConfig, keyword-only, optional
        The spreads drawn from (the figures above are :data:`GLOVE_TUNING`'s, the
        default; :data:`GLOVE_HELDOUT` sets others).

    Returns
    -------
    GloveUser

    Raises
    ------
    InvalidInputError
        A seed that is no non-negative integer, a `name` that is no string,
        or a `hand_length` outside :data:`HAND_LENGTH_RANGE`.
    """
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InvalidInputError(f"seed must be a non-negative integer, got {seed!r}")
    if name is not None and not isinstance(name, str):
        raise InvalidInputError(f"name must be a string, got {name!r}")
    c = check_options(config, GloveConfig, name="config")
    rng = np.random.default_rng([int(seed), 19])
    n = len(JOINT_NAMES)
    rest = rng.normal(0.0, c.rest_sd_deg, n)
    rest[_MCP] += 5.0
    lead = np.ones(n)
    lead[_MCP] = rng.uniform(*c.mcp_lead, _MCP.size)
    other = np.setdiff1d(np.arange(n), _MCP)
    lead[other] = rng.uniform(*c.other_lead, other.size)
    return GloveUser(
        name=name or f"user{seed}",
        hand_length=hand_length if hand_length is not None else float(rng.uniform(0.92, 1.08)),
        rest_deg=rest,
        style_scale=rng.normal(1.0, c.style_scale_sd, n),
        style_offset_deg=rng.normal(0.0, c.style_offset_sd_deg, n),
        lead=lead,
        dip_ratio=rng.uniform(*c.dip_ratio, 5),
    )


def don_glove(user: GloveUser, kind: str, *, seed: int, glove_seed: int = 0,
              config: GloveConfig | None = None) -> SensorParams:
    """Sensor parameters of glove `kind` number `glove_seed` as worn by `user` once.

    The glove itself (`glove_seed`) fixes each sensor's nominal gain 3-5
    counts/deg (so a full bend spans more than the 8-bit minimum dynamic
    range of the 5DT manual), nonlinearity 0-0.2, hysteresis 2-5 deg and
    noise 1.5-3 counts s.d.  Each donning (`seed`) then draws the offset
    1200-1800 counts, a gain change of s.d. 5 %, the slip toward the
    knuckle (extra MCP weight 0.02-0.10 plus 0.8 per unit of hand length
    below 1: a glove of one size sits farther down a short finger) and a
    placement error of the distal joint weight of s.d. 5 %.  All spreads are
    assumptions; no datasheet gives them (the flex-sensor datasheet's flat
    resistance tolerance of +/-30 %, Spectra Symbol v.2014 Rev A, is in line
    with an offset drawn per sensor and donning but does not give its spread
    in counts; see :class:`SensorParams` for what is sourced).  Calibration
    and test data come from the same ranges (other draws, not other
    figures; docs/glove.md, "The simulation").

    Parameters
    ----------
    user : GloveUser
        Only its ``hand_length`` is used (the slip toward the knuckle).
    kind : {"dg5", "5dt"}
        Glove design.
    seed : int, keyword-only
        Seed of this donning (offset, gain change, slip, distal weight error).
    glove_seed : int, keyword-only
        Seed of the glove itself (nominal gain, nonlinearity, hysteresis,
        noise): the same `glove_seed` is the same physical glove.
    config : GloveConfig, keyword-only, optional
        The spreads drawn from (the figures above are :data:`GLOVE_TUNING`'s, the
        default; :data:`GLOVE_HELDOUT` sets others).

    Returns
    -------
    SensorParams
        Gains in counts/deg, offsets and noise in counts, hysteresis in deg;
        ``adc_max`` the default 4095.

    Raises
    ------
    InvalidInputError
        `kind` not one of :data:`GLOVE_KINDS` (from :class:`SensorParams`).
    """
    c = check_options(config, GloveConfig, name="config")
    g = np.random.default_rng([int(glove_seed), 23])
    rng = np.random.default_rng([int(seed), 37])
    slip = rng.uniform(*c.slip, 5) + c.slip_per_short * max(0.0, 1.0 - user.hand_length)
    return SensorParams(
        kind=kind,
        gain=g.uniform(*c.gain_counts_per_deg, 5) * rng.normal(1.0, c.gain_donning_sd, 5),
        offset=rng.uniform(*c.offset_counts, 5),
        nonlinearity=g.uniform(*c.nonlinearity, 5),
        hysteresis_deg=g.uniform(*c.hysteresis_deg, 5),
        noise_counts=g.uniform(*c.noise_counts, 5),
        crosstalk=slip,
        distal_weight_error=rng.normal(0.0, c.distal_weight_sd, 5),
    )


def _smooth(u: np.ndarray) -> np.ndarray:
    """Minimum-jerk profile on [0, 1]."""
    u = np.clip(u, 0.0, 1.0)
    return u**3 * (10 - 15 * u + 6 * u**2)


def _couple_distal(angles: np.ndarray, user: GloveUser, rng) -> None:
    """Distal joints follow the middle ones at the user's ratio, with noise."""
    pairs = [(2, 3)] + [(6 + 4 * k, 7 + 4 * k) for k in range(4)]
    for k, (mid, dist) in enumerate(pairs):
        angles[:, dist] = user.dip_ratio[k] * angles[:, mid] + rng.normal(0, 1.0)


def _trial_angles(user: GloveUser, posture: np.ndarray, rng, *, rate_hz: float,
                  close_s: float, hold_s: float, jitter_deg: float) -> np.ndarray:
    target = user.style_scale * posture + user.style_offset_deg + \
        rng.normal(0.0, jitter_deg, posture.shape)
    target = np.where(np.abs(posture) < 1e-9, 0.5 * user.style_offset_deg, target)
    rest = user.rest_deg + rng.normal(0.0, 1.0, posture.shape)
    dur = close_s * rng.uniform(0.8, 1.25)
    delay = np.repeat(rng.uniform(0.0, 0.15, 5), 4) * dur  # per finger
    lead = user.lead * rng.uniform(0.9, 1.1, posture.shape)
    pad = 0.3
    total = pad + dur + hold_s + dur + pad
    t = np.arange(0.0, total, 1.0 / rate_hz)
    t_close = (t[:, None] - pad - delay) / dur
    t_open = (t[:, None] - pad - dur - hold_s - delay) / dur
    u = _smooth(t_close) - _smooth(t_open)       # 0 -> 1 -> 0
    progress = np.clip(u, 0.0, 1.0) ** lead
    angles = rest + progress * (target - rest)
    _couple_distal(angles, user, rng)
    return np.clip(angles, JOINT_LIMITS_DEG[:, 0], JOINT_LIMITS_DEG[:, 1])


def simulate_session(user: GloveUser, sensors: SensorParams, motions, *, trials: int = 5,
                     seed: int = 0, rate_hz: float = 60.0, close_s: float = 1.5,
                     hold_s: float = 0.5, jitter_deg: float = 4.0,
                     reference_noise_deg: float = 1.5) -> GloveRecording:
    """`trials` repetitions of each motion from the open hand and back.

    Parameters
    ----------
    user : GloveUser
    sensors : SensorParams
        The glove as worn (:func:`don_glove`).
    motions : sequence of str
        Names from :data:`MOTIONS`, each at most once (one name alone is
        taken as a sequence of one).
    trials : int, keyword-only
        Repetitions of each motion.
    seed : int, keyword-only
        Seed of trial variation, sensor noise and reference-glove noise.
    rate_hz : float, keyword-only
        Sampling rate (60 Hz: the 5DT manual's minimum full-hand rate).
    close_s, hold_s : float, keyword-only
        Nominal closing time (each trial draws 0.8-1.25 times it) and hold
        at the grasp, s.
    jitter_deg : float, keyword-only
        Trial-to-trial s.d. of the grasp posture, deg (default 4: an
        assumption, as are the closing-time spread 0.8-1.25 and the
        per-finger onset delays of up to 0.15 of it).
    reference_noise_deg : float, keyword-only
        S.d. of the reference glove's error added to ``angles`` (default
        1.5 deg: inside the 0.99-2.38 deg RMSE of the SenGlove, David et
        al., Bioengineering 10:324, 2023; module notes).

    Returns
    -------
    GloveRecording
        ``truth`` holds the noise-free angles, ``angles`` the reference.
    """
    if isinstance(trials, bool) or not isinstance(trials, (int, np.integer)) or trials < 1:
        raise InvalidInputError(f"trials must be a positive integer, got {trials!r}")
    if not rate_hz > 0:
        raise InvalidInputError(f"rate_hz must be positive, got {rate_hz!r}")
    motions = [motions] if isinstance(motions, str) else list(motions)
    if not motions:
        raise InvalidInputError("motions must name at least one motion, got none")
    for i, m in enumerate(motions):
        if m not in MOTIONS:
            raise InvalidInputError(f"unknown motion {m!r}; expected one of {', '.join(MOTIONS)}")
        if m in motions[:i]:
            # its trials would share numbers and read back as one trial of two grasps
            raise InvalidInputError(f"motions: {m!r} is given twice; ask for more trials instead")
    rng = np.random.default_rng([int(seed), 29])
    parts, labels, trial_ids = [], [], []
    order = [(m, k) for k in range(trials) for m in motions]
    for m, k in order:
        a = _trial_angles(user, grasp_posture(m), rng, rate_hz=rate_hz, close_s=close_s,
                          hold_s=hold_s, jitter_deg=jitter_deg)
        parts.append(a)
        labels += [m] * len(a)
        trial_ids += [k] * len(a)
    truth = np.vstack(parts)
    counts = simulate_sensors(truth, sensors, rng=rng)
    ref = truth + rng.normal(0.0, reference_noise_deg, truth.shape)
    time_s = np.arange(len(truth)) / rate_hz
    return GloveRecording(sensors=counts, angles=ref, motion=np.array(labels, dtype=object),
                          trial=np.array(trial_ids), time_s=time_s, kind=sensors.kind,
                          truth=truth, adc_max=float(sensors.adc_max),
                          meta={"user": user.name, "seed": int(seed)})


def simulate_poses(user: GloveUser, sensors: SensorParams, postures: np.ndarray, *,
                   seed: int = 0, hold_samples: int = 30) -> GloveRecording:
    """Static holds of `postures` (M, 20) deg, `hold_samples` samples each.

    Used for a short range calibration (open hand and fist) of a new
    wearer.  The user's style is not applied: the postures are what the
    user is asked to hold, plus 3 deg s.d. of not holding them exactly (an
    assumption).

    Parameters
    ----------
    user : GloveUser
        Not used by the code (the user's slip is already in `sensors`).
    sensors : SensorParams
        The glove as worn (:func:`don_glove`).
    postures : array_like, shape (M, 20) or (20,), deg
        Canonical order; one 3 deg s.d. error is drawn per posture and kept
        over its hold, then the angles are clipped to the joint limits.
    seed : int, keyword-only
        Seed of the holding error and the sensor noise.
    hold_samples : int, keyword-only
        Samples per posture; the holds follow each other in one sequence, so
        the sensors' hysteresis carries from one hold into the next.

    Returns
    -------
    GloveRecording
        ``M * hold_samples`` samples; ``angles`` and ``truth`` both hold the
        held angles (no reference-glove error), ``trial`` the posture index,
        ``motion`` is ``""`` and ``time_s`` the sample index (the default of
        :class:`GloveRecording`, not seconds).

    Raises
    ------
    InvalidInputError
        Postures not finite (from :func:`simulate_sensors`).
    ValueError
        Postures without 20 columns (numpy's broadcasting error: the shape is
        not checked first).
    """
    rng = np.random.default_rng([int(seed), 31])
    postures = np.atleast_2d(np.asarray(postures, dtype=np.float64))
    held = np.repeat(postures, hold_samples, axis=0) + \
        np.repeat(rng.normal(0, 3.0, postures.shape), hold_samples, axis=0)
    held = np.clip(held, JOINT_LIMITS_DEG[:, 0], JOINT_LIMITS_DEG[:, 1])
    counts = simulate_sensors(held, sensors, rng=rng)
    return GloveRecording(sensors=counts, angles=held, truth=held, kind=sensors.kind,
                          trial=np.repeat(np.arange(len(postures)), hold_samples),
                          adc_max=float(sensors.adc_max))


def simulate_range_holds(user: GloveUser, sensors: SensorParams, *, seed: int = 0,
                         start_s: float = 0.0, rate_hz: float = 60.0, hold_samples: int = 30,
                         with_angles: bool = True) -> GloveRecording:
    """The open-hand and fist holds of a range calibration, labelled as such.

    :func:`simulate_poses` of the named poses ``open`` and ``fist``, with
    ``motion`` :data:`RANGE_LABELS` (``"range_open"``, ``"range_fist"``),
    which :func:`range_readings` and ``glove apply --range`` read.

    Parameters
    ----------
    user : GloveUser
    sensors : SensorParams
        The glove as worn (:func:`don_glove`).
    seed : int, keyword-only
        Seed of the holding error and the sensor noise.
    start_s : float, keyword-only
        Time of the first sample, s (for holds appended to a session: after
        its last sample).
    rate_hz : float, keyword-only
        Sampling rate of ``time_s``, Hz (:func:`simulate_session`'s default).
    hold_samples : int, keyword-only
        Samples per hold.
    with_angles : bool, keyword-only
        Keep the held angles as the reference ``angles``.

    Returns
    -------
    GloveRecording
        ``2 * hold_samples`` samples, open hand first.
    """
    if not rate_hz > 0:
        raise InvalidInputError(f"rate_hz must be > 0, got {rate_hz!r}")
    holds = simulate_poses(user, sensors, np.stack([NAMED_POSES["open"], NAMED_POSES["fist"]]),
                           seed=seed, hold_samples=hold_samples)
    return GloveRecording(
        sensors=holds.sensors, angles=holds.angles if with_angles else None,
        motion=np.repeat(RANGE_LABELS, hold_samples), trial=holds.trial,
        time_s=start_s + np.arange(holds.n_samples) / rate_hz, kind=holds.kind,
        adc_max=holds.adc_max)
