import dataclasses

import numpy as np
import pytest

from handsynth.db import (
    Features,
    contour,
    extract_features,
    extract_features_batch,
    hilditch_thinning,
    hlac,
    pack_mask,
)
from handsynth.errors import InvalidInputError


def test_fields_match_the_individual_functions(shapes):
    for name, sil in shapes.items():
        f = extract_features(sil)
        assert isinstance(f, Features)
        np.testing.assert_array_equal(f.silhouette, sil, err_msg=name)
        np.testing.assert_array_equal(f.contour, contour(sil), err_msg=name)
        np.testing.assert_array_equal(f.hlac, hlac(sil), err_msg=name)
        np.testing.assert_array_equal(f.ridge, hilditch_thinning(sil), err_msg=name)
        np.testing.assert_array_equal(f.sil_bits, pack_mask(sil), err_msg=name)
        np.testing.assert_array_equal(f.ridge_bits, pack_mask(f.ridge), err_msg=name)
        assert f.ridge_area == int(f.ridge.sum()), name
        assert f.hlac.dtype == np.uint8 and f.hlac.shape == (1600,)


def test_batch_equals_single(shapes):
    names = sorted(shapes)
    stack = np.stack([shapes[n] for n in names])
    out = extract_features_batch(stack)
    assert out["hlac"].shape == (len(names), 1600)
    assert out["ridge_area"].dtype == np.uint16
    for i, name in enumerate(names):
        f = extract_features(stack[i])
        for key in ("contour", "hlac", "ridge", "sil_bits", "ridge_bits"):
            np.testing.assert_array_equal(out[key][i], getattr(f, key), err_msg=f"{name} {key}")
        assert out["ridge_area"][i] == f.ridge_area


def test_features_are_frozen_and_read_only(shapes):
    f = extract_features(shapes["disc"])
    with pytest.raises(dataclasses.FrozenInstanceError):
        f.ridge_area = 3
    with pytest.raises(ValueError):
        f.hlac[0] = 1


def test_input_is_copied():
    sil = np.zeros((64, 64), bool)
    sil[20:40, 20:40] = True
    f = extract_features(sil)
    sil[:] = False
    assert f.silhouette.sum() == 400


def test_accepts_0_1_numbers():
    sil = np.zeros((64, 64), np.float32)
    sil[10:30, 10:30] = 1.0
    np.testing.assert_array_equal(extract_features(sil).hlac, hlac(sil.astype(bool)))


@pytest.mark.parametrize(
    "value, pattern",
    [
        (np.zeros((64, 63), bool), r"silhouette must have shape \(64, 64\), got .*\(64, 63\)"),
        (np.zeros(4096, bool), r"silhouette .*\(4096,\)"),
        (np.full((64, 64), np.nan), r"silhouette must be finite.*nan.*\(0, 0\)"),
        (np.full((64, 64), 2, np.uint8), r"silhouette must contain only 0 and 1, got 2"),
        (np.full((64, 64), "a"), r"silhouette must be a bool array.*<U1"),
    ],
)
def test_invalid_input_is_refused_with_a_clear_message(value, pattern):
    with pytest.raises(InvalidInputError, match=pattern):
        extract_features(value)


def test_batch_rejects_single_image():
    with pytest.raises(InvalidInputError, match=r"silhouettes must have shape \(N, 64, 64\)"):
        extract_features_batch(np.zeros((64, 64), bool))
