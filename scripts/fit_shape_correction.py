"""Fit the photo measurement's shape correction and check it on other hands.

Prints the 4 x 5 coefficients for ``handsynth.estimate._measure.MODEL_SHAPE_CORRECTION``
(fitted on photos of random model hands, :func:`fit_shape_correction`) and the
errors of the measured ratios on held-out hands without and with it.

    python scripts/fit_shape_correction.py [--hands 60] [--test-hands 30]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from handsynth.eval import random_hand_shapes
from handsynth.measure import (
    NO_SHAPE_CORRECTION,
    MeasureOptions,
    ShapeCorrection,
    fit_shape_correction,
    measure_photo,
    render_measurement_photo,
)

RATIOS = ("length", "width", "palm", "thumb")


def errors(shapes, correction: ShapeCorrection, scales, seed: int) -> np.ndarray:
    """Measured minus true ratios, shape (len(shapes) * len(scales), 4)."""
    rng = np.random.default_rng(seed)
    opts = MeasureOptions(shape_correction=correction)
    out = []
    for shape in shapes:
        for scale in scales:
            photo = render_measurement_photo(shape, mm_per_px=scale,
                                             roll_deg=float(rng.uniform(-180, 180)))
            found = measure_photo(photo.image, mm_per_px=scale, options=opts).shape
            out.append([getattr(found, n) - getattr(shape, n) for n in RATIOS])
    return np.array(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hands", type=int, default=60)
    ap.add_argument("--test-hands", type=int, default=30)
    ap.add_argument("--margin", type=float, default=0.75)
    args = ap.parse_args()
    t = time.perf_counter()
    train = random_hand_shapes(args.hands, seed=1000, margin=args.margin)
    fitted = fit_shape_correction(train, mm_per_px=(0.15, 0.25, 0.4), seed=1000)
    print(f"fitted on {args.hands} hands x 3 scales in {time.perf_counter() - t:.0f} s")
    print("coefficients=(")
    for row in fitted.coefficients:
        print("    (" + ", ".join(f"{v:.5f}" for v in row) + "),")
    print(")")
    test = random_hand_shapes(args.test_hands, seed=2000, margin=0.5)
    for scale in (0.15, 0.25, 0.4, 0.5):
        for name, corr in (("raw", NO_SHAPE_CORRECTION), ("corrected", fitted)):
            e = errors(test, corr, [scale], seed=2000)
            rms = np.sqrt((e ** 2).mean(axis=0))
            mx = np.abs(e).max(axis=0)
            print(f"{scale:.2f} mm/px {name:9s} rms " + " ".join(f"{v:.4f}" for v in rms)
                  + "  max " + " ".join(f"{v:.4f}" for v in mx) + "  (length width palm thumb)")


if __name__ == "__main__":
    main()
