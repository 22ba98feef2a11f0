"""Test shapes for the feature tests of handsynth.db (64x64 bool images)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from scipy import ndimage

N = 64


def _disc(cy, cx, r):
    yy, xx = np.mgrid[:N, :N]
    return (yy - cy) ** 2 + (xx - cx) ** 2 <= r**2


def _ellipse(cy, cx, ry, rx, angle_deg=0.0):
    img = np.zeros((N, N), np.uint8)
    cv2.ellipse(img, (cx, cy), (rx, ry), angle_deg, 0, 360, 1, -1)
    return img.astype(bool)


def _rect(img, r0, r1, c0, c1):
    img[r0:r1, c0:c1] = True
    return img


def _hand(spread: int, flex: int) -> np.ndarray:
    """Palm ellipse + four finger bars + a thumb ellipse, roughly a dorsal view."""
    img = _ellipse(44, 30, 14, 16)
    for i, x in enumerate((16, 25, 34, 43)):
        top = int(6 + 3 * abs(i - 1.5)) + flex
        left = x + int((i - 1.5) * spread)
        _rect(img, top, 40, left, left + 6)
    img |= _ellipse(40, 52, 4, 10, -40)
    return img


def _letter(ch: str, thickness: int) -> np.ndarray:
    img = np.zeros((N, N), np.uint8)
    cv2.putText(img, ch, (8, 54), cv2.FONT_HERSHEY_SIMPLEX, 1.9, 1, thickness)
    return img.astype(bool)


def _blob(seed: int, sigma: float, level: float) -> np.ndarray:
    rng = np.random.default_rng(seed)
    field = ndimage.gaussian_filter(rng.standard_normal((N, N)), sigma)
    return field > level * field.std()


def make_shapes() -> dict[str, np.ndarray]:
    shapes = {
        "empty": np.zeros((N, N), bool),
        "full": np.ones((N, N), bool),
        "pixel": _rect(np.zeros((N, N), bool), 30, 31, 30, 31),
        "disc": _disc(32, 32, 20),
        "small_disc": _disc(10, 50, 4),
        "ring": _disc(32, 32, 22) & ~_disc(32, 32, 12),
        "two_rings": (_disc(20, 20, 12) & ~_disc(20, 20, 5))
        | (_disc(44, 44, 14) & ~_disc(44, 44, 6)),
        "border_touching": _rect(np.zeros((N, N), bool), 0, 20, 0, 64),
    }
    for spread in (0, 4):
        for flex in (0, 12):
            shapes[f"hand_s{spread}_f{flex}"] = _hand(spread, flex)
    for ch in "ABHOPRSX8":
        shapes[f"letter_{ch}"] = _letter(ch, 5)
    for seed in range(12):
        shapes[f"blob_{seed}"] = _blob(seed, sigma=2.5 + seed % 3, level=0.3 * (seed % 4 - 1))
    return shapes


@pytest.fixture(scope="session")
def shapes() -> dict[str, np.ndarray]:
    return make_shapes()
