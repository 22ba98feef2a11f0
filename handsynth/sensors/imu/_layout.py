"""Link chains of the 20-IMU system: which sensor measures which link.

Seed 003 Table 3.6 (with the Type 3 hand of section 3.4.3): every finger is a
serial chain from the elbow to the fingertip; each link is measured by one
sensor and runs from a proximal to a distal point (joint centre or tip).
The forearm plate's sensors 1, 2, 3 serve the index/middle, ring/little and
thumb chains; the hand sensor 11 (index/middle side) is shared by every
chain, the ring/little-side sensor 4 carries the ulnar CM joint.
"""

from __future__ import annotations

from types import MappingProxyType

__all__ = ["CHAINS", "FLEX_JOINT", "LINKS", "POINTS"]

#: Named points whose true positions a simulation records (joint centres and tips).
POINTS: tuple[str, ...] = (
    "elbow", "wrist", "ulnar_cm",
    "thumb_cmc", "thumb_mcp", "thumb_ip", "thumb_tip",
    *(f"{f}_{j}" for f in ("index", "middle", "ring", "little") for j in ("mcp", "pip", "dip", "tip")),
)


def _finger(f: str, fore: str, ulnar: bool):
    links = [(fore, "elbow", "wrist")]
    if ulnar:
        links += [("hand_radial", "wrist", "ulnar_cm"), ("hand_ulnar", "ulnar_cm", f"{f}_mcp")]
    else:
        links += [("hand_radial", "wrist", f"{f}_mcp")]
    links += [(f"{f}_proximal", f"{f}_mcp", f"{f}_pip"), (f"{f}_middle", f"{f}_pip", f"{f}_dip"),
              (f"{f}_distal", f"{f}_dip", f"{f}_tip")]
    return tuple(links)


#: finger -> ((sensor, proximal point, distal point), ...), elbow first.
CHAINS = MappingProxyType({
    "thumb": (("forearm_3", "elbow", "wrist"), ("hand_radial", "wrist", "thumb_cmc"),
              ("thumb_metacarpal", "thumb_cmc", "thumb_mcp"),
              ("thumb_proximal", "thumb_mcp", "thumb_ip"),
              ("thumb_distal", "thumb_ip", "thumb_tip")),
    "index": _finger("index", "forearm_1", False),
    "middle": _finger("middle", "forearm_1", False),
    "ring": _finger("ring", "forearm_2", True),
    "little": _finger("little", "forearm_2", True),
})

#: Every distinct (sensor, proximal point, distal point) link.
LINKS: tuple[tuple[str, str, str], ...] = tuple(dict.fromkeys(
    link for chain in CHAINS.values() for link in chain))

#: The flexion joint at the proximal end of each sensor's segment (skin
#: motion follows it; link frames take their x axis from it, eq. 5.1).
FLEX_JOINT = MappingProxyType({
    "forearm_1": "elbow_flex", "forearm_2": "elbow_flex", "forearm_3": "elbow_flex",
    "hand_radial": "wrist_flex", "hand_ulnar": "ulnar_cm_flex",
    "thumb_metacarpal": "thumb_cmc_flex", "thumb_proximal": "thumb_mcp_flex",
    "thumb_distal": "thumb_ip_flex",
    **{f"{f}_{s}": f"{f}_{j}_flex" for f in ("index", "middle", "ring", "little")
       for s, j in (("proximal", "mcp"), ("middle", "pip"), ("distal", "dip"))},
    **{f"{f}_tip": ("thumb_ip_flex" if f == "thumb" else f"{f}_dip_flex")
       for f in ("thumb", "index", "middle", "ring", "little")},
})
