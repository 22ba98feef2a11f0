"""Segment lengths L1..L14 from estimated joint centres.

Order of the 14 segments (joint centre to joint centre; the distal
phalanges from the distal joint to the fingertip), the order that database
selection (SPEC section 1, eq. 1) takes them in:

==== ===================  ====  ===================
L1   thumb proximal       L8   middle distal
L2   thumb distal         L9   ring proximal
L3   index proximal       L10  ring middle
L4   index middle         L11  ring distal
L5   index distal         L12  little proximal
L6   middle proximal      L13  little middle
L7   middle middle        L14  little distal
==== ===================  ====  ===================

A segment's length needs two points in one rigid frame: the centre of its
proximal joint seen from the sensor on it (``P_L`` of the proximal joint's
estimate) and the centre of its distal joint seen from the same sensor
(``P_U`` of the distal joint's estimate), or a digitised fingertip in that
sensor's frame.  The sensor must stay glued on the segment between the two
trials.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

import numpy as np

from ...errors import InvalidInputError
from ...models import SEGMENT_COEFFICIENTS, SEGMENTS
from ._checks import check_vector3
from ._result import JointCentreResult

__all__ = ["SEGMENT_NAMES", "segment_length_mm", "segment_lengths_mm"]

#: Segment names of L1..L14, in order (``<finger>_<segment>`` of :data:`handsynth.models.SEGMENTS`).
SEGMENT_NAMES: tuple[str, ...] = tuple(f"{f}_{seg}" for f, seg in SEGMENTS)
#: Names that may carry the upper sensor of an MCP joint besides the segments.
_UPPER_ONLY = ("palm", "thumb_metacarpal")

# No phalanx is longer than this, nor is a fingertip farther from a sensor on
# the distal phalanx: the longest phalanx coefficient of Buchholz, Armstrong
# & Goldstein (1992) Table 1 (middle proximal, 0.277 of hand length) times
# 300 mm, the largest hand length handsynth.models accepts (adults are about
# 160-210 mm; Gordon et al. 1989 give means of 193.8 mm for men and 180.4 mm
# for women).  About 83 mm.
_MAX_SEGMENT_MM = 300.0 * max(max(c[1:]) for c in SEGMENT_COEFFICIENTS.values())


def _check_length(length_mm: float, what: str) -> float:
    """Refuse a length (mm) that no finger has, with a hint at the unit."""
    if not length_mm <= _MAX_SEGMENT_MM:
        raise InvalidInputError(
            f"{what} is {length_mm:.4g} mm, longer than any phalanx "
            f"({_MAX_SEGMENT_MM:.0f} mm at most); are the positions in metres?"
        )
    return length_mm


def _check_labels(r: JointCentreResult, i: int) -> None:
    """Refuse an estimate whose labels are not segment names."""
    known_upper = SEGMENT_NAMES + _UPPER_ONLY
    bad = []
    if r.labels[0] not in known_upper:
        bad.append(f"upper {r.labels[0]!r}")
    if r.labels[1] not in SEGMENT_NAMES:
        bad.append(f"lower {r.labels[1]!r}")
    if bad:
        raise InvalidInputError(
            f"results[{i}] (joint {r.joint!r}): labels {' and '.join(bad)} are not "
            f"segment names, so its centre cannot be placed on a segment; give the "
            f"Recording labels=(upper, lower) from {', '.join(known_upper)}"
        )


def segment_length_mm(proximal: JointCentreResult, distal: JointCentreResult) -> float:
    """Length of the segment between two estimated joints, millimetres.

    Parameters
    ----------
    proximal : JointCentreResult
        Estimate of the segment's proximal joint (the segment carries its
        *lower* sensor).
    distal : JointCentreResult
        Estimate of the segment's distal joint (the segment carries its
        *upper* sensor).

    Raises
    ------
    InvalidInputError
        If the two estimates do not share a segment, or the length is longer
        than any phalanx (about 83 mm: centres not in metres).
    """
    for name, r in (("proximal", proximal), ("distal", distal)):
        if not isinstance(r, JointCentreResult):
            raise InvalidInputError(f"{name}: expected JointCentreResult, got {type(r).__name__}")
    seg = proximal.labels[1]
    if distal.labels[0] != seg:
        raise InvalidInputError(
            f"proximal estimate's lower segment {seg!r} is not the distal estimate's "
            f"upper segment {distal.labels[0]!r}"
        )
    length = float(np.linalg.norm(proximal.centre_lower - distal.centre_upper) * 1e3)
    return _check_length(length, f"segment {seg!r} between the estimated centres")


def segment_lengths_mm(
    results: Iterable[JointCentreResult],
    *,
    tips: Mapping[str, np.ndarray] | None = None,
) -> np.ndarray:
    """Lengths L1..L14 (see module docstring) from joint-centre estimates.

    Parameters
    ----------
    results : iterable of JointCentreResult
        Estimates whose ``labels`` are segment names of
        :data:`SEGMENT_NAMES` (or ``"palm"`` / ``"thumb_metacarpal"`` for the
        upper side of an MCP joint).
    tips : mapping of str to (3,) array_like, optional
        Fingertip position in the frame of the sensor on a distal segment,
        metres, keyed by segment name (``"index_distal"``).

    Returns
    -------
    (14,) ndarray of float64
        Millimetres; NaN where the estimates do not determine a segment.

    Raises
    ------
    InvalidInputError
        An estimate whose ``labels`` are not segment names (such as a
        recording's default ``("upper", "lower")``), a tip keyed by an
        unknown segment or not 3 finite numbers, or a tip or length farther
        than any phalanx is long (about 83 mm, see ``_MAX_SEGMENT_MM``):
        positions in millimetres instead of metres.
    """
    by_lower: dict[str, JointCentreResult] = {}
    by_upper: dict[str, JointCentreResult] = {}
    for i, r in enumerate(results):
        if not isinstance(r, JointCentreResult):
            raise InvalidInputError(f"results: expected JointCentreResult, got {type(r).__name__}")
        _check_labels(r, i)
        by_upper[r.labels[0]] = r
        by_lower[r.labels[1]] = r
    tips = dict(tips or {})
    unknown = sorted(set(tips) - set(SEGMENT_NAMES))
    if unknown:
        raise InvalidInputError(
            f"tips: unknown segments {unknown}; known are {', '.join(SEGMENT_NAMES)}"
        )
    tip_at: dict[str, np.ndarray] = {}
    for seg, value in tips.items():
        tip = check_vector3(value, f"tips[{seg!r}]")
        _check_length(float(np.linalg.norm(tip) * 1e3), f"tips[{seg!r}] from its sensor")
        tip_at[seg] = tip
    out = np.full(len(SEGMENT_NAMES), np.nan)
    for i, seg in enumerate(SEGMENT_NAMES):
        prox = by_lower.get(seg)
        if prox is None:
            continue
        if seg in by_upper:
            out[i] = segment_length_mm(prox, by_upper[seg])
        elif seg in tip_at:
            length = float(np.linalg.norm(prox.centre_lower - tip_at[seg]) * 1e3)
            out[i] = _check_length(length, f"segment {seg!r} to tips[{seg!r}]")
    return out
