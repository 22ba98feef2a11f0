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
from ...models import SEGMENTS
from ._result import JointCentreResult

__all__ = ["SEGMENT_NAMES", "segment_length_mm", "segment_lengths_mm"]

#: Segment names of L1..L14, in order (``<finger>_<segment>`` of :data:`handsynth.models.SEGMENTS`).
SEGMENT_NAMES: tuple[str, ...] = tuple(f"{f}_{seg}" for f, seg in SEGMENTS)


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
        If the two estimates do not share a segment.
    """
    seg = proximal.labels[1]
    if distal.labels[0] != seg:
        raise InvalidInputError(
            f"proximal estimate's lower segment {seg!r} is not the distal estimate's "
            f"upper segment {distal.labels[0]!r}"
        )
    return float(np.linalg.norm(proximal.centre_lower - distal.centre_upper) * 1e3)


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
    """
    by_lower: dict[str, JointCentreResult] = {}
    by_upper: dict[str, JointCentreResult] = {}
    for r in results:
        if not isinstance(r, JointCentreResult):
            raise InvalidInputError(f"results: expected JointCentreResult, got {type(r).__name__}")
        by_upper[r.labels[0]] = r
        by_lower[r.labels[1]] = r
    tips = dict(tips or {})
    unknown = sorted(set(tips) - set(SEGMENT_NAMES))
    if unknown:
        raise InvalidInputError(f"tips: unknown segments {unknown}")
    out = np.full(len(SEGMENT_NAMES), np.nan)
    for i, seg in enumerate(SEGMENT_NAMES):
        prox = by_lower.get(seg)
        if prox is None:
            continue
        if seg in by_upper:
            out[i] = segment_length_mm(prox, by_upper[seg])
        elif seg in tips:
            tip = np.asarray(tips[seg], dtype=np.float64)
            if tip.shape != (3,) or not np.isfinite(tip).all():
                raise InvalidInputError(f"tips[{seg!r}]: expected 3 finite numbers, got {tips[seg]!r}")
            out[i] = float(np.linalg.norm(prox.centre_lower - tip) * 1e3)
    return out
