"""Options of the camera evaluation, its conditions, targets and the paper's figures."""

from __future__ import annotations

import os
from dataclasses import dataclass, fields
from pathlib import Path

from .._checks import check_integer, check_side
from .._cores import usable_cores
from ..db import check_render_size
from ..errors import InvalidInputError
from ..models import PAPER_SIZE, HandShape
from ..render import CameraMount

__all__ = ["CONDITIONS", "MAX_FRAMES", "MAX_HANDS", "EvalOptions"]


#: Conditions of the experiment, in report order (module docstring).
CONDITIONS: tuple[str, ...] = ("standard", "selected", "selected_none", "personal",
                                "calibrated", "own_shape")
_CONDITION_TEXT = {
    "standard": "standard database",
    "selected": "selected database (formulas (1)-(4), palm-width normalisation, the paper's)",
    "selected_none": "selected database (formulas (1)-(4), no normalisation)",
    "personal": "database built for the hand's shape as measured on a photo",
    "calibrated": ("grid database that fits the hand's open-hand frame best, searched with the "
                   "ignore mask that frame gives (grown by {dilation} px); the pose is the mean "
                   "of the entries near the best, weighted exp(-(X - X_min) / {temperature:g} "
                   "px) (beyond the paper)"),
    "own_shape": "frames of the selected grid shape in its own database (diagnostic floor)",
}
_NORMALIZE = {"selected": "palm_width", "selected_none": "none"}
_HANDS = ("model", "mesh")
_MOUNTS = {"paper": CameraMount.paper, "whole-hand": CameraMount.whole_hand}
SCHEMA = "handsynth.eval/1"

#: Growth of the ignore mask of the ``calibrated`` condition, pixels (4-neighbour steps).
CALIBRATION_DILATION_PX = 1
#: ``T`` of the ``calibrated`` condition's weighted mean, pixels (the library's default).
CALIBRATION_TEMPERATURE_PX = 1.0

#: A joint counts as moving in a frame when its true angle is farther than this from 0, degrees.
MOVING_DEG = 1.0

#: Targets of issue 4, degrees, per test-hand kind: off-grid model hands, and the realistic
#: mesh hand; checked on the ``selected`` and the ``personal`` condition.
TARGETS = {
    "model": {"index_pip_abs_mean_deg": 1.0, "index_pip_sd_deg": 8.0, "thumb_cmc_sd_deg": 6.0},
    "mesh": {"index_pip_sd_deg": 12.0},
}
#: Conditions whose figures are checked against :data:`TARGETS`.
TARGET_CONDITIONS = ("selected", "personal", "calibrated")
#: The paper's figures (SPEC.md section 1 table), mean and s.d. in degrees.
PAPER = {
    "standard": {"index_pip_flex": (-3.66, 18.41), "thumb_cmc_flex": (3.76, 11.76)},
    "selected": {"index_pip_flex": (-0.86, 17.67), "thumb_cmc_flex": (0.98, 11.56)},
}


#: The ``handsynth eval`` option of each field, named in messages beside the field.
_FLAGS = {"n_hands": "--hands", "frames_per_hand": "--frames", "count": "--count",
          "seed": "--seed", "workers": "--workers", "render_size": "--render-size",
          "frame_size": "--frame-size", "db_folder": "--db", "pose_sets": "--pose-sets",
          "db_pose_set": "--db-pose-set"}


def _field(name: str) -> str:
    flag = _FLAGS.get(name)
    return f"EvalOptions.{name}" + (f" ({flag})" if flag else "")


#: Most test hands and frames per hand and pose set (every frame of a hand is held in memory,
#: 0.35 MB at 720x480: 10,000 frames are 3.5 GB).
MAX_HANDS = 1000
MAX_FRAMES = 10_000


def _check_int(value, name: str, lo: int, hi: int | None = None) -> int:
    return check_integer(value, _field(name), minimum=lo, maximum=hi)


def _check_size(value, name: str) -> tuple[int, int]:
    return check_render_size(value, _field(name))


@dataclass(frozen=True)
class EvalOptions:
    """What :func:`evaluate` runs.

    Parameters
    ----------
    db_folder : str or os.PathLike
        Folder of the databases (``<shape.name>.h5``); the ones needed are
        built there on demand and reused when they verify.
    n_hands : int
        Test hands, 1 to :data:`MAX_HANDS` (random off-grid ratios for ``hand="model"``; for
        ``hand="mesh"`` the one mesh, each "hand" with its own poses).
    frames_per_hand : int
        Test frames per hand *and per pose set*, 1 to :data:`MAX_FRAMES`.
    pose_sets : tuple of str
        Pose sets of the test frames (``"paper"``, ``"natural"``).
    seed : int
        Seed of the test hands' ratios and poses (databases use `db_seed`).
    ratio_margin : float
        How far beyond the outer grid levels the ratios may go, in grid steps
        (module docstring); 0 keeps them within the grid's range.
    hand_shapes : tuple of HandShape, optional
        Explicit test hands (then `n_hands` is their number); random otherwise.
    hand : {"model", "mesh"}
        Test-hand renderer; ``"mesh"`` renders :mod:`handsynth.testhands`.
    conditions : tuple of str
        Subset of :data:`CONDITIONS`, evaluated in that order.
    count : int
        Entries per database (20,448 in the paper).
    db_pose_set : str
        Pose set the databases are built from (the paper's).
    db_seed : int
        Seed of the databases' pose set.
    render_size : (int, int), optional
        (width, height) of database renders; the library's default if None.
    mount : {"paper", "whole-hand"}
        Camera mount preset of databases and test frames alike.
    frame_size : (int, int)
        (width, height) of the test frames: the device's 720x480 by default,
        as a live camera delivers them.
    workers : int
        Worker processes for building missing databases, at most the CPU
        cores this process may use (each renders on one core).
    side : {"right", "left"}
    ties : {"mean", "first"}
        What the lookups report when several entries match equally well
        (:class:`PoseLookup`'s `ties`).
    photo_mm_per_px : float
        Scale of the top-down photos that measure model hands for the
        ``personal`` condition, mm per pixel (0.25: a 300 mm field of 1,200
        pixels, well within a phone camera's).

    Raises
    ------
    InvalidInputError
        A field with an unusable value (the message names it), or
        ``hand="mesh"`` while the mesh-hand module is not installed.
    """

    db_folder: str | os.PathLike
    n_hands: int = 8
    frames_per_hand: int = 100
    pose_sets: tuple[str, ...] = ("paper", "natural")
    seed: int = 0
    ratio_margin: float = 0.5
    hand_shapes: tuple[HandShape, ...] | None = None
    hand: str = "model"
    conditions: tuple[str, ...] = CONDITIONS
    count: int = PAPER_SIZE
    db_pose_set: str = "paper"
    db_seed: int = 0
    render_size: tuple[int, int] | None = None
    mount: str = "paper"
    frame_size: tuple[int, int] = (720, 480)
    workers: int = 1
    side: str = "right"
    ties: str = "mean"
    photo_mm_per_px: float = 0.25

    def __post_init__(self) -> None:
        from ..models import POSE_SETS

        try:
            object.__setattr__(self, "db_folder", Path(self.db_folder))
        except TypeError:
            raise InvalidInputError(
                f"{_field('db_folder')} must be a folder path, got {self.db_folder!r}") from None
        for name, lo, hi in (("n_hands", 1, MAX_HANDS), ("frames_per_hand", 1, MAX_FRAMES),
                             ("seed", 0, None), ("count", 1, None), ("db_seed", 0, None),
                             ("workers", 1, usable_cores())):
            object.__setattr__(self, name, _check_int(getattr(self, name), name, lo, hi))
        sets = (self.pose_sets,) if isinstance(self.pose_sets, str) else tuple(self.pose_sets)
        if not sets or any(s not in POSE_SETS for s in sets) or len(set(sets)) != len(sets):
            raise InvalidInputError(
                f"{_field('pose_sets')} must be distinct names from {sorted(POSE_SETS)}, "
                f"got {self.pose_sets!r}")
        object.__setattr__(self, "pose_sets", sets)
        if self.db_pose_set not in POSE_SETS:
            raise InvalidInputError(f"{_field('db_pose_set')} must be one of {sorted(POSE_SETS)}, "
                                    f"got {self.db_pose_set!r}")
        try:
            margin = float(self.ratio_margin)
        except (TypeError, ValueError):
            margin = float("nan")
        if not 0.0 <= margin <= 4.0:
            raise InvalidInputError(
                f"EvalOptions.ratio_margin must be a number of grid steps in [0, 4], "
                f"got {self.ratio_margin!r}")
        object.__setattr__(self, "ratio_margin", margin)
        if self.hand_shapes is not None:
            shapes = tuple(self.hand_shapes)
            if not shapes or not all(isinstance(s, HandShape) for s in shapes):
                raise InvalidInputError(
                    f"EvalOptions.hand_shapes must be HandShape objects, got {self.hand_shapes!r}")
            object.__setattr__(self, "hand_shapes", shapes)
            object.__setattr__(self, "n_hands", len(shapes))
        if self.hand not in _HANDS:
            raise InvalidInputError(f"EvalOptions.hand must be one of {_HANDS}, got {self.hand!r}")
        if self.hand == "mesh" and self.hand_shapes is not None:
            raise InvalidInputError("EvalOptions.hand_shapes applies to hand='model' only, "
                                    "got hand='mesh' with hand_shapes")
        conds = (self.conditions,) if isinstance(self.conditions, str) else tuple(self.conditions)
        if not conds or any(c not in CONDITIONS for c in conds) or len(set(conds)) != len(conds):
            raise InvalidInputError(f"EvalOptions.conditions must be distinct names from "
                                    f"{CONDITIONS}, got {self.conditions!r}")
        object.__setattr__(self, "conditions", tuple(c for c in CONDITIONS if c in conds))
        if self.render_size is not None:
            object.__setattr__(self, "render_size", _check_size(self.render_size, "render_size"))
        object.__setattr__(self, "frame_size", _check_size(self.frame_size, "frame_size"))
        if self.mount not in _MOUNTS:
            raise InvalidInputError(
                f"EvalOptions.mount must be one of {tuple(_MOUNTS)}, got {self.mount!r}")
        check_side(self.side, name="EvalOptions.side")
        if self.ties not in ("mean", "first"):
            raise InvalidInputError(f"EvalOptions.ties must be 'mean' or 'first', got {self.ties!r}")
        try:
            scale = float(self.photo_mm_per_px)
        except (TypeError, ValueError):
            scale = float("nan")
        if not 0.05 <= scale <= 1.0:
            raise InvalidInputError("EvalOptions.photo_mm_per_px must be a scale in [0.05, 1] mm "
                                    f"per pixel, got {self.photo_mm_per_px!r}")
        object.__setattr__(self, "photo_mm_per_px", scale)

    def camera(self) -> CameraMount:
        """The :class:`CameraMount` of the `mount` preset."""
        return _MOUNTS[self.mount]()

    def as_dict(self) -> dict:
        """The options as plain JSON values."""
        out = {}
        for f in fields(self):
            v = getattr(self, f.name)
            if isinstance(v, Path):
                v = str(v)
            elif f.name == "hand_shapes" and v is not None:
                v = [s.as_dict() for s in v]
            elif isinstance(v, tuple):
                v = list(v)
            out[f.name] = v
        return out
