"""Exact silhouette masks by rasterizing the projected convex hulls of the hand's parts.

Every part of the hand model is a convex mesh (MuJoCo builds each part's
convex hull from its vertices, and renders that hull).  Under a pinhole
camera the image of a convex body in front of the camera is the convex
hull of its projected vertices, and a silhouette needs no depth test: the
mask is the union of those convex polygons.  :class:`SilhouetteRasterizer`
computes it directly, with the rasterization rule of OpenGL's fill (a pixel
is hand when its centre lies inside a polygon), so it gives the masks of
:class:`~handsynth.render.SilhouetteRenderer` (MuJoCo's renderer) at a
fraction of the cost and with no GL context (tests compare the two).

It is what the database build uses: masks at the device's full frame size
cost about as much as a 240x160 render.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..errors import RenderError
from ..models import HandShape
from ._camera import CameraMount
from ._masks import MaskMaker

__all__ = ["SilhouetteRasterizer"]


@njit(cache=True, nogil=True)
def _turns_left(px, py, a, b, p):
    """Whether a -> b -> p is a strict counter-clockwise turn (image axes)."""
    return (px[b] - px[a]) * (py[p] - py[a]) - (py[b] - py[a]) * (px[p] - px[a]) > 0


@njit(cache=True, nogil=True)
def _hull(px, py, idx):
    """Convex hull of points `idx`, as the indices of its vertices in order.

    Andrew's monotone chain: the lower chain over the points sorted by x,
    then the upper chain back, each keeping only strict turns.
    """
    order = idx[np.argsort(px[idx] + 1e-9 * py[idx])]
    n = order.size
    out = np.empty(2 * n + 1, np.int64)
    k = 0
    n_lower = 0  # hull size after the lower chain
    for step in range(2 * n - 1):  # forward over the sorted points, then back
        p = order[step] if step < n else order[2 * n - 2 - step]
        floor = 2 if step < n else n_lower + 1
        while k >= floor and not _turns_left(px, py, out[k - 2], out[k - 1], p):
            k -= 1
        out[k] = p
        k += 1
        if step == n - 1:
            n_lower = k
    return out[:k - 1]


@njit(cache=True, nogil=True)
def _rasterize(verts, starts, geom_of, xpos, xmat, cam_rot, cam_pos, fx, fy, cx, cy, out):
    """Fill `out` (uint8, (H, W)) with the union of the parts' projected hulls.

    Returns False when a vertex is not in front of the camera.
    """
    h, w = out.shape
    n = verts.shape[0]
    px = np.empty(n)
    py = np.empty(n)
    for i in range(n):
        g = geom_of[i]
        wx = xpos[g, 0] - cam_pos[0]
        wy = xpos[g, 1] - cam_pos[1]
        wz = xpos[g, 2] - cam_pos[2]
        for k in range(3):
            wx += xmat[g, 3 * 0 + k] * verts[i, k]
            wy += xmat[g, 3 * 1 + k] * verts[i, k]
            wz += xmat[g, 3 * 2 + k] * verts[i, k]
        # camera coordinates: pc = (world - cam_pos) @ cam_rot
        x = wx * cam_rot[0, 0] + wy * cam_rot[1, 0] + wz * cam_rot[2, 0]
        y = wx * cam_rot[0, 1] + wy * cam_rot[1, 1] + wz * cam_rot[2, 1]
        z = wx * cam_rot[0, 2] + wy * cam_rot[1, 2] + wz * cam_rot[2, 2]
        if z <= 1e-6:
            return False
        px[i] = fx * x / z + cx
        py[i] = fy * y / z + cy
    for g in range(starts.size - 1):
        hull = _hull(px, py, np.arange(starts[g], starts[g + 1]))
        m = hull.size
        if m < 3:
            continue
        ymin = py[hull[0]]
        ymax = ymin
        for k in range(m):
            ymin = min(ymin, py[hull[k]])
            ymax = max(ymax, py[hull[k]])
        y0 = max(int(math.ceil(ymin)), 0)
        y1 = min(int(math.floor(ymax)), h - 1)
        for yy in range(y0, y1 + 1):
            xl = math.inf
            xr = -math.inf
            for k in range(m):
                a = hull[k]
                b = hull[(k + 1) % m]
                ya, yb = py[a], py[b]
                if ya == yb:
                    continue
                if (ya <= yy <= yb) or (yb <= yy <= ya):
                    x = px[a] + (yy - ya) * (px[b] - px[a]) / (yb - ya)
                    xl = min(xl, x)
                    xr = max(xr, x)
            if xl > xr:
                continue
            x0 = max(int(math.ceil(xl)), 0)
            x1 = min(int(math.floor(xr)), w - 1)
            for xx in range(x0, x1 + 1):
                out[yy, xx] = 1
    return True


class SilhouetteRasterizer(MaskMaker):
    """Boolean hand masks as the device camera sees them, without OpenGL.

    Same interface and masks as :class:`~handsynth.render.SilhouetteRenderer`
    (pixels whose centre the hand covers), computed from the model's convex
    parts; thread-safe per instance only when each thread has its own.

    Parameters
    ----------
    shape : HandShape, optional
        The standard hand by default.
    mount : CameraMount, optional
        The paper's device by default.
    side : {"right", "left"}, keyword-only
    width_px, height_px : int, keyword-only
        Mask size (the mount's 720x480 by default).
    forearm : bool, keyword-only
        Include the forearm stub behind the wrist.
    """

    def __init__(self, shape: HandShape | None = None, mount: CameraMount | None = None, *,
                 side: str = "right", width_px: int | None = None, height_px: int | None = None,
                 forearm: bool = True) -> None:
        self._load_hand(shape, mount, side=side, width_px=width_px, height_px=height_px,
                        forearm=forearm)
        m = self.hand.model
        geoms = [g for g in range(m.ngeom) if m.geom_rgba[g, 3] > 0 and m.geom_group[g] <= 2]
        if any(m.geom_type[g] != 7 for g in geoms):  # mjGEOM_MESH
            raise RenderError("SilhouetteRasterizer needs a model made of convex meshes only")
        verts, owner = [], []
        for g in geoms:
            mid = m.geom_dataid[g]
            a, n = m.mesh_vertadr[mid], m.mesh_vertnum[mid]
            verts.append(np.asarray(m.mesh_vert[a:a + n], dtype=np.float64))
            owner.append(np.full(n, g, dtype=np.int64))
        self._verts = np.ascontiguousarray(np.concatenate(verts))
        self._owner = np.concatenate(owner)
        self._starts = np.concatenate([[0], np.cumsum([len(v) for v in verts])]).astype(np.int64)
        pose = self.mount.pose_in_hand(side=side)
        self._cam_rot = np.ascontiguousarray(pose[:3, :3])
        self._cam_pos = np.ascontiguousarray(pose[:3, 3])
        k = self.mount.intrinsics(self.width_px, self.height_px)
        self._k = (float(k[0, 0]), float(k[1, 1]), float(k[0, 2]), float(k[1, 2]))

    def _draw(self, pose: np.ndarray, out: np.ndarray) -> None:
        self.hand.set_pose(pose, check=False)
        out[...] = False
        self._fill(out.view(np.uint8))

    def _fill(self, buf: np.ndarray) -> None:
        d = self.hand.data
        ok = _rasterize(self._verts, self._starts, self._owner, d.geom_xpos, d.geom_xmat,
                        self._cam_rot, self._cam_pos, *self._k, buf)
        if not ok:
            raise RenderError("a part of the hand is behind the camera; the mount cannot see "
                              "this pose")

    # context-manager symmetry with SilhouetteRenderer (nothing to release)
    def close(self) -> None:
        """Nothing to release (no GL context); for symmetry with SilhouetteRenderer."""

    def __enter__(self) -> SilhouetteRasterizer:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
