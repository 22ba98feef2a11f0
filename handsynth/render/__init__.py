"""Camera, off-screen renderer and the preprocessing shared by database and live frames.

Besides the renderers, the pieces another renderer needs to draw into the
same scene are public: :class:`GLContextOwner` and :class:`MaskMaker` (the
GL context and the mask interface of :class:`SilhouetteRenderer`),
:func:`offscreen_renderer`, :func:`scene_parts` and :func:`label_image`.

Beyond the paper: :func:`coverage` (the fixed-frame grid of the learned
estimator), :func:`fit_skin_colour` and :func:`skin_mask` (the hand told
from an ordinary background by the colour of the user's skin) and
:class:`VariedRasterizer` with :class:`HandVariation` and :class:`MountVariation`
(model hands beyond the four ratios, a moved device), and :class:`LensCorrection`
with :func:`read_intrinsics` (a real camera's frames remapped to the device's pinhole view).
"""

from .._gl import backend, ensure_backend
from ._calibration_files import read_intrinsics
from ._camera import CameraMount, as_mount
from ._coverage import DEFAULT_CELLS, coverage
from ._io import read_image, write_png
from ._lens import CameraIntrinsics, LensCorrection
from ._masks import MaskMaker
from ._preprocess import (
    MIN_CONTRAST,
    binarize,
    check_frame,
    crop_resize,
    largest_component,
    preprocess,
    preprocess_reference,
    wrist_cut_keep,
)
from ._raster import SilhouetteRasterizer
from ._renderer import (
    GLContextOwner,
    SilhouetteRenderer,
    offscreen_renderer,
    render_rgb,
)
from ._scene import scene_include_mjcf, scene_mjcf, scene_parts, standard_assets
from ._segment import (
    WORK_WIDTH_PX,
    SkinColour,
    brightness_overlap,
    fit_skin_colour,
    palm_region,
    skin_mask,
)
from ._sheet import contact_sheet, label_image
from ._varied import HandVariation, MountVariation, VariedRasterizer

__all__ = [
    "DEFAULT_CELLS",
    "MIN_CONTRAST",
    "WORK_WIDTH_PX",
    "CameraIntrinsics",
    "CameraMount",
    "GLContextOwner",
    "HandVariation",
    "LensCorrection",
    "MaskMaker",
    "MountVariation",
    "SilhouetteRasterizer",
    "SilhouetteRenderer",
    "SkinColour",
    "VariedRasterizer",
    "as_mount",
    "backend",
    "binarize",
    "brightness_overlap",
    "check_frame",
    "contact_sheet",
    "coverage",
    "crop_resize",
    "ensure_backend",
    "fit_skin_colour",
    "label_image",
    "largest_component",
    "offscreen_renderer",
    "palm_region",
    "preprocess",
    "preprocess_reference",
    "read_image",
    "read_intrinsics",
    "render_rgb",
    "scene_include_mjcf",
    "scene_mjcf",
    "scene_parts",
    "skin_mask",
    "standard_assets",
    "wrist_cut_keep",
    "write_png",
]
