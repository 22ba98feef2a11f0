import numpy as np
import pytest

from handsynth.db import (
    complement_bits,
    count_outside,
    count_outside_batch,
    pack_mask,
    popcount64,
    popcount_bits,
    unpack_mask,
)
from handsynth.errors import InvalidInputError


def test_bit_order_is_row_word_column_bit():
    mask = np.zeros((64, 64), bool)
    mask[3, 5] = True
    mask[63, 63] = True
    mask[0, 0] = True
    bits = pack_mask(mask)
    assert bits.dtype == np.uint64 and bits.shape == (64,)
    assert int(bits[3]) == 1 << 5
    assert int(bits[63]) == 1 << 63
    assert int(bits[0]) == 1
    assert np.count_nonzero(bits) == 3


def test_round_trip_single_and_batch():
    rng = np.random.default_rng(1)
    masks = rng.random((7, 64, 64)) < 0.4
    bits = pack_mask(masks)
    assert bits.shape == (7, 64)
    np.testing.assert_array_equal(unpack_mask(bits), masks)
    np.testing.assert_array_equal(pack_mask(masks[2]), bits[2])
    np.testing.assert_array_equal(unpack_mask(bits[2]), masks[2])


def test_complement_and_popcount():
    rng = np.random.default_rng(2)
    mask = rng.random((64, 64)) < 0.3
    bits = pack_mask(mask)
    np.testing.assert_array_equal(unpack_mask(complement_bits(bits)), ~mask)
    assert popcount_bits(bits) == mask.sum()
    assert isinstance(popcount_bits(bits), int)
    np.testing.assert_array_equal(
        popcount_bits(pack_mask(np.stack([mask, ~mask]))), [mask.sum(), 4096 - mask.sum()]
    )


def test_count_outside_matches_boolean_definition():
    rng = np.random.default_rng(3)
    a = rng.random((50, 64, 64)) < 0.2
    b = rng.random((50, 64, 64)) < 0.6
    a_bits, b_bits = pack_mask(a), pack_mask(b)
    expected = (a & ~b).sum(axis=(1, 2))
    got = [count_outside(a_bits[i], b_bits[i]) for i in range(50)]
    np.testing.assert_array_equal(got, expected)
    np.testing.assert_array_equal(count_outside_batch(a_bits, b_bits), expected)
    # broadcasting: one input ridge against every entry's silhouette (P1)
    np.testing.assert_array_equal(
        count_outside_batch(a_bits[0], b_bits), (a[0] & ~b).sum(axis=(1, 2))
    )
    # high bit (column 63) is counted too
    hi = np.zeros(64, np.uint64)
    hi[5] = np.uint64(1 << 63)
    assert count_outside(hi, np.zeros(64, np.uint64)) == 1
    assert count_outside(hi, hi) == 0


def test_bits_reject_wrong_dtype():
    with pytest.raises(InvalidInputError, match=r"a_bits.*int64"):
        count_outside_batch(np.zeros(64, np.int64), np.zeros(64, np.uint64))
    with pytest.raises(InvalidInputError, match=r"bits.*\(63,\)"):
        unpack_mask(np.zeros(63, np.uint64))
    with pytest.raises(InvalidInputError, match=r"mask.*\(64, 65\)"):
        pack_mask(np.zeros((64, 65), bool))


_ONES = np.full(64, 2**64 - 1, np.uint64)


@pytest.mark.parametrize("a, b, words", [
    # issue: lengths 64 and 32 gave 3501, the kernel reading past the shorter array
    (_ONES, np.zeros(32, np.uint64), r"b_bits must be a uint64 numpy array of shape \(64,\), got "
                                     r"dtype uint64 shape \(32,\)"),
    (np.zeros(32, np.uint64), _ONES, r"a_bits .*shape \(32,\)"),
    (_ONES.astype(float), _ONES, r"a_bits .*got dtype float64 shape \(64,\)"),  # was: TypingError
    (_ONES, _ONES.astype(np.int64), r"b_bits .*got dtype int64"),
    (_ONES.reshape(8, 8), _ONES.reshape(8, 8), r"a_bits .*shape \(8, 8\)"),
    ([1] * 64, _ONES, r"a_bits must be a uint64 numpy array of shape \(64,\), got list \[1, 1"),
])
def test_count_outside_refuses_what_is_not_one_packed_mask(a, b, words):
    with pytest.raises(InvalidInputError, match=words):
        count_outside(a, b)


def test_count_outside_batch_refuses_stacks_that_do_not_broadcast():
    with pytest.raises(InvalidInputError, match=r"a_bits and b_bits must broadcast .*got shapes "
                                                r"\(3, 64\) and \(4, 64\)"):
        count_outside_batch(np.zeros((3, 64), np.uint64), np.zeros((4, 64), np.uint64))


@pytest.mark.parametrize("x, words", [
    (1.5, r"x must be an integer, got 1.5"),  # was: a numba TypingError
    (-1, r"x must be an integer >= 0 and < 2\*\*64 \(one uint64 word\), got -1"),  # was: 64
    (2**64, r"x must be an integer >= 0 and < 2\*\*64 .*got 18446744073709551616"),
    (True, r"x must be an integer, got True \(bool\)"),
    ("3", r"x must be an integer, got '3' \(str\)"),
    (np.float64(3.0), r"x must be an integer, got np.float64\(3.0\)"),
])
def test_popcount64_refuses_what_is_not_one_word(x, words):
    with pytest.raises(InvalidInputError, match=words):
        popcount64(x)


def test_popcount64_counts_words_and_stays_a_kernel_in_compiled_code():
    from numba import njit

    assert [popcount64(v) for v in (0, 5, np.uint64(7), np.int64(3), 2**64 - 1)] == [0, 2, 3, 2, 64]
    assert isinstance(popcount64(np.uint64(2**63)), int)

    @njit
    def total(a, b):  # the public names called from compiled code (as the search does)
        t = 0
        for r in range(a.shape[0]):
            t += popcount64(a[r])
        return t + count_outside(a, b)

    b = np.zeros(64, np.uint64)
    b[0] = 1
    assert total(_ONES, b) == 2 * 4096 - 1
