"""A motion-quality report of a recording, before any joint centre is estimated.

What a user must see to judge a recording: how far the joint moved about
each principal direction of the relative rotation, how well that motion
determines the centre (:mod:`~handsynth.sensors.trackers._determinability`),
whether a sensor lay still, and what the reader found and dropped (lost
lines, duplicates, glitches, invalid frames).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from ..common import matrix_to_rotvec
from ._determinability import Determinability, assess_determinability
from ._recording import Recording

__all__ = ["MotionQuality", "motion_quality"]

#: A sensor whose position moves less than this (1st-99th percentile range,
#: any coordinate, mm) and whose orientation turns less than
#: ``_STATIC_DEG`` lay still.
_STATIC_MM = 2.0
_STATIC_DEG = 2.0
_READER_COUNTS = ("duplicates", "half_frames", "invalid_frames", "glitch_frames", "dropout_frames",
                  "frozen_frames", "skipped_lines", "non_increasing_times", "rows_after_restart",
                  "quaternion_sign_flips")


@dataclass(frozen=True)
class MotionQuality:
    """What a recording offers an estimator.

    Attributes
    ----------
    n_frames : int
        Frames in the recording (after the reader's drops).
    duration_s, rate_hz : float
    rom_deg : (3,) ndarray of float64
        Range (1st-99th percentile) of the relative rotation about the three
        principal directions of :class:`Determinability`, in its order
        (element 0: about the direction of least spread, the joint axis),
        degrees.
    determinability : Determinability
    sensor_range_mm, sensor_turn_deg : (2,) ndarray of float64
        Largest 1st-99th percentile range of each sensor's position
        coordinates (mm) and of its orientation (deg), upper and lower.
    static_sensors : tuple of str
        ``"upper"`` / ``"lower"`` for sensors that lay still.
    reader : dict
        The reader's counts (duplicates, half frames, glitches, ...), units
        and layout, from the recording's metadata.
    """

    n_frames: int
    duration_s: float
    rate_hz: float
    rom_deg: np.ndarray
    determinability: Determinability
    sensor_range_mm: np.ndarray
    sensor_turn_deg: np.ndarray
    static_sensors: tuple[str, ...]
    reader: dict

    def lines(self) -> list[str]:
        """The report as text lines."""
        det = self.determinability
        out = [
            f"motion: {self.n_frames} frames, {self.duration_s:.1f} s at {self.rate_hz:.0f} Hz; "
            f"range of motion {self.rom_deg[2]:.1f} / {self.rom_deg[1]:.1f} / "
            f"{self.rom_deg[0]:.1f} deg about the principal directions (the last about the "
            f"joint axis)",
            f"determinability: principal directions turn {det.spread_deg[2]:.2f} / "
            f"{det.spread_deg[1]:.2f} / {det.spread_deg[0]:.2f} deg RMS (the last is the "
            f"joint axis); expected error {det.expected_error_mm[1]:.2g} mm "
            f"across the axis, {min(det.expected_error_mm[0], 1e6):.2g} mm along it "
            f"(residual {det.residual_mm:.2f} mm, {det.n_effective:.0f} independent frames)",
            "sensors: " + ", ".join(
                f"{role} moves {r:.1f} mm / turns {t:.1f} deg"
                for role, r, t in zip(("upper", "lower"), self.sensor_range_mm,
                                      self.sensor_turn_deg))
            + (f"; {' and '.join(self.static_sensors)} lay still" if self.static_sensors else ""),
        ]
        rd = self.reader
        if rd:
            counts = ", ".join(f"{k.replace('_', ' ')} {rd[k]}" for k in _READER_COUNTS
                               if rd.get(k))
            fmt = f"{rd.get('format', '?')} ({rd.get('layout', '')}), units {rd.get('units', '?')}"
            if rd.get("units_note"):
                fmt += f" [{rd['units_note']}]"
            if rd.get("decimal_comma"):
                fmt += ", decimal commas"
            out.append(f"file: {fmt}" + (f"; {counts}" if counts else "; nothing dropped"))
        return out

    def to_dict(self) -> dict:
        """JSON-serialisable report."""
        return {
            "n_frames": self.n_frames,
            "duration_s": round(self.duration_s, 4),
            "rate_hz": round(self.rate_hz, 3),
            "rom_deg": np.round(self.rom_deg, 3).tolist(),
            "determinability": self.determinability.to_dict(),
            "sensor_range_mm": np.round(self.sensor_range_mm, 3).tolist(),
            "sensor_turn_deg": np.round(self.sensor_turn_deg, 3).tolist(),
            "static_sensors": list(self.static_sensors),
            "reader": self.reader,
        }


def motion_quality(recording: Recording) -> MotionQuality:
    """Report what `recording` offers an estimator (see module docstring).

    Parameters
    ----------
    recording : Recording

    Returns
    -------
    MotionQuality
    """
    q, d = recording.relative()
    det = assess_determinability(q, d)
    mean = Rotation.from_matrix(q).mean().as_matrix()
    rv = np.rad2deg(matrix_to_rotvec(q @ mean.T))
    proj = rv @ det.directions_upper.T  # (n, 3), about each principal direction
    lo, hi = np.percentile(proj, [1.0, 99.0], axis=0)
    rom = hi - lo
    pos = recording.positions * 1e3
    plo, phi = np.percentile(pos, [1.0, 99.0], axis=0)  # (2, 3)
    rng = (phi - plo).max(axis=1)
    turn = np.empty(2)
    for s in range(2):
        m = Rotation.from_matrix(recording.rotations[:, s]).mean().as_matrix()
        ang = np.rad2deg(np.linalg.norm(matrix_to_rotvec(recording.rotations[:, s] @ m.T), axis=1))
        turn[s] = 2 * np.percentile(ang, 99.0)
    static = tuple(role for role, r, t in zip(("upper", "lower"), rng, turn)
                   if r < _STATIC_MM and t < _STATIC_DEG)
    meta = recording.metadata
    reader = {k: meta[k] for k in ("format", "layout", "units", "units_note", "decimal_comma",
                                   *_READER_COUNTS, "time_origin_unix_s") if k in meta}
    return MotionQuality(
        n_frames=recording.n_frames,
        duration_s=recording.duration_s,
        rate_hz=recording.rate_hz,
        rom_deg=rom,
        determinability=det,
        sensor_range_mm=rng,
        sensor_turn_deg=turn,
        static_sensors=static,
        reader=reader,
    )
