"""Realistic skinned hands (glTF) posed by canonical angles, for testing the camera estimator.

The databases are built from handsynth's own parametric hand; these hands
are not, so looking up their frames measures what a real user's hand would
meet.  Two hands ship with the package, with their licences
(:data:`TEST_HANDS`, :func:`shipped_hand_path`): the Godot XR Tools hand
(CC0) and the MRTK3 hand (BSD-3-Clause / MIT).  Any rigged glTF 2.0 hand
with OpenXR joint names loads the same way (:func:`load_mesh_rig`).
"""

from ._gltf import (
    TEST_HANDS,
    MeshHandRenderer,
    MeshRig,
    default_mesh_path,
    load_mesh_rig,
    mesh_hand_sheet,
    shipped_hand_path,
)

__all__ = [
    "TEST_HANDS",
    "MeshHandRenderer",
    "MeshRig",
    "default_mesh_path",
    "load_mesh_rig",
    "mesh_hand_sheet",
    "shipped_hand_path",
]
