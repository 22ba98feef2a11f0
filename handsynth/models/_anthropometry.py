"""Anthropometric proportions of the standard hand.

All lengths are for the *standard* hand of handsynth (every ratio of
:class:`~handsynth.models.HandShape` equal to 1), in millimetres, and are
scaled to metres only where the MJCF is written.

Sources
-------
- Segment lengths as fractions of hand length: Buchholz, Armstrong &
  Goldstein, "Anthropometric data for describing the kinematics of the human
  hand", *Ergonomics* 35(3):261-273 (1992), Table 1 (coefficients of hand
  length for the metacarpals and phalanges, distal phalanges to the
  fingertip).
- Hand length and breadth: close to the pooled mean of men and women in the
  1988 US Army anthropometric survey (Gordon et al., *1988 Anthropometric
  Survey of U.S. Army Personnel*, Natick/TR-89/044, 1989: hand length men
  193.8 mm, women 180.4 mm; hand breadth men 89.7 mm, women 79.0 mm).  The
  standard hand takes 187 mm and 84 mm.
- Finger breadths at the PIP and DIP joints: Greiner, *Hand Anthropometry of
  U.S. Army Personnel*, Natick/TR-92/011 (1991), pooled and rounded to 0.5 mm.
  Finger depth (dorsal-palmar) is taken as 0.85 of breadth, as in the same
  report's ratio of finger depth to finger breadth at the joints.
- Palm thickness at the metacarpal heads about 28 mm: Greiner (1991),
  "hand thickness at metacarpale III".

The positions of the MCP joints across the palm and of the thumb CMC joint
are derived from the same hand length and breadth (finger spacing =
breadth / 4, MCP arc from the metacarpal lengths of Buchholz Table 1); the
derivation is in :func:`standard_layout_mm`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "DEPTH_TO_BREADTH",
    "FINGER_BREADTH_MM",
    "HAND_BREADTH_MM",
    "HAND_LENGTH_MM",
    "PALM_THICKNESS_MM",
    "SEGMENT_COEFFICIENTS",
    "StandardLayout",
    "standard_layout_mm",
]

#: Hand length and breadth, mm: about the pooled mean of men and women in
#: Gordon et al. (1989), 1988 US Army survey (module docstring, "Sources").
HAND_LENGTH_MM: float = 187.0
HAND_BREADTH_MM: float = 84.0
#: Palm thickness at the metacarpal heads, mm: Greiner (1991), "hand thickness
#: at metacarpale III" (module docstring, "Sources").
PALM_THICKNESS_MM: float = 28.0

#: Buchholz et al. (1992) Table 1: segment length / hand length.
#: Thumb: metacarpal, proximal, distal.  Fingers: metacarpal, proximal,
#: middle, distal (distal phalanx measured to the fingertip).
SEGMENT_COEFFICIENTS: dict[str, tuple[float, ...]] = {
    "thumb": (0.251, 0.196, 0.158),
    "index": (0.374, 0.265, 0.143, 0.097),
    "middle": (0.373, 0.277, 0.170, 0.108),
    "ring": (0.336, 0.259, 0.165, 0.107),
    "little": (0.295, 0.206, 0.117, 0.093),
}

#: Greiner (1991): finger breadth at (proximal joint, distal joint) in mm;
#: for the thumb (MCP, IP).
FINGER_BREADTH_MM: dict[str, tuple[float, float]] = {
    "thumb": (22.0, 21.0),
    "index": (20.0, 18.0),
    "middle": (20.5, 18.5),
    "ring": (19.5, 17.5),
    "little": (17.5, 16.0),
}

#: Finger depth (dorsal-palmar) / finger breadth at the joints: Greiner (1991)
#: (module docstring, "Sources").
DEPTH_TO_BREADTH: float = 0.85


@dataclass(frozen=True)
class StandardLayout:
    """Joint positions of the standard right hand at rest, hand frame, mm.

    Attributes
    ----------
    mcp : dict of str to ndarray, shape (3,)
        MCP joint centres of the four fingers.
    thumb_cmc : ndarray, shape (3,)
        Thumb CMC joint centre.
    finger_yaw_deg : dict of str to float
        Rest direction of each finger in the palm plane, degrees from +y,
        positive toward the thumb (the natural slight fan of an open hand).
    """

    mcp: dict[str, np.ndarray]
    thumb_cmc: np.ndarray
    finger_yaw_deg: dict[str, float]


def standard_layout_mm() -> StandardLayout:
    """Joint layout of the standard right hand, derived from Buchholz (1992).

    The middle-finger MCP lies on the +y axis (that is the definition of the
    hand frame) at ``HL * (1 - sum of middle phalanx coefficients)``, so that
    the extended middle fingertip lies one hand length from the wrist.  The
    other MCPs sit one finger spacing (``breadth / 4``) apart across the palm
    and lower by the difference of their metacarpal length from the middle
    one's, which reproduces the arc of the metacarpal heads.  The thumb CMC
    lies on the radial side of the palm, 0.13 hand lengths from the wrist
    and 8 mm palmar of the palm plane (the trapezium is palmar of the other
    carpals).

    Returns
    -------
    StandardLayout
    """
    hl = HAND_LENGTH_MM
    spacing = HAND_BREADTH_MM / 4.0
    mid = SEGMENT_COEFFICIENTS["middle"]
    y_mid = hl * (1.0 - sum(mid[1:]))
    # x toward the little finger is +x for a right hand seen from the back
    xs = {"index": -spacing, "middle": 0.0, "ring": spacing, "little": 2.0 * spacing}
    mcp = {}
    for f, x in xs.items():
        dy = hl * (SEGMENT_COEFFICIENTS[f][0] - mid[0])
        # the little-finger metacarpal also angles away: its head sits lower still
        mcp[f] = np.array([x, y_mid + dy, 0.0])
    thumb_cmc = np.array([-0.28 * HAND_BREADTH_MM, 0.13 * hl, -8.0])
    yaw = {"index": 2.0, "middle": 0.0, "ring": -2.0, "little": -5.0}
    return StandardLayout(mcp=mcp, thumb_cmc=thumb_cmc, finger_yaw_deg=yaw)

#: Height of the back of the hand (dorsum over the metacarpal heads) above
#: the hand frame's x-y plane, mm: 0.4 of the palm thickness (the joint
#: centres lie 0.6 of the thickness above the palmar skin).
DORSUM_Z_MM: float = 0.4 * PALM_THICKNESS_MM
__all__.append("DORSUM_Z_MM")
