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
  ``T_height`` (a header row is optional, and when given must be
  ``name,value_mm``: other units are refused; ``#`` starts a comment line).

A value far off the others (a misplaced decimal point, other units) is
refused by name (:meth:`HandMeasurements.check_consistent`), and a hand far
from a person's size gives a warning.
"""

from __future__ import annotations

import csv
import itertools
import json
import math
import warnings
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from .._checks import check_instance, check_number, check_options, check_path, short_repr
from ..errors import InvalidShapeError
from ._hand import HandModel
from ._joints import FINGERS
from ._mjcf import hand_spec
from ._shape import HandShape

__all__ = ["NORMALIZATIONS", "SEGMENTS", "HandMeasurements", "formula_ratios", "hull_width_at",
           "model_measurements"]

#: The 14 segments of ``L1..L14`` / ``W1..W14`` in order, as (finger, segment).
SEGMENTS: tuple[tuple[str, str], ...] = (
    ("thumb", "proximal"),
    ("thumb", "distal"),
    *((f, s) for f in FINGERS[1:] for s in ("proximal", "middle", "distal")),
)
_N_SEG = len(SEGMENTS)
_SCALARS = ("P_width", "P_height", "T_width", "T_height")
# wrist to middle fingertip of a person's hand, generously (adults: about 160-210 mm)
_HAND_LENGTH_MM = (100.0, 300.0)
# a value this many times what the others suggest is refused when read (the
# corners of the supported range reach 4.2)
_ABSURD_FACTOR = 5.0
_RANGE_SLACK = 0.05  # check_consistent: ratios this fraction beyond [0.5, 2.0] still pass


def _positive_vector(value, name: str) -> tuple[float, ...]:
    if isinstance(value, (str, bytes)) or np.ndim(value) != 1:
        raise InvalidShapeError(f"{name} must be {_N_SEG} numbers in mm, got {short_repr(value)}")
    items = list(value)
    if len(items) != _N_SEG:
        raise InvalidShapeError(f"{name} must hold {_N_SEG} values (mm), got {len(items)}")
    return tuple(check_number(v, f"{name}{i + 1}", above=0.0, error=InvalidShapeError)
                 for i, v in enumerate(items))


def _positive_scalar(value, name: str) -> float:
    return check_number(value, name, above=0.0, error=InvalidShapeError)


def _made(source, cls, values: dict):
    """``cls(**values)``, its errors naming `source` (a file) when given."""
    try:
        return cls(**values)
    except InvalidShapeError as exc:
        if source is None:
            raise
        raise InvalidShapeError(f"{source}: {exc}") from None


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
    def from_dict(cls, values: dict, *, source=None) -> HandMeasurements:
        """Build from the JSON object form (see the module docstring).

        Parameters
        ----------
        values : dict
            The JSON object.
        source : str or path, keyword-only, optional
            Where the values come from (a file), named in the errors.

        Raises
        ------
        InvalidShapeError
            Unknown or missing keys, units other than ``"mm"``, or a value so
            far off the others that the values give no hand shape
            (:meth:`check_consistent`, naming `source` and the value).

        Warns
        -----
        UserWarning
            A hand far from a person's size (values not in millimetres?).
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
        measured = _made(source, cls, values)
        measured._refuse_absurd(source)
        measured._warn_if_not_hand_sized(source)
        return measured

    @classmethod
    def from_file(cls, path) -> HandMeasurements:
        """Read a ``.json`` or ``.csv`` measurement file (format in the module docstring).

        Raises
        ------
        InvalidShapeError
            `path` is not a file name (None, a number, ``""``); an
            unreadable or non-UTF-8 file, unknown suffix, a name given twice,
            a CSV value column other than ``value_mm``, or bad values (naming
            file, line and field; a value so far off the others that the values
            give no hand shape: :meth:`check_consistent`).  A UTF-8
            byte-order mark is allowed.

        Warns
        -----
        UserWarning
            A hand far from a person's size, naming the file (values not in
            millimetres?).
        """
        path = check_path(path, "path", kind="file", error=InvalidShapeError)
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
                obj = json.loads(text)
            except json.JSONDecodeError as exc:
                raise InvalidShapeError(f"measurement file {path} is not JSON: {exc}") from None
            return cls.from_dict(obj, source=path)
        if suffix == ".csv":
            values: dict[str, float] = {}
            seen: dict[str, int] = {}
            first = True
            for k, row in enumerate(csv.reader(text.splitlines()), 1):
                if not row or not row[0].strip() or row[0].lstrip().startswith("#"):
                    continue
                if len(row) != 2:
                    raise InvalidShapeError(f"{path} line {k}: expected 'name,value_mm', got {row}")
                name, value = row[0].strip(), row[1].strip()
                if first and name.lower() == "name":
                    first = False
                    if value.lower() != "value_mm":
                        # the values are read as millimetres: another unit would be
                        # read as mm silently (value_cm: a hand 10 times too small)
                        raise InvalidShapeError(
                            f"{path} line {k}: the value column is {value!r}, expected "
                            "'value_mm': give the measurements in millimetres (header "
                            "'name,value_mm')")
                    continue
                first = False
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
            return cls.from_flat(values, source=path)
        raise InvalidShapeError(f"measurement file must end in .json or .csv, got {str(path)!r}")

    @classmethod
    def from_flat(cls, values: dict[str, float], *, source=None) -> HandMeasurements:
        """Build from flat names ``L1..L14, W1..W14, P_width, P_height, T_width, T_height``.

        `source` (keyword-only, optional) names where the values come from in
        the errors and warnings; checks and warnings as :meth:`from_dict`.
        """
        names = [f"L{i}" for i in range(1, 15)] + [f"W{i}" for i in range(1, 15)] + list(_SCALARS)
        unknown = sorted(set(values) - set(names))
        missing = [n for n in names if n not in values]
        if unknown or missing:
            raise InvalidShapeError(
                f"measurements have unknown names {unknown} and missing names {missing}"
            )
        measured = _made(source, cls, {"L": tuple(values[f"L{i}"] for i in range(1, 15)),
                                       "W": tuple(values[f"W{i}"] for i in range(1, 15)),
                                       **{n: values[n] for n in _SCALARS}})
        measured._refuse_absurd(source)
        measured._warn_if_not_hand_sized(source)
        return measured

    # -- plausibility ----------------------------------------------------------------
    def _flat(self) -> dict[str, float]:
        out = {f"L{i}": v for i, v in enumerate(self.L, 1)}
        out.update({f"W{i}": v for i, v in enumerate(self.W, 1)})
        out.update({n: getattr(self, n) for n in _SCALARS})
        return out

    @property
    def hand_length_mm(self) -> float:
        """Wrist to middle fingertip: ``P_height + L6 + L7 + L8``, mm."""
        return self.P_height + sum(self.L[5:8])

    def _warn_if_not_hand_sized(self, source) -> None:
        """Warn when the hand is far from any person's size (values in other units?)."""
        lo, hi = _HAND_LENGTH_MM
        length = self.hand_length_mm
        if not lo <= length <= hi:
            where = f"{source}: " if source is not None else ""
            warnings.warn(
                f"{where}the hand measures {length:.4g} mm from the wrist to the middle "
                f"fingertip (P_height + L6 + L7 + L8), far from a person's {lo:.0f}-{hi:.0f} "
                "mm: are the values in millimetres?", stacklevel=3)

    def _ratios_to_standard(self) -> tuple[dict[str, float], float]:
        """Each value over the standard hand's, and the median of those 32 ratios."""
        mine, theirs = self._flat(), model_measurements(HandShape())._flat()
        ratio = {n: mine[n] / theirs[n] for n in mine}
        return ratio, float(np.median(list(ratio.values())))

    def _refuse_absurd(self, source) -> None:
        """:meth:`check_consistent` where a value is far off the others (a reader's check).

        A value more than :data:`_ABSURD_FACTOR` times (or less than its
        inverse) what the other values suggest is beyond any hand of the
        supported range (at most 4.2 times at its corners).
        """
        ratio, median = self._ratios_to_standard()
        odd = sorted((n for n, r in ratio.items()
                      if abs(math.log(r / median)) > math.log(_ABSURD_FACTOR)),
                     key=lambda n: -abs(math.log(ratio[n] / median)))
        if not odd:
            return
        self.check_consistent(source=source)  # its message where the ratios leave the range
        # the ratios stay in range, one value diluted among its digit's (L4 ten times too
        # long gave L 1.725): the value is still beyond any hand of the supported range
        mine, theirs = self._flat(), model_measurements(HandShape())._flat()
        where = f"{source}: " if source is not None else ""
        raise InvalidShapeError(
            f"{where}" + "; ".join(
                f"{n} {mine[n]:.6g} mm is {ratio[n] / median:.3g} times what the other values "
                f"suggest (about {median * theirs[n]:.3g} mm)" for n in odd[:3])
            + f": beyond any hand ({_ABSURD_FACTOR:g} times at most); check the value and that "
            "it is in millimetres")

    def check_consistent(self, *, source=None) -> None:
        """Refuse values that give no hand shape, naming the values that stand out.

        Formulas (1)-(4) of SPEC.md section 1 turn the values into four ratios
        to the standard hand (:func:`handsynth.estimate.shape_ratios`), each of
        which must lie in [0.5, 2.0].  Where they do not with either
        normalisation (``"palm_width"`` or ``"none"``), a value is wrong, not
        the hand: typically one number with a misplaced decimal point or in
        other units.  The error names the values whose ratio to the standard
        hand's is more than twice or less than half the median ratio of all 32.
        The readers (:meth:`from_file`, :meth:`from_dict`, :meth:`from_flat`)
        call it where one value is more than 5 times (or less than a fifth of)
        what the others suggest, and refuse that value when this passes; call it before
        :func:`~handsynth.estimate.select_shape` to get this error instead of
        a bare ratio out of range.

        Parameters
        ----------
        source : str or path, keyword-only, optional
            Where the values come from (a file), named in the error.

        Raises
        ------
        InvalidShapeError
            The ratios are outside [0.5, 2.0] with both normalisations.
        """
        std = model_measurements(HandShape())
        lo, hi = 0.5, 2.0
        out_of_range: list[str] = []
        for normalize in ("palm_width", "none"):
            ratios = formula_ratios(self, std, normalize=normalize)
            # a little beyond the range: rounding, or a hand at its edge (shape_ratios
            # decides those), not a wrong value
            bad = [(n, r) for n, r in ratios.items()
                   if not lo * (1.0 - _RANGE_SLACK) <= r <= hi * (1.0 + _RANGE_SLACK)]
            if not bad:
                return  # one normalisation gives a hand: the values may be right
            n, r = bad[0]
            how = "normalised by P_width" if normalize == "palm_width" else "as measured"
            out_of_range.append(f"a {n} ratio of {r:.3g} ({how})")
        mine, theirs = self._flat(), std._flat()
        ratio, median = self._ratios_to_standard()
        odd = sorted((n for n in ratio if not 0.5 <= ratio[n] / median <= 2.0),
                     key=lambda n: -abs(math.log(ratio[n] / median)))
        blamed = "; ".join(
            f"{n} {mine[n]:.6g} mm is {ratio[n] / median:.3g} times what the other values "
            f"suggest (about {median * theirs[n]:.3g} mm)" for n in odd[:3])
        if len(odd) > 3:
            blamed += f"; and {len(odd) - 3} more"
        where = f"{source}: " if source is not None else ""
        raise InvalidShapeError(
            f"{where}the measurements give {' and '.join(out_of_range)}, outside "
            f"[{lo}, {hi}]: " + (blamed + "; " if blamed else "")
            + "check the values and that they are in millimetres")


#: How formulas (1)-(4) scale the user's measurements: by the palm width (the paper's, for
#: photos without a scale) or not at all (millimetres as measured).
NORMALIZATIONS: tuple[str, ...] = ("palm_width", "none")


def formula_ratios(user: HandMeasurements, standard: HandMeasurements, *,
                   normalize: str = "palm_width") -> dict[str, float]:
    """Formulas (1)-(4) of SPEC.md section 1: the user's ratios to the standard hand.

    With ``s = P'_width / P_width`` (``normalize="palm_width"``) or ``s = 1``
    (``"none"``) the normalised values are ``X'' = s X`` and

    * (1) ``length = mean_i(L''_i / L'_i)``, i = 1..14
    * (2) ``width  = mean_i(W''_i / W'_i)``
    * (3) ``palm   = (P''_w / P'_w + T''_w / T'_w) / (2 P''_h / P'_h)``
    * (4) ``thumb  = T''_h / T'_h``

    Plain numbers, unchecked: :func:`handsynth.estimate.shape_ratios` makes
    them a :class:`HandShape` (which refuses ratios outside [0.5, 2]), and
    :meth:`HandMeasurements.check_consistent` names the values behind a
    ratio out of range.

    Parameters
    ----------
    user, standard : HandMeasurements
        The user's hand and the standard model, mm.
    normalize : {"palm_width", "none"}, keyword-only
        One of :data:`NORMALIZATIONS`.

    Returns
    -------
    dict
        ``{"length", "width", "palm", "thumb"}`` to the ratio.

    Raises
    ------
    InvalidShapeError
        `user` or `standard` is not a :class:`HandMeasurements`, or `normalize`
        is not one of :data:`NORMALIZATIONS` (a misspelt ``"palm-width"`` was
        read as ``"none"``).
    """
    check_instance(user, HandMeasurements, name="user", error=InvalidShapeError)
    check_instance(standard, HandMeasurements, name="standard", error=InvalidShapeError)
    if not isinstance(normalize, str) or normalize not in NORMALIZATIONS:
        raise InvalidShapeError(f"normalize must be one of {NORMALIZATIONS}, got "
                                f"{short_repr(normalize)}")
    s = standard.P_width / user.P_width if normalize == "palm_width" else 1.0
    return {
        "length": float(np.mean(s * np.asarray(user.L) / np.asarray(standard.L))),  # (1)
        "width": float(np.mean(s * np.asarray(user.W) / np.asarray(standard.W))),  # (2)
        "palm": float((s * user.P_width / standard.P_width + s * user.T_width / standard.T_width)
                      / (2.0 * s * user.P_height / standard.P_height)),  # (3)
        "thumb": float(s * user.T_height / standard.T_height),  # (4)
    }


def hull_width_at(points_xy: np.ndarray, y: float) -> float:
    """Breadth along x of the convex hull of `points_xy` (M, 2) cut by the line at `y`.

    Parameters
    ----------
    points_xy : ndarray, shape (M, 2), float
        Points (x, y), e.g. a mesh's vertices seen from the back of the hand; mm
        in this package's callers (the message of the error says mm).
    y : float
        Height of the horizontal cutting line, in the unit of `points_xy`.

    Returns
    -------
    float
        Largest minus smallest x where the hull's edges cross the line, in the
        unit of `points_xy`.

    Raises
    ------
    InvalidShapeError
        The hull does not reach height `y` (fewer than two crossings).
    InvalidInputError
        `points_xy` is not an (M, 2) array of finite numbers with M >= 3, or
        `y` is not a finite number.
    """
    from scipy.spatial import ConvexHull

    from ..errors import InvalidInputError

    try:
        pts = np.asarray(points_xy, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidInputError(f"points_xy must be an (M, 2) array of numbers, got "
                                f"{type(points_xy).__name__} {short_repr(points_xy)}") from None
    if pts.ndim != 2 or pts.shape[1] != 2 or pts.shape[0] < 3:
        raise InvalidInputError(f"points_xy must have shape (M, 2) with M >= 3 points, got "
                                f"shape {pts.shape}")
    if not np.isfinite(pts).all():
        raise InvalidInputError("points_xy must be finite, got NaN or inf at row "
                                f"{int(np.argwhere(~np.isfinite(pts))[0, 0])}")
    y = check_number(y, "y")
    hull = pts[ConvexHull(pts).vertices]
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
    return _model_measurements(check_options(shape, HandShape, name="shape",
                                             error=InvalidShapeError))


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


