"""Realistic skinned hands (glTF) posed by canonical angles, for testing the camera estimator.

The databases are built from handsynth's own parametric hand; these hands
are not, so looking up their frames measures what a real user's hand would
meet.  Three hands ship with the package, with their licences
(:data:`TEST_HANDS`, :func:`shipped_hand_path`): the Godot XR Tools hand
(CC0), the MRTK3 hand (BSD-3-Clause / MIT) and the WebXR generic hand (MIT);
the protocol tests on the first two unless told otherwise
(:data:`PROTOCOL_HANDS`).  Any rigged glTF 2.0 hand whose joints are named as in OpenXR, WebXR, Mixamo,
Unity or VRM humanoids or MANO loads the same way (:func:`load_mesh_rig`).
"""

from ._gltf import (
    PROTOCOL_HANDS,
    TEST_HANDS,
    MeshHandRenderer,
    MeshRig,
    default_mesh_path,
    load_mesh_rig,
    mesh_hand_sheet,
    shipped_hand_path,
)
from ._held import HeldObject, grasped_cylinder

__all__ = [
    "PROTOCOL_HANDS",
    "TEST_HANDS",
    "HeldObject",
    "MeshHandRenderer",
    "MeshRig",
    "default_mesh_path",
    "grasped_cylinder",
    "load_mesh_rig",
    "mesh_hand_sheet",
    "shipped_hand_path",
]
