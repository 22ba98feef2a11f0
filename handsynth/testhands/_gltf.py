"""A realistic skinned hand mesh (glTF) posed by canonical angles, seen by the device camera.

The database is built from handsynth's own parametric hand.  To test the
lookup on a hand geometry it was *not* built from, like a real user's, this
module poses a rigged hand mesh with the same 20 canonical joint angles and
renders it through the same :class:`CameraMount`, as white-on-black masks
exactly like :class:`~handsynth.render.SilhouetteRenderer`.

The default mesh is ``hand_r.gltf`` of the Godot XR Tools hand models
(MakeHuman-based, CC0, by DigitalN8m4r3), shipped in
``handsynth/testhands/data/godot_xr_tools`` with its licence
(:func:`shipped_hand_path`), or the file named by the environment variable
``HANDSYNTH_MESH_HAND`` or passed explicitly.

Method
------
1. *glTF*: the JSON document and its buffers are parsed with numpy (glTF 2.0
   specification, Khronos): positions, triangles, ``JOINTS_0``/``WEIGHTS_0``,
   the skin's ``inverseBindMatrices`` and the node hierarchy.  The rest-pose
   vertices are the skinned vertices at the nodes' own transforms.
2. *Bones*: the skin's joints by their node names, in one of these namings
   (case, the separators ``_ . -`` and space, an FBX namespace such as
   ``mixamorig:`` or ``mixamorig1:`` and a side marker aside: a ``Right`` /
   ``Left`` prefix, an ``_R`` / ``_L`` / ``.R`` / ``_r`` ... suffix or an
   ``r_`` / ``l_`` prefix):

   - OpenXR: ``<digit>_<bone>`` with digit in thumb, index, middle, ring,
     little (or pinky) and bone in metacarpal, proximal, intermediate,
     distal, tip, their WebXR Hand Input spellings
     (``index-finger-phalanx-proximal``, ``pinky-finger-tip``) and ``wrist``;
   - Mixamo and FBX humanoids: ``mixamorig:RightHand`` (the wrist),
     ``RightHandThumb1`` to ``4`` (CMC, MCP, IP, tip), ``RightHandIndex1``
     to ``4`` (MCP, PIP, DIP, tip), ``Middle``, ``Ring``, ``Pinky``;
   - Unity and VRM humanoids: ``RightHand``, ``RightIndexProximal``,
     ``Intermediate``, ``Distal`` ... ``RightLittle...``; the thumb's
     ``Proximal``, ``Intermediate``, ``Distal`` (Unity, VRM 0) are its CMC,
     MCP and IP joints, VRM 1.0's ``rightThumbMetacarpal``, ``Proximal``,
     ``Distal`` are named as in OpenXR;
   - MANO: ``wrist`` or ``root``, ``index1`` to ``3`` (MCP, PIP, DIP),
     ``thumb1`` to ``3`` (CMC, MCP, IP), ``pinky`` or ``little``; Unreal's
     ``index_01_r`` and Blender Rigify's ``DEF-f_index.01.R`` number the same
     way.

   The wrist is the joint named ``wrist``, else ``hand``, else ``root``; two
   joints read as the same bone (a skin of both hands) are refused.  Nodes
   one joint proximal of their OpenXR names, as in the MRTK hand, are read
   one joint distal (:func:`_shifted_rig`).  A node's origin is its joint
   centre.  The metacarpals of the fingers may be missing (they do not
   move).  A fingertip may be a node that is no skin joint (named as a tip,
   or the only childless child of the distal node, like an ``_end`` node) or
   missing: then it is where the skin ends along the distal bone, the
   farthest of the vertices mostly weighted to that bone along the direction
   from its joint to their centroid.
3. *Hand frame* (README "Conventions"): origin at the wrist node, +y toward
   the middle-finger MCP (the ``middle_proximal`` node), the palm plane
   through the index-to-little MCP line, +z out of the back of the hand (the
   side away from which the rest-pose fingers curl), x = y cross z.  Where
   the rest fingers are flat (a T-pose, MANO's zero pose) the side the node
   names say decides instead (a right hand's thumb is on -x); flat fingers
   without a side in the names, or names that say the other side than the
   curl, are refused.  The mesh keeps its own size (metres);
   :attr:`MeshHandRenderer.hand_length_mm` reports it.  A hand outside
   100-300 mm from the wrist to the middle fingertip is refused, with the
   unit its file is likely in (centimetres, millimetres, inches): it is not
   rescaled.
4. *Joint axes from the rest pose*: a finger's flexion axis is perpendicular
   to the finger's direction (MCP to tip node, in the palm plane) and to the
   palm normal.  The thumb's rest pose is nearly straight and pronated, so its
   MCP/IP flexion axis is the broad axis of its distal phalanx's cross-section
   (the nail's width), from plane sections of the mesh, with the nail on the
   radial-dorsal side (the pulp faces the index finger), so that flexion
   curls the thumb across the palm.
5. *Zero pose = handsynth's zero pose*: joint angles are applied as in
   :func:`handsynth.models.hand_mjcf`, so a pose means the same segment
   directions on both hands: at zero each finger is straight in the palm plane
   along handsynth's rest fan (index +2, middle 0, ring -2, little -5 deg
   toward the thumb); MCP abduction turns it about the palm normal, then MCP,
   PIP and DIP flexion about its flexion axis toward the palm.  The thumb
   metacarpal is turned from its rest direction in the mesh to handsynth's
   (40 deg toward the thumb side, 12 deg palmar of the palm plane) keeping the
   mesh's own twist about its axis; CMC flexion and palmar abduction use
   handsynth's axes, MCP and IP flexion the thumb's axis of step 4.  The
   metacarpals of the fingers and the wrist do not move (a rigid palm, as in
   the model).
6. *Linear blend skinning* of the vertices, per pose, in numpy.
7. *Rendering*: the mesh is a MuJoCo ``<skin>`` whose bones are mocap bodies,
   in the scene of :func:`handsynth.render._scene.scene_mjcf` (same
   ``"device"`` camera, same flat white material on black).  Per pose the
   bone transforms go to ``data.mocap_pos``/``mocap_quat``; MuJoCo blends the
   vertices (the same linear blend skinning, equal to :meth:`MeshHandRenderer.vertices`
   to 1e-7 m) and uploads them when it renders.  Measured against writing
   ``model.mesh_vert`` and calling ``mujoco.mjr_uploadMesh`` per pose (identical
   masks): 0.9 vs 2.1 ms per 240x160 mask, 3.1 vs 5.3 ms per 720x480 mask
   (2 shared cores, llvmpipe).  A left hand is the mirror image x -> -x of the
   right (same joint senses).

The mesh ends at the wrist; the preprocessing's wrist cut removes the same
band of the image as for the model (whose forearm stub it also removes).

Notes
-----
Measured on the default mesh: the open hand is 216 mm from the wrist node to
the middle fingertip (handsynth's standard hand: 187 mm); its MCP joints lie
about 25 mm farther from the wrist than the model's, its proximal phalanges
are shorter and its distal ones longer (index 38/31/28 mm against the
model's 50/27/18 mm, joint nodes of the rig).  The mesh's thumb nail
faces radially (twist -63 deg about the thumb's axis from an untwisted
thumb), the model's thumb nail faces the index finger (+50 deg), so thumb
MCP/IP flexion curls the mesh thumb across the palm and the model's thumb
away from it.
"""

from __future__ import annotations

import base64
import itertools
import json
import os
import re
import struct
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from .._checks import check_side
from ..errors import (
    InvalidCameraError,
    InvalidInputError,
    InvalidPoseError,
    RenderError,
)
from ..models import FINGERS, JOINT_NAMES, as_angles, standard_layout_mm
from ..render import CameraMount, GLContextOwner, MaskMaker, as_mount, ensure_backend
from ._held import HeldObject

__all__ = [
    "PROTOCOL_HANDS",
    "TEST_HANDS",
    "MeshHandRenderer",
    "MeshRig",
    "default_mesh_path",
    "load_mesh_rig",
    "mesh_hand_sheet",
    "shipped_hand_path",
]

#: Environment variable naming the glTF file of the mesh hand.
MESH_ENV = "HANDSYNTH_MESH_HAND"

_FINGER_BONES = ("metacarpal", "proximal", "intermediate", "distal", "tip")
_THUMB_BONES = ("metacarpal", "proximal", "distal", "tip")

# Which of the two senses of the thumb's nail-width axis is the nail: the
# radial-dorsal side, hand frame of a right hand (the thumb's pulp faces the
# index finger, as in a key pinch).
_THUMB_NAIL_SIDE = np.array([-1.0, 0.0, 1.0]) / np.sqrt(2.0)

_MIRROR = np.diag([-1.0, 1.0, 1.0])

# wrist to the middle fingertip of a child's or an adult's hand, mm, and the units
# (with their factor to metres) that a file outside it is likely in
_HAND_LENGTH_MM = (100.0, 300.0)
_UNITS = (("centimetres", 0.01), ("millimetres", 0.001), ("inches", 0.0254))

# glTF 2.0 accessor component types and element sizes
_COMPONENT = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16,
              5125: np.uint32, 5126: np.float32}
_N_COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}


#: The glTF hands shipped with the package, by name (files and licences in
#: ``handsynth/testhands/data/<name>/``).
TEST_HANDS: dict[str, str] = {
    "godot_xr_tools": "godot_xr_tools/hand_r.gltf",  # CC0 (License.md)
    "mrtk": "mrtk/hand_r.glb",  # BSD-3-Clause / MIT (License.txt)
    "webxr_generic": "webxr_generic/hand_r.glb",  # MIT (License.md)
}
#: The glTF hands the protocol and the studies test on unless told otherwise.  The
#: development runs printed their figures (no choice followed them);
#: ``webxr_generic`` came after every choice and is measured when named.
PROTOCOL_HANDS: tuple[str, ...] = ("godot_xr_tools", "mrtk")
DATA_DIR = Path(__file__).resolve().parent / "data"


def shipped_hand_path(name: str = "godot_xr_tools") -> Path:
    """The file of a glTF hand shipped with the package.

    Parameters
    ----------
    name : str
        A key of :data:`TEST_HANDS`.

    Raises
    ------
    InvalidInputError
        An unknown name.
    """
    if name not in TEST_HANDS:
        raise InvalidInputError(f"test hand must be one of {sorted(TEST_HANDS)}, got {name!r}")
    return DATA_DIR / TEST_HANDS[name]


def default_mesh_path() -> Path:
    """The glTF file of the default mesh hand.

    ``$HANDSYNTH_MESH_HAND`` if set, else the shipped Godot XR Tools hand
    (:func:`shipped_hand_path`).
    """
    env = os.environ.get(MESH_ENV)
    if env:
        return Path(env)
    return shipped_hand_path("godot_xr_tools")


# ---------------------------------------------------------------------------
# glTF reading
# ---------------------------------------------------------------------------
def _rot(axis: np.ndarray, angle_rad: float) -> np.ndarray:
    """Rotation matrix (3, 3) about unit `axis` by `angle_rad` (right-hand rule)."""
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + np.sin(angle_rad) * k + (1.0 - np.cos(angle_rad)) * (k @ k)


def _quat_mat(q) -> np.ndarray:
    x, y, z, w = (float(v) for v in q)
    n = np.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / n, y / n, z / n, w / n
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


class _Gltf:
    """The parts of a glTF 2.0 JSON document that a skinned mesh needs."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self._glb_bin: bytes | None = None
        try:
            raw = path.read_bytes()
        except OSError as exc:
            raise InvalidInputError(f"cannot read mesh hand {path}: {exc}") from None
        if raw[:4] == b"glTF":
            raw, self._glb_bin = self._glb_chunks(raw)
        try:
            self.doc = json.loads(raw.decode("utf-8"))
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise InvalidInputError(f"mesh hand {path} is not a glTF JSON document: {exc}") from None
        if not isinstance(self.doc, dict) or not str(self.doc.get("asset", {}).get("version", "")
                                                     ).startswith("2"):
            raise InvalidInputError(f"mesh hand {path}: asset.version must be glTF 2.x")
        self._buffers: dict[int, bytes] = {}

    def _glb_chunks(self, raw: bytes) -> tuple[bytes, bytes | None]:
        """JSON and BIN chunks of a binary glTF (glTF 2.0 specification, section 4.4)."""
        if len(raw) < 20:
            raise InvalidInputError(f"mesh hand {self.path}: GLB file of {len(raw)} bytes is truncated")
        version, length = struct.unpack_from("<II", raw, 4)
        if version != 2 or length > len(raw):
            raise InvalidInputError(f"mesh hand {self.path}: GLB header says version {version}, "
                                    f"{length} bytes (file has {len(raw)}); need version 2")
        chunks: dict[bytes, bytes] = {}
        at = 12
        while at + 8 <= length:
            size, kind = struct.unpack_from("<I4s", raw, at)
            if at + 8 + size > length:
                raise InvalidInputError(f"mesh hand {self.path}: GLB chunk at byte {at} is truncated")
            chunks.setdefault(kind, raw[at + 8:at + 8 + size])
            at += 8 + size
        if b"JSON" not in chunks:
            raise InvalidInputError(f"mesh hand {self.path}: GLB file has no JSON chunk")
        return chunks[b"JSON"], chunks.get(b"BIN\x00")

    def field(self, key: str, index: int) -> dict:
        try:
            item = self.doc[key][index]
        except (KeyError, IndexError, TypeError):
            raise InvalidInputError(f"mesh hand {self.path}: {key}[{index}] is missing") from None
        if not isinstance(item, dict):
            raise InvalidInputError(f"mesh hand {self.path}: {key}[{index}] must be an object")
        return item

    def buffer(self, index: int) -> bytes:
        if index not in self._buffers:
            b = self.field("buffers", index)
            uri = b.get("uri")
            if uri is None and index == 0 and self._glb_bin is not None:
                data = self._glb_bin  # the GLB's own binary chunk
            elif not isinstance(uri, str):
                raise InvalidInputError(f"mesh hand {self.path}: buffers[{index}].uri is missing")
            elif uri.startswith("data:"):
                try:
                    data = base64.b64decode(uri.split(",", 1)[1], validate=True)
                except (IndexError, ValueError) as exc:
                    raise InvalidInputError(
                        f"mesh hand {self.path}: buffers[{index}].uri is not base64 data: {exc}"
                    ) from None
            else:
                try:
                    data = (self.path.parent / uri).read_bytes()
                except OSError as exc:
                    raise InvalidInputError(
                        f"mesh hand {self.path}: cannot read buffers[{index}].uri {uri!r}: {exc}"
                    ) from None
            if len(data) < int(b.get("byteLength", 0)):
                raise InvalidInputError(
                    f"mesh hand {self.path}: buffers[{index}] holds {len(data)} bytes, "
                    f"byteLength says {b.get('byteLength')}")
            self._buffers[index] = data
        return self._buffers[index]

    def accessor(self, index: int) -> np.ndarray:
        """Accessor `index` as an array (count, components), floats normalised as glTF says."""
        a = self.field("accessors", index)
        where = f"mesh hand {self.path}: accessors[{index}]"
        if "sparse" in a:
            raise InvalidInputError(f"{where}: sparse accessors are not supported")
        ctype, atype = a.get("componentType"), a.get("type")
        if ctype not in _COMPONENT:
            raise InvalidInputError(f"{where}.componentType must be one of {sorted(_COMPONENT)}, "
                                    f"got {ctype!r}")
        if atype not in _N_COMPONENTS:
            raise InvalidInputError(f"{where}.type must be one of {sorted(_N_COMPONENTS)}, "
                                    f"got {atype!r}")
        if "bufferView" not in a:
            raise InvalidInputError(f"{where}.bufferView is missing")
        dtype = np.dtype(_COMPONENT[ctype]).newbyteorder("<")
        n, count = _N_COMPONENTS[atype], int(a.get("count", 0))
        view = self.field("bufferViews", a["bufferView"])
        data = self.buffer(int(view.get("buffer", 0)))
        start = int(view.get("byteOffset", 0)) + int(a.get("byteOffset", 0))
        stride = int(view.get("byteStride", n * dtype.itemsize))
        end = start + (count - 1) * stride + n * dtype.itemsize if count else start
        if count < 1 or end > int(view.get("byteOffset", 0)) + int(view.get("byteLength", 0)) \
                or end > len(data):
            raise InvalidInputError(f"{where}: count {count} x stride {stride} does not fit "
                                    f"bufferViews[{a['bufferView']}]")
        arr = np.ndarray((count, n), dtype=dtype, buffer=data, offset=start,
                         strides=(stride, dtype.itemsize)).copy()
        scalar = dtype.type
        if a.get("normalized") and issubclass(scalar, np.unsignedinteger):
            return arr.astype(np.float64) / np.iinfo(scalar).max
        return arr

    def node_local(self, i: int) -> np.ndarray:
        node = self.field("nodes", i)
        if "matrix" in node:
            m = np.asarray(node["matrix"], dtype=np.float64)
            if m.shape != (16,):
                raise InvalidInputError(f"mesh hand {self.path}: nodes[{i}].matrix must hold 16 numbers")
            return m.reshape(4, 4).T  # column-major
        out = np.eye(4)
        out[:3, :3] = _quat_mat(node.get("rotation", (0, 0, 0, 1))) @ np.diag(node.get("scale", (1, 1, 1)))
        out[:3, 3] = node.get("translation", (0, 0, 0))
        return out

    def node_world(self) -> list[np.ndarray]:
        nodes = self.doc.get("nodes", [])
        parent: dict[int, int] = {}
        for i, nd in enumerate(nodes):
            for c in nd.get("children", []):
                parent[int(c)] = i
        out: dict[int, np.ndarray] = {}

        def world(i: int, depth: int = 0) -> np.ndarray:
            if depth > len(nodes):
                raise InvalidInputError(f"mesh hand {self.path}: the node hierarchy has a cycle")
            if i not in out:
                local = self.node_local(i)
                out[i] = world(parent[i], depth + 1) @ local if i in parent else local
            return out[i]

        return [world(i) for i in range(len(nodes))]


# ---------------------------------------------------------------------------
# the rig in the hand frame
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class MeshRig:
    """A skinned right-hand mesh in handsynth's hand frame, metres.

    Attributes
    ----------
    vertices : ndarray, shape (V, 3), float64
        Rest-pose vertices (duplicates of the file merged), hand frame.
    faces : ndarray, shape (F, 3), int32
        Triangles, counter-clockwise seen from outside.
    bone_index : ndarray, shape (V, 4), intp
        Bones of each vertex (rows of `bone_names`).
    bone_weight : ndarray, shape (V, 4), float64
        Skin weights, rows summing to 1.
    bone_names : tuple of str
        ``"wrist"``, ``"<digit>_<bone>"`` (OpenXR's names, whatever naming
        the file used, module docstring), or ``"other:<node name>"`` for
        bones handsynth does not pose.  A fingertip that is no skin joint is
        appended and carries no weights.
    joints : dict of str to ndarray, shape (3,)
        Rest-pose joint centre of each named bone, hand frame.
    frames : dict of str to ndarray, shape (3, 3)
        Rest-pose anatomical frame of each posable bone (columns: flexion
        axis toward the little-finger side, bone direction, dorsal side).
    tip_mm : dict of str to float
        Distance from the distal joint to the skin's end along the distal
        bone, per digit.
    to_hand : ndarray, shape (4, 4)
        Transform from the glTF scene to the hand frame.
    source_side : {"right", "left"}
        The side of the hand in the file (a left hand is mirrored on loading).
    path : Path
    """

    vertices: np.ndarray
    faces: np.ndarray
    bone_index: np.ndarray
    bone_weight: np.ndarray
    bone_names: tuple[str, ...]
    joints: dict
    frames: dict
    tip_mm: dict
    to_hand: np.ndarray
    source_side: str
    path: Path

    def bone(self, name: str) -> int:
        return self.bone_names.index(name)

    def scaled(self, factor: float) -> MeshRig:
        """The same hand made larger or smaller about its wrist joint.

        Parameters
        ----------
        factor : float
            Multiplies every length (vertices, joint centres, fingertip
            distances); 1 gives the rig unchanged.  Between 0.5 and 2.

        Returns
        -------
        MeshRig
            Same bones, weights, frames and faces.

        Raises
        ------
        InvalidInputError
            A `factor` that is not a number in [0.5, 2].
        """
        if isinstance(factor, bool) or not isinstance(factor, (int, float, np.floating)) \
                or not 0.5 <= factor <= 2.0:
            raise InvalidInputError(f"scale must be a number in [0.5, 2], got {factor!r}")
        f = float(factor)
        to_hand = self.to_hand.copy()
        to_hand[:3] *= f  # the hand frame's origin is the wrist joint
        return replace(self, vertices=self.vertices * f,
                       joints={k: v * f for k, v in self.joints.items()},
                       tip_mm={k: v * f for k, v in self.tip_mm.items()}, to_hand=to_hand)


# A side marker in a node name: RightHand / rightIndexProximal, index_proximal_R / hand.L,
# r_index1 / L_hand.
_SIDE_PATTERNS = (r"^(right|left)(?=.)", r"[._\s-](r|l|right|left)$", r"^(r|l)[._\s-]")
# a digit joint once separators are removed: index_proximal, index-finger-phalanx-proximal,
# IndexProximal, index1 / index_01, f_index.01 (Blender's Rigify)
_DIGIT_JOINT = re.compile(r"f?(thumb|index|middle|ring|little)(?:finger)?(?:phalanx)?"
                          r"(metacarpal|proximal|intermediate|distal|tip|0?[1-4])")
# joints numbered from 1 (Mixamo, MANO, Unreal): the thumb's first is its CMC joint,
# a finger's first its MCP joint; 4 is the tip
_NUMBERED = {"thumb": _THUMB_BONES, **dict.fromkeys(FINGERS[1:], _FINGER_BONES[1:])}
# the names of the wrist joint, in the order they are taken: Mixamo's and Unity's wrist
# is their "hand", MANO's the "root" of its tree
_WRIST_WORDS = ("wrist", "hand", "root")
# the conventions read, for the message that refuses a rig
_CONVENTIONS = ("OpenXR or WebXR (wrist, index_proximal_R, index-finger-phalanx-proximal), "
                "Mixamo or FBX humanoid (mixamorig:RightHand, mixamorig:RightHandIndex1), "
                "Unity or VRM humanoid (RightHand, RightIndexProximal, rightThumbMetacarpal), "
                "MANO (wrist or root, index1, thumb1)")


def _split_side(name: str) -> tuple[str, str | None]:
    """A node name without its namespace and side marker, and the side it names.

    ``mixamorig:RightHandIndex1`` gives ``("HandIndex1", "right")``; a name
    without a side marker gives None.  The namespace is what precedes the last
    colon (``mixamorig:``, ``mixamorig1:``) or a ``mixamorig_`` or ``DEF-`` prefix.
    """
    n = re.sub(r"^.*:", "", name.strip())
    n = re.sub(r"^(mixamorig\d*_|def[-_.])", "", n, flags=re.IGNORECASE)
    for pattern in _SIDE_PATTERNS:
        m = re.search(pattern, n, flags=re.IGNORECASE)
        if m:
            side = "right" if m.group(1)[0] in "rR" else "left"
            return n[:m.start()] + n[m.end():], side
    return n, None


def _parse_bone(name: str) -> tuple[str | None, str | None]:
    """The canonical bone and the side that a glTF node name says (module docstring, step 2).

    Returns
    -------
    bone : str or None
        ``"<digit>_<bone>"``, one of :data:`_WRIST_WORDS` (:func:`_rig_names`
        takes the first that names a joint as the wrist) or None.  The thumb
        of Unity's humanoid reads as ``thumb_proximal`` /
        ``thumb_intermediate`` / ``thumb_distal`` here; :func:`_rig_names`
        moves it one joint proximal.
    side : {"right", "left"} or None
    """
    core, side = _split_side(name)
    n = re.sub(r"[._\s-]", "", core.lower()).replace("pinky", "little")
    if n in _WRIST_WORDS:
        return n, side
    m = _DIGIT_JOINT.fullmatch(n.removeprefix("hand"))  # Mixamo: RightHandIndex1
    if m is None:
        return None, side
    digit, bone = m.groups()
    if bone[-1].isdigit():
        bone = _NUMBERED[digit][int(bone) - 1]
    return f"{digit}_{bone}", side


def _shifted_rig(g: _Gltf, joints_nodes: list, names: list[str]
                 ) -> tuple[list[str], list] | None:
    """Canonical names for a rig whose nodes sit one joint proximal of their names.

    Some exports (the MRTK hand: FBX armatures converted to glTF) put each
    bone's node at the joint *proximal* of the one OpenXR names: the node
    ``index_intermediate`` is at the index MCP, ``index_tip`` at the DIP and a
    childless ``index_tip_end`` at the fingertip, while the ``<digit>_metacarpal``
    nodes all sit at the wrist and the skin has no ``wrist`` bone.  Such a rig
    is recognised by those two facts (no wrist bone; every digit's ``tip`` node
    has a ``tip_end`` child) and renamed one step distal: ``<digit>_tip_end``
    becomes ``<digit>_tip``, ``tip`` becomes ``distal`` and so on; the
    ``<digit>_metacarpal`` nodes at the wrist become bones handsynth does not
    pose, and the common parent of the digit chains is the wrist.  Nodes that
    are not skin joints (the wrist, the tips) are appended to the joint list
    and carry no skin weights.

    Returns
    -------
    (names, joints_nodes) or None
        None when the rig does not follow this convention.
    """
    if "wrist" in names:
        return None
    nodes = g.doc.get("nodes", [])
    by_name = {str(nd.get("name", "")).lower(): i for i, nd in enumerate(nodes)
               if isinstance(nd, dict)}
    parent = {c: i for i, nd in enumerate(nodes) if isinstance(nd, dict)
              for c in nd.get("children", [])}
    tip_ends = {}
    for digit in FINGERS:
        tip, end = by_name.get(f"{digit}_tip"), by_name.get(f"{digit}_tip_end")
        if tip is None or end is None or parent.get(end) != tip:
            return None
        tip_ends[digit] = end
    bases = {parent.get(by_name.get(f"{d}_metacarpal", -1)) for d in FINGERS}
    if len(bases) != 1 or None in bases:
        return None
    distal_of = {"thumb": dict(zip(("metacarpal", "proximal", "distal", "tip"),
                                   ("other", "metacarpal", "proximal", "distal"))),
                 **{d: dict(zip(_FINGER_BONES, ("other", "metacarpal", "proximal",
                                                "intermediate", "distal")))
                    for d in FINGERS[1:]}}
    out = []
    for nm in names:
        digit, _, bone = nm.partition("_")
        new = distal_of.get(digit, {}).get(bone, "other")
        out.append(f"other:{nm}" if new == "other" or nm.startswith("other:")
                   else f"{digit}_{new}")
    extra = [("wrist", bases.pop()), *((f"{d}_tip", tip_ends[d]) for d in FINGERS)]
    return out + [n for n, _ in extra], list(joints_nodes) + [i for _, i in extra]


def _node_name(g: _Gltf, i: int) -> str:
    return str(g.field("nodes", i).get("name", ""))


def _rig_names(g: _Gltf, joints_nodes: list) -> tuple[list[str], list, str | None]:
    """Canonical bone names of the skin's joints, and the side their names say.

    Reads the names (:func:`_parse_bone`), the wrist as the joints named
    ``wrist``, else ``hand``, else ``root``, a rig one joint proximal of its
    names (:func:`_shifted_rig`) and the thumb of Unity's humanoid
    (Proximal at the CMC joint, Intermediate at the MCP) where the thumb has
    an intermediate bone and no metacarpal.  Joints handsynth does not know
    read as ``"other:<node name>"``.

    Returns
    -------
    names : list of str
    joints_nodes : list of int
        The skin's joints and any nodes appended for the names appended.
    side : {"right", "left"} or None
        The side the names say, None if none says one or they disagree.

    Raises
    ------
    InvalidInputError
        Two joints read as the same bone (a skin of both hands, say).
    """
    raw = [_node_name(g, n) for n in joints_nodes]
    parsed = [_parse_bone(nm) for nm in raw]
    names = [b if b is not None else f"other:{nm}" for (b, _), nm in zip(parsed, raw)]
    word = next((w for w in _WRIST_WORDS if w in names), "wrist")
    names = [("wrist" if n == word else f"other:{nm}") if n in _WRIST_WORDS else n
             for n, nm in zip(names, raw)]
    shifted = _shifted_rig(g, joints_nodes, names)
    if shifted is not None:
        names, joints_nodes = shifted
    if "thumb_intermediate" in names and "thumb_metacarpal" not in names:
        unity = {"thumb_proximal": "thumb_metacarpal", "thumb_intermediate": "thumb_proximal"}
        names = [unity.get(n, n) for n in names]
    seen: dict[str, int] = {}
    for n, k in zip(names, joints_nodes):
        if n in seen and not n.startswith("other:"):
            raise InvalidInputError(
                f"mesh hand {g.path}: the skin's nodes {_node_name(g, seen[n])!r} and "
                f"{_node_name(g, k)!r} both read as the bone {n}; one hand in one naming is expected")
        seen[n] = k
    sides = {s for b, s in parsed if b is not None and s is not None}
    return names, list(joints_nodes), sides.pop() if len(sides) == 1 else None


def _tip_nodes(g: _Gltf, names: list[str], joints_nodes: list, side: str | None
               ) -> tuple[list[str], list]:
    """Append the fingertip nodes that are not joints of the skin.

    A digit whose skin has no tip joint takes the one other node named as its
    tip (on the same side, if named), else the only child of its distal node
    that is not a skin joint and has no children, mesh or camera (an ``_end``
    node of an exported armature).  A digit with neither keeps no tip node.
    """
    nodes = g.doc.get("nodes", [])
    joints = set(joints_nodes)
    named: dict[str, list[int]] = {}
    for i, nd in enumerate(nodes):
        if i not in joints and isinstance(nd, dict):
            bone, s = _parse_bone(str(nd.get("name", "")))
            if bone is not None and bone.endswith("_tip") and s in (None, side):
                named.setdefault(bone, []).append(i)
    names, joints_nodes = list(names), list(joints_nodes)
    for digit in FINGERS:
        tip = f"{digit}_tip"
        if tip in names:
            continue
        found = named.get(tip, [])
        if len(found) != 1:
            distal = g.field("nodes", joints_nodes[names.index(f"{digit}_distal")])
            found = [c for c in distal.get("children", []) if c not in joints
                     and not {"children", "mesh", "camera", "skin"} & set(g.field("nodes", c))]
        if len(found) == 1:
            names.append(tip)
            joints_nodes.append(found[0])
    return names, joints_nodes


def _bone_vertices(v: np.ndarray, dom: np.ndarray, k: int, where: str) -> np.ndarray:
    """The vertices (n, 3) whose largest skin weight is on bone `k` (`dom`: that bone per vertex).

    Raises
    ------
    InvalidInputError
        None (`where` names the bone).
    """
    sel = v[dom == k]
    if len(sel) == 0:
        raise InvalidInputError(f"{where}: no vertex of the skin is mostly weighted to it, so "
                                "the fingertip cannot be placed")
    return sel


def _skin_end(points: np.ndarray, origin: np.ndarray, direction: np.ndarray) -> float:
    """How far the farthest of `points` lies from `origin` along unit `direction`."""
    return float(((points - origin) @ direction).max())


def _skin_tip(points: np.ndarray, distal: np.ndarray) -> np.ndarray:
    """A fingertip where the skin ends along the distal bone, for a rig without a tip node.

    `points` are the vertices mostly weighted to the distal bone whose joint
    is at `distal`; the bone's direction is from its joint to their
    centroid, the tip the farthest of them along it (:func:`_skin_end`).
    """
    ydir = _unit(points.mean(axis=0) - distal)
    return distal + ydir * _skin_end(points, distal, ydir)


def _check_hand_length(pos: dict, path: Path) -> None:
    """Refuse a hand whose size says the file is not in metres.

    Raises
    ------
    InvalidInputError
        Wrist to middle fingertip outside :data:`_HAND_LENGTH_MM`, naming the
        length and the unit that would make it a hand's.
    """
    length = float(np.linalg.norm(pos["middle_tip"] - pos["wrist"])) * 1e3
    lo, hi = _HAND_LENGTH_MM
    if lo <= length <= hi:
        return
    likely = [f"the file is likely in {unit} (that would make it {length * f:.0f} mm); export it "
              f"in metres, as glTF requires, or give its root node the scale {f:g}"
              for unit, f in _UNITS if lo <= length * f <= hi]
    cause = likely[0] if likely else ("no common unit explains it; check the scale of the "
                                      "nodes above the skeleton")
    raise InvalidInputError(
        f"mesh hand {path}: the hand is {length:.1f} mm from the wrist to the middle fingertip "
        f"(the file's lengths read as metres), outside the {lo:.0f}-{hi:.0f} mm of a child's or "
        f"an adult's hand; {cause}")


def _hand_axes(pos: dict, named: str | None, path: Path) -> tuple[np.ndarray, str]:
    """The hand frame's axes in scene coordinates, and the side of the hand in the file.

    +y toward the middle MCP, the palm plane through the index-to-little
    MCP line, +z away from the side toward which the rest-pose fingers curl
    (module docstring, step 3).  A rig whose rest fingers are flat (mean curl
    under 1 mm) takes the side its node names say (`named`): the thumb is on
    the hand frame's -x side of a right hand.

    Returns
    -------
    rot : ndarray, shape (3, 3)
        Rows: the hand axes x, y, z.
    side : {"right", "left"}

    Raises
    ------
    InvalidInputError
        Flat rest fingers and no side in the names, or a curl that makes the
        hand the other side than its names say.
    """
    wrist = pos["wrist"]
    y = _unit(pos["middle_proximal"] - wrist)
    across = pos["little_proximal"] - pos["index_proximal"]
    z = _unit(np.cross(across, y))
    # the fingers of a relaxed rigged hand curl toward the palm: +z is dorsal
    curl = np.mean([(pos[f"{f_}_tip"] - pos[f"{f_}_proximal"]) @ z for f_ in FINGERS[1:]])
    flat = abs(curl) < 1e-3  # metres
    if flat and named is None:
        raise InvalidInputError(
            f"mesh hand {path}: the rest-pose fingers are flat and no node name says right or "
            "left (as RightHand or index_proximal_R do), so the back of the hand cannot be told "
            "from the palm")
    if not flat and curl > 0:
        z = -z
    x = np.cross(y, z)
    side = "right" if x @ (pos["thumb_proximal"] - wrist) < 0 else "left"
    if flat and side != named:
        x, z, side = -x, -z, str(named)
    elif named is not None and side != named:
        raise InvalidInputError(
            f"mesh hand {path}: the node names say a {named} hand, but its rest-pose fingers curl "
            f"toward the palm of a {side} hand ({abs(curl) * 1e3:.1f} mm), so the back of the hand "
            "cannot be told from the palm; correct the names or the rest pose")
    return np.stack([x, y, z]), side


def _unit(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v)
    if not n > 1e-12:
        raise InvalidInputError("mesh hand: two joint centres of the rig coincide")
    return v / n


def _frame(x_hint: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Orthonormal frame (columns x, y, z = x cross y) with bone direction `y`."""
    y = _unit(y)
    x = _unit(x_hint - (x_hint @ y) * y)
    return np.column_stack([x, y, np.cross(x, y)])


def _plane_section(vertices: np.ndarray, faces: np.ndarray, origin: np.ndarray,
                   normal: np.ndarray) -> np.ndarray:
    """Points (2M, 3) where the triangle edges cross the plane (`origin`, `normal`)."""
    d = (vertices - origin) @ normal
    tri = d[faces]
    pts = []
    for a, b in ((0, 1), (1, 2), (2, 0)):
        da, db = tri[:, a], tri[:, b]
        cross = (da * db) < 0
        t = da[cross] / (da[cross] - db[cross])
        va, vb = vertices[faces[cross, a]], vertices[faces[cross, b]]
        pts.append(va + t[:, None] * (vb - va))
    return np.vstack(pts) if pts else np.empty((0, 3))


def load_mesh_rig(path: str | os.PathLike | None = None) -> MeshRig:
    """Read a rigged hand glTF and express it in handsynth's hand frame.

    Parameters
    ----------
    path : str or path-like, optional
        A ``.gltf`` file (JSON with embedded or external buffers) or a
        ``.glb``; :func:`default_mesh_path` by default.

    Returns
    -------
    MeshRig
        Always a right hand (a left-hand file is mirrored).

    Raises
    ------
    InvalidInputError
        A missing file, a malformed glTF (naming the field), a skeleton
        without the wrist and the digit joints named as in the module
        docstring (naming those missing, those found and the namings read),
        two joints read as the same bone, flat rest-pose fingers without a
        side in the names or a curl against them, or a hand outside 100-300 mm
        long (naming its length and likely unit).
    """
    path = Path(path) if path is not None else default_mesh_path()
    if not path.is_file():
        raise InvalidInputError(
            f"mesh hand file {str(path)!r} does not exist; set {MESH_ENV} to a rigged hand .gltf")
    g = _Gltf(path)
    skin_nodes = [(i, nd) for i, nd in enumerate(g.doc.get("nodes", []))
                  if isinstance(nd, dict) and "mesh" in nd and "skin" in nd]
    if not skin_nodes:
        raise InvalidInputError(f"mesh hand {path}: no node has both 'mesh' and 'skin'")
    _, node = skin_nodes[0]
    skin = g.field("skins", node["skin"])
    mesh = g.field("meshes", node["mesh"])
    joints_nodes = skin.get("joints")
    if not isinstance(joints_nodes, list) or not joints_nodes:
        raise InvalidInputError(f"mesh hand {path}: skins[{node['skin']}].joints is missing")
    worlds = g.node_world()
    nb = len(joints_nodes)
    if "inverseBindMatrices" in skin:
        ibm = g.accessor(skin["inverseBindMatrices"]).astype(np.float64)
        if ibm.shape != (nb, 16):
            raise InvalidInputError(f"mesh hand {path}: skins[{node['skin']}].inverseBindMatrices "
                                    f"must hold {nb} MAT4, got {ibm.shape}")
        ibm = ibm.reshape(nb, 4, 4).transpose(0, 2, 1)
    else:
        ibm = np.broadcast_to(np.eye(4), (nb, 4, 4))
    skin_mats = np.stack([worlds[j] @ ibm[k] for k, j in enumerate(joints_nodes)])

    verts, faces, bidx, bw = [], [], [], []
    offset = 0
    for p, prim in enumerate(mesh.get("primitives", [])):
        where = f"meshes[{node['mesh']}].primitives[{p}]"
        if prim.get("mode", 4) != 4:
            raise InvalidInputError(f"mesh hand {path}: {where}.mode must be 4 (triangles)")
        attrs = prim.get("attributes", {})
        for key in ("POSITION", "JOINTS_0", "WEIGHTS_0"):
            if key not in attrs:
                raise InvalidInputError(f"mesh hand {path}: {where}.attributes.{key} is missing")
        v = g.accessor(attrs["POSITION"]).astype(np.float64)
        j = g.accessor(attrs["JOINTS_0"]).astype(np.intp)
        w = g.accessor(attrs["WEIGHTS_0"]).astype(np.float64)
        if v.shape[1] != 3 or j.shape != (len(v), 4) or w.shape != (len(v), 4):
            raise InvalidInputError(f"mesh hand {path}: {where} POSITION/JOINTS_0/WEIGHTS_0 "
                                    f"shapes {v.shape} {j.shape} {w.shape} do not match")
        if j.min() < 0 or j.max() >= nb:
            raise InvalidInputError(f"mesh hand {path}: {where}.attributes.JOINTS_0 refers to "
                                    f"joint {j.max()} of a skin with {nb} joints")
        f = (g.accessor(prim["indices"]).reshape(-1) if "indices" in prim
             else np.arange(len(v))).astype(np.intp)
        if len(f) % 3 or f.max() >= len(v):
            raise InvalidInputError(f"mesh hand {path}: {where}.indices are not triangles of "
                                    f"its {len(v)} vertices")
        s = w.sum(axis=1, keepdims=True)
        if not np.all(s > 0):
            raise InvalidInputError(f"mesh hand {path}: {where}.attributes.WEIGHTS_0 has a "
                                    "vertex without weights")
        w = w / s
        # rest-pose positions: the skinned vertices at the nodes' own transforms
        m = np.einsum("vk,vkij->vij", w, skin_mats[j])
        v = np.einsum("vij,vj->vi", m[:, :3, :3], v) + m[:, :3, 3]
        verts.append(v)
        faces.append(f.reshape(-1, 3) + offset)
        bidx.append(j)
        bw.append(w)
        offset += len(v)
    if not verts:
        raise InvalidInputError(f"mesh hand {path}: meshes[{node['mesh']}] has no primitives")
    v, f, j, w = np.vstack(verts), np.vstack(faces), np.vstack(bidx), np.vstack(bw)

    names, joints_nodes, named_side = _rig_names(g, joints_nodes)
    need = ["wrist", *(f"thumb_{b}" for b in _THUMB_BONES[:3]),
            *(f"{f_}_{b}" for f_ in FINGERS[1:] for b in _FINGER_BONES[1:4])]
    missing = [n for n in need if n not in names]
    if missing:
        raise InvalidInputError(f"mesh hand {path}: the skin has no bones named like "
                                f"{', '.join(missing)} (found {', '.join(names)}); expected the "
                                f"wrist and the digits' joints named as in {_CONVENTIONS}")
    names, joints_nodes = _tip_nodes(g, names, joints_nodes, named_side)
    pos = {n: worlds[joints_nodes[k]][:3, 3] for k, n in enumerate(names)}
    bone_at = {f"{fg}_distal": f"mesh hand {path}: bone {fg}_distal (node "
             f"{_node_name(g, joints_nodes[names.index(f'{fg}_distal')])!r})" for fg in FINGERS}
    dom = j[np.arange(len(j)), np.argmax(w, axis=1)]
    for fg in FINGERS:  # no tip node: where the skin ends along the distal bone
        if f"{fg}_tip" not in pos:
            dist = f"{fg}_distal"
            pos[f"{fg}_tip"] = _skin_tip(_bone_vertices(v, dom, names.index(dist), bone_at[dist]), pos[dist])
            names.append(f"{fg}_tip")
    _check_hand_length(pos, path)

    # --- hand frame -------------------------------------------------------------
    wrist = pos["wrist"]
    rot, side = _hand_axes(pos, named_side, path)  # rows: hand axes in scene coordinates
    mirror = np.eye(3) if side == "right" else _MIRROR
    to_hand = np.eye(4)
    to_hand[:3, :3] = mirror @ rot
    to_hand[:3, 3] = -(mirror @ rot @ wrist)

    def h(p):
        return to_hand[:3, :3] @ p + to_hand[:3, 3]

    v = v @ to_hand[:3, :3].T + to_hand[:3, 3]
    if side == "left":
        f = f[:, ::-1]
    # merge duplicate vertices (seams of normals and texture coordinates)
    _, first, inverse = np.unique(np.round(v, 7), axis=0, return_index=True, return_inverse=True)
    order = np.sort(first)
    remap = np.empty(len(v), dtype=np.intp)
    remap[order] = np.arange(len(order))
    f = remap[first[inverse.reshape(-1)]][f]
    v, j, w = v[order], j[order], w[order]
    joints = {n: h(p) for n, p in pos.items() if not n.startswith("other:")}

    # --- rest-pose anatomical frames -----------------------------------------------
    frames: dict[str, np.ndarray] = {}
    zh = np.array([0.0, 0.0, 1.0])
    for fg in FINGERS[1:]:
        chain = [joints[f"{fg}_{b}"] for b in _FINGER_BONES[1:]]
        along = chain[-1] - chain[0]
        along[2] = 0.0
        axis = np.cross(_unit(along), zh)  # toward the little-finger side
        for b, p0, p1 in zip(_FINGER_BONES[1:4], chain[:-1], chain[1:]):
            frames[f"{fg}_{b}"] = _frame(axis, p1 - p0)
    tchain = [joints[f"thumb_{b}"] for b in _THUMB_BONES]
    axis = _thumb_flexion_axis(v, f, j, w, names, tchain)
    for b, p0, p1 in zip(_THUMB_BONES[:3], tchain[:-1], tchain[1:]):
        frames[f"thumb_{b}"] = _frame(axis, p1 - p0)

    # skin's end along each distal bone (vertices mostly on that bone)
    tip_mm = {}
    dom = j[np.arange(len(j)), np.argmax(w, axis=1)]
    for fg in FINGERS:
        dist = f"{fg}_distal"
        pts = _bone_vertices(v, dom, names.index(dist), bone_at[dist])
        tip_mm[fg] = _skin_end(pts, joints[dist], frames[dist][:, 1]) * 1e3
    return MeshRig(v, f.astype(np.int32), j, w, tuple(names), joints, frames, tip_mm,
                   to_hand, side, path)


def _thumb_flexion_axis(v, f, j, w, names, tchain) -> np.ndarray:
    """Broad axis of the thumb's distal phalanx (the nail's width), hand frame.

    The principal axis of the plane sections of the mesh at 30-70 % of the
    distal phalanx, with the sign that puts the nail (x cross y) on the side
    of handsynth's rest thumb nail.
    """
    ip, tip = tchain[2], tchain[3]
    ydir = _unit(tip - ip)
    thumb = [names.index(f"thumb_{b}") for b in ("proximal", "distal", "tip")]
    dom = j[np.arange(len(j)), np.argmax(w, axis=1)]
    f = f[np.all(np.isin(dom[f], thumb), axis=1)]
    cov = np.zeros((3, 3))
    radius = 0.6 * np.linalg.norm(tip - ip)
    for frac in (0.3, 0.4, 0.5, 0.6, 0.7):
        o = ip + frac * (tip - ip)
        pts = _plane_section(v, f, o, ydir)
        pts = pts[np.linalg.norm(pts - o, axis=1) < radius]
        if len(pts) < 6:
            continue
        q = pts - pts.mean(axis=0)
        cov += q.T @ q / len(q)
    if not np.any(cov):
        raise InvalidInputError("mesh hand: no mesh surface around the thumb's distal phalanx")
    _, evecs = np.linalg.eigh(cov)
    axis = evecs[:, 2] - (evecs[:, 2] @ ydir) * ydir
    axis = _unit(axis)
    nail = np.cross(axis, ydir)
    return axis if nail @ _THUMB_NAIL_SIDE >= 0 else -axis


def _thumb_rest_direction() -> np.ndarray:
    """handsynth's rest direction (3,) of the right thumb metacarpal, hand frame.

    Turned ``THUMB_YAW_DEG`` (40) from +y toward the thumb side and
    ``THUMB_PITCH_DEG`` (12) palmar, as in :func:`handsynth.models.hand_mjcf`.
    """
    from ..models import THUMB_PITCH_DEG, THUMB_YAW_DEG

    rz = _rot(np.array([0.0, 0.0, 1.0]), np.radians(THUMB_YAW_DEG))
    rx = _rot(np.array([1.0, 0.0, 0.0]), np.radians(-THUMB_PITCH_DEG))
    return rz @ rx @ np.array([0.0, 1.0, 0.0])


def _swing(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The smallest rotation taking unit vector `a` to unit vector `b`."""
    c = float(np.clip(a @ b, -1.0, 1.0))
    ax = np.cross(a, b)
    s = np.linalg.norm(ax)
    if s < 1e-12:
        return np.eye(3)
    return _rot(ax / s, np.arctan2(s, c))


# ---------------------------------------------------------------------------
# posing
# ---------------------------------------------------------------------------
class _Poser:
    """Bone transforms and skinned vertices of a rig for canonical angles."""

    def __init__(self, rig: MeshRig) -> None:
        self.rig = rig
        nb = len(rig.bone_names)
        self._n_bones = nb
        ez = np.array([0.0, 0.0, 1.0])
        d_rest = _thumb_rest_direction()
        self._cmc_flex_axis = -ez                      # across the palm (handsynth)
        self._cmc_abd_axis = _unit(np.cross(d_rest, -ez))  # palmar abduction (handsynth)
        meta = rig.frames["thumb_metacarpal"]
        self._thumb_zero = _swing(meta[:, 1], d_rest) @ meta
        # handsynth's rest fan of the fingers (degrees toward the thumb)
        yaw = standard_layout_mm().finger_yaw_deg
        self._finger_zero = {f: _rot(ez, np.radians(yaw[f])) for f in FINGERS[1:]}
        self._mats = np.zeros((nb, 3, 4))
        self._mats[:, :, :3] = np.eye(3)
        self._v1 = np.hstack([rig.vertices, np.ones((len(rig.vertices), 1))])
        # dense (V, bones) weights: blending is one matrix product
        self._dense = np.zeros((len(rig.vertices), nb))
        np.add.at(self._dense, (np.arange(len(rig.vertices))[:, None], rig.bone_index),
                  rig.bone_weight)

    def _bone_poses(self, a_deg: np.ndarray) -> tuple[dict, dict]:
        """Posed anatomical frames and joint centres of the digit bones."""
        a = np.radians(a_deg)
        ex = np.array([1.0, 0.0, 0.0])
        frames: dict[str, np.ndarray] = {}
        joints: dict[str, np.ndarray] = {}
        # thumb: CMC flexion, CMC palmar abduction, MCP, IP
        meta = (_rot(self._cmc_flex_axis, a[0]) @ _rot(self._cmc_abd_axis, a[1])
                @ self._thumb_zero)
        prox = meta @ _rot(ex, -a[2])
        dist = prox @ _rot(ex, -a[3])
        self._chain("thumb", _THUMB_BONES[:3], (meta, prox, dist), frames, joints)
        for k, fg in enumerate(FINGERS[1:]):
            mcp_f, mcp_a, pip, dip = a[4 + 4 * k: 8 + 4 * k]
            p = self._finger_zero[fg] @ _rot(np.array([0.0, 0.0, 1.0]), mcp_a) @ _rot(ex, -mcp_f)
            m = p @ _rot(ex, -pip)
            d = m @ _rot(ex, -dip)
            self._chain(fg, _FINGER_BONES[1:4], (p, m, d), frames, joints)
        return frames, joints

    def _chain(self, digit, bones, posed, frames, joints) -> None:
        rig = self.rig
        base = f"{digit}_{bones[0]}"
        joints[base] = rig.joints[base]
        for k, (b, fr) in enumerate(zip(bones, posed)):
            name = f"{digit}_{b}"
            frames[name] = fr
            nxt = f"{digit}_{bones[k + 1]}" if k + 1 < len(bones) else f"{digit}_tip"
            delta = fr @ rig.frames[name].T
            joints[nxt] = joints[name] + delta @ (rig.joints[nxt] - rig.joints[name])

    def bone_transforms(self, a_deg: np.ndarray) -> np.ndarray:
        """Rest-to-pose transforms (bones, 3, 4) ``[R | t]`` of every bone, hand frame.

        A bone that does not move (wrist, finger metacarpals, bones handsynth
        does not know) has the identity; a tip bone moves with its distal bone.
        """
        rig = self.rig
        frames, joints = self._bone_poses(a_deg)
        mats = self._mats.copy()
        for name, fr in frames.items():
            k = rig.bone(name)
            delta = fr @ rig.frames[name].T
            mats[k, :, :3] = delta
            mats[k, :, 3] = joints[name] - delta @ rig.joints[name]
            if name.endswith("distal"):
                mats[rig.bone(name.replace("distal", "tip"))] = mats[k]
        return mats

    def vertices(self, a_deg: np.ndarray) -> np.ndarray:
        """Skinned vertices (V, 3) of the right hand, metres, hand frame."""
        mats = self.bone_transforms(a_deg)
        blend = (self._dense @ mats.reshape(self._n_bones, 12)).reshape(-1, 3, 4)
        return np.einsum("vij,vj->vi", blend, self._v1)

    def keypoints(self, a_deg: np.ndarray) -> np.ndarray:
        """The 21 keypoints (21, 3) of the right hand, metres, hand frame."""
        rig = self.rig
        frames, joints = self._bone_poses(a_deg)
        out = [np.zeros(3)]
        for fg in FINGERS:
            bones = ("metacarpal", "proximal", "distal") if fg == "thumb" else \
                ("proximal", "intermediate", "distal")
            out.extend(joints[f"{fg}_{b}"] for b in bones)
            out.append(joints[f"{fg}_distal"] + frames[f"{fg}_distal"][:, 1] * rig.tip_mm[fg] * 1e-3)
        return np.array(out)


# ---------------------------------------------------------------------------
# rendering
# ---------------------------------------------------------------------------
def _fmt(values) -> str:
    return " ".join(f"{v:.9g}" for v in np.ravel(values))


def _scene_xml(vertices: np.ndarray, faces: np.ndarray, mount: CameraMount, side: str,
               silhouette: bool, w: int, h: int) -> str:
    from ..render import scene_parts

    visual, world = scene_parts(mount, side, silhouette, w, h)
    material = ('rgba="1 1 1 1" emission="1" specular="0" shininess="0"' if silhouette
                else 'rgba="0.87 0.70 0.60 1" specular="0.15" shininess="0.3"')
    return f"""<mujoco model="handsynth_mesh_hand_{side}">
{visual}  <compiler angle="degree"/>
  <asset>
    <material name="skin" {material}/>
    <mesh name="hand" vertex="{_fmt(vertices)}" face="{" ".join(map(str, np.ravel(faces)))}"/>
  </asset>
  <worldbody>
    <geom name="hand" type="mesh" mesh="hand" material="skin" contype="0" conaffinity="0"/>
{world}  </worldbody>
</mujoco>
"""


def _skin_scene_xml(rig: MeshRig, side: str, mount: CameraMount, w: int, h: int,
                    holding: bool = False) -> tuple[str, list[int]]:
    """The silhouette scene with the rig as a MuJoCo ``<skin>`` on mocap bodies.

    Returns the document and the rig bones that carry weights, in the order
    of the mocap bodies ``bone<k>``.  A left hand's skin is the mirrored rest mesh.
    With `holding`, also a mocap body ``held`` with a cylinder of material ``held``
    (placed and sized by :meth:`MeshHandRenderer.mask_holding`).
    """
    from ..render import scene_parts

    visual, world = scene_parts(mount, side, True, w, h)
    v, f = rig.vertices, rig.faces
    if side == "left":
        v, f = v @ _MIRROR, f[:, ::-1]
    bones, elems = [], []
    for k in range(len(rig.bone_names)):
        vid = np.nonzero((rig.bone_index == k) & (rig.bone_weight > 0))
        if len(vid[0]) == 0:
            continue
        bones.append(k)
        elems.append(f'      <bone body="bone{k}" bindpos="0 0 0" bindquat="1 0 0 0" '
                     f'vertid="{" ".join(map(str, vid[0]))}" '
                     f'vertweight="{_fmt(rig.bone_weight[vid])}"/>')
    bodies = "".join(f'    <body name="bone{k}" mocap="true"/>\n' for k in bones)
    held = ""
    if holding:
        # out of view behind the camera until placed (a far body would widen the model's
        # extent, and the near clipping plane with it)
        bodies += ('    <body name="held" mocap="true" pos="0 0 0.5"><geom name="held" '
                   'type="cylinder" '
                   'size="0.01 0.01" material="held" contype="0" conaffinity="0"/></body>\n')
        held = ('    <material name="held" rgba="1 1 1 1" emission="1" specular="0" '
                'shininess="0"/>\n')
    xml = f"""<mujoco model="handsynth_mesh_hand_{side}">
{visual}  <asset>
    <material name="skin" rgba="1 1 1 1" emission="1" specular="0" shininess="0"/>
{held}  </asset>
  <worldbody>
{bodies}{world}  </worldbody>
  <deformable>
    <skin name="hand" material="skin" vertex="{_fmt(v)}" face="{" ".join(map(str, np.ravel(f)))}">
{chr(10).join(elems)}
    </skin>
  </deformable>
</mujoco>
"""
    return xml, bones


def _palm_bones(names: tuple[str, ...]) -> list[int]:
    """The bones whose vertices make the palm, rows of `names` (:attr:`MeshRig.bone_names`).

    The wrist and the finger metacarpals; in a rig without finger metacarpal
    bones (Mixamo, Unity, MANO), the wrist and the bones handsynth does not pose.
    """
    meta = [n for n in names if n.endswith("metacarpal") and not n.startswith("thumb")]
    return [k for k, n in enumerate(names)
            if n == "wrist" or n in meta or (not meta and n.startswith("other:"))]


class MeshHandRenderer(GLContextOwner, MaskMaker):
    """Boolean masks of a realistic skinned hand mesh as the device camera sees it.

    The same interface as :class:`~handsynth.render.SilhouetteRenderer`, for a
    hand geometry the databases were not built from (module docstring: how
    the mesh is posed with handsynth's joint angles).  Rendering is
    deterministic.

    Parameters
    ----------
    mount : CameraMount, optional
        The paper's device by default.
    side : {"right", "left"}, keyword-only
        A left hand is the mirror image of the right (same joint senses).
    width_px, height_px : int, keyword-only
        Render size (the mount's 720x480 by default); the horizontal field of
        view is kept and pixels are square.
    path : str or path-like, keyword-only
        A rigged hand ``.gltf``; :func:`default_mesh_path` by default.
    scale : float, keyword-only
        The hand made larger or smaller about its wrist joint
        (:meth:`MeshRig.scaled`); 1 (the default) as in the file.
    holding : bool, keyword-only
        Make room in the scene for an object in the hand (:meth:`mask_holding`).

    Raises
    ------
    InvalidInputError
        A missing or malformed mesh file.
    InvalidCameraError
        A bad `side` or image size.
    RenderError
        No off-screen GL context.

    Examples
    --------
    >>> r = MeshHandRenderer(width_px=180, height_px=120)
    >>> r.mask(named_pose("fist")).shape
    (120, 180)
    >>> round(r.hand_length_mm)  # wrist node to the middle fingertip, open hand
    216
    """

    def __init__(self, mount: CameraMount | None = None, *, side: str = "right",
                 width_px: int | None = None, height_px: int | None = None,
                 path: str | os.PathLike | None = None, scale: float = 1.0,
                 holding: bool = False) -> None:
        check_side(side, error=InvalidCameraError)
        mount = as_mount(mount)
        ensure_backend()
        import mujoco

        from ..render import offscreen_renderer

        self._mj = mujoco
        self.mount = mount
        self.side = side
        self.width_px, self.height_px = self.mount.size(width_px, height_px)
        self.rig = load_mesh_rig(path)
        if scale != 1.0:
            self.rig = self.rig.scaled(scale)
        self.path = self.rig.path
        self._poser = _Poser(self.rig)
        self._faces = self.rig.faces if side == "right" else self.rig.faces[:, ::-1]
        if not isinstance(holding, bool):
            raise InvalidCameraError(f"holding must be True or False, got {holding!r}")
        xml, self._bones = _skin_scene_xml(self.rig, side, self.mount, self.width_px,
                                           self.height_px, holding)
        try:
            self.model = mujoco.MjModel.from_xml_string(xml)
        except ValueError as exc:
            raise RenderError(f"MuJoCo could not compile the mesh hand scene: {exc}") from None
        self.data = mujoco.MjData(self.model)
        mujoco.mj_forward(self.model, self.data)  # also places the camera (mj_camlight)
        self._mocap = np.array([self.model.body_mocapid[self.model.body(f"bone{k}").id]
                                for k in self._bones], dtype=np.intp)
        self._quat = np.empty(4)
        self._held = self.model.body_mocapid[self.model.body("held").id] if holding else None
        self._renderer = offscreen_renderer(self.model, self.width_px, self.height_px)
        self._cam = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_CAMERA, "device")
        self._buf = np.empty((self.height_px, self.width_px, 3), dtype=np.uint8)

    # -- geometry -------------------------------------------------------------------
    def _posed(self, a_deg: np.ndarray) -> np.ndarray:
        v = self._poser.vertices(a_deg)
        return v if self.side == "right" else v @ _MIRROR

    def vertices(self, angles) -> np.ndarray:
        """Posed mesh vertices in the hand frame.

        Parameters
        ----------
        angles : array_like, shape (20,), or mapping of str to float
            Degrees, canonical order.

        Returns
        -------
        ndarray, shape (V, 3), float64
            Metres.
        """
        return self._posed(self._one(angles))

    @property
    def faces(self) -> np.ndarray:
        """Triangles (F, 3), int32, indices into :meth:`vertices`."""
        return self._faces.copy()

    def keypoints(self, angles=None) -> np.ndarray:
        """The 21 keypoints of the posed mesh hand in the hand frame, metres.

        Joint centres are the rig's joint nodes; a fingertip is the skin's end
        along the distal bone.  Order as
        :meth:`handsynth.models.HandModel.keypoints`: wrist, thumb CMC, MCP,
        IP, tip, then MCP, PIP, DIP, tip of index, middle, ring, little.

        Parameters
        ----------
        angles : array_like, shape (20,), or mapping, optional
            Degrees; the open hand (all zero) by default.

        Returns
        -------
        ndarray, shape (21, 3), float64
        """
        a = np.zeros(len(JOINT_NAMES)) if angles is None else self._one(angles)
        kp = self._poser.keypoints(a)
        return kp if self.side == "right" else kp @ _MIRROR

    @property
    def hand_length_mm(self) -> float:
        """Wrist node to the middle fingertip in the open pose, mm (handsynth: 187)."""
        kp = self.keypoints()
        return float(np.linalg.norm(kp[12] - kp[0]) * 1e3)

    def measurements(self):
        """The hand's measurements for database selection (formulas (1)-(4)).

        Measured on the open pose as :func:`handsynth.estimate.model_measurements`
        measures the model: lengths between keypoints; a segment's width is the
        breadth of the mesh's plane section at mid-segment across the
        segment's flexion axis (as seen from the back of the hand); ``P_width``
        the breadth of the palm without thumb and fingers (vertices mostly on
        the wrist and the finger metacarpals; in a rig without finger
        metacarpal bones, on the wrist and the bones handsynth does not
        pose), seen from the back of the hand, at the height midway between
        the thumb CMC and the mean of the MCPs.

        Returns
        -------
        HandMeasurements
            Millimetres.
        """
        from ..models import SEGMENTS, HandMeasurements, hull_width_at

        rig = self.rig
        a0 = np.zeros(len(JOINT_NAMES))
        kp = self._poser.keypoints(a0) * 1e3
        v = self._poser.vertices(a0) * 1e3
        frames, _ = self._poser._bone_poses(a0)
        chains = {"thumb": [2, 3, 4], **{f: [5 + 4 * k + i for i in range(4)]
                                          for k, f in enumerate(FINGERS[1:])}}
        bone_of = {("thumb", "proximal"): "thumb_proximal", ("thumb", "distal"): "thumb_distal"}
        for f in FINGERS[1:]:
            bone_of.update({(f, "proximal"): f"{f}_proximal", (f, "middle"): f"{f}_intermediate",
                            (f, "distal"): f"{f}_distal"})
        dom = rig.bone_index[np.arange(len(v)), np.argmax(rig.bone_weight, axis=1)]
        lengths, widths = [], []
        seg_rows = {f: list(itertools.pairwise(r)) for f, r in chains.items()}
        counters = dict.fromkeys(FINGERS, 0)
        for f, seg in SEGMENTS:
            ra, rb = seg_rows[f][counters[f]]
            counters[f] += 1
            pa, pb = kp[ra], kp[rb]
            length = float(np.linalg.norm(pb - pa))
            lengths.append(length)
            digit = [rig.bone(n) for n in rig.bone_names if n.startswith(f + "_")
                     and not n.endswith("metacarpal")]
            faces = rig.faces[np.all(np.isin(dom[rig.faces], digit), axis=1)]
            o = 0.5 * (pa + pb)
            ydir = (pb - pa) / length
            pts = _plane_section(v, faces, o, ydir)
            pts = pts[np.linalg.norm(pts - o, axis=1) < 0.9 * length]
            if len(pts) < 3:
                raise InvalidInputError(f"mesh hand: no surface at the middle of {f} {seg}")
            across = frames[bone_of[(f, seg)]][:, 0]
            s = (pts - o) @ across
            widths.append(float(s.max() - s.min()))
        palm = v[np.isin(dom, _palm_bones(rig.bone_names)), :2]
        cmc = kp[1]
        y_mid = 0.5 * (cmc[1] + kp[[5, 9, 13, 17], 1].mean())
        return HandMeasurements(
            L=lengths, W=widths, P_width=hull_width_at(palm, y_mid),
            P_height=float(kp[9, 1] - kp[0, 1]), T_width=float(abs(kp[9, 0] - cmc[0])),
            T_height=float(cmc[1] - kp[0, 1]),
        )

    # -- rendering ------------------------------------------------------------------
    def _draw(self, pose: np.ndarray, out: np.ndarray) -> None:
        out[...] = self._render(pose)

    def render_rgb(self, angles, *, camera: str = "device") -> np.ndarray:
        """A lit colour picture of the posed mesh hand (a fresh model per call).

        Parameters
        ----------
        angles : array_like, shape (20,), or mapping
            Degrees, canonical order.
        camera : {"device", "side", "top"}, keyword-only
            As :func:`handsynth.render.render_rgb`.

        Returns
        -------
        ndarray, shape (height_px, width_px, 3), uint8
            RGB.
        """
        if camera not in ("device", "side", "top"):
            raise InvalidCameraError(f"camera must be 'device', 'side' or 'top', got {camera!r}")
        from ..render import offscreen_renderer

        v = self._posed(self._one(angles))
        xml = _scene_xml(v, self._faces, self.mount, self.side, False, self.width_px, self.height_px)
        model = self._mj.MjModel.from_xml_string(xml)
        data = self._mj.MjData(model)
        self._mj.mj_forward(model, data)
        r = offscreen_renderer(model, self.width_px, self.height_px)
        try:
            r.update_scene(data, camera=camera)
            return r.render().copy()
        finally:
            r.close()

    def mask_holding(self, angles, held: HeldObject) -> np.ndarray:
        """The device's view of the posed hand holding an object.

        Parameters
        ----------
        angles : array_like, shape (20,), or mapping
            Degrees, canonical order.
        held : HeldObject
            The object, in this renderer's hand frame (as :meth:`keypoints` gives
            it, so a left hand's x is the mirror of a right hand's); a bright one
            joins the hand's pixels, a dark one only hides what lies behind it (as
            the fingertips behind a cup).

        Returns
        -------
        ndarray, shape (height_px, width_px), bool
            True where the hand, or a bright object, is seen.

        Raises
        ------
        InvalidCameraError
            A renderer made without ``holding=True``; `held` not a
            :class:`HeldObject`.
        """
        if self._held is None:
            raise InvalidCameraError("mask_holding needs a MeshHandRenderer made with "
                                     "holding=True")
        if not isinstance(held, HeldObject):
            raise InvalidCameraError(f"held must be a HeldObject, got {type(held).__name__}")
        centre = np.asarray(held.centre_mm) * 1e-3
        axis_quat = held.quat()
        model, g = self.model, self.model.geom("held").id
        model.geom_size[g, :2] = held.radius_mm * 1e-3, held.length_mm * 0.5e-3
        model.mat_rgba[model.geom_matid[g], :3] = 1.0 if held.bright else 0.0
        self.data.mocap_pos[self._held] = centre
        self.data.mocap_quat[self._held] = axis_quat
        try:
            return self._render(self._one(angles)).copy()
        finally:
            self.data.mocap_pos[self._held] = (0.0, 0.0, 0.5)  # out of view again

    def _one(self, angles) -> np.ndarray:
        a = as_angles(angles)
        if a.ndim != 1:
            raise InvalidPoseError(f"angles must be one pose of shape (20,), got {a.shape}")
        return a

    def _render(self, a_deg: np.ndarray) -> np.ndarray:
        if self._renderer is None:
            raise RenderError("this MeshHandRenderer is closed")
        mats = self._poser.bone_transforms(a_deg)[self._bones]
        if self.side == "left":
            mats = _MIRROR @ mats
            mats[:, :, :3] = mats[:, :, :3] @ _MIRROR
        mj, data = self._mj, self.data
        data.mocap_pos[self._mocap] = mats[:, :, 3]
        for i, m in zip(self._mocap, mats):
            mj.mju_mat2Quat(self._quat, np.ascontiguousarray(m[:, :3]).ravel())
            data.mocap_quat[i] = self._quat
        mj.mj_kinematics(self.model, data)
        # MuJoCo skins the mesh (linear blend) on the CPU and uploads it in mjr_render
        self._renderer.update_scene(data, camera=self._cam)
        self._renderer.render(out=self._buf)
        return self._buf[:, :, 0] > 127



def mesh_hand_sheet(poses=("open", "spread", "fist", "point", "pinch", "grasp"),
                    mount: CameraMount | None = None, *, tile_width_px: int = 240,
                    path: str | os.PathLike | None = None) -> tuple[np.ndarray, dict]:
    """The mesh hand next to handsynth's standard model hand, from the device camera.

    One column per pose; rows: the lit mesh hand, the lit model hand, and
    their masks overlaid (mesh red, model green, both yellow) labelled with
    the IoU of the two preprocessed 64x64 silhouettes
    (:func:`handsynth.render.preprocess`) of full-size (mount-size) masks.

    Parameters
    ----------
    poses : sequence of str
        Names of :data:`handsynth.models.NAMED_POSES`.
    mount : CameraMount, optional
        The paper's device by default.
    tile_width_px : int, keyword-only
    path : str or path-like, keyword-only
        The mesh hand (:func:`default_mesh_path` by default).

    Returns
    -------
    sheet : ndarray, shape (H, W, 3), uint8
        RGB.
    iou : dict of str to float
        Silhouette IoU per pose.
    """
    import cv2

    from ..models import named_pose
    from ..render import SilhouetteRenderer, label_image, preprocess, render_rgb

    mount = as_mount(mount)
    tw = tile_width_px
    th = round(tw * mount.height_px / mount.width_px)
    angles = np.stack([named_pose(p) for p in poses])
    with MeshHandRenderer(mount, path=path) as mesh, SilhouetteRenderer(mount=mount) as model:
        full_mesh, full_model = mesh.masks(angles), model.masks(angles)
    iou = {}
    for p, a, b in zip(poses, full_mesh, full_model):
        sa, sb = preprocess(a, mount), preprocess(b, mount)
        iou[p] = float((sa & sb).sum() / max(int((sa | sb).sum()), 1))
    rows: list[list[np.ndarray]] = [[], [], []]
    with MeshHandRenderer(mount, width_px=tw, height_px=th, path=path) as mesh, \
            SilhouetteRenderer(mount=mount, width_px=tw, height_px=th) as model:
        for p, a in zip(poses, angles):
            rows[0].append(label_image(mesh.render_rgb(a), f"mesh hand: {p}"))
            rows[1].append(label_image(render_rgb(a, None, mount, width_px=tw, height_px=th),
                                  f"model hand: {p}"))
            over = np.zeros((th, tw, 3), np.uint8)
            over[..., 0] = mesh.mask(a) * 255
            over[..., 1] = model.mask(a) * 255
            rows[2].append(label_image(over, f"{p}: IoU {iou[p]:.2f}"))
    sheet = np.vstack([np.hstack(r) for r in rows])
    sheet = cv2.copyMakeBorder(sheet, 2, 2, 2, 2, cv2.BORDER_CONSTANT, value=(255, 255, 255))
    return sheet, iou
