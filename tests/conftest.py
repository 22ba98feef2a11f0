"""Shared fixtures: headless rendering, and a small rendered database (rendered once per session)."""

from __future__ import annotations

import os

import numpy as np
import pytest

# Headless rendering for the whole suite (the library sets the same default).
if not os.environ.get("DISPLAY"):
    os.environ.setdefault("MUJOCO_GL", "egl")

from handsynth.db import database_meta, render_entries, write_database
from handsynth.models import HandShape, paper_pose_set
from handsynth.render import CameraMount

N_ENTRIES = 240
RENDER_SIZE = (180, 120)


def pytest_collection_modifyitems(items):
    """Run the tests marked slow first, so that parallel workers end together.

    The order is stable (the same on every worker, as pytest-xdist needs) and
    only moves slow tests ahead; tests do not depend on one another's order.
    """
    items.sort(key=lambda item: item.get_closest_marker("slow") is None)


@pytest.fixture(scope="session")
def read_video():
    """A function reading a video file whole: ``read_video(path) -> (frames, (width, height))``,
    its decoded BGR frames and the frame size its container states."""
    import cv2

    def read(path):
        cap = cv2.VideoCapture(str(path))
        size = (cap.get(cv2.CAP_PROP_FRAME_WIDTH), cap.get(cv2.CAP_PROP_FRAME_HEIGHT))
        frames = []
        while True:
            ok, frame = cap.read()
            if not ok:
                break
            frames.append(frame)
        cap.release()
        return frames, size

    return read

@pytest.fixture(scope="session")
def small_rows():
    """Rows of a 240-entry database of the standard hand (paper pose set)."""
    angles = paper_pose_set(N_ENTRIES, seed=1)
    return render_entries(angles, HandShape(), CameraMount(), render_size=RENDER_SIZE)


@pytest.fixture(scope="session")
def db_folder(tmp_path_factory, small_rows):
    """A folder holding the small database as ``<shape.name>.h5``."""
    folder = tmp_path_factory.mktemp("dbs")
    shape, mount = HandShape(), CameraMount()
    write_database(
        folder / f"{shape.name}.h5",
        angles=small_rows["angles"], hlac=small_rows["hlac"], sil_bits=small_rows["sil_bits"],
        ridge_bits=small_rows["ridge_bits"], ridge_area=small_rows["ridge_area"],
        keypoints=small_rows["keypoints"],
        meta=database_meta(shape, mount, side="right", pose_set="paper", count=N_ENTRIES, seed=1,
                           render_size=RENDER_SIZE),
    )
    return folder


@pytest.fixture(scope="session")
def query_rows():
    """Frames of an off-grid hand in other poses (not in the database)."""
    from handsynth.models import natural_pose_set

    angles = np.vstack([natural_pose_set(12, seed=5), paper_pose_set(12, seed=9)])
    return render_entries(angles, HandShape(length=1.03, width=1.06, palm=0.98, thumb=1.04),
                          CameraMount(), render_size=RENDER_SIZE)


def _mount_tmpfs(path, *options: str):
    import subprocess

    if os.geteuid() != 0:
        pytest.skip("needs root to mount a small tmpfs (full-disk and read-only cases)")
    path.mkdir(parents=True, exist_ok=True)
    res = subprocess.run(["mount", "-t", "tmpfs", "-o", ",".join(("size=256k",) + options),
                          "tmpfs", str(path)], capture_output=True, text=True)
    if res.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {res.stderr.strip()}")


def _unmount(path):
    import subprocess

    subprocess.run(["umount", "-l", str(path)], capture_output=True)


@pytest.fixture
def full_disk(tmp_path):
    """A 256 KiB tmpfs: a disk that fills up (skipped unless running as root)."""
    path = tmp_path / "small_disk"
    _mount_tmpfs(path)
    yield path
    _unmount(path)


@pytest.fixture
def read_only_folder(tmp_path):
    """An empty folder on a read-only file system (skipped unless running as root)."""
    path = tmp_path / "read_only"
    _mount_tmpfs(path, "ro")
    yield path
    _unmount(path)
