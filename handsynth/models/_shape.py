"""Hand shape: the four ratios of the paper's 81-shape grid (SPEC.md section 1)."""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, fields

from .._checks import check_instance
from ..errors import InvalidShapeError

__all__ = ["GRID_LEVELS", "HandShape"]

#: Levels of each ratio in the paper's grid (SPEC.md section 1, table "Hand
#: shapes (81)"): (small, standard, large).
GRID_LEVELS: dict[str, tuple[float, float, float]] = {
    "length": (0.95, 1.0, 1.05),
    "width": (0.9, 1.0, 1.1),
    "palm": (0.95, 1.0, 1.05),
    "thumb": (0.9, 1.0, 1.1),
}

#: Ratios outside this range are refused: they no longer describe a human hand.
_RATIO_RANGE = (0.5, 2.0)


@dataclass(frozen=True)
class HandShape:
    """Shape of a hand as four ratios to the standard hand.

    Each ratio changes exactly what the paper's table says it changes and
    nothing else:

    ``length``
        the lengths of the 14 phalanges (thumb proximal and distal, three per
        finger); metacarpals and palm are unchanged.
    ``width``
        the breadth and depth of every phalanx (finger thickness).
    ``palm``
        the palm's horizontal width: the x coordinates (across the hand) of
        the MCP joints, of the thumb CMC joint and of the palm surface.
    ``thumb``
        the height of the thumb base (the CMC joint centre) above the palm's
        lower edge (the line y = 0 through the wrist joint centre).

    Parameters
    ----------
    length, width, palm, thumb : float
        Positive ratios, 1.0 for the standard hand; continuous values between
        and beyond the grid levels are allowed (0.5 to 2.0).

    Raises
    ------
    InvalidShapeError
        If a ratio is not a finite number in [0.5, 2.0].
    """

    length: float = 1.0
    width: float = 1.0
    palm: float = 1.0
    thumb: float = 1.0

    def __post_init__(self) -> None:
        lo, hi = _RATIO_RANGE
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, bool) or getattr(getattr(value, "dtype", None), "kind", "") == "b":
                raise InvalidShapeError(f"HandShape.{f.name} must be a number, got {value!r}")
            try:
                v = float(value)
            except (TypeError, ValueError):
                raise InvalidShapeError(
                    f"HandShape.{f.name} must be a number, got {value!r}"
                ) from None
            if not math.isfinite(v) or v <= 0:
                raise InvalidShapeError(
                    f"HandShape.{f.name} must be a positive finite ratio, got {value!r}"
                )
            if not lo <= v <= hi:
                raise InvalidShapeError(
                    f"HandShape.{f.name}={v} is outside the supported range [{lo}, {hi}]"
                )
            object.__setattr__(self, f.name, v)

    @classmethod
    def grid(cls) -> list[HandShape]:
        """The paper's 81 shapes: every combination of the three levels of each ratio.

        Returns
        -------
        list of HandShape
            81 distinct shapes, ``length`` varying slowest.
        """
        names = list(GRID_LEVELS)
        return [
            cls(**dict(zip(names, combo)))
            for combo in itertools.product(*(GRID_LEVELS[n] for n in names))
        ]

    def nearest_grid(self) -> HandShape:
        """The grid shape whose level is nearest to each of this shape's ratios."""
        return HandShape(
            **{
                n: min(levels, key=lambda lv: abs(lv - getattr(self, n)))
                for n, levels in GRID_LEVELS.items()
            }
        )

    @property
    def is_grid(self) -> bool:
        """Whether every ratio is exactly one of the grid levels."""
        return all(getattr(self, n) in lv for n, lv in GRID_LEVELS.items())

    @property
    def name(self) -> str:
        """A file-name-safe identifier, e.g. ``"L1.000_W0.900_P1.050_T1.000"``."""
        return (
            f"L{self.length:.3f}_W{self.width:.3f}_P{self.palm:.3f}_T{self.thumb:.3f}"
        )

    @classmethod
    def from_name(cls, name: str) -> HandShape:
        """Parse :attr:`name` back into a shape.

        Raises
        ------
        InvalidShapeError
            If `name` is not a str, or does not have the form produced by :attr:`name`.
        """
        check_instance(name, str, name="name", error=InvalidShapeError)
        parts = name.split("_")
        keys = {"L": "length", "W": "width", "P": "palm", "T": "thumb"}
        try:
            if len(parts) != 4 or [p[:1] for p in parts] != list(keys):
                raise ValueError
            ratios = {keys[p[0]]: float(p[1:]) for p in parts}
        except ValueError:
            raise InvalidShapeError(
                f"hand-shape name {name!r} is not of the form 'L1.000_W1.000_P1.000_T1.000'"
            ) from None
        try:
            return cls(**ratios)
        except InvalidShapeError as exc:  # of the form, outside the supported ratios
            raise InvalidShapeError(f"hand-shape name {name!r}: {exc}") from None

    def as_dict(self) -> dict[str, float]:
        """The four ratios as a plain dict (for JSON and HDF5 attributes)."""
        return {f.name: getattr(self, f.name) for f in fields(self)}
