"""Hand measurements: the values that choose a hand's database, in millimetres.

The user's hand is measured on a picture of the open, flat hand
(:mod:`handsynth.measure`); the same values are measured on the built model
(:func:`model_measurements`).  :mod:`handsynth.estimate` turns the two into
the four shape ratios of formulas (1)-(4) of SPEC.md section 1.

Measurement definitions (all in millimetres)
--------------------------------------------
``L1..L14`` -- joint-to-joint lengths of the 14 phalanges, in this order:
    L1 thumb proximal (MCP-IP), L2 thumb distal (IP-tip), then for index,
    middle, ring and little in turn: proximal (MCP-PIP), middle (PIP-DIP),
    distal (DIP-tip).  See :data:`SEGMENTS`.
``W1..W14`` -- breadth of the same segments at the middle between their joints.
``P_width`` -- palm breadth at the height midway between the thumb base (CMC
    joint) and the mean height of the four finger bases (MCP joints).
``P_height`` -- middle-finger base (MCP) to the palm's lower edge (the
    wrist crease; the model's line y = 0 through the wrist joint centre).
``T_width`` -- thumb base (CMC) to middle-finger base, across the hand.
``T_height`` -- thumb base (CMC) to the palm's lower edge, along the hand.

File format
-----------
:meth:`HandMeasurements.from_file` reads either

* JSON: one object ``{"L": [14 numbers], "W": [14 numbers], "P_width": x,
  "P_height": x, "T_width": x, "T_height": x}`` (an optional ``"units"``
  field must be ``"mm"``), or
* CSV: two columns ``name,value_mm`` with one row per value, names ``L1`` ..
  ``L14``, ``W1`` .. ``W14``, ``P_width``, ``P_height``, ``T_width``,
  ``T_height`` (a header row is optional; ``#`` starts a comment line).
"""

from __future__ import annotations

import csv
import itertools
import json
import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from ..errors import InvalidShapeError
from ._hand import HandModel
from ._joints import FINGERS
from ._mjcf import hand_spec
from ._shape import HandShape

__all__ = ["SEGMENTS", "HandMeasurements", "hull_width_at", "model_measurements"]

#: The 14 segments of ``L1..L14`` / ``W1..W14`` in order, as (finger, segment).
SEGMENTS: tuple[tuple[str, str], ...] = (
    ("thumb", "proximal"),
    ("thumb", "distal"),
    *((f, s) for f in FINGERS[1:] for s in ("proximal", "middle", "distal")),
)
_N_SEG = len(SEGMENTS)
_SCALARS = ("P_width", "P_height", "T_width", "T_height")


def _positive_vector(value, name: str) -> tuple[float, ...]:
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidShapeError(f"{name} must be {_N_SEG} numbers in mm, got {value!r}") from None
    if arr.shape != (_N_SEG,):
        raise InvalidShapeError(f"{name} must hold {_N_SEG} values (mm), got shape {arr.shape}")
    bad = ~np.isfinite(arr) | (arr <= 0)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise InvalidShapeError(
            f"{name}{i + 1} must be a positive finite length in mm, got {arr[i].item()!r}"
        )
    return tuple(float(v) for v in arr)


def _positive_scalar(value, name: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InvalidShapeError(f"{name} must be a length in mm, got {value!r}") from None
    if not math.isfinite(v) or v <= 0:
        raise InvalidShapeError(f"{name} must be a positive finite length in mm, got {value!r}")
    return v


@dataclass(frozen=True)
class HandMeasurements:
    """The measurements of one hand used to choose its database, in millimetres.

    Parameters
    ----------
    L : sequence of 14 float
        Segment lengths ``L1..L14`` in the order of :data:`SEGMENTS`, mm.
    W : sequence of 14 float
        Segment widths ``W1..W14`` at mid-segment, same order, mm.
    P_width, P_height, T_width, T_height : float
        Palm and thumb-base values, mm (definitions in the module docstring).

    Raises
    ------
    InvalidShapeError
        A missing, non-finite or non-positive value, naming it (e.g. ``W3``).
    """

    L: tuple[float, ...]
    W: tuple[float, ...]
    P_width: float
    P_height: float
    T_width: float
    T_height: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "L", _positive_vector(self.L, "L"))
        object.__setattr__(self, "W", _positive_vector(self.W, "W"))
        for name in _SCALARS:
            object.__setattr__(self, name, _positive_scalar(getattr(self, name), name))

    # -- conversions -------------------------------------------------------------
    def as_dict(self) -> dict:
        """The JSON form of the file format (lists for ``L`` and ``W``, ``units="mm"``)."""
        out = {"units": "mm", "L": list(self.L), "W": list(self.W)}
        out.update({n: getattr(self, n) for n in _SCALARS})
        return out

    @classmethod
    def from_dict(cls, values: dict) -> HandMeasurements:
        """Build from the JSON object form (see the module docstring).

        Raises
        ------
        InvalidShapeError
            Unknown or missing keys, or units other than ``"mm"``.
        """
        if not isinstance(values, dict):
            raise InvalidShapeError(f"measurements must be a JSON object, got {type(values).__name__}")
        values = dict(values)
        units = values.pop("units", "mm")
        if units != "mm":
            raise InvalidShapeError(f"measurement units must be 'mm', got {units!r}")
        expected = {"L", "W", *_SCALARS}
        unknown = sorted(set(values) - expected)
        missing = sorted(expected - set(values))
        if unknown or missing:
            raise InvalidShapeError(
                f"measurements have unknown keys {unknown} and missing keys {missing}; "
                f"expected {sorted(expected)}"
            )
        return cls(**values)

    @classmethod
    def from_file(cls, path) -> HandMeasurements:
        """Read a ``.json`` or ``.csv`` measurement file (format in the module docstring).

        Raises
        ------
        InvalidShapeError
            Unreadable or non-UTF-8 file, unknown suffix, a name given twice,
            or bad values (naming file, line and field).  A UTF-8 byte-order
            mark is allowed.
        """
        path = Path(path)
        suffix = path.suffix.lower()
        try:
            # utf-8-sig: a byte-order mark (Excel's "CSV UTF-8") is not part of the text
            text = path.read_text(encoding="utf-8-sig")
        except OSError as exc:
            raise InvalidShapeError(f"cannot read measurement file {path}: "
                                    f"{exc.strerror or exc}") from None
        except UnicodeDecodeError as exc:
            raise InvalidShapeError(
                f"measurement file {path} is not UTF-8 text (byte {exc.object[exc.start]:#04x} at "
                f"offset {exc.start}); save it as UTF-8") from None
        if suffix == ".json":
            try:
                return cls.from_dict(json.loads(text))
            except json.JSONDecodeError as exc:
                raise InvalidShapeError(f"measurement file {path} is not JSON: {exc}") from None
        if suffix == ".csv":
            values: dict[str, float] = {}
            seen: dict[str, int] = {}
            for k, row in enumerate(csv.reader(text.splitlines()), 1):
                if not row or not row[0].strip() or row[0].lstrip().startswith("#"):
                    continue
                if len(row) != 2:
                    raise InvalidShapeError(f"{path} line {k}: expected 'name,value_mm', got {row}")
                name, value = row[0].strip(), row[1].strip()
                if k == 1 and name.lower() == "name":
                    continue
                if name in values:
                    raise InvalidShapeError(
                        f"{path} line {k}: {name} is given again (line {seen[name]} gave it "
                        "first); give each measurement once")
                seen[name] = k
                try:
                    values[name] = float(value)
                except ValueError:
                    raise InvalidShapeError(
                        f"{path} line {k}: value of {name} must be a number, got {value!r}"
                    ) from None
            return cls.from_flat(values)
        raise InvalidShapeError(f"measurement file must end in .json or .csv, got {str(path)!r}")

    @classmethod
    def from_flat(cls, values: dict[str, float]) -> HandMeasurements:
        """Build from flat names ``L1..L14, W1..W14, P_width, P_height, T_width, T_height``."""
        names = [f"L{i}" for i in range(1, 15)] + [f"W{i}" for i in range(1, 15)] + list(_SCALARS)
        unknown = sorted(set(values) - set(names))
        missing = [n for n in names if n not in values]
        if unknown or missing:
            raise InvalidShapeError(
                f"measurements have unknown names {unknown} and missing names {missing}"
            )
        return cls(
            L=tuple(values[f"L{i}"] for i in range(1, 15)),
            W=tuple(values[f"W{i}"] for i in range(1, 15)),
            **{n: values[n] for n in _SCALARS},
        )


def hull_width_at(points_xy: np.ndarray, y: float) -> float:
    """Breadth along x of the convex hull of `points_xy` (M, 2) cut by the line at `y`."""
    from scipy.spatial import ConvexHull

    hull = points_xy[ConvexHull(points_xy).vertices]
    xs = []
    for (x0, y0), (x1, y1) in zip(hull, np.roll(hull, -1, axis=0)):
        if (y0 - y) * (y1 - y) <= 0 and y0 != y1:
            xs.append(x0 + (y - y0) * (x1 - x0) / (y1 - y0))
    if len(xs) < 2:
        raise InvalidShapeError(f"the model's outline does not reach height {y:.1f} mm")
    return float(max(xs) - min(xs))


def model_measurements(shape: HandShape | None = None) -> HandMeasurements:
    """The measurements of the built MuJoCo hand of `shape` (right hand, open pose).

    Lengths are joint-to-joint distances between the model's keypoints
    (:meth:`handsynth.models.HandModel.keypoints`); widths are read off the
    model's own geometry (:func:`handsynth.models.hand_spec`): the
    breadth of the convex outline of each phalanx mesh, seen from the back of
    the hand, at mid-segment, and the breadth of the palm mesh at the
    ``P_width`` height.  So a photo of the model hand measured by hand would
    give these numbers.

    Parameters
    ----------
    shape : HandShape, optional
        The standard hand by default.

    Returns
    -------
    HandMeasurements
        In millimetres.
    """
    return _model_measurements(shape or HandShape())


@lru_cache(maxsize=128)
def _model_measurements(shape: HandShape) -> HandMeasurements:
    """:func:`model_measurements`, cached per shape (``None`` and ``HandShape()`` alike)."""
    kp = HandModel(shape, forearm=False).keypoints() * 1e3  # (21, 3) mm
    # keypoint rows: 1..4 thumb cmc, mcp, ip, tip; 5 + 4k .. finger k mcp, pip, dip, tip
    chains = {"thumb": [2, 3, 4], **{f: [5 + 4 * k + j for j in range(4)]
                                      for k, f in enumerate(FINGERS[1:])}}
    lengths = []
    for seg_rows in chains.values():
        for a, b in itertools.pairwise(seg_rows):
            lengths.append(float(np.linalg.norm(kp[b] - kp[a])))

    spec = hand_spec(shape)
    bodies = {}
    stack = [spec.root]
    while stack:
        body = stack.pop()
        bodies[body.name] = body
        stack.extend(body.children)
    widths = []
    for (f, seg), length in zip(SEGMENTS, lengths):
        mesh = bodies[f"{f}_{seg}"].mesh  # body frame: y along the segment, x across
        widths.append(hull_width_at(mesh[:, :2], 0.5 * length))

    cmc = kp[1]
    mcp_rows = [5, 9, 13, 17]
    y_mid = 0.5 * (cmc[1] + kp[mcp_rows, 1].mean())
    p_width = hull_width_at(spec.root.mesh[:, :2], y_mid)
    return HandMeasurements(
        L=tuple(lengths),
        W=tuple(widths),
        P_width=p_width,
        P_height=float(kp[9, 1] - kp[0, 1]),
        T_width=float(abs(kp[9, 0] - cmc[0])),
        T_height=float(cmc[1] - kp[0, 1]),
    )


