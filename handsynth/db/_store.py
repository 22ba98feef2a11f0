"""Pose database files: one HDF5 file per hand shape (SPEC.md section 1, "Database").

Layout (format version 2)
-------------------------
The file starts with a 512-byte HDF5 user block that HDF5 itself ignores:
the ASCII line ``handsynth.pose_database <version>``, then
``sha256:<hex of the SHA-256 of every byte after the user block>`` and
``bytes:<number of bytes after the user block>``, each ending in a newline,
zero-padded to 512 bytes.  A reader checks this seal on the raw bytes before
handing a single byte to HDF5, so a truncated, zero-filled or bit-flipped file
(which can crash the HDF5 library itself) is refused with a clear error, and
so is a file changed after it was written.  Format version 1 had no seal.

Datasets, all with ``N`` rows (one per rendered pose), gzip level 4, the
multi-byte ones byte-shuffled, chunks of at most 1 MiB:

============== ============== ====== ==============================================
name           shape          dtype  content
============== ============== ====== ==============================================
``angles``     (N, 20)        <f4    joint angles in degrees, order ``JOINT_NAMES``
``hlac``       (N, 1600)      u1     block HLAC of the contour (:func:`hlac`)
``sil_bits``   (N, 64)        <u8    packed silhouette, pixel (r, c) = bit c of word r
``ridge_bits`` (N, 64)        <u8    packed Hilditch ridge lines, same bit order
``ridge_area`` (N,)           <u2    number of ridge pixels
``keypoints``  (N, 21, 3)     <i2    21 hand keypoints in the hand frame, units of
                                     :data:`KEYPOINT_SCALE_M` (10 micrometres)
============== ============== ====== ==============================================

Keypoints are stored as int16 multiples of 10 um (range +/-327.67 mm, error at
most 5 um) instead of float32 metres so that a 20,448-entry database stays
under 60 MB in memory: 20,448 x 2,832 bytes = 57.9 MB (float32 would need
60.5 MB).  :meth:`Database.keypoints_m` converts to float32 metres.

Root attributes: ``format`` (``"handsynth.pose_database"``), ``format_version``,
``n_entries``, ``meta`` (the caller's metadata as canonical JSON: sorted keys,
no spaces), ``checksum`` (``"sha256:<hex>"``) and, written last, ``complete``.

The checksum is SHA-256 over, in this order: the format name and version,
then for each dataset in the table order its name, dtype, shape and raw
C-order little-endian bytes, then the canonical metadata JSON.  It covers the
uncompressed content, so it does not depend on the HDF5 filters.

Writes are atomic and deterministic: the file is made in memory with fixed
HDF5 options (no timestamps, fixed library version bounds, fixed dataset
order) and written by :func:`handsynth._io.write_bytes` to
``<name>.tmp-<pid>`` in the same folder, fsynced, then renamed with
:func:`os.replace`.  Identical inputs give identical bytes.  Files whose name
contains ``.tmp-`` are never opened.

Reading is one exception boundary: whatever a damaged or hand-edited file
makes h5py or numpy raise becomes a :class:`DatabaseCorruptError` naming the
file and the field being read, and the attributes must have their exact
types (``format_version`` an integer, not ``1.5`` or ``"1"``).  A file named
like a hand shape (``<HandShape.name>.h5``) must hold that shape, and one
named ``<HandShape.name>_left.h5`` that shape's left hand.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np

from .._io import TMP_MARK, is_tmp_name, write_bytes
from ..errors import (
    DatabaseCorruptError,
    DatabaseError,
    DatabaseMismatchError,
    InvalidInputError,
)
from ..models import JOINT_LIMITS_DEG, JOINT_NAMES
from ._validation import IMAGE_SIZE
from .features import HLAC_SIZE

__all__ = [
    "FORMAT_VERSION",
    "KEYPOINT_SCALE_M",
    "Database",
    "check_rows",
    "open_database",
    "verify",
    "write_database",
]

#: Version of the file layout described in this module.
FORMAT_VERSION: int = 2
#: Size in metres of one unit of the stored int16 keypoints (10 um).
KEYPOINT_SCALE_M: float = 1e-5
N_KEYPOINTS: int = 21

_FORMAT_NAME = "handsynth.pose_database"
_SEAL_SIZE = 512  # the HDF5 user block: a power of two >= 512
_HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"
_CHUNK_BYTES = 1 << 20
_GZIP_LEVEL = 4
_MAX_META_BYTES = 60_000  # HDF5 compact attribute storage holds < 64 KiB
_KEYPOINT_LIMIT = np.iinfo(np.int16).max
#: Suffix of a left hand's database file name (a right hand's has none).
LEFT_SUFFIX = "_left"
_LIMIT_TOL_DEG = 1e-3  # angles beyond a joint limit by more are refused

# name, per-entry shape, on-disk dtype, units/description attribute
_DATASETS: tuple[tuple[str, tuple[int, ...], str, str], ...] = (
    ("angles", (len(JOINT_NAMES),), "<f4", "degree; columns in handsynth JOINT_NAMES order"),
    ("hlac", (HLAC_SIZE,), "|u1", "count; (block_row*8 + block_col)*25 + pattern"),
    ("sil_bits", (IMAGE_SIZE,), "<u8", "packed mask; pixel (r, c) = bit c (LSB first) of word r"),
    ("ridge_bits", (IMAGE_SIZE,), "<u8", "packed mask; pixel (r, c) = bit c (LSB first) of word r"),
    ("ridge_area", (), "<u2", "pixel count of ridge_bits"),
    ("keypoints", (N_KEYPOINTS, 3), "<i2", "1e-5 metre; hand frame"),
)
_NATIVE = {"<f4": np.float32, "|u1": np.uint8, "<u8": np.uint64, "<u2": np.uint16, "<i2": np.int16}


@dataclass(frozen=True, eq=False)
class Database:
    """A pose database loaded fully into memory; all arrays are read-only.

    Attributes
    ----------
    path : pathlib.Path
        File it was read from.
    meta : dict
        The metadata passed to :func:`write_database` (after a JSON round trip).
    angles : ndarray of float32, shape (N, 20)
        Joint angles in degrees, canonical ``JOINT_NAMES`` order.
    hlac : ndarray of uint8, shape (N, 1600)
        Block HLAC vectors.
    sil_bits, ridge_bits : ndarray of uint64, shape (N, 64)
        Packed silhouettes and ridge lines (bit ``c`` of word ``r`` = pixel (r, c)).
    ridge_area : ndarray of uint16, shape (N,)
        Ridge pixel counts.
    keypoints_raw : ndarray of int16, shape (N, 21, 3)
        Keypoints in the hand frame in units of :data:`KEYPOINT_SCALE_M`.
    """

    path: Path
    meta: dict
    angles: np.ndarray
    hlac: np.ndarray
    sil_bits: np.ndarray
    ridge_bits: np.ndarray
    ridge_area: np.ndarray
    keypoints_raw: np.ndarray

    def __len__(self) -> int:
        return self.angles.shape[0]

    @property
    def nbytes(self) -> int:
        """Bytes held by the arrays."""
        arrays = (
            self.angles,
            self.hlac,
            self.sil_bits,
            self.ridge_bits,
            self.ridge_area,
            self.keypoints_raw,
        )
        return sum(a.nbytes for a in arrays)

    def keypoints_m(self, index=slice(None)) -> np.ndarray:
        """Keypoints of entries `index` in metres.

        Parameters
        ----------
        index : int, slice or array_like of int, optional
            Entries to convert (default all).

        Returns
        -------
        ndarray of float32, shape (21, 3) or (M, 21, 3)
            Hand-frame coordinates in metres (resolution 10 um).
        """
        return self.keypoints_raw[index].astype(np.float32) * np.float32(KEYPOINT_SCALE_M)


# --------------------------------------------------------------------------- helpers


def _canonical_json(value, name: str) -> str:
    try:
        return json.dumps(
            value, sort_keys=True, separators=(",", ":"), ensure_ascii=False, allow_nan=False
        )
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(
            f"{name} must be JSON-serialisable without NaN/inf: {exc}"
        ) from None


def _rows_per_chunk(n: int, row_shape: tuple[int, ...], dtype: str) -> int:
    row_bytes = int(np.prod(row_shape, dtype=np.int64)) * np.dtype(dtype).itemsize
    return max(1, min(n, _CHUNK_BYTES // row_bytes))


def _hash_header(hasher) -> None:
    hasher.update(f"{_FORMAT_NAME}\0{FORMAT_VERSION}\0".encode())


def _hash_dataset_header(hasher, name: str, dtype: str, shape: tuple[int, ...]) -> None:
    hasher.update(f"{name}\0{np.dtype(dtype).str}\0{shape}\0".encode())


def _hash_meta(hasher, meta_json: str) -> None:
    hasher.update(b"meta\0" + meta_json.encode("utf-8"))


def _seal(body) -> bytes:
    """The user block of a file whose bytes after the user block are `body`."""
    text = (f"{_FORMAT_NAME} {FORMAT_VERSION}\nsha256:{hashlib.sha256(body).hexdigest()}\n"
            f"bytes:{len(body)}\n").encode("ascii")
    return text.ljust(_SEAL_SIZE, b"\0")


def _check_seal(path: Path, stream) -> None:
    """Refuse the file open as `stream` unless its user block seals the rest.

    Reads the file once, 1 MiB at a time, before HDF5 sees a byte of it.
    """
    head = stream.read(_SEAL_SIZE)
    if head.startswith(_HDF5_SIGNATURE):
        raise DatabaseMismatchError(
            f"database {path}: key 'format_version' is 1 or older in the file (no seal) but "
            f"{FORMAT_VERSION} is expected; rebuild it (handsynth build-db)")
    if not head.startswith(_FORMAT_NAME.encode() + b" "):
        raise DatabaseCorruptError(
            f"database {path} is not a handsynth pose database (it does not start with "
            f"{_FORMAT_NAME!r}; truncated or damaged, or another kind of file)")
    try:
        first, digest, size = head.rstrip(b"\0").decode("ascii").split("\n")[:3]
        version = int(first.split(" ")[1])
        if not digest.startswith("sha256:") or not size.startswith("bytes:"):
            raise ValueError
        size_n = int(size[len("bytes:"):])
    except (ValueError, IndexError, UnicodeDecodeError):
        raise DatabaseCorruptError(
            f"database {path}: its first {_SEAL_SIZE} bytes (the seal) are damaged") from None
    if version != FORMAT_VERSION:
        raise DatabaseMismatchError(
            f"database {path}: key 'format_version' is {version} in the file but "
            f"{FORMAT_VERSION} is expected")
    hasher, length = hashlib.sha256(), 0
    while block := stream.read(_CHUNK_BYTES):
        hasher.update(block)
        length += len(block)
    computed = "sha256:" + hasher.hexdigest()
    if computed != digest or length != size_n:
        raise DatabaseCorruptError(
            f"database {path} fails its file checksum (stored {digest} of {size_n} bytes, "
            f"computed {computed} of {length} bytes): the file is truncated or damaged, or "
            "was changed after it was written")


# --------------------------------------------------------------------------- writing


def _as_rows(value, name: str, n: int | None, row_shape: tuple[int, ...]) -> np.ndarray:
    arr = np.asarray(value)
    expected = ("N",) + row_shape if n is None else (n,) + row_shape
    if (
        arr.ndim != 1 + len(row_shape)
        or arr.shape[1:] != row_shape
        or (n is not None and arr.shape[0] != n)
    ):
        raise InvalidInputError(
            f"{name} must have shape ({', '.join(map(str, expected))}), "
            f"got array of shape {arr.shape} and dtype {arr.dtype}"
        )
    return arr


def _check_int_range(arr: np.ndarray, name: str, lo: int, hi: int) -> None:
    if arr.dtype.kind not in "iu":
        raise InvalidInputError(f"{name} must be an integer array, got dtype {arr.dtype}")
    if arr.size and (arr.min() < lo or arr.max() > hi):
        bad = arr[(arr < lo) | (arr > hi)][0]
        raise InvalidInputError(f"{name} must lie in [{lo}, {hi}], got {bad.item()}")


def _check_joint_limits(ang: np.ndarray) -> None:
    """Refuse finite angles outside their joints' limits (as :func:`as_angles` does).

    The tolerance, :data:`_LIMIT_TOL_DEG`, covers float32 rounding of an
    angle clipped to its limit.
    """
    lo, hi = JOINT_LIMITS_DEG[:, 0], JOINT_LIMITS_DEG[:, 1]
    values = np.asarray(ang, dtype=np.float64)
    out = (values < lo - _LIMIT_TOL_DEG) | (values > hi + _LIMIT_TOL_DEG)
    if out.any():
        i, j = (int(v) for v in np.argwhere(out)[0])
        raise InvalidInputError(
            f"angles row {i}: {JOINT_NAMES[j]}={values[i, j]:g} deg is outside its limits "
            f"[{lo[j]:g}, {hi[j]:g}]")


def _prepare(angles, hlac, sil_bits, ridge_bits, ridge_area, keypoints) -> dict[str, np.ndarray]:
    """Validate the arrays and convert them to their on-disk dtypes."""
    ang = _as_rows(angles, "angles", None, (len(JOINT_NAMES),))
    n = ang.shape[0]
    if n == 0:
        raise InvalidInputError("angles must hold at least one entry, got shape (0, 20)")
    if ang.dtype.kind not in "iuf":
        raise InvalidInputError(f"angles must be numbers (degrees), got dtype {ang.dtype}")
    if not np.isfinite(ang).all():
        i, j = (int(v) for v in np.argwhere(~np.isfinite(ang))[0])
        raise InvalidInputError(
            f"angles must be finite, got {ang[i, j].item()} at index ({i}, {j})"
        )
    _check_joint_limits(ang)
    hl = _as_rows(hlac, "hlac", n, (HLAC_SIZE,))
    _check_int_range(hl, "hlac", 0, 255)
    bits = {}
    for name, value in (("sil_bits", sil_bits), ("ridge_bits", ridge_bits)):
        arr = _as_rows(value, name, n, (IMAGE_SIZE,))
        if arr.dtype != np.uint64:
            raise InvalidInputError(f"{name} must have dtype uint64, got {arr.dtype}")
        bits[name] = arr
    area = _as_rows(ridge_area, "ridge_area", n, ())
    _check_int_range(area, "ridge_area", 0, IMAGE_SIZE * IMAGE_SIZE)
    counted = np.bitwise_count(bits["ridge_bits"]).sum(axis=1, dtype=np.int64)
    wrong = np.nonzero(counted != area)[0]
    if wrong.size:
        i = int(wrong[0])
        raise InvalidInputError(
            f"ridge_area[{i}] is {area[i].item()} but ridge_bits[{i}] has {counted[i]} pixels set"
        )
    kp = _as_rows(keypoints, "keypoints", n, (N_KEYPOINTS, 3))
    if kp.dtype.kind not in "iuf" or not np.isfinite(kp).all():
        raise InvalidInputError(
            f"keypoints must be finite numbers (metres), got dtype {kp.dtype}"
            + ("" if kp.dtype.kind not in "iuf" else " with non-finite values")
        )
    kp_q = np.rint(np.asarray(kp, dtype=np.float64) / KEYPOINT_SCALE_M)
    if np.abs(kp_q).max() > _KEYPOINT_LIMIT:
        raise InvalidInputError(
            f"keypoints must lie within +/-{_KEYPOINT_LIMIT * KEYPOINT_SCALE_M:.5f} m of the hand "
            f"frame origin, got {np.abs(kp).max():.5f} m"
        )
    values = {
        "angles": ang,
        "hlac": hl,
        "sil_bits": bits["sil_bits"],
        "ridge_bits": bits["ridge_bits"],
        "ridge_area": area,
        "keypoints": kp_q,
    }
    return {
        name: np.ascontiguousarray(values[name], dtype=dtype) for name, _, dtype, _ in _DATASETS
    }


def check_rows(rows: Mapping, name: str = "rows") -> dict[str, np.ndarray]:
    """Check database rows as :func:`write_database` does; return them in their stored dtypes.

    Parameters
    ----------
    rows : mapping
        ``angles``, ``hlac``, ``sil_bits``, ``ridge_bits``, ``ridge_area``
        and ``keypoints`` as :func:`write_database` takes them (e.g. the
        output of :func:`handsynth.db.render_entries`); other keys are
        ignored.
    name : str
        Name of `rows` in error messages.

    Returns
    -------
    dict of str to ndarray
        The six arrays in their on-disk dtypes (``keypoints`` as int16
        multiples of :data:`KEYPOINT_SCALE_M`), C-contiguous.

    Raises
    ------
    InvalidInputError
        `rows` is not a mapping or lacks a key, or an array has the wrong
        shape, dtype or range (angles outside their joint limits, keypoints
        beyond +/-0.32767 m...); the message names the array, and the row
        and joint of a bad angle.
    """
    if not isinstance(rows, Mapping):
        raise InvalidInputError(f"{name} must be a mapping of arrays, got {type(rows).__name__}")
    missing = [k for k, _, _, _ in _DATASETS if k not in rows]
    if missing:
        raise InvalidInputError(
            f"{name} must have the keys {', '.join(k for k, _, _, _ in _DATASETS)}; "
            f"missing {', '.join(missing)}")
    return _prepare(**{k: rows[k] for k, _, _, _ in _DATASETS})


def write_database(
    path, *, angles, hlac, sil_bits, ridge_bits, ridge_area, keypoints, meta: Mapping,
    inputs=(),
) -> Path:
    """Write one hand shape's pose database, atomically and deterministically.

    Parameters
    ----------
    path : str or os.PathLike
        Final file name (conventionally ``*.h5``); its folder must exist.
        Must not contain ``.tmp-``.
    angles : array_like of float, shape (N, 20)
        Joint angles in degrees, canonical ``JOINT_NAMES`` order, finite and
        within :data:`~handsynth.models.JOINT_LIMITS_DEG` (to 0.001 deg);
        stored float32.
    hlac : array_like of int, shape (N, 1600)
        Block HLAC vectors, values 0..255; stored uint8.
    sil_bits, ridge_bits : ndarray of uint64, shape (N, 64)
        Packed silhouettes and ridge lines (:func:`pack_mask`).
    ridge_area : array_like of int, shape (N,)
        Ridge pixel counts; must equal the popcount of `ridge_bits`.
    keypoints : array_like of float, shape (N, 21, 3)
        Hand-frame keypoints in metres, within +/-0.32767 m; stored as int16
        multiples of :data:`KEYPOINT_SCALE_M`.
    meta : mapping
        JSON-serialisable description of how the database was built (hand
        shape ratios, camera mount, model and feature parameters, pose set
        and seed, handsynth version...).  Read back by :func:`open_database`
        and compared with its `expect`.
    inputs : iterable of path-like, keyword-only
        Files the caller read; `path` must be none of them.

    Returns
    -------
    pathlib.Path
        `path`.

    Raises
    ------
    InvalidInputError
        An array with the wrong shape, dtype or range (an angle outside its
        joint's limits names the row and the joint), or `meta` not JSON-able
        (the checks of :func:`check_rows`).
    DatabaseError
        The file could not be written: its folder is missing or read-only,
        the disk is full, or `path` is a folder or one of `inputs` (the
        temporary file is removed; `path` keeps its old content).
    """
    path = Path(path)
    if is_tmp_name(path):
        raise InvalidInputError(f"path must not contain {TMP_MARK!r}, got {str(path)!r}")
    if not isinstance(meta, Mapping):
        raise InvalidInputError(f"meta must be a mapping, got {type(meta).__name__}")
    meta_json = _canonical_json(dict(meta), "meta")
    if len(meta_json.encode("utf-8")) > _MAX_META_BYTES:
        raise InvalidInputError(
            f"meta must serialise to at most {_MAX_META_BYTES} bytes of JSON, "
            f"got {len(meta_json.encode('utf-8'))}"
        )
    arrays = _prepare(angles, hlac, sil_bits, ridge_bits, ridge_area, keypoints)
    n = arrays["angles"].shape[0]

    hasher = hashlib.sha256()
    _hash_header(hasher)
    for name, _, dtype, _ in _DATASETS:
        _hash_dataset_header(hasher, name, dtype, arrays[name].shape)
        hasher.update(arrays[name].data.cast("B"))  # .data: the array's memoryview
    _hash_meta(hasher, meta_json)
    checksum = "sha256:" + hasher.hexdigest()

    # The file is made in memory and written to disk in one go by the atomic
    # writer: a full disk or a read-only folder then fails in a plain write
    # (a clear OSError), never inside the HDF5 library, which cannot recover
    # from a failed write of its own.
    buffer = io.BytesIO()
    with h5py.File(buffer, "w", libver=("earliest", "v110"), track_order=False,
                   userblock_size=_SEAL_SIZE) as f:
        f.attrs["format"] = _FORMAT_NAME
        f.attrs["format_version"] = np.int64(FORMAT_VERSION)
        f.attrs["n_entries"] = np.int64(n)
        f.attrs["meta"] = meta_json
        for name, row_shape, dtype, units in _DATASETS:
            data = arrays[name]
            ds = f.create_dataset(
                name,
                data=data,
                chunks=(_rows_per_chunk(n, row_shape, dtype),) + row_shape,
                compression="gzip",
                compression_opts=_GZIP_LEVEL,
                shuffle=data.dtype.itemsize > 1,
                track_times=False,
            )
            ds.attrs["units"] = units
        f["angles"].attrs["joint_names"] = json.dumps(list(JOINT_NAMES))
        f.attrs["checksum"] = checksum
        f.flush()
        f.attrs["complete"] = True  # last: marks a finished write
    file_bytes = buffer.getbuffer()
    file_bytes[:_SEAL_SIZE] = _seal(file_bytes[_SEAL_SIZE:])
    write_bytes(path, file_bytes, what="database", inputs=inputs, error=DatabaseError)
    return path


# --------------------------------------------------------------------------- reading


def _first_difference(stored, expected, key: str):
    """Return (key path, stored, expected) of the first difference, or None."""
    if isinstance(expected, dict) and isinstance(stored, dict):
        for k in sorted(expected):
            sub = f"{key}.{k}" if key else k
            if k not in stored:
                return sub, "<missing>", expected[k]
            diff = _first_difference(stored[k], expected[k], sub)
            if diff is not None:
                return diff
        return None
    if stored != expected or (type(stored) is bool) != (type(expected) is bool):
        return key, stored, expected
    return None


class _Field:
    """The field being read, for the message of an unexpected failure."""

    name = "the file header"


def _scalar(attrs, name: str, kind: str, path: Path):
    """Attribute `name` as a Python scalar of `kind` ("str", "int", "bool")."""
    if name not in attrs:
        raise DatabaseCorruptError(f"database {path}: attribute {name!r} is missing")
    value = attrs[name]
    ok = {"str": lambda v: isinstance(v, (str, bytes)),
          "int": lambda v: isinstance(v, (int, np.integer)) and not isinstance(v, (bool, np.bool_)),
          "bool": lambda v: isinstance(v, (bool, np.bool_))}[kind]
    if not ok(value):
        shown = (repr(value.item() if isinstance(value, np.generic) else value)
                 if np.ndim(value) == 0 else f"an array of shape {np.shape(value)}")
        raise DatabaseCorruptError(
            f"database {path}: attribute {name!r} must be {'an' if kind == 'int' else 'a'} "
            f"{kind} scalar, got {shown}")
    if isinstance(value, bytes):
        return value.decode("utf-8")
    return value.item() if isinstance(value, np.generic) else value


def _check_file_name(path: Path, meta) -> None:
    """A file named ``<HandShape.name>.h5`` must hold that shape's database, and one
    named ``<HandShape.name>_left.h5`` that shape's left hand."""
    from ..models import HandShape

    if not isinstance(meta, dict):
        return
    stem, left = path.stem, path.stem.endswith(LEFT_SUFFIX)
    if left:
        stem = stem[:-len(LEFT_SUFFIX)]
    try:
        named = HandShape.from_name(stem).name
    except InvalidInputError:
        return  # not named after a shape
    stored = meta.get("shape_name")
    if isinstance(stored, str) and named != stored:
        raise DatabaseMismatchError(
            f"database {path} is named for shape {named} but holds the database of shape "
            f"{stored}: it was copied or renamed; rebuild it (handsynth build-db)")
    if left and meta.get("side", "right") != "left":
        raise DatabaseMismatchError(
            f"database {path} is named for the left hand but holds the "
            f"{meta.get('side', 'right')} hand: it was copied or renamed; rebuild it "
            "(handsynth build-db)")


def _read(path, expect: Mapping | None, *, keep: bool):
    """Check a database file; return (meta, arrays or None).

    Every failure is a :class:`DatabaseError` (the exception boundary of the
    reader): the expected ones are raised with their own message, anything a
    damaged file makes h5py or numpy raise is reported with the field read.
    A `path` that is not a file name is an :class:`InvalidInputError`.
    """
    if not isinstance(path, (str, os.PathLike)):
        raise InvalidInputError(
            f"path must be a file name (str or os.PathLike), got {type(path).__name__}")
    path = Path(path)
    if is_tmp_name(path):
        raise DatabaseCorruptError(
            f"database {path} is the temporary file of an unfinished write "
            f"(name contains {TMP_MARK!r}); it is never read"
        )
    if expect is not None:
        if not isinstance(expect, Mapping):
            raise InvalidInputError(
                f"expect must be a mapping or None, got {type(expect).__name__}"
            )
        expect = json.loads(_canonical_json(dict(expect), "expect"))
    if path.is_dir():
        raise DatabaseError(f"database {path} is a folder, not a file")
    if not path.is_file():
        if path.is_symlink():
            raise DatabaseError(f"database {path} is a link to {os.readlink(path)!r}, "
                                "which does not exist")
        raise DatabaseError(f"database {path} does not exist")
    field = _Field()
    try:
        meta, arrays = _read_checked(path, keep, field)
    except DatabaseError:
        raise
    except MemoryError:
        raise DatabaseCorruptError(
            f"database {path}: {field.name} claims more data than fits in memory "
            "(damaged file)") from None
    except Exception as exc:  # the boundary: a damaged file can make h5py raise anything
        # chained, so that a fault of handsynth's own behind it keeps its traceback
        raise DatabaseCorruptError(
            f"database {path} is damaged: {field.name} cannot be read "
            f"({type(exc).__name__}: {exc})") from exc
    _check_file_name(path, meta)
    if expect is not None:
        diff = _first_difference(meta, expect, "")
        if diff is not None:
            key, stored, wanted = diff
            raise DatabaseMismatchError(
                f"database {path}: meta key {key!r} is {json.dumps(stored)} in the file "
                f"but {json.dumps(wanted)} is expected"
            )
    return meta, arrays


def _read_checked(path: Path, keep: bool, field: _Field):
    try:
        stream = open(path, "rb")  # noqa: SIM115 - closed below, after HDF5 is done with it
    except OSError as exc:
        raise DatabaseError(f"database {path} cannot be read: {exc.strerror or exc}") from None
    with stream:
        field.name = "the seal (first 512 bytes)"
        _check_seal(path, stream)
        checked = os.fstat(stream.fileno())
        field.name = "the HDF5 structure"
        try:
            f = h5py.File(path, "r")  # HDF5's own file driver: 4x faster than a Python stream
        except OSError as exc:
            raise DatabaseCorruptError(
                f"database {path} is not a readable HDF5 file (truncated or damaged): {exc}"
            ) from None
        opened = os.stat(path)
        if (opened.st_dev, opened.st_ino) != (checked.st_dev, checked.st_ino):
            f.close()
            raise DatabaseError(f"database {path} was replaced while it was read; read it again")
        return _read_open(path, f, keep, field)


def _read_open(path: Path, f, keep: bool, field: _Field):
    with f:
        attrs = f.attrs
        field.name = "attribute 'format'"
        if "format" not in attrs or attrs["format"] != _FORMAT_NAME:
            raise DatabaseCorruptError(
                f"database {path} is not a handsynth pose database "
                f"(attribute 'format' is {attrs.get('format')!r})"
            )
        field.name = "attribute 'complete'"
        if "complete" not in attrs or not _scalar(attrs, "complete", "bool", path):
            raise DatabaseCorruptError(
                f"database {path} has no complete mark: its write did not finish"
            )
        field.name = "attribute 'format_version'"
        version = _scalar(attrs, "format_version", "int", path)
        if version != FORMAT_VERSION:
            raise DatabaseMismatchError(
                f"database {path}: key 'format_version' is {version} in the file "
                f"but {FORMAT_VERSION} is expected"
            )
        field.name = "attribute 'meta'"
        meta_json = _scalar(attrs, "meta", "str", path)
        try:
            meta = json.loads(meta_json)
        except ValueError as exc:
            raise DatabaseCorruptError(
                f"database {path}: attribute 'meta' is not JSON: {exc}") from None
        field.name = "attribute 'n_entries'"
        n = _scalar(attrs, "n_entries", "int", path)
        if n < 1:
            raise DatabaseCorruptError(f"database {path}: attribute 'n_entries' is {n}")
        field.name = "attribute 'checksum'"
        stored_checksum = _scalar(attrs, "checksum", "str", path)

        hasher = hashlib.sha256()
        _hash_header(hasher)
        arrays = {}
        for name, row_shape, dtype, _ in _DATASETS:
            field.name = f"dataset {name!r}"
            if name not in f or not isinstance(f[name], h5py.Dataset):
                raise DatabaseCorruptError(f"database {path} has no dataset {name!r}")
            ds = f[name]
            shape = (n,) + row_shape
            if ds.shape != shape or ds.dtype != np.dtype(dtype):
                raise DatabaseCorruptError(
                    f"database {path}: dataset {name!r} has shape {ds.shape} and dtype "
                    f"{ds.dtype}, expected shape {shape} and dtype {np.dtype(dtype)}"
                )
            _hash_dataset_header(hasher, name, dtype, shape)
            out = np.empty(shape if keep else (0,) + row_shape, dtype=_NATIVE[dtype])
            step = ds.chunks[0] if ds.chunks else max(n, 1)
            for start in range(0, n, step):
                stop = min(n, start + step)
                field.name = f"dataset {name!r} rows {start}-{stop - 1}"
                block = np.ascontiguousarray(ds[start:stop], dtype=dtype)
                hasher.update(block.data.cast("B"))
                if keep:
                    out[start:stop] = block
            if keep:
                out.setflags(write=False)
                arrays[name] = out
        _hash_meta(hasher, meta_json)
        computed = "sha256:" + hasher.hexdigest()
        if computed != stored_checksum:
            raise DatabaseCorruptError(
                f"database {path} fails its checksum (stored {stored_checksum}, "
                f"computed {computed}): the file is damaged"
            )
        if not isinstance(meta, dict):
            raise DatabaseCorruptError(
                f"database {path}: attribute 'meta' must be a JSON object, got "
                f"{type(meta).__name__}")
    return meta, (arrays if keep else None)


def open_database(path, *, expect: Mapping | None = None) -> Database:
    """Read a pose database fully into memory after checking it.

    Parameters
    ----------
    path : str or os.PathLike
        File written by :func:`write_database`.
    expect : mapping, optional
        Metadata the caller requires.  Every key of `expect` (recursively for
        nested mappings) must be present in the stored metadata with an equal
        value (after a JSON round trip, so tuples equal lists); keys the
        file has in addition are ignored.

    Returns
    -------
    Database
        Read-only, C-contiguous arrays and the metadata.

    Raises
    ------
    DatabaseCorruptError
        Temporary file name, missing complete mark, truncated or unreadable
        file, missing or misshapen dataset, or checksum mismatch.
    DatabaseMismatchError
        A key of `expect` differs from the stored metadata (the message names
        the key, both values and the file), or another format version.
    DatabaseError
        The file does not exist.
    InvalidInputError
        `path` is not a file name (``None``, a number...), or `expect` is
        not a mapping.
    """
    meta, arrays = _read(path, expect, keep=True)
    return Database(
        path=Path(path),
        meta=meta,
        angles=arrays["angles"],
        hlac=arrays["hlac"],
        sil_bits=arrays["sil_bits"],
        ridge_bits=arrays["ridge_bits"],
        ridge_area=arrays["ridge_area"],
        keypoints_raw=arrays["keypoints"],
    )


def verify(path, *, expect: Mapping | None = None) -> dict:
    """Check a database file's completeness and checksum without keeping its arrays.

    Reads the datasets one chunk at a time (memory stays near 1 MiB), so a
    resumable build can decide cheaply whether a file may be skipped.

    Parameters
    ----------
    path : str or os.PathLike
    expect : mapping, optional
        As in :func:`open_database`.

    Returns
    -------
    dict
        The stored metadata.

    Raises
    ------
    DatabaseCorruptError, DatabaseMismatchError, DatabaseError
        As :func:`open_database`.
    """
    meta, _ = _read(path, expect, keep=False)
    return meta
