import json
from dataclasses import asdict, replace

import numpy as np
import pytest

from handsynth.db import LearningSetOptions, render_learning_set
from handsynth.estimate import (
    LEARNED_ENSEMBLE,
    LEARNED_PERCEPTRONS,
    SHIPPED_LEARNING_SETS,
    LearnedEstimator,
    LearnedOptions,
    _learned,
    learned_ensemble,
    learned_estimator,
    member_learning_set,
    shipped_members,
    shipped_perceptrons,
)
from handsynth.estimate._learned import learned_file_name, train_learned
from handsynth.estimate._shipped import (
    SHIPPED_FOLDER,
    fingerprint,
    fingerprint_differs,
    read_manifest,
    ship,
    shipped_path,
)
from handsynth.render import CameraMount

DEFAULT_PERCEPTRONS = [(opts, member_learning_set(LearningSetOptions(), changes))
                       for opts, _weight, changes in LEARNED_ENSEMBLE if opts.kind == "mlp"]
PERCEPTRONS = shipped_perceptrons()


def _same_arrays(a: LearnedEstimator, b: LearnedEstimator) -> bool:
    return a._a.keys() == b._a.keys() and all(np.array_equal(a._a[k], b._a[k]) for k in a._a)


def test_shipped_perceptrons_are_the_members_of_each_shipped_learning_set():
    relaxed = LearningSetOptions(open_rest_share=0.0)
    assert (LearningSetOptions(), relaxed) == SHIPPED_LEARNING_SETS
    of_relaxed = [(opts, member_learning_set(relaxed, changes))
                  for opts, _weight, changes in LEARNED_ENSEMBLE if opts.kind == "mlp"]
    # the default set's relaxed-rest member is also the relaxed set's seed-0 member: once
    assert DEFAULT_PERCEPTRONS + [p for p in of_relaxed if p not in DEFAULT_PERCEPTRONS] == PERCEPTRONS
    assert len(PERCEPTRONS) == len(set(PERCEPTRONS)) == 4
    assert shipped_perceptrons(bases=()) == []
    assert shipped_perceptrons(members=[(LearnedOptions(kind="fingers"), 1.0)]) == []


@pytest.mark.parametrize(("opts", "data"), PERCEPTRONS)
def test_every_perceptron_of_the_ensemble_is_shipped_for_each_learning_set(opts, data):
    name = learned_file_name(opts, data, CameraMount.paper(), "right")
    path = shipped_path(name)
    assert path is not None, f"{name} is not shipped: run scripts/ship_perceptrons.py"
    entry = read_manifest()["files"][name]
    assert entry["learning_set"] == json.loads(json.dumps(asdict(data)))
    est = LearnedEstimator.load(path, options=opts)
    assert est.options.digest() == opts.digest() and est.mount == CameraMount.paper()


def test_shipped_learning_sets_still_render_as_when_shipped():
    manifest = read_manifest()
    assert manifest["files"], "nothing is shipped"
    done = set()
    for opts, data in PERCEPTRONS:
        fp = manifest["files"][learned_file_name(opts, data, CameraMount.paper(), "right")]["fingerprint"]
        if fp in done:
            continue
        done.add(fp)
        with np.load(SHIPPED_FOLDER / fp) as z:
            stored = {k: z[k] for k in z.files}
        why = fingerprint_differs(stored, fingerprint(data, CameraMount.paper(), "right"))
        assert why is None, (f"{fp}: {why}; the shipped perceptrons no longer match their learning "
                             f"set: run scripts/ship_perceptrons.py")


def test_fingerprint_differs_names_what_changed():
    rng = np.random.default_rng(0)
    fp = {"grids": rng.integers(0, 256, (20, 50), dtype=np.uint8),
          "rest_grids": rng.integers(0, 256, (2, 50), dtype=np.uint8),
          "angles": rng.normal(size=(20, 20)).astype(np.float32),
          "rest_angles": rng.normal(size=(2, 20)).astype(np.float32)}
    assert fingerprint_differs(fp, dict(fp)) is None
    few = dict(fp, grids=np.clip(fp["grids"].astype(int) + (rng.random((20, 50)) < 0.1), 0, 255))
    assert fingerprint_differs(fp, few) is None  # a few cells rounded the other way
    moved = dict(fp, grids=np.roll(fp["grids"], 1, axis=1))
    assert "grids differ" in fingerprint_differs(fp, moved)
    posed = dict(fp, angles=fp["angles"] + 0.01)
    assert "angles differ" in fingerprint_differs(fp, posed)
    fewer = dict(fp, rest_grids=fp["rest_grids"][:1])
    assert "rest_grids have shape" in fingerprint_differs(fp, fewer)


def test_a_shipped_perceptron_is_read_instead_of_learnt(tmp_path, monkeypatch):
    def no_learning(*args, **kwargs):
        raise AssertionError("rendered a learning set")

    monkeypatch.setattr(_learned, "learning_set", no_learning)
    for opts, data in PERCEPTRONS:  # the relaxed-rest set's too (--learned-rest relaxed)
        said = []
        est = learned_estimator(tmp_path, opts, data=data, progress=said.append)
        name = learned_file_name(opts, data, CameraMount.paper(), "right")
        assert said == [f"mlp ({name}): shipped with handsynth"]  # which of them, by its file
        assert _same_arrays(est, LearnedEstimator.load(SHIPPED_FOLDER / name))
    opts, data = PERCEPTRONS[0]
    with pytest.raises(AssertionError, match="rendered a learning set"):
        learned_estimator(tmp_path, opts, data=data, shipped=False)
    with pytest.raises(AssertionError, match="rendered a learning set"):  # other options: not shipped
        learned_estimator(tmp_path, replace(opts, seed=7), data=data)


def test_the_perceptrons_alone_are_read_from_the_package_and_weigh_alike(tmp_path, monkeypatch):
    def no_learning(*args, **kwargs):
        raise AssertionError("rendered a learning set")

    monkeypatch.setattr(_learned, "learning_set", no_learning)
    assert [(o, c) for o, _w, c in LEARNED_PERCEPTRONS] == [
        (o, c) for o, _w, c in LEARNED_ENSEMBLE if o.kind == "mlp"]
    ens = learned_ensemble(tmp_path, members=LEARNED_PERCEPTRONS)
    np.testing.assert_allclose(ens.weights, [1 / 3] * 3)
    for est, shipped in zip(ens.members, shipped_members(members=LEARNED_PERCEPTRONS), strict=True):
        assert _same_arrays(est, shipped)
    assert not list(tmp_path.iterdir())  # nothing learnt, nothing written


def test_ship_writes_what_shipped_path_then_trusts(tmp_path):
    data = LearningSetOptions(hands=4, poses_per_hand=10, seed=3)
    opts = LearnedOptions(kind="mlp", components=8, hidden=(8,), epochs=1)
    cache = tmp_path / "cache"
    cache.mkdir()
    src = cache / "learnt.npz"
    train_learned(render_learning_set(data), opts).save(src)
    out = tmp_path / "shipped"
    out.mkdir()
    (out / "learned_mlp_stale.npz").write_bytes(b"old")
    (out / "fingerprint_stale.npz").write_bytes(b"old")
    (out / "mirror_check.npz").write_bytes(b"not a perceptron's")  # kept: not ship()'s
    manifest = ship({"learned_mlp_x.npz": (src, data)}, folder=out)
    assert sorted(p.name for p in out.iterdir()) == sorted(
        ["learned_mlp_x.npz", "manifest.json", f"fingerprint_{data.digest()}.npz",
         "mirror_check.npz"])
    assert manifest == read_manifest(out)
    path = shipped_path("learned_mlp_x.npz", folder=out)
    assert path is not None and path.read_bytes() == src.read_bytes()
    with np.load(out / manifest["files"]["learned_mlp_x.npz"]["fingerprint"]) as z:
        assert z["grids"].shape == (2 * 10, 30 * 45)
        assert fingerprint_differs({k: z[k] for k in z.files},
                                   fingerprint(data, CameraMount.paper(), "right")) is None
    assert shipped_path("learned_mlp_y.npz", folder=out) is None  # not in the manifest
    raw = bytearray(path.read_bytes())
    raw[len(raw) // 2] ^= 1
    path.write_bytes(bytes(raw))
    assert shipped_path("learned_mlp_x.npz", folder=out) is None  # bytes differ
    assert shipped_path("learned_mlp_x.npz", folder=tmp_path / "none") is None


def test_shipped_members_reads_the_default_perceptrons_and_leaves_out_the_rest():
    got = shipped_members()
    assert [e.options for e in got] == [opts for opts, _data in DEFAULT_PERCEPTRONS]
    for est, (opts, data) in zip(got, DEFAULT_PERCEPTRONS):
        name = learned_file_name(opts, data, CameraMount.paper(), "right")
        assert _same_arrays(est, LearnedEstimator.load(SHIPPED_FOLDER / name))
    assert shipped_members(members=[(LearnedOptions(kind="fingers"), 1.0)]) == []
    assert shipped_members(members=[(LearnedOptions(kind="mlp", seed=0), 1.0)]) == []  # 4,000 hands


def test_camera_frames_made_worse_read_as_their_masks(tmp_path):
    """Noise, compression, blur, shading and half resolution: what no learning frame had.

    docs/camera_estimator.md ("Imaging on a dark background") reports that they move the
    finger flexion MAE by at most 0.1 deg; a change in binarization or in the coverage grid
    that lost that would fail here.
    """
    import cv2

    from handsynth.eval import (
        model_test_hands,
        natural_test_poses,
        paper_protocol_poses,
        relaxed_rest_posture,
    )

    est = learned_ensemble(tmp_path, members=LEARNED_PERCEPTRONS)  # shipped: nothing learnt
    made = model_test_hands(1, seed=31, spread=1.5)[0].make()
    rng = np.random.default_rng(4)
    rest = relaxed_rest_posture(rng)
    poses = np.vstack([paper_protocol_poses(rest, 6, rng)[0], natural_test_poses(rest, 6, rng)[0]])
    masks = made.masks(poses)
    skin = np.array([120, 150, 210], np.float32)
    shade = np.linspace(0.55, 1.0, 720, dtype=np.float32)[None, :, None]

    def paint(mask, noise):
        f = np.full((480, 720, 3), 20, np.float32)
        f[mask] = skin
        f[mask] *= np.broadcast_to(shade, f.shape)[mask]
        return np.clip(f + noise.normal(0, 20, f.shape), 0, 255).astype(np.uint8)

    def worse(mask, noise):
        f = cv2.GaussianBlur(paint(mask, noise), (0, 0), 1.0)
        f = cv2.imdecode(cv2.imencode(".jpg", f, [cv2.IMWRITE_JPEG_QUALITY, 40])[1], cv2.IMREAD_COLOR)
        return cv2.resize(f, (360, 240), interpolation=cv2.INTER_AREA)

    clean = est.calibrated(made.mask(rest))
    noise = np.random.default_rng(5)
    bad = est.calibrated(worse(made.mask(rest), noise))
    a = np.stack([clean.estimate(m).angles for m in masks])
    b = np.stack([bad.estimate(worse(m, noise)).angles for m in masks])
    assert np.isfinite(b).all()
    assert np.abs(a - b).mean() < 0.5
    assert np.abs(a - b).max() < 5.0


def test_frames_over_a_bright_coloured_ground_read_as_their_masks_by_the_skin_s_colour(tmp_path):
    """Otsu's threshold fails over an ordinary background; the skin's colour much less.

    docs/camera_estimator.md ("Telling the hand from an ordinary background"): the skin's
    colour from the rest frame loses a finger cut off by a seam of mixed pixels, and takes in
    ground of the skin's colour next to the hand.
    """
    import cv2

    from handsynth.eval import model_test_hands, natural_test_poses, relaxed_rest_posture

    est = learned_ensemble(tmp_path, members=LEARNED_PERCEPTRONS)
    made = model_test_hands(1, seed=33, spread=1.5)[0].make()
    rng = np.random.default_rng(6)
    rest = relaxed_rest_posture(rng)
    poses = natural_test_poses(rest, 8, rng)[0]
    skin = np.array([95, 125, 180], np.float32)

    def paint(mask, k):
        ground = cv2.resize(np.random.default_rng(k).integers(0, 256, (5, 8, 3)).astype(np.uint8),
                            (720, 480), interpolation=cv2.INTER_CUBIC).astype(np.float32)
        ground[mask] = skin
        return np.clip(ground + rng.normal(0, 5, ground.shape), 0, 255).astype(np.uint8)

    masks = made.masks(poses)
    a = np.stack([est.calibrated(made.mask(rest)).estimate(m).angles for m in masks])
    frames = [paint(m, k) for k, m in enumerate(masks)]
    by_colour = est.calibrated(paint(made.mask(rest), 99), segment="colour")
    b = np.stack([by_colour.estimate(f).angles for f in frames])
    by_brightness = est.calibrated(paint(made.mask(rest), 99), segment="brightness")
    assert est.calibrated(paint(made.mask(rest), 99)).segment == "colour"  # auto
    c = np.stack([by_brightness.estimate(f).angles for f in frames])
    flex = [4, 6, 7, 8, 10, 11, 12, 14, 15, 16, 18, 19]
    mae = {k: np.abs(v[:, flex] - poses[:, flex]).mean() for k, v in (("mask", a), ("colour", b),
                                                                        ("brightness", c))}
    constant = np.abs(poses[:, flex]).mean()
    assert mae["brightness"] > 0.5 * constant  # the ground taken for hand
    assert mae["colour"] < mae["mask"] + 0.25 * (mae["brightness"] - mae["mask"])


def test_the_shipped_perceptrons_flag_frames_of_no_hand_and_not_a_held_out_hand(tmp_path):
    """Each shipped perceptron keeps a novelty limit (docs/camera_estimator.md, "What
    `low_confidence` flags"): a held-out model hand's frames stay under it, frames that
    show no hand or not as the device sees one do not."""
    import cv2

    from handsynth.eval import model_test_hands, natural_test_poses, relaxed_rest_posture

    for est in shipped_members(members=LEARNED_PERCEPTRONS):
        limit = float(est._a["novelty_limit"])
        assert 3.0 < limit < 8.0  # 4.87-4.90 as shipped; learning frames' median about 2.9
    ens = learned_ensemble(tmp_path, members=LEARNED_PERCEPTRONS)  # shipped: nothing learnt
    made = model_test_hands(1, seed=47)[0].make()
    rng = np.random.default_rng(8)
    rest = relaxed_rest_posture(rng)
    masks = made.masks(natural_test_poses(rest, 12, rng)[0])
    cal = ens.calibrated(made.mask(rest))
    got = [cal.estimate(m) for m in masks]
    assert not any(g.low_confidence for g in got)
    rect = np.zeros((480, 720), bool)
    rect[140:340, 210:510] = True
    disc = np.zeros((480, 720), np.uint8)
    cv2.circle(disc, (360, 240), 150, 255, -1)
    noise = np.random.default_rng(1).integers(0, 256, (480, 720, 3), dtype=np.uint8)
    for frame in (rect, disc > 0, noise, masks[0][::-1], np.roll(masks[0], 120, axis=1)):
        e = cal.estimate(frame)
        assert e.low_confidence and not e.no_hand
        for member in cal.members:  # each perceptron: what its components leave out
            m = member.estimate(frame)
            assert m.low_confidence == (m.error > float(member._a["novelty_limit"]))


def test_flush_subnormals_zeroes_those_alone_and_copies_only_what_it_changes():
    tiny = np.finfo(np.float32).tiny
    w = np.array([1e-45, -3e-39, tiny, -tiny, 0.0, 0.5, -2.0], np.float32)
    clean = np.array([0.25, 0.0], np.float32)
    ints = np.array([0, 1], np.int32)
    arrays = {"w": w, "clean": clean, "ints": ints, "layers": 3}
    out = _learned._flush_subnormals(arrays)
    assert out["w"].dtype == np.float32
    np.testing.assert_array_equal(out["w"], [0.0, 0.0, tiny, -tiny, 0.0, 0.5, -2.0])
    assert w[0] != 0 and w[1] != 0  # the caller's array is left as it was
    assert out["clean"] is clean and out["ints"] is ints and out["layers"] == 3
    assert out is not arrays
    # the learning frames' codes and angles are left unread when asked
    kept = _learned._flush_subnormals({"d0_codes": w, "d0_w": w}, skip=("codes", "angles"))
    assert kept["d0_codes"] is w and kept["d0_w"][0] == 0


def test_shipped_perceptrons_read_without_subnormals_give_the_same_answers(monkeypatch):
    """Weight decay left thousands of subnormal weights in each shipped perceptron (slow
    products on many processors); reading them as 0 must not change a single answer."""
    from handsynth.eval import model_test_hands, natural_test_poses, relaxed_rest_posture

    made = model_test_hands(1, seed=47)[0].make()
    rng = np.random.default_rng(3)
    rest = relaxed_rest_posture(rng)
    masks = made.masks(natural_test_poses(rest, 6, rng)[0])
    flushed = shipped_members(members=LEARNED_PERCEPTRONS)
    monkeypatch.setattr(_learned, "_flush_subnormals", dict)
    raw = shipped_members(members=LEARNED_PERCEPTRONS)
    for a, b in zip(flushed, raw, strict=True):
        subnormal = [k for k, v in b._a.items() if isinstance(v, np.ndarray) and v.dtype.kind == "f"
                     and ((v != 0) & (np.abs(v) < np.finfo(v.dtype).tiny)).any()]
        assert "w1" in subnormal  # what the flush is for: as shipped, they hold some
        assert not any(((v != 0) & (np.abs(v) < np.finfo(v.dtype).tiny)).any()
                       for v in a._a.values() if isinstance(v, np.ndarray) and v.dtype.kind == "f")
        ca, cb = a.calibrated(made.mask(rest)), b.calibrated(made.mask(rest))
        for m in masks:
            ea, eb = ca.estimate(m), cb.estimate(m)
            np.testing.assert_allclose(ea.angles, eb.angles, rtol=0, atol=1e-9)
            assert ea.error == pytest.approx(eb.error, rel=1e-9)


def test_perceptrons_with_the_rest_frame_folded_in_read_as_with_the_plain_product():
    """A calibrated perceptron reads half its projection (the rest frame folded in, cells no
    component weighs left out): its codes and angles must be those of the plain product."""
    from handsynth.eval import model_test_hands, natural_test_poses, relaxed_rest_posture

    made = model_test_hands(1, seed=48)[0].make()
    rng = np.random.default_rng(4)
    rest = relaxed_rest_posture(rng)
    masks = made.masks(natural_test_poses(rest, 6, rng)[0])
    for est in shipped_members(members=LEARNED_PERCEPTRONS):
        cal = est.calibrated(made.mask(rest))
        plain = est.calibrated(made.mask(rest))
        plain._fold = None
        keep = cal._fold[0]
        assert 1000 < len(keep) < 1350  # the cells no component weighs are left out
        for m in masks:
            np.testing.assert_allclose(cal.code(m), plain.code(m), rtol=0, atol=1e-4)
            a, b = cal.estimate(m), plain.estimate(m)
            np.testing.assert_allclose(a.angles, b.angles, rtol=0, atol=1e-3)
            assert a.error == pytest.approx(b.error, rel=1e-5)
            assert a.confidence == pytest.approx(b.confidence, rel=1e-5)
