"""handsynth's own HDF5 format for recordings.

Layout (format ``"handsynth.recording"``, version 2)::

    /                attrs: format, version, joint, labels (JSON), metadata (JSON),
                            checksum, complete
    /times           (n,)        float64, s
    /positions       (n, 2, 3)   float64, m, transmitter frame
    /rotations       (n, 2, 3, 3) float64, sensor -> transmitter
    /truth/          (simulations only)
        centre_world      (n, 3)
        centre_sensor     (n, 2, 3)
        reference_centre  (2, 3)
        attrs: joint_kind

Files are made in memory and written by :func:`handsynth._io.write_bytes` (a
temporary file in the target folder, fsynced, moved into place with
:func:`os.replace`), so a reader never sees a half-written file.
Like the pose databases, a file carries a SHA-256 ``checksum`` (``"sha256:<hex>"``)
over, in this order, the format name and version, the joint, labels and
metadata strings, and the raw little-endian float64 bytes of ``times``,
``positions``, ``rotations`` and, when present, the truth arrays; the
``complete`` attribute is written last.  A file whose data do not match its
checksum (a flipped bit) is refused.  Version 1 files (no checksum) are
read with a warning.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import warnings
from pathlib import Path

import h5py
import numpy as np

from ..._checks import check_path
from ..._io import write_bytes
from ...errors import InvalidInputError, RecordingError
from ._recording import GroundTruth, Recording

__all__ = ["load_recording", "save_recording"]

_FORMAT = "handsynth.recording"
_VERSION = 2
_READABLE = (1, 2)
#: Suffixes of recording files (what :func:`~handsynth.sensors.read_recording`
#: sends to :func:`load_recording`).
SUFFIXES = (".h5", ".hdf5")


def _checksum(joint: str, labels: str, meta: str, arrays: list[np.ndarray]) -> str:
    h = hashlib.sha256()
    for text in (_FORMAT, str(_VERSION), joint, labels, meta):
        h.update(text.encode("utf-8"))
        h.update(b"\0")
    for a in arrays:
        h.update(np.ascontiguousarray(a, dtype="<f8").tobytes())
    return "sha256:" + h.hexdigest()


def _text(value, name: str, path: Path) -> str:
    """A string attribute as ``str`` (h5py gives ``str``, ``bytes`` or numpy strings)."""
    if isinstance(value, (bytes, np.bytes_)):
        try:
            return bytes(value).decode("utf-8")
        except UnicodeDecodeError:
            raise RecordingError(f"{str(path)!r}: attribute {name!r} is not UTF-8 text") from None
    if isinstance(value, (str, np.str_)):
        return str(value)
    raise RecordingError(f"{str(path)!r}: attribute {name!r} is not text (got {type(value).__name__})")


def _arrays(rec: Recording) -> list[np.ndarray]:
    out = [rec.times, rec.positions, rec.rotations]
    if rec.truth is not None:
        out += [rec.truth.centre_world, rec.truth.centre_sensor, rec.truth.reference_centre]
    return out


def save_recording(path: str | os.PathLike, recording: Recording, *, inputs=()) -> Path:
    """Write `recording` to HDF5 atomically.

    Parameters
    ----------
    path : path-like
        Target file, ending in ``.h5`` or ``.hdf5`` (any case); its
        directory must exist.
    recording : Recording

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    InvalidInputError
        `recording` is not a Recording, its metadata are not
        JSON-serialisable, or `path` has another suffix (the file would not
        be read back as HDF5 by :func:`~handsynth.sensors.read_recording`).
    """
    if not isinstance(recording, Recording):
        raise InvalidInputError(
            f"recording: expected a Recording, got {type(recording).__name__}"
        )
    path = Path(path)
    if path.suffix.lower() not in SUFFIXES:
        raise InvalidInputError(
            f"path: a recording is written as HDF5 and needs the suffix "
            f"{' or '.join(SUFFIXES)}, got {path.suffix or 'none'!r} in {str(path)!r}"
        )
    try:
        meta = json.dumps(dict(recording.metadata))
    except TypeError as exc:
        raise InvalidInputError(f"recording metadata is not JSON-serialisable: {exc}") from None
    labels = json.dumps(list(recording.labels))
    checksum = _checksum(recording.joint, labels, meta, _arrays(recording))
    # made in memory, then written whole by the atomic writer: a full disk fails in a
    # plain write, never inside the HDF5 library
    buffer = io.BytesIO()
    with h5py.File(buffer, "w") as f:
        f.attrs["format"] = _FORMAT
        f.attrs["version"] = _VERSION
        f.attrs["joint"] = recording.joint
        f.attrs["labels"] = labels
        f.attrs["metadata"] = meta
        f["times"] = recording.times
        f["positions"] = recording.positions
        f["rotations"] = recording.rotations
        if recording.truth is not None:
            g = f.create_group("truth")
            g.attrs["joint_kind"] = recording.truth.joint_kind
            g["centre_world"] = recording.truth.centre_world
            g["centre_sensor"] = recording.truth.centre_sensor
            g["reference_centre"] = recording.truth.reference_centre
        f.attrs["checksum"] = checksum
        f.attrs["complete"] = True
    return write_bytes(path, buffer.getbuffer(), what="recording", inputs=inputs)


def load_recording(path: str | os.PathLike) -> Recording:
    """Read a recording written by :func:`save_recording`.

    Parameters
    ----------
    path : str or os.PathLike
        An HDF5 file of a readable format version.

    Returns
    -------
    Recording
        With its labels, joint, metadata and, when stored, its ground truth.

    Raises
    ------
    RecordingError
        `path` not a file name (None, a number, ``""``), missing or
        unreadable file, another format or version, missing or damaged data
        (checksum), attributes that are not the text or JSON written.

    Warns
    -----
    UserWarning
        A version-1 file, which has no checksum to verify.
    """
    path = check_path(path, "path", error=RecordingError)
    try:
        f = h5py.File(path, "r")
    except (OSError, ValueError) as exc:
        raise RecordingError(f"cannot open {str(path)!r} as HDF5: {exc}") from None
    with f:
        try:
            return _load(f, path)
        except RecordingError:  # already says what is wrong (not "damaged")
            raise
        except (KeyError, ValueError, TypeError, OSError) as exc:
            raise RecordingError(f"{str(path)!r} is damaged or incomplete: {exc}") from None


def _load(f: h5py.File, path: Path) -> Recording:
    fmt = f.attrs.get("format")
    fmt = _text(fmt, "format", path) if fmt is not None else None
    if fmt != _FORMAT:
        raise RecordingError(f"{str(path)!r} is not a handsynth recording (format={fmt!r})")
    version = f.attrs.get("version", -1)
    if not isinstance(version, (int, np.integer)) or int(version) not in _READABLE:
        raise RecordingError(
            f"{str(path)!r}: recording format version {version!r} is not supported "
            f"(this handsynth reads versions {list(_READABLE)})"
        )
    version = int(version)
    if version >= 2 and not f.attrs.get("complete", False):
        raise RecordingError(f"{str(path)!r} is incomplete (no 'complete' mark)")
    joint = _text(f.attrs["joint"], "joint", path)
    meta_text = _text(f.attrs["metadata"], "metadata", path)
    try:
        metadata = json.loads(meta_text)
    except json.JSONDecodeError as exc:
        raise RecordingError(f"{str(path)!r}: attribute 'metadata' is not JSON ({exc})") from None
    if not isinstance(metadata, dict):
        raise RecordingError(f"{str(path)!r}: attribute 'metadata' is not a JSON object")
    raw_labels = f.attrs["labels"]
    if version >= 2:
        labels_text = _text(raw_labels, "labels", path)
        try:
            labels = json.loads(labels_text)
        except json.JSONDecodeError:
            raise RecordingError(f"{str(path)!r}: attribute 'labels' is not JSON") from None
    else:
        labels = [_text(v, "labels", path) for v in np.atleast_1d(raw_labels)]
    if not (isinstance(labels, list) and len(labels) == 2 and all(isinstance(v, str) for v in labels)):
        raise RecordingError(f"{str(path)!r}: attribute 'labels' must name 2 segments, got {labels!r}")
    arrays = {k: np.asarray(f[k][()], dtype=np.float64) for k in ("times", "positions", "rotations")}
    truth_arrays = {}
    if "truth" in f:
        g = f["truth"]
        truth_arrays = {k: np.asarray(g[k][()], dtype=np.float64)
                        for k in ("centre_world", "centre_sensor", "reference_centre")}
    if version >= 2:
        stored = _text(f.attrs["checksum"], "checksum", path)
        ordered = [arrays["times"], arrays["positions"], arrays["rotations"],
                   *truth_arrays.values()]
        computed = _checksum(joint, labels_text, meta_text, ordered)
        if computed != stored:
            raise RecordingError(
                f"{str(path)!r} fails its checksum (stored {stored[:19]}..., computed "
                f"{computed[:19]}...): the file is damaged"
            )
    else:
        warnings.warn(f"{path.name}: a version-1 recording has no checksum; not verified",
                      stacklevel=3)
    truth = None
    if truth_arrays:
        truth = GroundTruth(joint_kind=_text(f["truth"].attrs["joint_kind"], "joint_kind", path),
                            **truth_arrays)
    return Recording(
        times=arrays["times"],
        positions=arrays["positions"],
        rotations=arrays["rotations"],
        labels=(labels[0], labels[1]),
        joint=joint,
        metadata=metadata,
        truth=truth,
    )
