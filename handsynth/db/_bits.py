"""Bit-packed 64x64 masks and the pixel counts of the two-stage search.

SPEC.md section 1, "Search": P1 is the number of input ridge pixels outside
the entry's silhouette, P2 the number of the entry's ridge pixels outside
the input silhouette.  With masks packed one 64-bit word per row both are
``sum_rows popcount(a & ~b)``.

Bit order: row ``r`` of a (64, 64) mask is word ``r``; pixel ``(r, c)`` is bit
``c`` of that word, i.e. ``(word >> c) & 1``, so column 0 is the least
significant bit.  Words are native ``uint64`` in memory and little-endian
(``<u8``) in database files.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numba.extending import overload

from .._checks import check_integer, short_repr
from ..errors import InvalidInputError
from ._validation import IMAGE_SIZE, as_silhouette, as_silhouette_batch

__all__ = [
    "complement_bits",
    "count_outside",
    "count_outside_batch",
    "pack_mask",
    "popcount64",
    "popcount_bits",
    "unpack_mask",
]

_ALL_ONES = np.uint64(0xFFFFFFFFFFFFFFFF)


def _as_bits(value, name: str) -> np.ndarray:
    arr = np.asarray(value)
    if arr.dtype != np.uint64 or arr.ndim < 1 or arr.shape[-1] != IMAGE_SIZE:
        raise InvalidInputError(
            f"{name} must be a uint64 array of shape (..., {IMAGE_SIZE}), "
            f"got array of shape {arr.shape} and dtype {arr.dtype}"
        )
    return arr


def pack_mask(mask) -> np.ndarray:
    """Pack 64x64 masks into one uint64 word per row.

    Parameters
    ----------
    mask : array_like of bool, shape (64, 64) or (N, 64, 64)
        Masks to pack (0/1 numbers are accepted).

    Returns
    -------
    ndarray of uint64, shape (64,) or (N, 64)
        Pixel ``(r, c)`` is bit ``c`` (LSB = column 0) of word ``r``.

    Raises
    ------
    InvalidInputError
        Wrong shape or values other than 0/1.
    """
    arr = np.asarray(mask)
    single = arr.ndim == 2
    if single:
        stack = as_silhouette(arr, name="mask")[None]
    else:
        stack = as_silhouette_batch(arr, name="mask")
    packed = np.packbits(stack, axis=-1, bitorder="little")  # (N, 64, 8) uint8
    words = np.ascontiguousarray(packed).view("<u8")[..., 0].astype(np.uint64)
    return words[0] if single else words


def unpack_mask(bits) -> np.ndarray:
    """Inverse of :func:`pack_mask`.

    Parameters
    ----------
    bits : array_like of uint64, shape (..., 64)

    Returns
    -------
    ndarray of bool, shape (..., 64, 64)
    """
    arr = _as_bits(bits, "bits")
    raw = np.ascontiguousarray(arr.astype("<u8")).view(np.uint8)
    raw = raw.reshape(arr.shape + (8,))
    return np.unpackbits(raw, axis=-1, bitorder="little").astype(bool)


def complement_bits(bits) -> np.ndarray:
    """Packed complement: pixels set where the packed mask is not.

    Parameters
    ----------
    bits : array_like of uint64, shape (..., 64)

    Returns
    -------
    ndarray of uint64, shape (..., 64)
    """
    return np.bitwise_xor(_as_bits(bits, "bits"), _ALL_ONES)


def popcount_bits(bits) -> np.ndarray | int:
    """Number of pixels set in packed masks (the ridge area, SPEC.md section 1).

    Parameters
    ----------
    bits : array_like of uint64, shape (..., 64)

    Returns
    -------
    int or ndarray of int64, shape (...)
    """
    counts = np.bitwise_count(_as_bits(bits, "bits")).sum(axis=-1, dtype=np.int64)
    return int(counts) if counts.ndim == 0 else counts


@njit(cache=True, nogil=True, inline="always")
def _popcount64(x):
    """Set bits of one uint64, for compiled kernels (SWAR count, Hacker's Delight 5-2)."""
    x = x - ((x >> np.uint64(1)) & np.uint64(0x5555555555555555))
    x = (x & np.uint64(0x3333333333333333)) + ((x >> np.uint64(2)) & np.uint64(0x3333333333333333))
    x = (x + (x >> np.uint64(4))) & np.uint64(0x0F0F0F0F0F0F0F0F)
    return (x * np.uint64(0x0101010101010101)) >> np.uint64(56)


@njit(cache=True, nogil=True)
def _count_outside(a_bits, b_bits):
    """:func:`count_outside` unchecked: the compiled kernel."""
    total = np.uint64(0)
    for r in range(a_bits.shape[0]):
        total += _popcount64(a_bits[r] & ~b_bits[r])
    return int(total)


_WORD_END = 1 << 64  # one past the largest uint64


def popcount64(x) -> int:
    """Set bits of one 64-bit word (SWAR count, Hacker's Delight 5-2).

    Called from Python the argument is checked; in compiled (numba) code the
    name is the unchecked kernel itself, inlined.

    Parameters
    ----------
    x : int
        A Python or numpy integer in ``[0, 2**64)``.

    Returns
    -------
    int
        0 to 64.

    Raises
    ------
    InvalidInputError
        `x` is not an integer (a float, a bool, an array) or is outside
        ``[0, 2**64)`` (a negative number has no 64-bit word of its own).
    """
    v = check_integer(x, "x")
    if not 0 <= v < _WORD_END:
        raise InvalidInputError(f"x must be an integer >= 0 and < 2**64 (one uint64 word), "
                                f"got {short_repr(x)}")
    return int(_popcount64(np.uint64(v)))


@overload(popcount64, inline="always")
def _popcount64_compiled(x):
    """In compiled code :func:`popcount64` is the kernel, unchecked."""
    return _popcount64.py_func


def _as_words(value, name: str) -> np.ndarray:
    """`value` refused unless it is one packed mask: a uint64 numpy array of shape (64,)."""
    if not isinstance(value, np.ndarray):
        raise InvalidInputError(f"{name} must be a uint64 numpy array of shape ({IMAGE_SIZE},), "
                                f"got {type(value).__name__} {short_repr(value)}")
    if value.dtype != np.uint64 or value.shape != (IMAGE_SIZE,):
        raise InvalidInputError(f"{name} must be a uint64 numpy array of shape ({IMAGE_SIZE},), "
                                f"got dtype {value.dtype} shape {value.shape}")
    return value


def count_outside(a_bits, b_bits) -> int:
    """Pixels set in packed mask `a_bits` and not in `b_bits` (one pair).

    ``count_outside(ridge_in, sil_entry)`` is P1 and
    ``count_outside(ridge_entry, sil_in)`` is P2 of SPEC.md section 1.
    Called from Python the arguments are checked; in compiled (numba) code
    the name is the unchecked kernel (callable from other numba functions).

    Parameters
    ----------
    a_bits, b_bits : ndarray of uint64, shape (64,)
        Packed masks (see the module docstring).

    Returns
    -------
    int
        ``sum_r popcount(a_bits[r] & ~b_bits[r])``.

    Raises
    ------
    InvalidInputError
        `a_bits` or `b_bits` is not a uint64 numpy array of shape (64,) (the
        kernel would read past the shorter one, or fail on another dtype),
        naming it; :func:`count_outside_batch` takes stacks.
    """
    return _count_outside(_as_words(a_bits, "a_bits"), _as_words(b_bits, "b_bits"))


@overload(count_outside, inline="always")
def _count_outside_compiled(a_bits, b_bits):
    """In compiled code :func:`count_outside` is the kernel, unchecked."""
    def impl(a_bits, b_bits):
        return _count_outside(a_bits, b_bits)
    return impl


def count_outside_batch(a_bits, b_bits) -> np.ndarray:
    """Vectorised :func:`count_outside` over broadcast stacks of packed masks.

    Parameters
    ----------
    a_bits, b_bits : array_like of uint64, shape (..., 64)
        Broadcast against each other, e.g. one input ridge (64,) against all
        entries' silhouettes (N, 64) gives P1 of every entry.

    Returns
    -------
    ndarray of int64, shape (broadcast shape without the last axis)

    Raises
    ------
    InvalidInputError
        `a_bits` or `b_bits` is not a uint64 array of shape (..., 64), or the
        two do not broadcast (naming both shapes).
    """
    a = _as_bits(a_bits, "a_bits")
    b = _as_bits(b_bits, "b_bits")
    try:
        np.broadcast_shapes(a.shape, b.shape)
    except ValueError:
        raise InvalidInputError(f"a_bits and b_bits must broadcast against each other, got shapes "
                                f"{a.shape} and {b.shape}") from None
    return np.bitwise_count(a & ~b).sum(axis=-1, dtype=np.int64)
