"""Vertex clouds of the hand's segments (their convex hulls are the meshes).

Every segment is the convex hull of a few ellipsoids, so a mesh asset needs
only vertices: MuJoCo computes the hull of a vertex-only mesh.  Hulls of
~100 faces keep rendering cheap.  All coordinates are in millimetres in the
segment's own frame (bone along +y, +z dorsal) of a *right* hand.
"""

from __future__ import annotations

import numpy as np

__all__ = ["ellipsoid_points", "forearm_vertices", "palm_vertices", "phalanx_vertices"]


def ellipsoid_points(
    center, radii, *, n_around: int = 10, n_rings: int = 5, y_half: str | None = None
) -> np.ndarray:
    """Points on an axis-aligned ellipsoid surface.

    Parameters
    ----------
    center : array_like, shape (3,)
        Centre, mm.
    radii : array_like, shape (3,)
        Semi-axes along x, y, z, mm.
    n_around, n_rings : int, keyword-only
        Samples around the y axis and rings from pole to pole.
    y_half : {None, "pos", "neg"}, keyword-only
        Keep only the half with y >= centre ("pos") or y <= centre ("neg").

    Returns
    -------
    ndarray, shape (M, 3), float64
    """
    phi = np.linspace(0.0, np.pi, n_rings + 2)[1:-1]
    if y_half == "pos":
        phi = phi[phi <= np.pi / 2 + 1e-9]
    elif y_half == "neg":
        phi = phi[phi >= np.pi / 2 - 1e-9]
    theta = np.linspace(0.0, 2 * np.pi, n_around, endpoint=False)
    ph, th = np.meshgrid(phi, theta, indexing="ij")
    unit = np.stack(
        [np.sin(ph) * np.cos(th), np.cos(ph), np.sin(ph) * np.sin(th)], axis=-1
    ).reshape(-1, 3)
    poles = []
    if y_half != "neg":
        poles.append((0.0, 1.0, 0.0))
    if y_half != "pos":
        poles.append((0.0, -1.0, 0.0))
    unit = np.vstack([unit, np.array(poles).reshape(-1, 3)])
    return np.asarray(center, float) + unit * np.asarray(radii, float)


def phalanx_vertices(
    length_mm: float, breadth0_mm: float, breadth1_mm: float, *, depth_ratio: float, tip: bool
) -> np.ndarray:
    """A tapered phalanx from its proximal joint (y = 0) to y = `length_mm`.

    The proximal end is a round knuckle centred on the joint, so neighbouring
    segments overlap there and stay closed when the joint flexes.  A distal
    phalanx (`tip`) ends in a rounded fingertip that reaches exactly
    ``y = length_mm``; other phalanges end in a thin ellipse at the next joint.
    The dorsal surface is flatter than the palmar pad (centre 0.1 depth toward
    the palm).
    """
    r0 = 0.5 * breadth0_mm
    r1 = 0.5 * breadth1_mm
    z_off = -0.1 * depth_ratio * breadth0_mm
    near = ellipsoid_points((0, 0, z_off), (r0, 0.9 * r0, depth_ratio * r0), y_half="pos")
    if tip:
        ry = 0.9 * r1
        far = ellipsoid_points(
            (0, length_mm - ry, z_off * 0.8), (r1, ry, 0.8 * depth_ratio * r1), y_half="pos"
        )
    else:
        far = ellipsoid_points(
            (0, length_mm, z_off), (r1, 0.5 * r1, depth_ratio * r1), y_half="neg"
        )
    return np.vstack([near, far])


def palm_vertices(mcp: dict[str, np.ndarray], breadths: dict[str, float], *,
                  thickness_mm: float, wrist_halfwidth_mm: float,
                  x_scale: float) -> np.ndarray:
    """The palm: hull of the metacarpal heads, the heel of the hand and the wrist.

    Parameters
    ----------
    mcp : dict of str to ndarray, shape (3,)
        Standard MCP joint centres of index..little (hand frame, mm, right hand).
    breadths : dict of str to float
        Finger breadth at the MCP, mm.
    thickness_mm : float, keyword-only
        Palm thickness at the metacarpal heads.
    wrist_halfwidth_mm : float, keyword-only
        Half the width of the palm's lower edge.
    x_scale : float, keyword-only
        Horizontal scale of the whole palm (the palm ratio of HandShape).
    """
    t = thickness_mm
    pts = []
    for f, c in mcp.items():
        r = 0.55 * breadths[f]
        pts.append(ellipsoid_points(c + (0, -2.0, -0.1 * t), (r, 7.0, 0.5 * t)))
    # heel of the hand (thenar/hypothenar base) and wrist edge, slightly thinner
    w = wrist_halfwidth_mm
    lit = mcp["little"]
    pts.append(ellipsoid_points((lit[0] + 2.0, 0.45 * lit[1], -0.12 * t), (10.0, 14.0, 0.48 * t)))
    pts.append(ellipsoid_points((0.0, 4.0, -0.1 * t), (w, 8.0, 0.42 * t)))
    v = np.vstack(pts)
    v[:, 0] *= x_scale
    return v


def forearm_vertices(*, length_mm: float, halfwidth_mm: float, halfdepth_mm: float) -> np.ndarray:
    """The distal forearm stub from the wrist (y = 0) back to y = -`length_mm`."""
    a = ellipsoid_points((0, -2.0, -2.0), (halfwidth_mm, 6.0, halfdepth_mm), y_half="pos")
    b = ellipsoid_points((0, -length_mm, -2.0), (1.08 * halfwidth_mm, 4.0, 1.1 * halfdepth_mm),
                         y_half="neg")
    return np.vstack([a, b])
