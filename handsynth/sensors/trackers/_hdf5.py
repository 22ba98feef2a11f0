"""handsynth's own HDF5 format for recordings.

Layout (format ``"handsynth.recording"``, version 1)::

    /                attrs: format, version, joint, labels, metadata (JSON)
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
"""

from __future__ import annotations

import io
import json
import os
from pathlib import Path

import h5py

from ..._io import write_bytes
from ...errors import InvalidInputError, RecordingError
from ._recording import GroundTruth, Recording

__all__ = ["load_recording", "save_recording"]

_FORMAT = "handsynth.recording"
_VERSION = 1


def save_recording(path: str | os.PathLike, recording: Recording, *, inputs=()) -> Path:
    """Write `recording` to HDF5 atomically.

    Parameters
    ----------
    path : path-like
        Target file; its directory must exist.
    recording : Recording

    Returns
    -------
    pathlib.Path
        The path written.
    """
    if not isinstance(recording, Recording):
        raise InvalidInputError(
            f"recording: expected a Recording, got {type(recording).__name__}"
        )
    path = Path(path)
    try:
        meta = json.dumps(dict(recording.metadata))
    except TypeError as exc:
        raise InvalidInputError(f"recording metadata is not JSON-serialisable: {exc}") from None
    # made in memory, then written whole by the atomic writer: a full disk fails in a
    # plain write, never inside the HDF5 library
    buffer = io.BytesIO()
    with h5py.File(buffer, "w") as f:
        f.attrs["format"] = _FORMAT
        f.attrs["version"] = _VERSION
        f.attrs["joint"] = recording.joint
        f.attrs["labels"] = list(recording.labels)
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
    return write_bytes(path, buffer.getbuffer(), what="recording", inputs=inputs)


def load_recording(path: str | os.PathLike) -> Recording:
    """Read a recording written by :func:`save_recording`.

    Raises
    ------
    RecordingError
        Missing or unreadable file, another format or version, missing data.
    """
    path = Path(path)
    try:
        f = h5py.File(path, "r")
    except (OSError, ValueError) as exc:
        raise RecordingError(f"cannot open {str(path)!r} as HDF5: {exc}") from None
    with f:
        fmt = f.attrs.get("format")
        if fmt != _FORMAT:
            raise RecordingError(f"{str(path)!r} is not a handsynth recording (format={fmt!r})")
        version = int(f.attrs.get("version", -1))
        if version != _VERSION:
            raise RecordingError(
                f"{str(path)!r}: recording format version {version} is not supported "
                f"(this handsynth reads version {_VERSION})"
            )
        try:
            truth = None
            if "truth" in f:
                g = f["truth"]
                truth = GroundTruth(
                    centre_world=g["centre_world"][()],
                    centre_sensor=g["centre_sensor"][()],
                    reference_centre=g["reference_centre"][()],
                    joint_kind=str(g.attrs["joint_kind"]),
                )
            return Recording(
                times=f["times"][()],
                positions=f["positions"][()],
                rotations=f["rotations"][()],
                labels=tuple(str(s) for s in f.attrs["labels"]),
                joint=str(f.attrs["joint"]),
                metadata=json.loads(f.attrs["metadata"]),
                truth=truth,
            )
        except KeyError as exc:
            raise RecordingError(f"{str(path)!r} is incomplete: missing {exc}") from None
