"""Camera, off-screen renderer and the preprocessing shared by database and live frames."""

from ._camera import CameraMount
from ._gl import backend, ensure_backend
from ._mesh_hand import MeshHandRenderer
from ._preprocess import (
    binarize,
    check_frame,
    crop_resize,
    largest_component,
    preprocess,
    preprocess_reference,
    wrist_cut_keep,
)
from ._raster import SilhouetteRasterizer
from ._renderer import SilhouetteRenderer, render_rgb
from ._sheet import contact_sheet

__all__ = [
    "CameraMount",
    "MeshHandRenderer",
    "SilhouetteRasterizer",
    "SilhouetteRenderer",
    "backend",
    "binarize",
    "check_frame",
    "contact_sheet",
    "crop_resize",
    "ensure_backend",
    "largest_component",
    "preprocess",
    "preprocess_reference",
    "render_rgb",
    "wrist_cut_keep",
]
