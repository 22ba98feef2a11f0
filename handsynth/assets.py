"""The MJCF files of the standard hands shipped in ``assets/hand_mjcf/``."""

from __future__ import annotations

from .models import HandShape, hand_mjcf
from .render._scene import scene_include_mjcf

__all__ = ["standard_assets"]


def standard_assets() -> dict[str, str]:
    """File name -> MJCF text of the standard right and left hands and their scenes."""
    out = {}
    for side in ("right", "left"):
        out[f"{side}_hand.xml"] = hand_mjcf(HandShape(), side=side)
        out[f"scene_{side}.xml"] = scene_include_mjcf(f"{side}_hand.xml", side=side)
    return out
