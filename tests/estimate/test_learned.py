import json
import re
from dataclasses import replace

import numpy as np
import pytest

from handsynth.db import LearningSetOptions, render_learning_set
from handsynth.errors import DatabaseMismatchError, InvalidInputError
from handsynth.estimate import (
    LearnedEstimator,
    LearnedOptions,
    PoseEstimator,
    fit_mlp,
    learned_estimator,
    local_linear,
    train_learned,
)
from handsynth.models import named_pose
from handsynth.render import SilhouetteRasterizer

DATA = LearningSetOptions(hands=6, poses_per_hand=10, seed=2)


@pytest.fixture(scope="module")
def data():
    return render_learning_set(DATA)


def _frames(data, rows):
    """Masks whose coverage equals the learning set's stored grids (cells of 16x16 pixels)."""
    return [np.repeat(np.repeat(data.grids[i].reshape(30, 45), 16, 0), 16, 1) >= 128 for i in rows]


def test_fit_mlp_learns_a_smooth_function():
    rng = np.random.default_rng(0)
    x = rng.normal(size=(2000, 3)).astype(np.float32)
    y = np.stack([x[:, 0] - 2 * x[:, 1], np.abs(x[:, 2])], axis=1).astype(np.float32)
    w, b = fit_mlp(x, y, hidden=(32,), epochs=30, batch=64, learning_rate=3e-3)
    h = np.maximum(x @ w[0] + b[0], 0) @ w[1] + b[1]
    assert np.mean((h - y) ** 2) < 0.02 * np.var(y)


def test_fit_mlp_absolute_loss_answers_the_median_where_squared_answers_the_mean():
    # one input, skewed answers: 70 % at 0, 30 % at 10 (mean 3, median 0)
    rng = np.random.default_rng(1)
    x = np.ones((4000, 1), np.float32)
    y = np.where(rng.random((4000, 1)) < 0.3, 10.0, 0.0).astype(np.float32)
    out = {}
    for loss in ("squared", "absolute"):
        w, b = fit_mlp(x, y, hidden=(8,), epochs=20, batch=100, learning_rate=1e-2, loss=loss)
        out[loss] = float((np.maximum(x[:1] @ w[0] + b[0], 0) @ w[1] + b[1])[0, 0])
    assert abs(out["squared"] - 3.0) < 0.5 and abs(out["absolute"]) < 0.5
    with pytest.raises(InvalidInputError, match="loss must be 'squared' or 'absolute', got 'l1'"):
        fit_mlp(x, y, loss="l1")


def test_fit_mlp_reads_weights_decayed_to_subnormal_floats_as_zero(monkeypatch):
    """Weight decay takes the weights from inputs that never vary down to subnormal floats
    (slow products on many processors): fit_mlp sets them to 0 and learns the same function."""
    from handsynth.estimate import _learned

    rng = np.random.default_rng(0)
    x = rng.normal(size=(512, 6)).astype(np.float32)
    x[:, 3:] = 0  # their weights feel only the decay
    y = (x[:, :1] * 2 - x[:, 1:2]).astype(np.float32)
    tiny = np.finfo(np.float32).tiny

    def subnormal(arrays):
        return sum(int(((a != 0) & (np.abs(a) < tiny)).sum()) for a in arrays)

    flushed = fit_mlp(x, y, hidden=(16,), epochs=200, batch=64, seed=1)
    monkeypatch.setattr(_learned, "_flush_in_place", lambda arrays: None)
    kept = fit_mlp(x, y, hidden=(16,), epochs=200, batch=64, seed=1)
    assert subnormal(kept[0]) > 0 and subnormal(flushed[0]) == 0
    test = rng.normal(size=(200, 6)).astype(np.float32)
    np.testing.assert_allclose(_learned._relu_forward(test, *flushed)[-1],
                               _learned._relu_forward(test, *kept)[-1], rtol=1e-6, atol=1e-6)


def test_the_loss_names_a_new_cache_only_when_not_the_default():
    assert LearnedOptions(kind="mlp").digest() == LearnedOptions(kind="mlp", loss="squared").digest()
    assert LearnedOptions(kind="mlp").digest() != LearnedOptions(kind="mlp", loss="absolute").digest()


@pytest.mark.parametrize(("kind", "target"), [("knn", "delta"), ("knn", "angles"), ("mlp", "delta"),
                                              ("mlp", "angles"), ("fingers", "angles")])
def test_learned_estimators_implement_the_interface_and_need_the_rest_frame(data, kind, target):
    est = train_learned(data, LearnedOptions(kind=kind, target=target, components=16,
                                             hidden=(16,), epochs=2, k=1))
    assert isinstance(est, PoseEstimator)
    frame = SilhouetteRasterizer().mask(np.zeros(20))
    with pytest.raises(InvalidInputError, match="calibrated"):
        est.estimate(frame)
    cal = est.calibrated(frame)
    e = cal.estimate(frame)
    assert e.angles.shape == (20,) and np.isfinite(e.angles).all() and not e.no_hand
    assert cal.estimate(np.zeros((480, 720), bool)).no_hand
    with pytest.raises(InvalidInputError, match="rest_frame shows no hand"):
        est.calibrated(np.zeros((480, 720), bool))


def test_nearest_neighbour_of_a_learning_frame_is_that_frame(data):
    est = train_learned(data, LearnedOptions(kind="knn", target="angles", components=400, k=1))
    hand = 2
    rows = np.nonzero(data.hand == hand)[0][:4]
    rest = np.repeat(np.repeat(data.rest_grids[hand].reshape(30, 45), 16, 0), 16, 1) >= 128
    cal = est.calibrated(rest)
    cal._rest = data.rest_grids[hand]  # the stored grid itself (the mask above rounds it)
    for i, f in zip(rows, _frames(data, rows)):
        g = cal.grid(f).ravel()
        if np.array_equal(g, data.grids[i]):
            np.testing.assert_allclose(cal.estimate(f).angles, data.angles[i], atol=1e-3)


def test_each_digit_is_read_from_the_cells_it_changes():
    data = render_learning_set(LearningSetOptions(hands=20, poses_per_hand=20, seed=3))
    est = train_learned(data, LearnedOptions(kind="fingers", k=1))
    cells = 30 * 45
    for d in range(5):
        cols = est._a[f"d{d}_cols"]
        assert 0 < len(cols) < 2 * cells
        # the same cells of the frame and of its difference from the rest frame
        np.testing.assert_array_equal(cols[cols >= cells] - cells, cols[cols < cells])
    # the thumb side is at the top of the image: the index's cells weigh higher than the little's
    rows = {}
    for d in (1, 4):
        cols, w = est._a[f"d{d}_cols"], est._a[f"d{d}_w"]
        top = cols[np.argsort(w)[::-1][:20]] % cells
        rows[d] = np.mean(top // 45)
    assert rows[1] < rows[4]


def test_without_the_rest_frame_an_estimator_reads_frames_directly(data):
    est = train_learned(data, LearnedOptions(kind="mlp", use_rest=False, components=16,
                                             hidden=(8,), epochs=1))
    assert np.isfinite(est.estimate(SilhouetteRasterizer().mask(np.zeros(20))).angles).all()


def test_learnt_estimators_are_kept_in_the_caller_s_folder(tmp_path):
    opts = LearnedOptions(kind="mlp", components=8, hidden=(8,), epochs=1)
    small = LearningSetOptions(hands=2, poses_per_hand=5, seed=1)
    a = learned_estimator(tmp_path, opts, data=small)
    files = sorted(p.name.split("_")[0] for p in tmp_path.glob("*.npz"))
    assert files == ["learned", "learning"]
    b = learned_estimator(tmp_path, opts, data=small)
    assert isinstance(b, LearnedEstimator)
    frame = SilhouetteRasterizer().mask(np.full(20, 5.0))
    np.testing.assert_array_equal(a.calibrated(frame).estimate(frame).angles,
                                  b.calibrated(frame).estimate(frame).angles)


def test_the_local_linear_fit_reads_a_linear_neighbourhood_exactly_and_shrinks_to_the_mean():
    rng = np.random.default_rng(3)
    x = rng.normal(size=(40, 5))
    slope = rng.normal(size=(5, 2))
    y = 30.0 + x @ slope * 10
    w = rng.uniform(0.5, 2.0, 40)
    # the neighbours lie on a plane: the fit at the query (x = 0) is its offset
    np.testing.assert_allclose(local_linear(x, y, w, ridge=0.0), [30.0, 30.0], atol=1e-9)
    # the weighted mean is pulled off by the neighbours' asymmetric spread
    x_shifted = x + 1.0
    mean = w @ (30.0 + x_shifted @ slope * 10) / w.sum()
    fit = local_linear(x_shifted, 30.0 + x_shifted @ slope * 10, w, ridge=0.0)
    np.testing.assert_allclose(fit, [30.0, 30.0], atol=1e-9)
    assert np.abs(mean - 30.0).max() > 1.0
    # a very large ridge leaves only the intercept: the weighted mean
    np.testing.assert_allclose(local_linear(x_shifted, 30.0 + x_shifted @ slope * 10, w,
                                            ridge=1e9), mean, atol=1e-4)


@pytest.mark.parametrize("ridge", [0.0, 3.0])
def test_the_digits_fitted_together_read_as_each_fitted_alone(ridge):
    from handsynth.estimate._learned import _local_linear, _local_linear_stack

    rng = np.random.default_rng(5)
    x = rng.normal(size=(5, 128, 64)).astype(np.float32)
    y = rng.normal(20.0, 15.0, size=(5, 128, 4)).astype(np.float32)
    w = rng.uniform(0.1, 3.0, size=(5, 128))
    alone = [_local_linear(x[b], y[b], w[b], ridge=ridge) for b in range(5)]
    np.testing.assert_allclose(_local_linear_stack(x, y, w, ridge=ridge), alone,
                               rtol=0, atol=1e-9)


def test_the_cholesky_solve_says_where_a_system_is_not_positive_definite(monkeypatch):
    from handsynth.estimate import _learned
    from handsynth.estimate._learned import _local_linear, _local_linear_stack, _solve_spd

    rng = np.random.default_rng(6)
    m = rng.normal(size=(3, 9, 9))
    a = m @ m.transpose(0, 2, 1) + 0.1 * np.eye(9)
    a[1] -= 50.0 * np.eye(9)  # indefinite
    b = rng.normal(size=(3, 9, 2))
    x, ok = _solve_spd(a, b)
    assert ok.tolist() == [True, False, True]
    np.testing.assert_allclose(x[[0, 2]], np.linalg.solve(a[[0, 2]], b[[0, 2]]), atol=1e-9)
    # a fit whose system the Cholesky refuses is solved by LU instead, to the same answer
    refused = _solve_spd

    def refuse_the_second(gram, rhs):
        x, ok = refused(gram, rhs)
        ok[1] = False
        return x, ok

    monkeypatch.setattr(_learned, "_solve_spd", refuse_the_second)
    xs = rng.normal(size=(3, 40, 6))
    ys = rng.normal(size=(3, 40, 4))
    ws = rng.uniform(0.5, 2.0, size=(3, 40))
    np.testing.assert_allclose(_local_linear_stack(xs, ys, ws, ridge=1.0),
                               [_local_linear(xs[i], ys[i], ws[i], ridge=1.0) for i in range(3)],
                               rtol=0, atol=1e-9)


def test_a_fingers_estimator_reads_each_digit_as_its_own_search_and_fit(data):
    from handsynth.estimate._learned import _inputs

    est = train_learned(data, LearnedOptions(kind="fingers", components=8, k=24, lists=0))
    cal = est.calibrated(SilhouetteRasterizer().mask(np.full(20, 4.0)))
    for frame in _frames(data, [3, 17, 42]):
        got = cal.estimate(frame).angles
        z = _inputs(cal.grid(frame).reshape(1, -1), cal._rest[None])
        alone = np.empty(20)
        for d, joints in enumerate(((0, 1, 2, 3), *(range(4 + 4 * k, 8 + 4 * k)
                                                     for k in range(4)))):
            alone[list(joints)] = cal._knn(f"d{d}_", cal._digit_code(d, z)[0])[0]
        assert cal._rest_angles is None  # angles learnt directly (target "angles")
        want = np.clip(alone, cal._lo, cal._hi)
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-9)


def test_the_linear_fit_falls_back_to_the_mean_with_fewer_neighbours_than_dimensions(data):
    rest = SilhouetteRasterizer().mask(np.full(20, 4.0))
    frame = SilhouetteRasterizer().mask(np.full(20, 20.0))
    lin = train_learned(data, LearnedOptions(kind="fingers", k=3, local="linear", lists=0))
    mean = train_learned(data, LearnedOptions(kind="fingers", k=3, local="mean", lists=0))
    np.testing.assert_array_equal(lin.calibrated(rest).estimate(frame).angles,
                                  mean.calibrated(rest).estimate(frame).angles)
    many = train_learned(data, LearnedOptions(kind="fingers", k=60, components=4, lists=0))
    many_mean = train_learned(data, LearnedOptions(kind="fingers", k=60, components=4, lists=0,
                                                   local="mean"))
    assert not np.allclose(many.calibrated(rest).estimate(frame).angles,
                           many_mean.calibrated(rest).estimate(frame).angles)


def test_a_frame_of_another_aspect_ratio_is_refused_with_its_size(data):
    est = train_learned(data, LearnedOptions(kind="fingers", k=2, use_rest=False))
    full = SilhouetteRasterizer().mask(np.full(20, 10.0))
    half = full[::2, ::2]  # the same view at half the resolution gives the same grid
    diff = np.abs(est.grid(half).astype(int) - est.grid(full).astype(int))
    assert diff.mean() < 2 and est.grid(full).mean() > 20
    with pytest.raises(InvalidInputError, match=r"frame is 640x480 pixels.*720x480"):
        est.estimate(np.zeros((480, 640), bool))


def test_frames_unlike_any_hand_are_flagged_low_confidence(data):
    est = train_learned(data, LearnedOptions(kind="fingers", k=8, lists=0))
    limit = float(est._a["novelty_limit"])
    assert limit > 0
    rest = _frames(data, [0])[0]
    cal = est.calibrated(rest)
    hand = cal.estimate(_frames(data, [1])[0])
    assert hand.error <= limit and not hand.low_confidence
    odd = cal.estimate(np.ones_like(rest))  # a bright background filling the view
    assert odd.error > limit and odd.low_confidence


def _rest_mask(data, hand):
    """A mask whose coverage is hand `hand`'s stored rest grid (cells of 16x16 pixels)."""
    return np.repeat(np.repeat(data.rest_grids[hand].reshape(30, 45), 16, 0), 16, 1) >= 128


@pytest.mark.parametrize("kind", ["mlp", "knn"])
def test_a_perceptron_flags_frames_whose_input_its_components_leave_out(data, kind):
    from handsynth.estimate._learned import _inputs, _left_out_norms

    est = train_learned(data, LearnedOptions(kind=kind, components=8, hidden=(8,), epochs=1))
    limit = float(est._a["novelty_limit"])
    # the limit is the 99th percentile of what the components leave out of the learning inputs
    z = _inputs(data.grids, data.rest_grids[data.hand])
    centred = z - est._a["mean"]
    norms = _left_out_norms(centred, centred @ est._a["components"])
    assert limit == pytest.approx(float(np.quantile(norms, 0.99)), rel=1e-5)
    assert 0 < limit < norms.max() + 1e-6
    rest = _rest_mask(data, 0)
    cal = est.calibrated(rest)
    frames = _frames(data, np.flatnonzero(data.hand == 0))
    ins = _inputs(np.stack([cal.grid(f).ravel() for f in frames]), cal.grid(rest).ravel()[None])
    centred = ins - est._a["mean"]
    left_out = _left_out_norms(centred, centred @ est._a["components"])
    got = [cal.estimate(f) for f in frames]
    assert [g.low_confidence for g in got] == list(left_out > limit)
    if kind == "mlp":  # its error is what the components leave out
        assert np.allclose([g.error for g in got], left_out, rtol=1e-4)
    white = cal.estimate(np.ones((480, 720), bool))  # a bright background filling the view
    assert white.low_confidence and not white.no_hand
    # an estimator stored without a limit (learnt by an earlier release) flags nothing
    del est._a["novelty_limit"]
    assert not est.calibrated(_rest_mask(data, 0)).estimate(np.ones((480, 720), bool)).low_confidence


def test_bad_options_are_refused_by_name():
    with pytest.raises(InvalidInputError, match="kind must be 'mlp', 'knn' or 'fingers'"):
        LearnedOptions(kind="forest")
    with pytest.raises(InvalidInputError, match="target"):
        LearnedOptions(target="pose")
    with pytest.raises(InvalidInputError, match="components"):
        LearnedOptions(components=0)
    with pytest.raises(InvalidInputError, match="local must be 'linear' or 'mean'"):
        LearnedOptions(local="cubic")
    with pytest.raises(InvalidInputError, match="ridge"):
        LearnedOptions(ridge=-1.0)
    with pytest.raises(InvalidInputError, match="loss must be 'squared' or 'absolute', got 'l2'"):
        LearnedOptions(loss="l2")
    for seed in (-1, 1.5, True):
        with pytest.raises(InvalidInputError, match=rf"LearnedOptions.seed must be an integer "
                                                    rf">= 0, got {seed!r}"):
            LearnedOptions(seed=seed)


def test_a_stored_estimator_missing_a_part_is_refused_on_load(data, tmp_path):
    from handsynth.errors import DatabaseCorruptError, DatabaseError

    with pytest.raises(DatabaseError, match=r"learnt estimator .*nowhere.npz does not exist"):
        LearnedEstimator.load(tmp_path / "nowhere.npz")
    est = train_learned(data, LearnedOptions(kind="mlp", components=8, hidden=(8,), epochs=1))
    est.save(tmp_path / "m.npz")
    with np.load(tmp_path / "m.npz") as z:
        parts = {k: z[k] for k in z.files}
    meta = json.loads(str(parts["meta"]))

    def damaged(name, **changed):
        path = tmp_path / name
        np.savez(path, **{**parts, **changed})
        return path

    no_b0 = damaged("no_b0.npz")
    np.savez(no_b0, **{k: v for k, v in parts.items() if k != "b0"})
    with pytest.raises(DatabaseCorruptError, match=r"no_b0.npz is incomplete: it has no array "
                                                   r"'b0'"):
        LearnedEstimator.load(no_b0)
    no_options = damaged("no_options.npz", meta=np.array(json.dumps(
        {k: v for k, v in meta.items() if k != "options"})))
    with pytest.raises(DatabaseCorruptError, match=r"no_options.npz: its meta has no 'options'"):
        LearnedEstimator.load(no_options)
    bad_side = damaged("bad_side.npz", meta=np.array(json.dumps(dict(meta, side="up"))))
    with pytest.raises(DatabaseCorruptError, match=r"bad_side.npz: meta 'side' is unusable"):
        LearnedEstimator.load(bad_side)
    for name in ("w0", "novelty_limit"):
        nan = damaged(f"nan_{name}.npz", **{name: np.where(np.arange(parts[name].size).reshape(
            parts[name].shape) == 0, np.nan, parts[name])})
        with pytest.raises(DatabaseCorruptError, match=rf"nan_{name}.npz is damaged: array "
                                                       rf"'{name}' holds 1 NaN or infinite values"):
            LearnedEstimator.load(nan)
    back = LearnedEstimator.load(damaged("whole.npz"))  # the parts as saved: read as before
    frame = _frames(data, [3])[0]
    rest = _frames(data, [0])[0]
    assert np.array_equal(back.calibrated(rest).estimate(frame).angles,
                          est.calibrated(rest).estimate(frame).angles)


def test_a_grid_of_other_cells_is_refused_with_its_shape(data):
    est = train_learned(data, LearnedOptions(kind="fingers", k=2, lists=0))
    with pytest.raises(InvalidInputError, match=r"30x45 uint8 coverage grid, got uint8 of "
                                                r"shape \(45, 30\)"):
        est.estimate_grid(np.zeros((45, 30), np.uint8))


def test_an_ensemble_reports_the_weighted_mean_and_calibrates_its_members(data):
    from handsynth.estimate import EnsembleEstimator

    a = train_learned(data, LearnedOptions(kind="fingers", k=2))
    b = train_learned(data, LearnedOptions(kind="knn", target="angles", components=16, k=1))
    ens = EnsembleEstimator([a, b], weights=[3, 1])
    assert isinstance(ens, PoseEstimator)
    rest = SilhouetteRasterizer().mask(np.full(20, 4.0))
    frame = SilhouetteRasterizer().mask(np.full(20, 12.0))
    cal = ens.calibrated(rest)
    expect = (0.75 * a.calibrated(rest).estimate(frame).angles
              + 0.25 * b.calibrated(rest).estimate(frame).angles)
    np.testing.assert_allclose(cal.estimate(frame).angles, expect)
    assert cal.estimate(np.zeros((480, 720), bool)).no_hand
    with pytest.raises(InvalidInputError, match="weights"):
        EnsembleEstimator([a, b], weights=[1, -1])
    with pytest.raises(InvalidInputError, match="at least one"):
        EnsembleEstimator([])


@pytest.mark.parametrize("quantize", [False, True])
def test_the_inverted_file_with_one_cell_answers_as_the_exact_search(data, quantize):
    exact = train_learned(data, LearnedOptions(kind="fingers", k=5, lists=0))
    ivf = train_learned(data, LearnedOptions(kind="fingers", k=5, lists=1, probes=1,
                                             quantize=quantize))
    kind = "IndexIVFScalarQuantizer" if quantize else "IndexIVFFlat"
    assert type(ivf._index["d1_"]).__name__ == kind
    assert type(exact._index["d1_"]).__name__ == "IndexFlatL2"
    rest = SilhouetteRasterizer().mask(np.full(20, 4.0))
    a, b = exact.calibrated(rest), ivf.calibrated(rest)
    for pose in (np.full(20, 12.0), np.full(20, 18.0), np.full(20, 8.0)):
        frame = SilhouetteRasterizer().mask(pose)
        ea, eb = a.estimate(frame), b.estimate(frame)
        np.testing.assert_allclose(ea.angles, eb.angles, atol=1e-4)
        # distances re-measured on the float codes: the quantised search reports exact ones
        assert eb.error == pytest.approx(ea.error, rel=1e-5)


@pytest.mark.parametrize("quantize", [False, True])
def test_a_saved_estimator_reads_its_inverted_files_back_instead_of_training_them(
        data, tmp_path, monkeypatch, quantize):
    import faiss

    opts = LearnedOptions(kind="fingers", k=5, lists=1, probes=1, quantize=quantize)
    est = train_learned(data, opts)
    est.save(tmp_path / "f.npz")
    suffix = "ivf_sq8" if quantize else "ivf_flat"
    with np.load(tmp_path / "f.npz") as z:
        assert sorted(k for k in z.files if "ivf" in k) == [f"d{d}_{suffix}" for d in range(5)]
    kind = faiss.IndexIVFScalarQuantizer if quantize else faiss.IndexIVFFlat

    def no_training(*_args):
        raise AssertionError("trained, not read")

    with monkeypatch.context() as m:
        m.setattr(kind, "train", no_training)
        back = LearnedEstimator.load(tmp_path / "f.npz")
    assert sorted(back._a) == sorted(est._a)  # the inverted files are not learnt arrays
    def neighbours(e, d):
        q = np.ascontiguousarray(est._a[f"d{d}_codes"][::3] + 0.01, np.float32)
        return e._index[f"d{d}_"].search(q, 5)[1]

    for d in range(5):
        assert type(back._index[f"d{d}_"]) is kind
        np.testing.assert_array_equal(neighbours(back, d), neighbours(est, d))
    # the other reading option trains its own, as an estimator learnt with it has
    flip = replace(opts, quantize=not quantize)
    other = LearnedEstimator.load(tmp_path / "f.npz", options=flip)
    assert type(other._index["d1_"]) is not kind and sorted(other._a) == sorted(est._a)
    np.testing.assert_array_equal(neighbours(other, 1), neighbours(train_learned(data, flip), 1))


def test_a_stored_inverted_file_that_does_not_fit_the_codes_is_trained_afresh(data):
    from handsynth.estimate._learned import _search_index

    opts = LearnedOptions(kind="fingers", lists=1, probes=1)
    codes = np.ascontiguousarray(data.grids[:, :8], np.float32)
    fresh = _search_index(codes, opts)
    for stored in (np.zeros(16, np.uint8),                                    # not an index
                   _search_index_bytes(codes[:-1], opts),                    # other codes
                   _search_index_bytes(codes, replace(opts, quantize=False))):  # other kind
        index = _search_index(codes, opts, stored=stored)
        assert type(index) is type(fresh) and index.ntotal == len(codes)
        np.testing.assert_array_equal(index.search(codes[:4], 3)[1], fresh.search(codes[:4], 3)[1])


def _search_index_bytes(codes, opts):
    import faiss

    from handsynth.estimate._learned import _search_index

    return faiss.serialize_index(_search_index(codes, opts))


def test_search_options_do_not_rename_a_perceptron_s_cache():
    # a perceptron searches nothing; its cache keeps the name earlier releases gave it
    assert LearnedOptions(kind="mlp").digest() == "f981de6f398ffdd8"
    assert LearnedOptions(kind="mlp", seed=1).digest() == "21e795ea8342a7c2"
    assert (LearnedOptions(kind="mlp", lists=64, probes=2).digest()
            == LearnedOptions(kind="mlp").digest())
    # what a perceptron learns still names it, and the search still names the per-digit kind
    assert LearnedOptions(kind="mlp", epochs=3).digest() != LearnedOptions(kind="mlp").digest()
    assert LearnedOptions(probes=2).digest() != LearnedOptions().digest()


def test_the_quantised_search_is_a_reading_option(tmp_path):
    assert LearnedOptions(quantize=False).digest() == LearnedOptions().digest()
    with pytest.raises(InvalidInputError, match="quantize must be True or False, got 'no'"):
        LearnedOptions(quantize="no")


def test_training_a_block_of_rows_at_a_time_equals_the_whole_set_at_once(data):
    """The inputs are made a block at a time; the plain reference makes them all at once."""
    from handsynth.estimate._learned import _correlations, _fit_digits, _inputs, _Rows

    rows = _Rows(data.grids, data.rest_grids, data.hand)
    whole = _inputs(data.grids, data.rest_grids[data.hand])
    np.testing.assert_array_equal(rows.take(slice(None)), whole)
    # reference correlation: numpy's corrcoef of each cell with each angle
    y = data.angles.astype(np.float64)
    x = whole[:, :data.grids.shape[1]].astype(np.float64)
    with np.errstate(invalid="ignore", divide="ignore"):  # constant cells correlate 0
        ref = np.nan_to_num(np.abs(np.corrcoef(x.T, y.T)[:x.shape[1], x.shape[1]:]))
    got = _correlations(rows, data.angles, data.grids.shape[1], block=7)
    np.testing.assert_allclose(got, ref, atol=1e-9)
    opts = LearnedOptions(components=16)
    small = _fit_digits(rows, data.angles, opts, np.random.default_rng(3), block=7)
    big = _fit_digits(rows, data.angles, opts, np.random.default_rng(3), block=10**9)
    assert small.keys() == big.keys()
    for key in small:
        np.testing.assert_allclose(small[key], big[key], rtol=1e-5, atol=1e-5, err_msg=key)
    # the codes are the components of the whole inputs' digit columns
    p = "d1_"
    ref_codes = (whole[:, big[p + "cols"]] * big[p + "w"] - big[p + "mean"]) @ big[p + "components"]
    np.testing.assert_allclose(big[p + "codes"], ref_codes, rtol=1e-5, atol=1e-5)


def test_reading_options_read_the_same_learnt_arrays(tmp_path):
    small = LearningSetOptions(hands=2, poses_per_hand=5, seed=1)
    first = LearnedOptions(kind="fingers", components=8, k=8, lists=0)
    a = learned_estimator(tmp_path, first, data=small)
    learnt = sorted(p.name for p in tmp_path.glob("learned_*.npz"))
    other = LearnedOptions(kind="fingers", components=8, k=4, ridge=0.5, local="mean", lists=0)
    b = learned_estimator(tmp_path, other, data=small)
    assert sorted(p.name for p in tmp_path.glob("learned_*.npz")) == learnt   # read, not learnt
    assert b.options == other and a.options == first
    # what it answers is what an estimator learnt with those options answers
    fresh = learned_estimator(tmp_path / "fresh", other, data=small)
    frame = SilhouetteRasterizer().mask(np.full(20, 20.0))
    rest = SilhouetteRasterizer().mask(np.full(20, 5.0))
    np.testing.assert_array_equal(b.calibrated(rest).estimate(frame).angles,
                                  fresh.calibrated(rest).estimate(frame).angles)
    # an option that shapes what is learnt makes another file, and cannot read this one
    c = learned_estimator(tmp_path, LearnedOptions(kind="fingers", components=6, lists=0),
                          data=small)
    assert len(list(tmp_path.glob("learned_*.npz"))) == 2 and c.options.components == 6
    with pytest.raises(DatabaseMismatchError, match="learnt with other options \\(components=8\\)"):
        LearnedEstimator.load(tmp_path / learnt[0], options=LearnedOptions(components=6, lists=0))


def test_an_ensemble_member_can_learn_from_another_learning_set(tmp_path):
    from handsynth.estimate import learned_ensemble

    mlp = LearnedOptions(kind="mlp", components=8, hidden=(8,), epochs=1, seed=0)
    first = learned_estimator(tmp_path, mlp, data=DATA)
    ens = learned_ensemble(tmp_path, members=((mlp, 0.5), (mlp, 0.5, (("seed", 5),))),
                           data=DATA, learnt=[first])
    # the first member is the one already read; the second, with the same options, is learnt
    # from the set the change makes, kept beside the first
    assert ens.members[0] is first and ens.members[1] is not first
    assert not np.allclose(ens.members[0]._a["mean"], ens.members[1]._a["mean"])
    assert len(list(tmp_path.glob("learning_*.npz"))) == 2
    assert len(list(tmp_path.glob("learned_mlp_*.npz"))) == 2
    same = learned_estimator(tmp_path, mlp, data=LearningSetOptions(hands=6, poses_per_hand=10,
                                                                     seed=5))
    np.testing.assert_array_equal(same._a["mean"], ens.members[1]._a["mean"])
    with pytest.raises(InvalidInputError, match="name no option of LearningSetOptions: hand"):
        learned_ensemble(tmp_path, members=((mlp, 1.0, (("hand", 3),)),), data=DATA)
    with pytest.raises(InvalidInputError, match="an ensemble member is"):
        learned_ensemble(tmp_path, members=((mlp,),), data=DATA)


def test_a_member_learning_set_may_scale_the_hands():
    from handsynth.estimate import member_learning_set

    assert member_learning_set(DATA, ()) == DATA
    assert member_learning_set(DATA, (("hands_factor", 2),)) == replace(DATA, hands=12)
    assert member_learning_set(DATA, [("hands_factor", 0.01)]).hands == 1
    both = member_learning_set(LearningSetOptions(), (("hands_factor", 2), ("open_rest_share", 0.0)))
    assert both == LearningSetOptions(hands=8000, open_rest_share=0.0)
    for bad in (0, -1, "2", True, float("nan")):
        with pytest.raises(InvalidInputError, match=f"hands_factor must be a positive number, "
                                                    f"got {bad!r}"):
            member_learning_set(DATA, (("hands_factor", bad),))
    with pytest.raises(InvalidInputError, match="name no option of LearningSetOptions: hands_scale"):
        member_learning_set(DATA, (("hands_scale", 2),))


def test_the_largest_learning_set_is_the_one_the_commands_judge_their_workers_by():
    from handsynth.db import learning_workers
    from handsynth.estimate import LEARNED_ENSEMBLES, largest_learning_set

    small = LearningSetOptions(hands=150)
    # the default ensemble's perceptrons learn from four times the hands
    assert largest_learning_set(small) == 600
    assert largest_learning_set(small, LEARNED_ENSEMBLES["perceptrons"]) == 600
    assert largest_learning_set(small, ()) == 150  # a single estimator learns from the set itself
    assert largest_learning_set(small, ((LearnedOptions(), 1.0, (("hands_factor", 0.5),)),)) == 150
    # so a run of 150 hands renders the perceptrons' sets of 600 on every core (at most 8)
    assert learning_workers(largest_learning_set(small)) == learning_workers(600) >= 1
    assert learning_workers(small.hands) == 1


def test_learned_ensemble_weights_its_members_and_reuses_those_already_read(tmp_path):
    from handsynth.estimate import EnsembleEstimator, learned_ensemble

    fingers = LearnedOptions(kind="fingers", components=6, k=4, lists=0)
    members = ((fingers, 0.5), (LearnedOptions(kind="mlp", components=8, hidden=(8,), epochs=1,
                                               seed=0), 0.2),
               (LearnedOptions(kind="mlp", components=8, hidden=(8,), epochs=1, seed=1), 0.3))
    first = learned_estimator(tmp_path, fingers, data=DATA)
    ens = learned_ensemble(tmp_path, members=members, data=DATA, learnt=[first])
    assert isinstance(ens, EnsembleEstimator) and ens.members[0] is first
    np.testing.assert_allclose(ens.weights, [0.5, 0.2, 0.3])
    assert [m.options.seed for m in ens.members[1:]] == [0, 1]
    # perceptrons of two seeds are two estimators, each kept in the folder
    assert not np.allclose(ens.members[1]._a["w0"], ens.members[2]._a["w0"])
    assert len(list(tmp_path.glob("learned_mlp_*.npz"))) == 2
    again = learned_ensemble(tmp_path, members=members, data=DATA)
    rest = SilhouetteRasterizer().mask(np.full(20, 4.0))
    frame = SilhouetteRasterizer().mask(np.full(20, 12.0))
    np.testing.assert_allclose(again.calibrated(rest).estimate(frame).angles,
                               ens.calibrated(rest).estimate(frame).angles)


def test_a_mirrored_estimator_reads_a_left_hand_as_the_right_reads_its_frame_upside_down(data):
    est = train_learned(data, LearnedOptions(kind="mlp", components=8, hidden=(8,), epochs=1))
    left = est.mirrored()
    assert (left.side, est.side) == ("left", "right") and left.mount == est.mount.mirrored()
    raster = SilhouetteRasterizer(mount=left.mount, side="left")
    rest, frame = raster.mask(np.full(20, 4.0)), raster.mask(named_pose("pinch"))
    got = left.calibrated(rest).estimate(frame)
    want = est.calibrated(rest[::-1]).estimate(frame[::-1])
    np.testing.assert_array_equal(got.angles, want.angles)
    assert got.moved == want.moved and not got.moved
    # calibrated then mirrored twice reads as the original; the mirror of a rest frame is no rest
    np.testing.assert_array_equal(est.calibrated(rest[::-1]).mirrored().mirrored().estimate(
        frame[::-1]).angles, want.angles)
    assert not np.array_equal(est.calibrated(rest).estimate(frame).angles, want.angles)


def test_a_left_hand_s_estimator_is_the_right_hand_s_mirrored_and_saves_what_was_learnt(tmp_path):
    opts = LearnedOptions(kind="mlp", components=8, hidden=(8,), epochs=1)
    small = LearningSetOptions(hands=2, poses_per_hand=5, seed=1)
    right = learned_estimator(tmp_path, opts, data=small)
    left = learned_estimator(tmp_path, opts, data=small, side="left")
    assert left.side == "left" and len(list(tmp_path.glob("*.npz"))) == 2  # nothing learnt again
    left.save(tmp_path / "again.npz")
    back = LearnedEstimator.load(tmp_path / "again.npz")
    assert back.side == "right"
    frame = SilhouetteRasterizer().mask(np.full(20, 5.0))
    np.testing.assert_array_equal(back.calibrated(frame).estimate(frame).angles,
                                  right.calibrated(frame).estimate(frame).angles)
    with pytest.raises(InvalidInputError, match="side must be 'right' or 'left', got 'both'"):
        learned_estimator(tmp_path, opts, data=small, side="both")


def test_segment_by_colour_is_an_option_of_the_calibration_and_follows_the_mirror(data):
    est = train_learned(data, LearnedOptions(kind="mlp", components=8, hidden=(8,), epochs=1))
    raster = SilhouetteRasterizer()
    rest_mask, mask = raster.mask(np.full(20, 4.0)), raster.mask(named_pose("pinch"))

    def paint(m):  # a skin-coloured hand over a ground brighter than it, where Otsu fails
        f = np.zeros(m.shape + (3,), np.uint8)
        f[:] = (230, 240, 200)
        f[m] = (120, 150, 210)
        return f

    with pytest.raises(InvalidInputError,
                       match="segment must be 'auto', 'brightness' or 'colour', got 'x'"):
        est.calibrated(paint(rest_mask), segment="x")
    with pytest.raises(InvalidInputError, match="rest_frame must be a uint8 colour"):
        est.calibrated(rest_mask, segment="colour")
    by_colour = est.calibrated(paint(rest_mask), segment="colour")
    assert ((by_colour.grid(paint(mask)) > 127) == (est.grid(mask) > 127)).mean() > 0.97
    by_brightness = est.calibrated(paint(rest_mask), segment="brightness")
    # Otsu's threshold takes the brighter ground for hand
    assert ((by_brightness.grid(paint(mask)) > 127) != (est.grid(mask) > 127)).mean() > 0.3
    # auto: by colour where the two disagree on the rest frame, by brightness where they agree
    assert (by_colour.segment, by_brightness.segment) == ("colour", "brightness")
    assert est.calibrated(paint(rest_mask)).segment == "colour"
    dark = paint(rest_mask)
    dark[~rest_mask] = 15
    assert est.calibrated(dark).segment == "brightness"
    assert est.calibrated(rest_mask).segment == "brightness"
    left = est.mirrored().calibrated(paint(rest_mask)[::-1], segment="colour")
    np.testing.assert_array_equal(left.estimate(paint(mask)[::-1]).angles,
                                  by_colour.estimate(paint(mask)).angles)


def test_an_ensemble_tells_the_hand_once_for_the_members_reading_one_view(data):
    from handsynth.estimate import EnsembleEstimator
    from handsynth.render import fit_skin_colour

    opts = LearnedOptions(kind="mlp", components=8, hidden=(8,), epochs=1)
    a, b = train_learned(data, opts), train_learned(data, replace(opts, seed=1))
    raster = SilhouetteRasterizer()
    rest = np.zeros((480, 720, 3), np.uint8)
    rest[:] = (230, 240, 200)  # a ground brighter than the hand
    rest[raster.mask(np.full(20, 4.0))] = (120, 150, 210)
    ens = EnsembleEstimator([a, b]).calibrated(rest)
    assert ens.segment == "colour" and ens.members[0].skin is ens.members[1].skin
    assert ens.members[1]._move_check is None  # the first member checks the shared grid
    # a fitted skin is taken as it is
    skin = fit_skin_colour(rest)
    assert a.calibrated(rest, segment=skin).skin is skin
    # a mirrored member reads its own grid (the frame turned over), never its neighbour's
    assert a.mirrored().view_key != a.view_key and a.view_key == b.view_key


def test_an_uncalibrated_estimator_stops_a_live_run_with_its_reason(data):
    from handsynth.errors import EstimationError
    from handsynth.estimate import EnsembleEstimator
    from handsynth.live import run_live

    est = train_learned(data, LearnedOptions(kind="knn", k=5, lists=0))
    frames = _frames(data, [3, 4, 5])

    class Source:
        reads = 0

        def read(self):
            self.reads += 1
            return frames[(self.reads - 1) % 3]

    for uncalibrated in (est, EnsembleEstimator([est, est])):
        src = Source()
        with pytest.raises(EstimationError, match=r"call calibrated\(rest_frame\) first"):
            run_live(uncalibrated, src)
        assert src.reads == 0
    rest = _frames(data, [0])[0]
    ready = est.calibrated(rest)
    ready.check_ready()
    EnsembleEstimator([ready]).check_ready()
    assert LearnedEstimator.check_ready(train_learned(
        data, LearnedOptions(kind="knn", k=5, lists=0, use_rest=False))) is None


def test_each_calibration_is_a_stream_of_its_own(data):
    # the move check remembers frames: one instance per camera stream
    est = train_learned(data, LearnedOptions(kind="knn", k=5, lists=0))
    rest = _frames(data, [0])[0]
    a, b = est.calibrated(rest), est.calibrated(rest)
    assert a._move_check is not None and a._move_check is not b._move_check
    assert a._a is b._a  # the learnt arrays are shared, not copied
    assert "one instance per\n    camera stream" in LearnedEstimator.__doc__
    assert "keeps no state" not in LearnedEstimator.__doc__


@pytest.mark.parametrize("value", [1, 1.0, 1.5, -0.1, float("nan"), float("inf"), "0.5", None,
                                   True, np.array([0.5])])
def test_smoothing_refuses_anything_but_a_finite_number_in_0_to_1_by_name(data, value):
    # the command line checked --smoothing; the estimator's attribute took 1.5 or "x"
    import re

    est = train_learned(data, LearnedOptions(kind="knn", k=5, lists=0))
    assert est.smoothing == 0.0
    with pytest.raises(InvalidInputError, match=rf"^smoothing must be a finite number >= 0 and "
                                                rf"< 1, got {re.escape(repr(value))}"):
        est.smoothing = value
    assert est.smoothing == 0.0  # unchanged


def test_smoothing_reports_the_weighted_mean_of_the_previous_and_the_new_answer(data):
    est = train_learned(data, LearnedOptions(kind="knn", k=5, lists=0))
    rest, a, b = _frames(data, [0, 3, 4])
    plain = est.calibrated(rest, check_moved=False)
    first, second = plain.estimate(a).angles, plain.estimate(b).angles
    smooth = est.calibrated(rest, check_moved=False)
    smooth.smoothing = np.float64(0.25)
    assert type(smooth.smoothing) is float and smooth.smoothing == 0.25
    assert np.allclose(smooth.estimate(a).angles, first)
    assert np.allclose(smooth.estimate(b).angles, 0.25 * first + 0.75 * second)
    kept = smooth.calibrated(rest)  # a copy keeps the setting, not the previous answer
    assert kept.smoothing == 0.25 and np.allclose(kept.estimate(b).angles, second)
    smooth.smoothing = 0  # off again
    assert smooth.smoothing == 0.0 and np.allclose(smooth.estimate(a).angles, first)


@pytest.mark.parametrize("field, value, words", [
    ("hidden", None, "LearnedOptions.hidden must be a tuple of positive integers (the widths of "
                     "the hidden layers), got NoneType None"),
    ("hidden", "384", "LearnedOptions.hidden must be a tuple of positive integers"),
    ("hidden", (), "LearnedOptions.hidden must be a tuple of positive integers"),
    ("hidden", (64, 0), "LearnedOptions.hidden[1] must be an integer >= 1, got 0"),
    ("hidden", (64.5,), "LearnedOptions.hidden[0] must be an integer >= 1, got 64.5"),
    ("hidden", (True,), "LearnedOptions.hidden[0] must be an integer >= 1, got True"),
    ("learning_rate", "0.01", "LearnedOptions.learning_rate must be a finite number > 0, "
                              "got '0.01' (str)"),
    ("learning_rate", float("inf"), "LearnedOptions.learning_rate must be a finite number > 0, "
                                    "got inf"),
    ("learning_rate", 0.0, "LearnedOptions.learning_rate must be a finite number > 0, got 0.0"),
    ("learning_rate", True, "LearnedOptions.learning_rate must be a finite number > 0, got True"),
    ("weight_decay", "x", "LearnedOptions.weight_decay must be a finite number >= 0, got 'x'"),
    ("weight_decay", float("nan"), "LearnedOptions.weight_decay must be a finite number >= 0, "
                                   "got nan"),
    ("weight_decay", -1e-5, "LearnedOptions.weight_decay must be a finite number >= 0"),
    ("ridge", True, "LearnedOptions.ridge must be a finite number >= 0, got True (bool)"),
    ("ridge", float("inf"), "LearnedOptions.ridge must be a finite number >= 0, got inf"),
    ("ridge", "3", "LearnedOptions.ridge must be a finite number >= 0, got '3' (str)"),
    ("use_rest", "no", "LearnedOptions.use_rest must be True or False, got 'no'"),
])
def test_each_numeric_field_is_checked_by_name(field, value, words):
    # hidden=None, learning_rate="0.01" and weight_decay="x" were raw TypeErrors;
    # learning_rate=inf and ridge=True were accepted
    with pytest.raises(InvalidInputError, match=re.escape(words)):
        LearnedOptions(**{field: value})


def test_valid_numeric_fields_keep_their_values():
    opts = LearnedOptions(hidden=[np.int64(16), 8], learning_rate=1, weight_decay=0, ridge=0)
    assert opts.hidden == (16, 8) and type(opts.hidden[0]) is int
    assert (opts.learning_rate, opts.weight_decay, opts.ridge) == (1, 0, 0)
    assert opts.digest() == LearnedOptions(hidden=(16, 8), learning_rate=1, weight_decay=0).digest()


def test_check_moved_must_be_a_bool(data):
    # check_moved="no" was read as True
    est = train_learned(data, LearnedOptions(kind="fingers", components=4, k=2, lists=0))
    rest = _frames(data, [0])[0]
    for value in ("no", 0, None, np.bool_(False)):
        with pytest.raises(InvalidInputError, match=rf"^check_moved must be a bool, got "
                                                    rf"{type(value).__name__} "):
            est.calibrated(rest, check_moved=value)
    assert est.calibrated(rest, check_moved=False)._move_check is None
    assert est.calibrated(rest)._move_check is not None


def test_a_folder_that_cannot_be_written_is_refused_before_the_learning_set(tmp_path,
                                                                            monkeypatch):
    # learned_estimator("some_file.h5") failed only after rendering the whole learning set
    import handsynth._io
    import handsynth.db._learning
    from handsynth.errors import DatabaseError

    def no_rendering(*args, **kwargs):
        raise AssertionError("the learning set was rendered")

    monkeypatch.setattr(handsynth.db._learning, "render_learning_set", no_rendering)
    small = LearningSetOptions(hands=2, poses_per_hand=3, seed=1)
    opts = LearnedOptions(kind="knn", components=4, k=2, lists=0)
    in_the_way = tmp_path / "some_file.h5"
    in_the_way.write_bytes(b"x")
    with pytest.raises(DatabaseError, match=rf"cannot create the learnt-estimator folder "
                                            rf"{re.escape(repr(str(in_the_way)))}"):
        learned_estimator(in_the_way, opts, data=small, shipped=False)
    monkeypatch.setattr(handsynth._io, "_unwritable", lambda folder: "the file system is read-only")
    with pytest.raises(DatabaseError, match=r"cannot write into the learnt-estimator folder .*"
                                            r"read-only"):
        learned_estimator(tmp_path / "cache", opts, data=small, shipped=False)
    for folder, words in ((None, "folder must be a folder name (str or path), got None"),
                          ("", "folder must name a folder, got ''")):
        with pytest.raises(InvalidInputError, match=re.escape(words)):
            learned_estimator(folder, opts, data=small)


def test_the_smallest_hand_covers_far_more_than_the_least_a_hand_covers():
    # MIN_HAND_COVERAGE's reason: every ratio 0.5, the most folded poses, the paper's view
    from handsynth.estimate import MIN_HAND_COVERAGE
    from handsynth.models import HandShape, named_pose
    from handsynth.render import CameraMount, SilhouetteRasterizer, coverage

    r = SilhouetteRasterizer(HandShape(length=0.5, width=0.5, palm=0.5, thumb=0.5),
                             CameraMount.paper())
    least = min(coverage(m, CameraMount.paper()).mean()
                for m in r.masks(np.array([named_pose(n) for n in ("fist", "grasp", "pinch")])))
    assert least > 6 * MIN_HAND_COVERAGE, least


def test_a_speck_is_no_hand_and_no_rest_frame(data):
    # one bright pixel in a dark view was read as a hand with confidence 0.66-0.74
    est = train_learned(data, LearnedOptions(kind="fingers", components=4, k=2, lists=0))
    speck = np.zeros((480, 720), bool)
    speck[200:202, 300:340] = True  # 80 pixels, 0.02 % of the view
    with pytest.raises(InvalidInputError, match=r"^rest_frame shows no hand: what stands out covers "
                                                r"0\.0\d % of the view, a hand at least 1 %"):
        est.calibrated(speck)
    cal = est.calibrated(_frames(data, [0])[0])
    got = cal.estimate(speck)
    assert got.no_hand and got.low_confidence and np.isnan(got.angles).all()
    assert not cal.estimate(_frames(data, [1])[0]).no_hand


@pytest.mark.parametrize("args, words", [
    (dict(x=np.zeros((3, 2)), y=np.zeros((4, 1)), w=np.ones(3)),
     r"y: expected shape \(3, n\), got \(4, 1\)"),
    (dict(x=np.zeros((3, 2)), y=np.zeros((3, 1)), w=np.ones(4)),
     r"w: expected shape \(3\), got \(4,\)"),
    (dict(x=np.zeros((0, 2)), y=np.zeros((0, 1)), w=np.ones(0)),
     r"x: expected at least 1 neighbours, got 0"),
    (dict(x=np.zeros(3), y=np.zeros((3, 1)), w=np.ones(3)),
     r"x: expected shape \(n, n\), got \(3,\)"),
    (dict(x=np.zeros((3, 2)), y="abc", w=np.ones(3)),
     r"y: expected a numeric array of shape \(3, n\), got str"),
    (dict(x=np.zeros((3, 2)), y=np.zeros((3, 1)), w=np.array([1.0, 0.0, 1.0])),
     r"w must be weights > 0, got 0.0 at neighbour 1"),
    (dict(x=np.full((3, 2), np.nan), y=np.zeros((3, 1)), w=np.ones(3)),
     r"x: 3 of 3 neighbours contain NaN or inf"),
])
def test_local_linear_refuses_arrays_that_do_not_fit_by_name(args, words):
    with pytest.raises(InvalidInputError, match=words):
        local_linear(**args, ridge=0.1)
    with pytest.raises(InvalidInputError, match="ridge"):
        local_linear(np.zeros((3, 2)), np.zeros((3, 1)), np.ones(3), ridge=-1.0)
