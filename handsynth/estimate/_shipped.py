"""Learnt estimators shipped with handsynth: the default ensemble's perceptrons.

The default ensemble's perceptrons (:data:`LEARNED_ENSEMBLE`) learn from two
16,000-hand learning sets, each 18-20 min to render and 2.3 GB to keep, and
took 18-28 min each to learn on two cores.  A perceptron's file is 3 MB, so
the three, and the seed-1 perceptron that the relaxed-rest learning set adds
(:func:`~handsynth.estimate.shipped_perceptrons`), are learnt once and
shipped in ``handsynth/estimate/shipped/``, under the names
:func:`~handsynth.estimate.learned_estimator` gives their cache files.  A
first run then renders only the learning set of the per-digit estimator
(whose 689 MB file cannot be shipped).

``manifest.json`` lists each shipped file with its SHA-256 and the options
it was learnt with, and names a *fingerprint* of its learning set: the first
two hands of that set (their coverage grids and angles), which depend on the
hand generator, the pose generator and the rasteriser.  A test renders them
again; when any of those changes, the shipped perceptrons no longer come from
the learning set the options name, and the test says to ship them again
(``python scripts/ship_perceptrons.py --cache DIR``).

A shipped file is used only when its name (a digest of the options, learning
set, mount and side) is asked for and its bytes match the manifest;
otherwise the estimator is learnt as before.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, replace
from pathlib import Path
from typing import Any

import numpy as np

from .._io import atomic_open
from ..db import LearningSetOptions, render_learning_set
from ..errors import DatabaseError
from ..render import CameraMount, as_mount

__all__ = ["SHIPPED_FOLDER", "fingerprint", "fingerprint_differs", "read_manifest", "ship",
           "shipped_path"]

#: Where the shipped files and their manifest live.
SHIPPED_FOLDER = Path(__file__).parent / "shipped"

# Hands of a learning set kept as its fingerprint.
_FINGERPRINT_HANDS = 2

_MANIFEST = "manifest.json"
_FINGERPRINT_ARRAYS = ("grids", "rest_grids", "angles", "rest_angles")


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def read_manifest(folder: Path = SHIPPED_FOLDER) -> dict:
    """The manifest of `folder` (``{"files": {}}`` when there is none)."""
    try:
        return json.loads((folder / _MANIFEST).read_text())
    except FileNotFoundError:
        return {"files": {}}


def shipped_path(name: str, *, folder: Path = SHIPPED_FOLDER) -> Path | None:
    """The shipped file named `name`, or None when none is shipped or its bytes differ.

    Parameters
    ----------
    name : str
        A cache file's name (``learned_<kind>_<digest>.npz``).
    folder : pathlib.Path, keyword-only
        Where to look (the package's folder by default).
    """
    entry = read_manifest(folder)["files"].get(name)
    path = folder / name
    if entry is None or not path.is_file() or _sha256(path) != entry["sha256"]:
        return None
    return path


def fingerprint(data: LearningSetOptions, mount: CameraMount, side: str) -> dict[str, np.ndarray]:
    """The first two hands of the learning set `data`, rendered.

    The hands of a set are drawn one after the other from one generator, so
    its first hands do not depend on how many it holds.

    Returns
    -------
    dict of str to ndarray
        ``grids`` (hands * poses, cells) uint8, ``rest_grids`` (hands,
        cells) uint8, ``angles`` (hands * poses, 20) float32 deg,
        ``rest_angles`` (hands, 20) float32 deg.
    """
    ls = render_learning_set(replace(data, hands=_FINGERPRINT_HANDS), mount=mount, side=side)
    return {name: getattr(ls, name) for name in _FINGERPRINT_ARRAYS}


def fingerprint_differs(stored: dict, rendered: dict) -> str | None:
    """What differs between a stored fingerprint and one rendered now (None: nothing).

    Angles must agree to 1e-4 deg; grids (0-255 per cell) to a mean absolute
    difference below 0.5, so that a few cells rounded the other way on
    another machine do not count.
    """
    for name in ("angles", "rest_angles"):
        if stored[name].shape != rendered[name].shape or \
                not np.allclose(stored[name], rendered[name], rtol=0, atol=1e-4):
            return f"the {name} differ (the hand or pose generator changed)"
    for name in ("grids", "rest_grids"):
        if stored[name].shape != rendered[name].shape:
            return f"the {name} have shape {rendered[name].shape}, shipped {stored[name].shape}"
        diff = float(np.mean(np.abs(stored[name].astype(np.int16) - rendered[name])))
        if diff >= 0.5:
            return f"the {name} differ by {diff:.2f} levels on average (the rasteriser changed)"
    return None


def ship(sources: dict[str, tuple[Path, LearningSetOptions]], *, mount: CameraMount | None = None,
         side: str = "right", folder: Path = SHIPPED_FOLDER) -> dict:
    """Copy learnt files into `folder` with their fingerprints and write its manifest.

    Parameters
    ----------
    sources : dict of str to (pathlib.Path, LearningSetOptions)
        Per name to ship under, the learnt file and the learning set it was
        learnt from.
    mount, side
        Of every source (the paper's mount by default).
    folder : pathlib.Path, keyword-only

    Returns
    -------
    dict
        The manifest written.  Files of `folder` it no longer names are removed.
    """
    mount = as_mount(mount)
    folder.mkdir(parents=True, exist_ok=True)
    files: dict[str, dict] = {}
    prints: set[str] = set()  # fingerprint files written
    for name, (src, data) in sources.items():
        content = Path(src).read_bytes()
        with atomic_open(folder / name, "wb", what="shipped estimator", error=DatabaseError) as f:
            f.write(content)
        fp = f"fingerprint_{data.digest()}.npz"
        if fp not in prints:
            prints.add(fp)
            arrays: dict[str, Any] = fingerprint(data, mount, side)  # as savez's **kwds
            with atomic_open(folder / fp, "wb", what="fingerprint", error=DatabaseError) as f:
                np.savez_compressed(f, **arrays)
        files[name] = {"sha256": hashlib.sha256(content).hexdigest(), "bytes": len(content),
                       "learning_set": asdict(data), "fingerprint": fp}
    text = json.dumps({"format": 1, "mount": mount.as_dict(), "side": side, "files": files},
                      indent=1, sort_keys=True)
    with atomic_open(folder / _MANIFEST, "w", what="manifest", error=DatabaseError) as f:
        f.write(text + "\n")
    keep = {_MANIFEST, *files, *prints}
    for path in folder.iterdir():  # perceptrons and fingerprints of earlier ships; not the rest
        if path.is_file() and path.name not in keep and \
                path.name.startswith(("learned_", "fingerprint_")):
            path.unlink()
    return json.loads(text)
