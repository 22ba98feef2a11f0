"""The accuracy experiment: statistics, database choice, report JSON and plots (small databases)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from handsynth.db import database_path, open_database
from handsynth.errors import InvalidInputError
from handsynth.estimate import SelectionOptions, select_shape, select_shape_from_frame
from handsynth.eval import (
    CONDITIONS,
    EvalOptions,
    EvalReport,
    evaluate,
    joint_stats,
    random_hand_shapes,
    ratio_distance,
    silhouette_ambiguity,
)
from handsynth.models import GRID_LEVELS, JOINT_NAMES, HandShape, model_measurements
from handsynth.render import CameraMount, SilhouetteRasterizer

#: One hand beyond the grid on three ratios, one inside but off the grid.
HANDS = (HandShape(length=1.02, width=0.85, palm=1.07, thumb=1.13),
         HandShape(length=1.03, width=1.06, palm=0.98, thumb=1.04))
SMALL = {"count": 150, "render_size": (120, 80), "frames_per_hand": 10}


@pytest.fixture(scope="module")
def report(tmp_path_factory) -> EvalReport:
    folder = tmp_path_factory.mktemp("eval_dbs")
    # ties="first": every estimate is one entry's angles (checked below)
    return evaluate(EvalOptions(db_folder=folder, hand_shapes=HANDS, ties="first", **SMALL))


# --------------------------------------------------------------------------- statistics


def test_joint_stats_on_hand_made_errors():
    e = np.zeros((4, 20))
    e[:, 0] = [1.0, -1.0, 3.0, 5.0]       # mean 2, |e| mean 2.5, sd sqrt(20/3)
    e[:, 6] = [-2.0, -2.0, -2.0, -2.0]    # constant: sd 0
    e[:, 19] = [4.0, np.nan, -2.0, np.nan]  # NaN left out: n 2, mean 1, MAE 3, sd sqrt(18)
    s = joint_stats(e)
    assert s.mean_deg[0] == 2.0 and s.mae_deg[0] == 2.5
    assert s.sd_deg[0] == pytest.approx(math.sqrt(20.0 / 3.0), rel=1e-12)
    assert (s.mean_deg[6], s.sd_deg[6], s.mae_deg[6]) == (-2.0, 0.0, 2.0)
    assert (s.n[19], s.mean_deg[19], s.mae_deg[19]) == (2, 1.0, 3.0)
    assert s.sd_deg[19] == pytest.approx(math.sqrt(18.0), rel=1e-12)
    assert list(s.n) == [4] * 19 + [2]
    assert s.joint("thumb_cmc_flex") == {"mean_deg": 2.0, "sd_deg": round(math.sqrt(20 / 3), 4),
                                         "mae_deg": 2.5, "n": 4}
    assert list(s.as_dict()) == list(JOINT_NAMES)
    one = joint_stats(np.ones((1, 20)))
    assert np.isnan(one.sd_deg).all() and one.joint("index_pip_flex")["sd_deg"] is None


@pytest.mark.parametrize("bad", [np.zeros((3, 19)), np.zeros(20), [["a"] * 20],
                                 np.full((2, 20), np.inf)])
def test_joint_stats_refuses_bad_arrays(bad):
    with pytest.raises(InvalidInputError, match="errors_deg"):
        joint_stats(bad)


def test_ratio_distance_counts_grid_steps():
    assert ratio_distance(HandShape(), HandShape()) == 0.0
    # half a step in length (0.025 of 0.05) and one step in thumb (0.1 of 0.1)
    d = ratio_distance(HandShape(length=1.025, thumb=1.1), HandShape())
    assert d == pytest.approx(math.sqrt(0.25 + 1.0))


def test_random_hands_are_off_grid_within_margin_and_reproducible():
    shapes = random_hand_shapes(200, seed=3, margin=0.5)
    assert shapes == random_hand_shapes(200, seed=3, margin=0.5)
    assert shapes != random_hand_shapes(200, seed=4, margin=0.5)
    outside = 0
    for name, (lo, mid, hi) in GRID_LEVELS.items():
        v = np.array([getattr(s, name) for s in shapes])
        assert v.min() >= lo - 0.5 * (mid - lo) and v.max() <= hi + 0.5 * (hi - mid)
        outside += int(((v < lo) | (v > hi)).sum())
        assert not np.isin(v, (lo, mid, hi)).any()
    assert outside > 0
    inside = random_hand_shapes(50, seed=3, margin=0.0)
    assert all(GRID_LEVELS["width"][0] <= s.width <= GRID_LEVELS["width"][2] for s in inside)


def test_silhouette_ambiguity_on_hand_made_database():
    from types import SimpleNamespace

    a, b = np.arange(64, dtype=np.uint64), np.arange(64, dtype=np.uint64)[::-1].copy()
    angles = np.zeros((4, 20))
    pip = JOINT_NAMES.index("index_pip_flex")
    angles[:, pip] = [0, 30, 50, 10]  # rows 0, 1, 3 share silhouette a: spread 30
    angles[:, 0] = [0, 5, 90, 2]      # thumb CMC spread 5 within a
    db = SimpleNamespace(sil_bits=np.stack([a, a, b, a]), angles=angles)
    r = silhouette_ambiguity(db, spread_deg=20)
    assert (r["entries"], r["distinct_silhouettes"], r["entries_sharing"]) == (4, 2, 3)
    assert r["ambiguous_entries"] == 3 and r["per_joint"]["index_pip_flex"] == 3
    assert r["per_joint"]["thumb_cmc_flex"] == 0 and list(r["per_joint"]) == list(JOINT_NAMES)
    assert silhouette_ambiguity(db, spread_deg=40)["ambiguous_entries"] == 0


# --------------------------------------------------------------------------- options


@pytest.mark.parametrize("field, value", [
    ("n_hands", 0), ("frames_per_hand", -1), ("pose_sets", ("paper", "papr")),
    ("pose_sets", ()), ("hand", "glove"), ("conditions", ("standard", "selectd")),
    ("count", 0), ("mount", "wholehand"), ("frame_size", (720,)), ("ratio_margin", -0.1),
    ("hand_shapes", (HandShape(), "L1")), ("seed", True), ("side", "middle"),
    ("ties", "median"),
])
def test_options_refuse_typos_naming_the_field(tmp_path, field, value):
    with pytest.raises(InvalidInputError, match=field):
        EvalOptions(db_folder=tmp_path, **{field: value})


def test_mesh_hand_is_an_option(tmp_path):
    assert EvalOptions(db_folder=tmp_path, hand="mesh").hand == "mesh"
    with pytest.raises(InvalidInputError, match="hand"):
        EvalOptions(db_folder=tmp_path, hand="glove")


def test_options_keep_condition_order_and_count_given_hands(tmp_path):
    o = EvalOptions(db_folder=tmp_path, conditions=("selected", "standard"), hand_shapes=HANDS)
    assert o.conditions == ("standard", "selected") and o.n_hands == 2
    assert json.loads(json.dumps(o.as_dict()))["hand_shapes"][0]["length"] == 1.02


# --------------------------------------------------------------------------- experiment


def test_conditions_use_the_right_databases(report):
    folder = report.options.db_folder
    for hand, shape in zip(report.hands, HANDS):
        dbs = hand["databases"]
        assert dbs["standard"] == HandShape().name
        assert dbs["selected"] == select_shape(model_measurements(shape)).shape.name
        none = select_shape(model_measurements(shape), options=SelectionOptions(normalize="none"))
        assert dbs["selected_none"] == none.shape.name == shape.nearest_grid().name
        assert dbs["own_shape"] == dbs["selected"]
        assert hand["ratios"] == shape.as_dict()  # ratios beyond the grid are accepted
        for cond in ("standard", "selected", "selected_none"):
            assert hand["ratio_distance"][cond] == pytest.approx(
                ratio_distance(shape, HandShape.from_name(dbs[cond])), abs=1e-4)
        assert hand["ratio_distance"]["own_shape"] == 0.0
        # personal: the shape measured on a photo of the hand, close to its true ratios
        photo = HandShape(**hand["selection_ratios"]["photo"])
        assert dbs["personal"] == photo.name != shape.nearest_grid().name
        assert hand["ratio_distance"]["personal"] < 0.25
        # calibrated: the grid shape whose open hand overlaps the hand's open frame most
        with SilhouetteRasterizer(shape, CameraMount()) as r:
            open_frame = r.masks(np.zeros((1, 20)))[0]
        assert dbs["calibrated"] == select_shape_from_frame(open_frame).shape.name
        assert hand["selection_ratios"]["open_frame"] == HandShape.from_name(
            dbs["calibrated"]).as_dict()
    # the palm-width normalisation moves the first hand to another database than the
    # nearest grid shape of its true ratios
    assert report.hands[0]["databases"]["selected"] != report.hands[0]["databases"]["selected_none"]
    # each estimate is an entry of the database its condition names
    for cond in CONDITIONS:
        for h, hand in enumerate(report.hands):
            db = open_database(database_path(folder, HandShape.from_name(hand["databases"][cond])))
            assert len(db) == SMALL["count"]
            rows = report.hand_index == h
            entries = report.entry[cond][rows]
            assert (entries >= 0).all()
            np.testing.assert_array_equal(report.estimates_deg[cond][rows],
                                          db.angles[entries].astype(np.float64))


def test_frames_truth_and_statistics(report):
    n = 2 * 2 * SMALL["frames_per_hand"]
    assert report.truth_deg.shape == (n, 20) and report.conditions == CONDITIONS
    assert list(np.unique(report.hand_index, return_counts=True)[1]) == [20, 20]
    assert (report.pose_set == "paper").sum() == (report.pose_set == "natural").sum() == n // 2
    for cond in CONDITIONS:
        e = report.estimates_deg[cond] - report.truth_deg
        s = report.stats(cond)
        np.testing.assert_allclose(s.mean_deg, np.nanmean(e, axis=0))
        np.testing.assert_allclose(s.mae_deg, np.nanmean(np.abs(e), axis=0))
        paper = report.stats(cond, pose_set="paper")
        np.testing.assert_allclose(paper.sd_deg, np.std(e[report.pose_set == "paper"], axis=0,
                                                       ddof=1))
        moving = report.stats(cond, pose_set="paper", moving=True)
        p = report.pose_set == "paper"
        for j in (0, JOINT_NAMES.index("index_pip_flex")):
            rows = p & (np.abs(report.truth_deg[:, j]) > 1.0)
            assert moving.n[j] == rows.sum()
            if rows.any():
                assert moving.mae_deg[j] == pytest.approx(np.abs(e[rows, j]).mean())
    assert report.errors("selected").shape == (n, 20)
    with pytest.raises(InvalidInputError, match="condition"):
        report.errors("best")


def test_report_json_schema(report):
    d = json.loads(report.to_json())
    assert d["schema"] == "handsynth.eval/1" and d["joint_names"] == list(JOINT_NAMES)
    assert len(d["hands"]) == 2 and d["options"]["count"] == SMALL["count"]
    assert set(d["conditions"]) == set(CONDITIONS)
    for cond, block in d["conditions"].items():
        assert block["databases"] == sorted({h["databases"][cond] for h in d["hands"]})
        for part, frames in (("all", 40), ("paper", 20), ("natural", 20)):
            b = block[part]
            assert b["frames"] == frames and list(b["joints"]) == list(JOINT_NAMES)
            for fig in b["joints"].values():
                assert set(fig) == {"mean_deg", "sd_deg", "mae_deg", "n"}
                assert fig["mae_deg"] >= abs(fig["mean_deg"]) - 1e-3
            exp = report.stats(cond, pose_set=None if part == "all" else part)
            assert b["joints"]["index_pip_flex"]["mae_deg"] == pytest.approx(
                exp.mae_deg[JOINT_NAMES.index("index_pip_flex")], abs=1e-4)
        assert set(block["moving"]) == {"note", "all", "paper", "natural"}
        assert list(block["moving"]["paper"]) == list(JOINT_NAMES)
    # the constant answer (the open hand) on the same frames, beside every condition
    const = d["constant"]
    assert set(const) == {"description", "all", "paper", "natural", "moving"}
    truth = report.truth_deg
    assert const["all"]["overall_mae_deg"] == pytest.approx(np.abs(truth).mean(), abs=1e-3)
    paper = truth[report.pose_set == "paper"]
    j = JOINT_NAMES.index("index_pip_flex")
    assert const["paper"]["joints"]["index_pip_flex"]["mean_deg"] == pytest.approx(
        -paper[:, j].mean(), abs=1e-3)
    moved = np.abs(truth[:, j]) > 1.0
    assert const["moving"]["all"]["index_pip_flex"]["mae_deg"] == pytest.approx(
        np.abs(truth[moved, j]).mean(), abs=1e-3)
    assert "constant" in report.format().splitlines()[4]  # the table's header, after the note
    t = d["targets"]["all"]
    assert set(t) == {"index_pip_abs_mean_deg", "index_pip_sd_deg", "thumb_cmc_sd_deg",
                      "selected_beats_standard"}
    assert t["index_pip_sd_deg"]["met"] == (t["index_pip_sd_deg"]["value"] <= 8.0)
    assert set(d["targets"]) == {"all", "paper", "natural"}
    for cond in ("personal", "calibrated"):
        tc = d[f"targets_{cond}"]
        assert set(tc) == {"all", "paper", "natural"}
        assert tc["paper"] == report.targets(pose_set="paper", condition=cond)
        assert f"{cond}_beats_standard" in tc["all"]
    amb = d["ambiguity"]
    assert set(amb) == {n for h in d["hands"] for n in h["databases"].values()}
    assert all(a["entries"] == SMALL["count"] for a in amb.values())
    full = report.to_dict(frames=True)
    assert len(full["frames"]) == 40
    f0 = full["frames"][0]
    assert len(f0["truth_deg"]) == 20 and len(f0["selected"]["angles_deg"]) == 20


@pytest.mark.slow
def test_plots_are_png_files(report, tmp_path):
    import matplotlib.image

    paths = report.write_plots(tmp_path / "plots")
    assert [p.name for p in paths] == ["eval_error_hist.png", "eval_error_vs_distance.png",
                                       "eval_joint_mae.png"]
    for p in paths:
        data = p.read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and data[-8:-4] == b"IEND"
        img = matplotlib.image.imread(p)
        assert img.ndim == 3 and img.shape[0] > 200 and img.shape[1] > 200
        assert img[..., :3].std() > 0.05  # not a blank canvas


def test_evaluate_refuses_other_options():
    with pytest.raises(InvalidInputError, match="EvalOptions"):
        evaluate({"db_folder": "x"})
