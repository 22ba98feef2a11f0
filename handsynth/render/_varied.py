"""Model hands beyond the four ratios: per-segment geometry and a moved camera, rasterized.

The paper's hand shapes change four ratios of one standard hand
(:class:`~handsynth.models.HandShape`).  Real hands, and hands rigged by
others, differ in more ways: each phalanx has its own length and breadth, the
palm its own length (how far the MCP joints lie from the wrist), each MCP its
own place, and the device sits a little differently on every wrist.
:class:`HandVariation` describes those differences as scale factors and
offsets applied to a built model hand, and :class:`VariedRasterizer` draws the
masks of the varied hand with the same exact rasterization as
:class:`~handsynth.render.SilhouetteRasterizer` (the convex parts are scaled in
their own body frames, so they stay convex).

No MJCF is generated for a variation: the compiled model's body positions and
the rasterizer's vertex arrays are changed in place, so a new hand costs
microseconds and a learning set can draw a different hand every few frames.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import numpy as np

from .._checks import check_instance, check_number
from ..errors import InvalidInputError, InvalidShapeError
from ..models import FINGERS, HandShape
from ._camera import CameraMount, as_mount
from ._raster import SilhouetteRasterizer

__all__ = ["HandVariation", "MountVariation", "VariedRasterizer"]

_DIGIT_BODIES = {
    "thumb": ("thumb_metacarpal", "thumb_proximal", "thumb_distal"),
    **{f: (f"{f}_proximal", f"{f}_middle", f"{f}_distal") for f in FINGERS[1:]},
}


def _quat_mat(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


@dataclass(frozen=True)
class HandVariation:
    """How one hand differs from a built model hand, beyond its four ratios.

    Every factor multiplies the built hand's value (1 = unchanged); offsets
    are added in the hand frame, except ``flesh_offset_mm`` (in each
    segment's own frame).

    Parameters
    ----------
    segment_length : tuple of 15 float
        Length of each segment, digits in :data:`~handsynth.models.FINGERS`
        order, base to tip (thumb: metacarpal, proximal, distal; fingers:
        proximal, middle, distal).
    digit_width : tuple of 5 float
        Breadth and depth of every segment of each digit.
    segment_width : tuple of 15 float
        Breadth and depth of each segment on top of its digit's
        ``digit_width`` (same order as ``segment_length``): how a finger
        tapers, or a knuckle bulges, differs from the built hand's.
    flesh_offset_mm : tuple of 30 float
        Where each segment's flesh sits on its joints: an (along the segment,
        dorsal-palmar) offset of the segment's surface in its own frame, mm,
        15 pairs in ``segment_length``'s order; the joints stay.  A rig puts
        its joint nodes at its own depth in the finger, and a real joint's
        centre of rotation is not the middle of the skin around it.
    palm_length : float
        Distance of the MCP joints and the thumb CMC from the wrist (hand
        frame y), and the palm's extent along the hand.
    palm_width : float
        The palm's breadth and the MCPs' and thumb CMC's x.
    palm_depth : float
        The palm's thickness.
    mcp_offset_mm : tuple of 8 float
        (x, y) offsets of the index, middle, ring and little MCP joints, mm.
    thumb_offset_mm : tuple of 3 float
        Offset of the thumb CMC joint, mm.

    Raises
    ------
    InvalidShapeError
        A factor that is not in [0.3, 3] or an offset beyond 30 mm, naming it.
    """

    segment_length: tuple[float, ...] = (1.0,) * 15
    digit_width: tuple[float, ...] = (1.0,) * 5
    segment_width: tuple[float, ...] = (1.0,) * 15
    flesh_offset_mm: tuple[float, ...] = (0.0,) * 30
    palm_length: float = 1.0
    palm_width: float = 1.0
    palm_depth: float = 1.0
    mcp_offset_mm: tuple[float, ...] = (0.0,) * 8
    thumb_offset_mm: tuple[float, ...] = (0.0,) * 3

    def __post_init__(self) -> None:
        sizes = {"segment_length": 15, "digit_width": 5, "segment_width": 15, "flesh_offset_mm": 30,
                 "mcp_offset_mm": 8, "thumb_offset_mm": 3}
        for f in fields(self):
            v = np.asarray(getattr(self, f.name), dtype=np.float64)
            n = sizes.get(f.name)
            if (n is None and v.ndim != 0) or (n is not None and v.shape != (n,)):
                raise InvalidShapeError(f"HandVariation.{f.name} must have {n or 1} values, "
                                        f"got shape {v.shape}")
            if f.name.endswith("_mm"):
                ok = np.all(np.isfinite(v)) and np.all(np.abs(v) <= 30.0)
            else:
                ok = np.all(np.isfinite(v)) and np.all((v >= 0.3) & (v <= 3.0))
            if not ok:
                raise InvalidShapeError(f"HandVariation.{f.name} out of range: {v.tolist()}")
            object.__setattr__(self, f.name, float(v) if n is None else tuple(map(float, v)))

    @classmethod
    def random(cls, rng: np.random.Generator, *, spread: float = 1.0,
               segment_width_sd: float = 0.0, flesh_offset_sd_mm: float = 0.0,
               breadth_follows_scale: float = 0.0) -> HandVariation:
        """A random hand: independent log-normal factors and normal offsets.

        The s.d.s (at ``spread=1``) are wide on purpose, wider than adult
        variation in segment lengths (coefficients of variation about 6-8 %,
        Buchholz et al. 1992, Table 1): a silhouette estimator must also meet
        hands whose joint centres were placed differently (a rig's joint
        nodes, a surface marker), so each segment length varies with s.d.
        15 %, on top of a common scale of s.d. 7 %; digit breadths 10 %; the
        palm's length 12 % (the distance of the MCPs from the wrist joint
        centre depends on where the wrist centre is taken), breadth 6 %,
        depth 10 %; MCP positions 3 mm, thumb CMC 5 mm.

        Parameters
        ----------
        rng : numpy.random.Generator
        spread : float, keyword-only
            Multiplies every s.d. (0: the built hand unchanged).
        segment_width_sd : float, keyword-only
            S.d. of the log of each segment's own width factor
            (``segment_width``), also multiplied by `spread`.  0 (the default)
            leaves every segment at its digit's width and draws nothing, so
            the hands of a seed are those drawn before the option existed.
        flesh_offset_sd_mm : float, keyword-only
            S.d. of each ``flesh_offset_mm`` (times `spread`), drawn after the
            widths; 0 (the default) draws nothing.
        breadth_follows_scale : float, keyword-only
            Power (0-2) of the common scale that the digits' breadths, the
            palm's breadth and its depth take on top of their own factors: 1
            makes a hand uniformly smaller or larger, as a child's is; 0 (the
            default) varies breadths independently of the lengths.  It draws
            nothing, so a seed gives the same lengths whatever its value.

        Raises
        ------
        InvalidShapeError
            `spread` not a finite number >= 0, `breadth_follows_scale` not a
            number in [0, 2], or an s.d. out of range
            (:meth:`with_random_surface`), naming it.
        """
        s = check_number(spread, "spread", minimum=0, error=InvalidShapeError)
        k = check_number(breadth_follows_scale, "breadth_follows_scale", minimum=0, maximum=2,
                         error=InvalidShapeError)
        common = rng.normal(0.0, 0.07 * s)
        out = cls(
            segment_length=tuple(np.exp(common + rng.normal(0.0, 0.15 * s, 15))),
            digit_width=tuple(np.exp(k * common + rng.normal(0.0, 0.10 * s, 5))),
            palm_length=float(np.exp(common + rng.normal(0.0, 0.12 * s))),
            palm_width=float(np.exp(k * common + rng.normal(0.0, 0.06 * s))),
            palm_depth=float(np.exp(k * common + rng.normal(0.0, 0.10 * s))),
            mcp_offset_mm=tuple(rng.normal(0.0, 3.0 * s, 8)),
            thumb_offset_mm=tuple(rng.normal(0.0, 5.0 * s, 3)),
        )
        return out.with_random_surface(rng, spread=s, segment_width_sd=segment_width_sd,
                                       flesh_offset_sd_mm=flesh_offset_sd_mm)

    def with_random_surface(self, rng: np.random.Generator, *, spread: float = 1.0,
                            segment_width_sd: float = 0.0,
                            flesh_offset_sd_mm: float = 0.0) -> HandVariation:
        """This hand with random ``segment_width`` and ``flesh_offset_mm``.

        Draws the widths (log-normal, s.d. ``segment_width_sd * spread``) and
        then the offsets (normal, s.d. ``flesh_offset_sd_mm * spread``, mm);
        an s.d. of 0 draws nothing and keeps the field as it is.

        Raises
        ------
        InvalidShapeError
            `spread` not a finite number >= 0, or an s.d. outside [0, 1]
            (widths) or [0, 10] mm (offsets), naming it.
        """
        spread = check_number(spread, "spread", minimum=0, error=InvalidShapeError)
        if not (np.isfinite(segment_width_sd) and 0.0 <= segment_width_sd <= 1.0):
            raise InvalidShapeError(f"segment_width_sd must be in [0, 1], got {segment_width_sd!r}")
        if not (np.isfinite(flesh_offset_sd_mm) and 0.0 <= flesh_offset_sd_mm <= 10.0):
            raise InvalidShapeError(f"flesh_offset_sd_mm must be in [0, 10], got {flesh_offset_sd_mm!r}")
        out = self
        if segment_width_sd:
            widths = np.exp(rng.normal(0.0, segment_width_sd * spread, 15))
            out = replace(out, segment_width=tuple(widths))
        if flesh_offset_sd_mm:
            offsets = rng.normal(0.0, flesh_offset_sd_mm * spread, 30)
            out = replace(out, flesh_offset_mm=tuple(offsets))
        return out


@dataclass(frozen=True)
class MountVariation:
    """Where the device sits on one wearer: s.d.s of normal offsets from a mount.

    Parameters
    ----------
    height_mm, thumb_offset_mm, along_mm, tilt_deg, roll_deg : float
        S.d. of the offset of each :class:`CameraMount` field.
    """

    height_mm: float = 10.0
    thumb_offset_mm: float = 6.0
    along_mm: float = 8.0
    tilt_deg: float = 4.0
    roll_deg: float = 4.0

    def __post_init__(self) -> None:
        for f in fields(self):
            sd = getattr(self, f.name)
            if (isinstance(sd, bool) or not isinstance(sd, (int, float, np.number))
                    or not np.isfinite(sd) or sd < 0):
                raise InvalidInputError(f"MountVariation.{f.name} must be a finite s.d. >= 0, "
                                        f"got {sd!r}")

    def scaled(self, factor: float) -> MountVariation:
        """These s.d.s times `factor`."""
        return MountVariation(**{f.name: getattr(self, f.name) * factor for f in fields(self)})

    def sample(self, mount: CameraMount, rng: np.random.Generator) -> CameraMount:
        """`mount` with every field offset by a normal draw of its s.d."""
        return mount.replace(**{f.name: getattr(mount, f.name) + rng.normal(0.0, getattr(self, f.name))
                                for f in fields(self)})


class VariedRasterizer(SilhouetteRasterizer):
    """:class:`SilhouetteRasterizer` of a hand whose geometry and camera can be changed.

    Parameters
    ----------
    shape : HandShape, optional
        The built hand (the standard hand by default); :meth:`vary` changes it
        further.
    mount : CameraMount, optional
        The paper's device by default; :meth:`set_mount` moves it.
    side, width_px, height_px, forearm : keyword-only
        As :class:`SilhouetteRasterizer`.
    """

    def __init__(self, shape: HandShape | None = None, mount: CameraMount | None = None, *,
                 side: str = "right", width_px: int | None = None, height_px: int | None = None,
                 forearm: bool = True) -> None:
        super().__init__(shape, mount, side=side, width_px=width_px, height_px=height_px,
                         forearm=forearm)
        m = self.hand.model
        self._base_mount = self.mount
        self._body_pos0 = m.body_pos.copy()
        self._site_pos0 = m.site_pos.copy()
        self._verts0 = self._verts.copy()
        # each geom's vertices in its body's frame: p_body = geom_pos + R_geom @ v
        self._geom_rot = []
        for g in range(len(self._starts) - 1):
            owner = int(self._owner[self._starts[g]])
            self._geom_rot.append((owner, int(m.geom_bodyid[owner]), _quat_mat(m.geom_quat[owner]),
                                   m.geom_pos[owner].copy()))
        self._bid = {m.body(b).name: b for b in range(m.nbody)}
        self.variation = HandVariation()

    def set_mount(self, mount: CameraMount) -> None:
        """Draw the following masks through `mount` (same frame size)."""
        as_mount(mount, optional=False)
        pose = mount.pose_in_hand(side=self.side)
        self._cam_rot = np.ascontiguousarray(pose[:3, :3])
        self._cam_pos = np.ascontiguousarray(pose[:3, 3])
        k = mount.intrinsics(self.width_px, self.height_px)
        self._k = (float(k[0, 0]), float(k[1, 1]), float(k[0, 2]), float(k[1, 2]))
        self.mount = mount

    def vary(self, variation: HandVariation) -> None:
        """Give the hand `variation` (relative to the built hand, not cumulative)."""
        check_instance(variation, HandVariation, name="variation", error=InvalidShapeError)
        m, v = self.hand.model, variation
        sign = -1.0 if self.side == "left" else 1.0
        m.body_pos[:] = self._body_pos0
        m.site_pos[:] = self._site_pos0
        scale = {}  # body id -> per-axis scale of its own frame
        flesh = {}  # body id -> offset of its parts in its own frame, m
        for d, bodies in enumerate(_DIGIT_BODIES.values()):
            for k, name in enumerate(bodies):
                i = 3 * d + k
                w = v.digit_width[d] * v.segment_width[i]
                scale[self._bid[name]] = np.array([w, v.segment_length[i], w])
                along, depth = v.flesh_offset_mm[2 * i: 2 * i + 2]
                flesh[self._bid[name]] = np.array([0.0, along, depth]) * 1e-3
        palm = self._bid["palm"]
        scale[palm] = np.array([v.palm_width, v.palm_length, v.palm_depth])
        # joint positions: a child sits at its parent's scaled offset
        for b in range(1, m.nbody):
            parent = m.body_parentid[b]
            if parent in scale and parent != palm:
                m.body_pos[b] = self._body_pos0[b] * scale[parent]
        for k, f in enumerate(FINGERS[1:]):
            b = self._bid[f"{f}_proximal"]
            dx, dy = v.mcp_offset_mm[2 * k: 2 * k + 2]
            m.body_pos[b] = self._body_pos0[b] * scale[palm] + np.array([sign * dx, dy, 0.0]) * 1e-3
        b = self._bid["thumb_metacarpal"]
        t = np.array(v.thumb_offset_mm) * np.array([sign, 1.0, 1.0]) * 1e-3
        m.body_pos[b] = self._body_pos0[b] * scale[palm] + t
        for s in range(m.nsite):
            sb = m.site_bodyid[s]
            if sb in scale:
                m.site_pos[s] = self._site_pos0[s] * scale[sb]
        verts = self._verts0.copy()
        for g, (_, body, rot, pos) in enumerate(self._geom_rot):
            if body not in scale:
                continue
            a, e = self._starts[g], self._starts[g + 1]
            p = (pos + self._verts0[a:e] @ rot.T) * scale[body] + flesh.get(body, 0.0)
            verts[a:e] = (p - pos) @ rot
        self._verts = np.ascontiguousarray(verts)
        self.variation = v
