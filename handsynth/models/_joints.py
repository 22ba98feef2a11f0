"""Canonical joint names, order, sign conventions and limits.

The 20 degrees of freedom are used in this order in every array, HDF5 file,
CSV column and API of handsynth.  Angles are in degrees at every public
interface.  Flexion is positive toward the palm; MCP abduction is positive
toward the thumb side (radial deviation).  Thumb CMC abduction is positive
away from the palm plane (palmar abduction).

Limits are active ranges of motion from the American Academy of Orthopaedic
Surgeons, *Joint Motion: Method of Measuring and Recording* (AAOS, 1965;
reprinted 1988), Table "Hand", with the small extension ranges of the finger
joints from Hume et al., "Functional range of motion of the joints of the
hand", J. Hand Surg. 15A:240-243 (1990).  Finger MCP abduction (+/-20 deg) and
thumb CMC ranges follow Kapandji, *The Physiology of the Joints*, vol. 1
(6th ed., 2007), ch. "The hand"; the thumb CMC flexion range here is the
flexion-extension of the first metacarpal in the palm plane, measured from
the neutral (relaxed) position.
"""

from __future__ import annotations

import numpy as np

__all__ = ["FINGERS", "JOINT_LIMITS_DEG", "JOINT_NAMES", "joint_index"]

FINGERS: tuple[str, ...] = ("thumb", "index", "middle", "ring", "little")

JOINT_NAMES: tuple[str, ...] = (
    "thumb_cmc_flex",
    "thumb_cmc_abd",
    "thumb_mcp_flex",
    "thumb_ip_flex",
    *(
        f"{f}_{j}"
        for f in FINGERS[1:]
        for j in ("mcp_flex", "mcp_abd", "pip_flex", "dip_flex")
    ),
)

#: ``(20, 2)`` float64 array of (lower, upper) limits in degrees, canonical order.
JOINT_LIMITS_DEG: np.ndarray = np.array(
    [
        # thumb: CMC flexion/extension, CMC palmar abduction, MCP, IP (AAOS; Kapandji)
        (-20.0, 50.0),
        (0.0, 70.0),
        (-10.0, 60.0),
        (-20.0, 80.0),
        # index .. little: MCP flex (AAOS 0-90, Hume hyperextension), MCP abd,
        # PIP (AAOS 0-100), DIP (AAOS 0-90 with Hume's 5-10 deg extension)
        *[(-20.0, 90.0), (-20.0, 20.0), (-5.0, 100.0), (-10.0, 90.0)] * 4,
    ],
    dtype=np.float64,
)
JOINT_LIMITS_DEG.setflags(write=False)


def joint_index(name: str) -> int:
    """Return the canonical index of joint `name`.

    Parameters
    ----------
    name : str
        A joint name of :data:`JOINT_NAMES` (case matters).

    Returns
    -------
    int
        Its position in :data:`JOINT_NAMES`, 0 to 19.

    Raises
    ------
    InvalidPoseError
        If `name` is not one of :data:`JOINT_NAMES`.
    """
    from ..errors import InvalidPoseError

    try:
        return JOINT_NAMES.index(name)
    except ValueError:
        raise InvalidPoseError(
            f"unknown joint name {name!r}; expected one of {', '.join(JOINT_NAMES)}"
        ) from None
