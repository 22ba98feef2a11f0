"""Calibration from an open-hand frame: ignore mask, masked search, shape from a frame."""

from __future__ import annotations

import numpy as np
import pytest

from handsynth.db import pack_mask
from handsynth.errors import InvalidInputError
from handsynth.estimate import (
    ApproximateOptions,
    Calibration,
    PoseLookup,
    masked_band_areas,
    masked_search,
    masked_search_reference,
    select_shape_from_frame,
)
from handsynth.models import HandShape
from handsynth.render import CameraMount, SilhouetteRasterizer

RENDER_SIZE = (180, 120)  # render size of the shared small database (tests/conftest.py)


def _box(r0, r1, c0, c1) -> np.ndarray:
    m = np.zeros((64, 64), bool)
    m[r0:r1, c0:c1] = True
    return m


# --------------------------------------------------------------------------- ignore mask


def test_ignore_mask_is_the_mismatch_grown_by_4_neighbour_steps():
    user, reference = _box(10, 30, 10, 40), _box(10, 30, 10, 38)  # user 2 columns wider
    c0 = Calibration.from_silhouettes(user, reference, dilation_px=0)
    assert c0.ignore.sum() == 40 and (c0.ignore == (user ^ reference)).all()
    assert c0.open_iou == pytest.approx(560 / 600)
    c1 = Calibration.from_silhouettes(user, reference, dilation_px=1)
    # a 20x2 block grown by one 4-neighbour step: +1 row above and below, +1 column each side
    assert c1.ignore.sum() == 40 + 2 * 2 + 2 * 20
    assert c1.ignore[9, 38] and c1.ignore[30, 39] and c1.ignore[15, 37] and c1.ignore[15, 40]
    assert not c1.ignore[9, 37]  # diagonal neighbours are not added
    np.testing.assert_array_equal(c1.keep_bits, pack_mask(~c1.ignore))
    assert Calibration.from_silhouettes(user, user).ignore.sum() == 0
    with pytest.raises(ValueError):
        c1.ignore[0, 0] = True  # read-only


@pytest.mark.parametrize("args, match", [
    ((_box(0, 5, 0, 5), _box(0, 5, 0, 5)[:32]), "one size"),
    ((_box(0, 5, 0, 5).astype(np.uint8), _box(0, 5, 0, 5)), "bool"),
    ((np.zeros((64, 64), bool), _box(0, 5, 0, 5)), "user silhouette shows no hand"),
    ((_box(0, 5, 0, 5), np.zeros((64, 64), bool)), "reference silhouette shows no hand"),
])
def test_calibration_refuses_bad_silhouettes(args, match):
    with pytest.raises(InvalidInputError, match=match):
        Calibration.from_silhouettes(*args)


@pytest.mark.parametrize("d", [-1, 9, 1.0, True, "1"])
def test_calibration_refuses_bad_dilation(d):
    with pytest.raises(InvalidInputError, match="dilation_px"):
        Calibration.from_silhouettes(_box(0, 5, 0, 5), _box(0, 6, 0, 5), dilation_px=d)


@pytest.mark.parametrize("t", [-0.5, 8.5, float("nan"), float("inf"), True, "1", None])
def test_calibration_refuses_bad_temperature(t):
    with pytest.raises(InvalidInputError, match="temperature_px"):
        Calibration.from_silhouettes(_box(0, 5, 0, 5), _box(0, 6, 0, 5), temperature_px=t)


# --------------------------------------------------------------------------- masked search


def test_masked_search_equals_the_reference_on_random_tables():
    rng = np.random.default_rng(3)
    table = pack_mask(rng.random((500, 64, 64)) < 0.3)
    table[400:410] = table[7]  # ties
    wider = 0
    for k in range(6):
        temperature = (0.0, 0.5, 3.0)[k % 3]
        if k < 4:  # random masks: large ignored areas, many ties
            cal = Calibration.from_silhouettes(rng.random((64, 64)) < 0.1,
                                               rng.random((64, 64)) < 0.1, dilation_px=k % 3,
                                               temperature_px=temperature, min_open_iou=0.0)
            sil = rng.random((64, 64)) < 0.3
        else:  # entry 7 itself, a small ignored block
            cal = Calibration.from_silhouettes(_box(0, 9, 0, 9), _box(0, 9, 0, 8),
                                               dilation_px=k - 4, temperature_px=temperature)
            sil = np.unpackbits(table[7].view(np.uint8), bitorder="little").astype(bool)
            sil = sil.reshape(64, 64)
        fast = masked_search(sil, table, cal)
        ref = masked_search_reference(sil, table, cal)
        assert (fast.index, fast.error, fast.union) == (ref.index, ref.error, ref.union)
        np.testing.assert_array_equal(fast.tied, ref.tied)
        np.testing.assert_array_equal(fast.near, ref.near)
        np.testing.assert_allclose(fast.weights, ref.weights, rtol=1e-12)
        wider += fast.near.size > fast.tied.size
    assert wider >= 1  # some windows held more than the ties
    assert fast.error == 0 and list(fast.tied) == [7, *range(400, 410)]


def test_band_areas_bound_the_masked_difference_from_below():
    rng = np.random.default_rng(5)
    masks = rng.random((200, 64, 64)) < rng.random((200, 1, 1))
    masks[:50, :, 20:] = False  # some entries with the same areas in a band, others not
    cal = Calibration.from_silhouettes(rng.random((64, 64)) < 0.05, rng.random((64, 64)) < 0.05,
                                       min_open_iou=0.0)
    table = pack_mask(masks)
    bands = masked_band_areas(table, cal)
    assert bands.shape == (200, 8) and bands.dtype == np.int32
    kept = masks & ~cal.ignore[None]
    np.testing.assert_array_equal(bands, kept.reshape(200, 8, -1).sum(axis=2))
    for q in masks[::20]:
        x = ((masks ^ q[None]) & ~cal.ignore[None]).sum(axis=(1, 2))
        qb = (q & ~cal.ignore).reshape(8, -1).sum(axis=1)
        bound = np.abs(bands - qb[None]).sum(axis=1)
        assert (bound <= x).all() and (bound < x).any()
    with pytest.raises(InvalidInputError, match="band_areas"):
        masked_search(masks[0], table, cal, band_areas=bands[:10])
    with pytest.raises(InvalidInputError, match="band_areas"):
        masked_search(masks[0], table, cal, band_areas=bands.astype(np.int64))


def test_masked_search_weights_entries_near_the_best():
    # entry k differs from the input in k pixels outside the (empty) ignore mask
    frame = _box(10, 30, 10, 40)
    masks = np.repeat(frame[None], 40, axis=0)
    for k in range(40):
        masks[k, 40, :k] = True
    masks[5] = masks[3]  # entry 5 ties with entry 3
    table = pack_mask(masks)
    x = np.array([k if k != 5 else 3 for k in range(40)])  # extra pixels of each entry
    for t in (0.0, 0.5, 1.0, 2.5):
        cal = Calibration.from_silhouettes(frame, frame, temperature_px=t)
        assert cal.window_px == int(10 * t)
        m = masked_search(masks[3], table, cal)  # input = entry 3: X_i = |x_i - 3|
        d = np.abs(x - 3)
        want = np.flatnonzero(d <= int(10 * t))
        np.testing.assert_array_equal(m.near, want)
        np.testing.assert_array_equal(m.tied, [3, 5])
        w = np.exp(-d[want] / t) if t > 0 else (d[want] == 0).astype(float)
        np.testing.assert_allclose(m.weights, w / w.sum(), rtol=1e-12)
        assert m.weights.sum() == pytest.approx(1.0)


def test_masked_search_without_mask_is_the_plain_pixel_difference():
    rng = np.random.default_rng(4)
    masks = rng.random((300, 64, 64)) < 0.4
    cal = Calibration.from_silhouettes(masks[0], masks[0])  # nothing ignored
    sil = rng.random((64, 64)) < 0.4
    xor = (masks ^ sil[None]).sum(axis=(1, 2))
    m = masked_search(sil, pack_mask(masks), cal)
    assert m.error == xor.min() and m.index == int(np.argmin(xor))
    assert m.union == (masks[m.index] | sil).sum()


def test_masked_search_ignores_what_the_calibration_frame_showed():
    hand = _box(20, 44, 0, 40)
    flexed = _box(20, 44, 0, 30)             # the entry of the true pose: a finger shorter
    blob = _box(10, 20, 5, 35)               # a part the user has and the model has not
    other = hand | _box(12, 20, 5, 35)       # an entry that happens to cover most of it
    table = pack_mask(np.stack([hand, other, flexed]))
    frame = flexed | blob                    # the user's hand, finger flexed
    cal = Calibration.from_silhouettes(hand | blob, hand, dilation_px=0)
    assert masked_search(frame, table, Calibration.from_silhouettes(hand, hand)).index == 1
    m = masked_search(frame, table, cal)
    assert (m.index, m.error) == (2, 0)


def test_masked_search_refuses_bad_input():
    cal = Calibration.from_silhouettes(_box(0, 9, 0, 9), _box(0, 8, 0, 9))
    table = pack_mask(np.stack([_box(0, 9, 0, 9)]))
    with pytest.raises(InvalidInputError, match="silhouette"):
        masked_search(np.zeros((64, 64), np.uint8), table, cal)
    with pytest.raises(InvalidInputError, match="calibration"):
        masked_search(_box(0, 9, 0, 9), table, "calibration")
    with pytest.raises(InvalidInputError, match="sil_bits"):
        masked_search(_box(0, 9, 0, 9), table[:, :32], cal)


# --------------------------------------------------------------------------- PoseLookup


def _open_frame(shape: HandShape) -> np.ndarray:
    with SilhouetteRasterizer(shape, CameraMount(), width_px=RENDER_SIZE[0],
                              height_px=RENDER_SIZE[1]) as r:
        return r.masks(np.zeros((1, 20)))[0]


def test_calibrated_lookup_with_the_models_own_hand_finds_the_entry(db_folder, small_rows):
    plain = PoseLookup.open(db_folder, shape=HandShape(), ties="first")
    lookup = plain.calibrated(_open_frame(HandShape()))
    assert plain.calibration is None and lookup.database is plain.database
    assert lookup.calibration.open_iou == 1.0 and lookup.calibration.ignore.sum() == 0
    with SilhouetteRasterizer(HandShape(), CameraMount(), width_px=RENDER_SIZE[0],
                              height_px=RENDER_SIZE[1]) as r:
        for i in (3, 50, 200):
            est = lookup.estimate(r.mask(small_rows["angles"][i]))
            assert est.error == 0.0 and est.confidence == 1.0 and not est.no_hand
            assert (lookup.database.sil_bits[est.entry] == small_rows["sil_bits"][i]).all()
            np.testing.assert_array_equal(est.angles, lookup.database.angles[est.entry])
    assert lookup.estimate(np.zeros((120, 180), bool)).no_hand


def test_calibrated_lookup_of_another_hand_ignores_its_mismatch(db_folder):
    lookup = PoseLookup.open(db_folder, shape=HandShape(), ties="first")
    cal = lookup.calibrated(_open_frame(HandShape(width=1.3, palm=1.1)), dilation_px=2)
    assert 0.5 < cal.calibration.open_iou < 1.0 and cal.calibration.ignore.any()
    assert cal.calibration.dilation_px == 2
    est = cal.estimate(_open_frame(HandShape(width=1.3, palm=1.1)))
    assert (est.entry, est.error) == (0, 0.0)  # the open-hand entry (first of its ties)
    assert np.all(est.angles == 0.0)


def test_calibrated_lookup_reports_the_weighted_mean_of_the_near_entries(db_folder, small_rows):
    user = HandShape(width=1.1, palm=1.05)
    with SilhouetteRasterizer(user, CameraMount(), width_px=RENDER_SIZE[0],
                              height_px=RENDER_SIZE[1]) as r:
        frame = r.mask(small_rows["angles"][40])
    soft = PoseLookup.open(db_folder, shape=HandShape()).calibrated(_open_frame(user),
                                                                    temperature_px=2.0)
    m = masked_search(soft.silhouette(frame), soft.tables.sil_bits, soft.calibration)
    assert m.near.size > m.tied.size
    db = soft.database
    est = soft.estimate(frame)
    np.testing.assert_allclose(est.angles, m.weights @ db.angles[m.near].astype(float))
    np.testing.assert_allclose(est.keypoints, np.tensordot(m.weights, db.keypoints_m(m.near), 1),
                               atol=1e-6)
    assert (est.entry, est.error) == (m.index, m.error)
    hard = PoseLookup.open(db_folder, shape=HandShape()).calibrated(_open_frame(user),
                                                                    temperature_px=0.0)
    np.testing.assert_allclose(hard.estimate(frame).angles, db.angles[m.tied].mean(axis=0))
    first = PoseLookup.open(db_folder, shape=HandShape(), ties="first").calibrated(
        _open_frame(user), temperature_px=2.0)
    np.testing.assert_array_equal(first.estimate(frame).angles, db.angles[m.index])


def test_calibrated_refuses_what_it_cannot_use(db_folder, small_rows):
    lookup = PoseLookup.open(db_folder, shape=HandShape())
    with pytest.raises(InvalidInputError, match="no hand"):
        lookup.calibrated(np.zeros((120, 180), bool))
    with pytest.raises(InvalidInputError, match="float"):
        lookup.calibrated(np.zeros((120, 180)))
    rows = {k: v[1:] for k, v in small_rows.items()}  # entry 0 is the open hand
    assert not np.all(small_rows["angles"][1:] == 0, axis=1).any()
    with pytest.raises(InvalidInputError, match="open-hand entry"):
        PoseLookup.from_rows(rows).calibrated(_open_frame(HandShape()))
    approx = PoseLookup.open(db_folder, shape=HandShape(),
                             approximate=ApproximateOptions(nlist=8, nprobe=8, dims=16))
    with pytest.raises(InvalidInputError, match="exact search"):
        approx.calibrated(_open_frame(HandShape()))


def test_lookup_from_an_open_frame_builds_and_calibrates_the_best_fitting_shape(tmp_path):
    from handsynth.db import BuildOptions

    shapes = [HandShape(), HandShape(width=1.1, palm=1.05), HandShape(length=0.95, thumb=0.9)]
    user = HandShape(width=1.08, palm=1.04)  # off the candidates, nearest the second
    build = BuildOptions(count=40, render_size=RENDER_SIZE)
    lookup = PoseLookup.from_open_frame(tmp_path, _open_frame(user), shapes=shapes, build=build,
                                        workers=1, temperature_px=0.5)
    assert lookup.database.path == tmp_path / f"{shapes[1].name}.h5" and len(lookup) == 40
    assert sorted(p.name for p in tmp_path.glob("*.h5")) == [f"{shapes[1].name}.h5"]
    cal = lookup.calibration
    assert cal.temperature_px == 0.5 and cal.dilation_px == 1 and 0.8 < cal.open_iou < 1.0
    est = lookup.estimate(_open_frame(user))
    assert (est.error, est.confidence) == (0.0, 1.0) and np.all(est.angles == 0.0)
    with pytest.raises(InvalidInputError, match="no hand"):
        PoseLookup.from_open_frame(tmp_path, np.zeros((120, 180), bool), shapes=shapes,
                                   build=build)
    with pytest.raises(InvalidInputError, match="build must be a BuildOptions"):
        PoseLookup.from_open_frame(tmp_path, _open_frame(user), build={"count": 5})


# --------------------------------------------------------------------------- shape from a frame


def test_shape_from_frame_picks_the_hand_that_made_the_frame():
    shapes = [HandShape(), HandShape(width=1.1, palm=1.05), HandShape(length=0.95, thumb=0.9)]
    for true in shapes:
        sel = select_shape_from_frame(_open_frame(true), shapes=shapes)
        assert sel.shape == true and sel.iou == 1.0
        assert set(sel.ious) == {s.name for s in shapes} and max(sel.ious.values()) == 1.0
        assert sorted(sel.ious.values())[-2] < 1.0


def test_shape_from_frame_refuses_bad_input():
    with pytest.raises(InvalidInputError, match="no hand"):
        select_shape_from_frame(np.zeros((120, 180), bool), shapes=[HandShape()])
    for bad in ([], ["L1"], [HandShape(), 3]):
        with pytest.raises(InvalidInputError, match="shapes"):
            select_shape_from_frame(_open_frame(HandShape()), shapes=bad)


def test_a_frame_without_an_open_hand_is_refused():
    # issue 16 item 8: calibration on random noise was accepted ("3744 of 4096 pixels ignored")
    from handsynth.errors import EstimationError
    from handsynth.render import preprocess

    reference = _open_frame(HandShape())
    ref = preprocess(reference, CameraMount())
    noise = np.random.default_rng(3).integers(0, 256, reference.shape + (3,), dtype=np.uint8)
    with pytest.raises(EstimationError, match=r"does not look like an open hand: .* IoU 0\.[0-4]"):
        Calibration.from_silhouettes(preprocess(noise, CameraMount()), ref)
    wide = preprocess(_open_frame(HandShape(length=1.2, width=0.8, palm=1.2, thumb=0.8)),
                      CameraMount())
    assert Calibration.from_silhouettes(wide, ref).open_iou > 0.6  # a real, other hand passes
    with pytest.raises(InvalidInputError, match=r"min_open_iou"):
        Calibration.from_silhouettes(wide, ref, min_open_iou=1.5)


def test_select_shape_from_frame_names_a_bad_mount_or_side():
    from handsynth.estimate import select_shape_from_frame

    frame = _open_frame(HandShape())
    with pytest.raises(InvalidInputError, match=r"mount must be a CameraMount, got str 'paper'"):
        select_shape_from_frame(frame, mount="paper", shapes=[HandShape()])
    with pytest.raises(InvalidInputError, match=r"side must be 'right' or 'left', got 'Right'"):
        select_shape_from_frame(frame, side="Right", shapes=[HandShape()])


def test_masked_search_names_a_bad_calibration_and_an_empty_or_narrow_table():
    # before: AttributeError, numpy's broadcast or reshape errors
    rng = np.random.default_rng(6)
    cal = Calibration.from_silhouettes(rng.random((64, 64)) < 0.05, rng.random((64, 64)) < 0.05,
                                       min_open_iou=0.0)
    sil = rng.random((64, 64)) < 0.3
    table = pack_mask(rng.random((5, 64, 64)) < 0.3)
    with pytest.raises(InvalidInputError, match=r"^calibration must be a Calibration, got str"):
        masked_band_areas(table, "cal")
    for bad in (table[:0], table[:, :32]):
        with pytest.raises(InvalidInputError, match=r"^sil_bits must have shape \(N, 64\) with N >= 1"):
            masked_band_areas(bad, cal)
        for search in (masked_search, masked_search_reference):
            with pytest.raises(InvalidInputError, match=r"^sil_bits must have shape \(N, 64\) with N >= 1"):
                search(sil, bad, cal)


def test_reference_silhouette_names_what_is_not_a_database():
    # reference_silhouette("x") was an AttributeError
    from handsynth.estimate import reference_silhouette

    with pytest.raises(InvalidInputError, match=r"^database must be a Database \(its angles, sil_bits "
                                                r"and path\), got str 'x'$"):
        reference_silhouette("x")


def test_select_shape_from_frame_refuses_a_speck():
    frame = np.zeros((480, 720), bool)
    frame[200:210, 300:310] = True  # 100 pixels: far under 1 % of the view
    with pytest.raises(InvalidInputError, match=r"open_frame shows no hand: .*less than 1 % of "
                                                r"the view \(MIN_HAND_COVERAGE\)"):
        select_shape_from_frame(frame, shapes=[HandShape()])
