"""Joint-angle time series of a repeated flexion-extension trial.

The protocol follows the patent (JP2010-88628, para. 0102-0104): the
receivers are recorded while the finger (or the mock's lower segment) is
flexed and extended repeatedly for 15-30 s at 240 Hz (120 Hz possible,
para. 0097).  A short static hold at the start gives the "standard state"
that the axis-angle filter refers to (para. 0084).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ...errors import InvalidInputError
from ._checks import check_interval, check_number

__all__ = ["MAX_SAMPLES", "FlexionMotion", "MotionSamples"]

#: Most samples of one simulated trial (about 1 GB of float64 poses): 11.6 h at 240 Hz.
MAX_SAMPLES = 10_000_000


@dataclass(frozen=True)
class MotionSamples:
    """Sampled angles, all ``(n,)`` float64 arrays; angles in radians.

    Attributes
    ----------
    times : seconds
    flexion : flexion of the joint under test
    wobble : abduction wobble of the joint under test
    proximal : flexion of the upper segment's own proximal joint
    """

    times: np.ndarray
    flexion: np.ndarray
    wobble: np.ndarray
    proximal: np.ndarray


@dataclass(frozen=True, kw_only=True)
class FlexionMotion:
    """Repeated flexion-extension with abduction wobble.

    Parameters
    ----------
    duration_s : float
        Length of the trial including the hold, seconds; the default 20 s lies
        in the patent's 15-30 s of flexion/extension (SPEC.md section 2).
    rate_hz : float
        Sampling rate; the Liberty runs at 240 Hz or 120 Hz (default 240 Hz:
        the patent's Polhemus Liberty, SPEC.md section 2).
    hold_s : float
        Static hold in extension at the start (the standard state), seconds.
    flexion_range_deg : (float, float)
        Extension and flexion ends of each cycle, degrees.
    cycle_s : float
        Mean duration of one flexion-extension cycle, seconds.
    variability : float
        Relative cycle-to-cycle spread of period and amplitude (0 = identical
        cycles).
    wobble_deg : float
        Amplitude of the abduction wobble, degrees (0 for the mock).
    wobble_hz : float
        Frequency of the wobble, Hz (incommensurate with the cycle).
    proximal_coupling : float
        The upper segment's proximal joint flexes by this fraction of the
        joint's flexion (PIP and DIP flex together in a real finger; 0 for a
        mock whose upper segment is held).
    """

    duration_s: float = 20.0
    rate_hz: float = 240.0
    hold_s: float = 0.5
    flexion_range_deg: tuple[float, float] = (0.0, 75.0)
    cycle_s: float = 1.6
    variability: float = 0.15
    wobble_deg: float = 3.0
    wobble_hz: float = 0.37
    proximal_coupling: float = 0.5

    def __post_init__(self) -> None:
        d = asdict(self)
        check_interval(d.pop("flexion_range_deg"), "flexion_range_deg")
        for name, v in d.items():
            check_number(v, name)
        for name in ("duration_s", "rate_hz", "cycle_s"):
            check_number(getattr(self, name), name, above=0.0)
        if not 0 <= self.hold_s < self.duration_s:
            raise InvalidInputError(
                f"duration_s ({self.duration_s!r} s) must be longer than hold_s "
                f"({self.hold_s!r} s, the still start), and hold_s at least 0"
            )
        if self.duration_s * self.rate_hz > MAX_SAMPLES:
            raise InvalidInputError(
                f"duration_s x rate_hz must be at most {MAX_SAMPLES:,} samples, got "
                f"{self.duration_s!r} s x {self.rate_hz!r} Hz")
        if not 0 <= self.variability < 1:
            raise InvalidInputError(f"variability must be in [0, 1), got {self.variability!r}")

    def sample(self, rng: np.random.Generator) -> MotionSamples:
        """Draw one trial.

        Parameters
        ----------
        rng : numpy.random.Generator
            Source of the cycle-to-cycle variability and wobble phase.

        Returns
        -------
        MotionSamples
        """
        n = int(round(self.duration_s * self.rate_hz))
        t = np.arange(n) / self.rate_hz
        lo, hi = np.deg2rad(self.flexion_range_deg)
        # cycle boundaries with jittered periods and amplitudes
        n_cycles = int(np.ceil(self.duration_s / self.cycle_s)) + 2
        periods = self.cycle_s * (1 + self.variability * rng.uniform(-1, 1, n_cycles))
        amps = 1 - self.variability * rng.uniform(0, 1, n_cycles)
        starts = self.hold_s + np.concatenate([[0.0], np.cumsum(periods)])
        k = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, n_cycles - 1)
        phase = np.clip((t - starts[k]) / periods[k], 0.0, 1.0)
        shape = 0.5 * (1 - np.cos(2 * np.pi * phase))  # 0 -> 1 -> 0, smooth
        moving = t >= self.hold_s
        flex = lo + (hi - lo) * amps[k] * shape * moving
        ramp = np.clip((t - self.hold_s) / 0.5, 0.0, 1.0)
        wobble = (
            np.deg2rad(self.wobble_deg)
            * ramp
            * np.sin(2 * np.pi * self.wobble_hz * (t - self.hold_s) + rng.uniform(0, 2 * np.pi))
        )
        return MotionSamples(
            times=t,
            flexion=flex,
            wobble=wobble,
            proximal=self.proximal_coupling * (flex - lo),
        )
