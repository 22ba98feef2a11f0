import json
import warnings

import numpy as np
import pytest

from handsynth.errors import InvalidInputError
from handsynth.eval import (
    JOINT_GROUPS,
    MOVING_DEG,
    ProtocolOptions,
    condition_stats,
    model_test_hands,
    natural_test_poses,
    open_rest_posture,
    paper_protocol_poses,
    relaxed_rest_posture,
    run_protocol,
)
from handsynth.models import JOINT_LIMITS_DEG, JOINT_NAMES

LO, HI = JOINT_LIMITS_DEG[:, 0], JOINT_LIMITS_DEG[:, 1]
DIGIT = np.r_[0, 0, 0, 0, np.repeat(np.arange(1, 5), 4)]


def test_rest_postures_are_relaxed_not_zero_and_within_the_limits():
    rng = np.random.default_rng(0)
    rests = np.stack([relaxed_rest_posture(rng) for _ in range(200)])
    assert np.all(rests >= LO) and np.all(rests <= HI)
    flex = rests[:, list(JOINT_GROUPS["finger_flexion"])]
    assert flex.mean() > 3 and (np.abs(flex) > 0.5).mean() > 0.8
    assert rests.std(axis=0).min() > 1.0  # every joint varies between hands


def test_open_rest_postures_flex_every_finger_joint_a_few_degrees():
    rng = np.random.default_rng(3)
    rests = np.stack([open_rest_posture(rng) for _ in range(200)])
    assert np.all(rests >= LO) and np.all(rests <= HI)
    flex = rests[:, list(JOINT_GROUPS["finger_flexion"])]
    assert 3.5 < flex.mean() < 4.5 and flex.min() > -1 and flex.max() < 9
    assert rests[:, [5, 17]].std(axis=0).min() > 2.0  # the fan varies between hands
    assert rests[:, :4].std(axis=0).min() > 3.0        # and the thumb's rest
    with pytest.raises(InvalidInputError, match="rest"):
        ProtocolOptions(rest="flat")


def test_paper_protocol_moves_one_digit_from_the_rest_posture():
    rng = np.random.default_rng(1)
    rest = relaxed_rest_posture(rng)
    poses, motion = paper_protocol_poses(rest, 300, rng)
    assert np.all(poses >= LO) and np.all(poses <= HI)
    for p, m in zip(poses, motion):
        moved = set(DIGIT[np.abs(p - rest) > 1e-9])
        assert moved <= {0 if m == 8 else 1 + m % 4}
    assert set(motion) == set(range(9))


def test_natural_poses_move_several_fingers():
    rng = np.random.default_rng(2)
    rest = relaxed_rest_posture(rng)
    poses, kind = natural_test_poses(rest, 400, rng)
    assert np.all(poses >= LO) and np.all(poses <= HI)
    fingers_moving = np.array([len(set(DIGIT[np.abs(p - rest) > 10]) - {0}) for p in poses])
    assert (fingers_moving >= 2).mean() > 0.5 and len(set(kind)) == 8


def test_constant_open_hand_has_zero_skill_and_the_truth_skill_one():
    rng = np.random.default_rng(3)
    rest = relaxed_rest_posture(rng)
    truth, _ = paper_protocol_poses(rest, 100, rng)
    const = condition_stats(np.zeros_like(truth), truth, rest)
    assert all(v == 0.0 for v in const["skill"].values())
    exact = condition_stats(truth, truth, rest)
    assert all(v == 1.0 for v in exact["skill"].values())
    j = JOINT_NAMES.index("index_pip_flex")
    moving = np.abs(truth[:, j] - rest[j]) > MOVING_DEG
    got = const["method"]["joints"]["index_pip_flex"]
    assert got["moving_frames"] == moving.sum() > 0
    np.testing.assert_allclose(got["moving_mae_deg"], np.abs(truth[moving, j]).mean(), atol=1e-3)
    # frames without a hand are counted and left out
    est = truth.copy()
    est[:5] = np.nan
    s = condition_stats(est, truth, rest)
    assert s["method"]["no_hand"] == 5 and s["method"]["frames"] == 95


def test_run_protocol_scores_methods_beside_the_constant():
    class Rest:  # answers the hand's rest posture read from nowhere: a method that knows it
        def __init__(self, rest):
            self.rest = rest

        def estimate(self, frame):
            class E:
                angles = self.rest
            return E()

    hands = model_test_hands(1, seed=4)
    out = run_protocol({"zero": lambda rest, hand: Rest(np.zeros(20)),
                        "skip": lambda rest, hand: None},
                       hands, ProtocolOptions(frames=6, pose_sets=("paper",)))
    rec = out["hands"]["model0"]
    assert list(rec["paper"]) == ["zero"]
    assert rec["paper"]["zero"]["skill"]["all"] == 0.0
    assert rec["paper"]["zero"]["moved_frames"] == 0  # an estimate without `moved` never moved
    json.dumps(out)


def test_a_slip_sees_the_frames_from_elsewhere_than_the_rest_frame():
    class Keep:  # keeps the frames it is asked to read
        def __init__(self, rest):
            self.rest, self.frames = rest, []

        def estimate(self, frame):
            self.frames.append(frame)

            class E:
                angles = np.zeros(20)
                moved = True  # the protocol counts what the estimates say
            return E()

    made = {}

    def make(rest, hand):
        made.setdefault("est", []).append(Keep(rest))
        return made["est"][-1]

    hands = model_test_hands(1, seed=4)
    opts = dict(frames=3, pose_sets=("paper",))
    still = run_protocol({"keep": make}, hands, ProtocolOptions(**opts))
    slipped = run_protocol({"keep": make}, hands, ProtocolOptions(**opts, slip=1.0))
    a, b = made["est"]
    assert np.array_equal(a.rest, b.rest)  # calibrated where the device was
    assert all(not np.array_equal(f, g) for f, g in zip(a.frames, b.frames))
    assert "slipped_mount" not in still["hands"]["model0"] and "slip" not in still["options"]
    assert slipped["hands"]["model0"]["paper"]["keep"]["moved_frames"] == 3
    moved = slipped["hands"]["model0"]["slipped_mount"]
    assert slipped["options"]["slip"] == 1.0 and moved["height_mm"] != 120.0
    again = run_protocol({"keep": make}, hands, ProtocolOptions(**opts, slip=1.0))
    assert again["hands"]["model0"]["slipped_mount"] == moved  # seeded
    with pytest.raises(InvalidInputError, match="slip"):
        ProtocolOptions(slip=-0.5)


def test_bad_options_are_refused():
    with pytest.raises(InvalidInputError, match="frames"):
        ProtocolOptions(frames=1)
    with pytest.raises(InvalidInputError, match="pose_sets"):
        ProtocolOptions(pose_sets=("fist",))
    with pytest.raises(InvalidInputError, match="method"):
        run_protocol({}, [])


@pytest.mark.parametrize("kwargs, named", [
    # before: a negative seed passed, and failed in numpy after the estimators had learnt
    ({"seed": -1}, "ProtocolOptions.seed must be an integer >= 0, got -1"),
    ({"seed": "3"}, "ProtocolOptions.seed must be an integer >= 0, got '3' (str)"),
    ({"frames": 10**6}, "ProtocolOptions.frames must be an integer >= 2 and <= 10000, got 1000000"),
    ({"pose_sets": ("paper", "paper")}, "ProtocolOptions.pose_sets must name 'paper' and/or "
                                        "'natural', each once, got ('paper', 'paper')"),
    ({"pose_sets": "paper"}, "ProtocolOptions.pose_sets must name 'paper' and/or 'natural', "
                             "each once, got 'paper'"),
    ({"slip": "1"}, "ProtocolOptions.slip must be a finite number >= 0 and <= 5, got '1' (str)"),
    ({"slip": float("nan")}, "ProtocolOptions.slip must be a finite number >= 0 and <= 5, got nan"),
])
def test_protocol_options_are_refused_by_field_and_value(kwargs, named):
    import re

    with pytest.raises(InvalidInputError, match=f"^{re.escape(named)}$"):
        ProtocolOptions(**kwargs)


def _stats(flexion, constant, pip):
    return {"method": {"groups_mae_deg": {"finger_flexion": flexion},
                       "joints": {"index_pip_flex": {"moving_mae_deg": pip}}},
            "constant": {"groups_mae_deg": {"finger_flexion": constant},
                         "joints": {"index_pip_flex": {"moving_mae_deg": 20.0}}}}


def test_protocol_headline_gives_none_with_a_reason_for_a_figure_no_hand_has():
    # before: a method that found the hand in no frame gave NaN figures without a word (and
    # NaN for every hand's mean when one hand had none), and a constant of 0 a skill of -inf
    from handsynth.eval import format_headline, protocol_headline

    nan = float("nan")
    result = {"options": {"pose_sets": ["paper", "natural"]}, "hands": {
        "model0": {"kind": "model",
                   "paper": {"ok": _stats(4.0, 10.0, 6.0), "blind": _stats(None, 10.0, None),
                             "still": _stats(1.0, 0.0, None)},
                   "natural": {"ok": _stats(8.0, 16.0, 12.0)}},
        "model1": {"kind": "model",
                   "paper": {"ok": _stats(nan, 12.0, None), "blind": _stats(nan, 8.0, None),
                             "still": _stats(3.0, 0.0, None)}},
        "model2": {"kind": "model"},  # a hand with no frames of either pose set
    }}
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no "divide by zero" or "mean of empty slice"
        head = protocol_headline(result)
    assert head["model/paper/ok"] == {
        "flexion_mae": 4.0, "constant": 10.0, "skill": 0.6, "index_pip_moving_mae": 6.0,
        "hands": 1, "note": "1 of 2 hands left out (model1: no frame with a reading: the method "
                            "found no hand, or there were no frames)"}
    blind = head["model/paper/blind"]
    assert blind["flexion_mae"] is None and blind["constant"] is None and blind["skill"] is None
    assert blind["index_pip_moving_mae"] is None and blind["hands"] == 0
    assert blind["note"].startswith("no flexion figure (model0, model1: no frame with a reading")
    still = head["model/paper/still"]
    assert still["flexion_mae"] == 2.0 and still["constant"] == 0.0 and still["skill"] is None
    assert "no skill: the constant's flexion MAE is 0" in still["note"]
    assert head["model/natural/ok"]["note"] is None and head["model/natural/ok"]["hands"] == 1
    assert all(v is None or (isinstance(v, (int, float, str)) and v == v)
               for row in head.values() for v in row.values())  # no NaN anywhere
    json.dumps(head, allow_nan=False)
    text = format_headline(head).splitlines()
    assert text[1].startswith("model/paper/blind") and "flexion MAE      - (constant      -, " \
        "skill -); index PIP where it moves: MAE - [no flexion figure" in text[1]
    assert text[0].endswith("MAE 6.0 [1 of 2 hands left out (model1: no frame with a reading: "
                            "the method found no hand, or there were no frames)]")


def test_protocol_headline_names_a_result_of_another_shape():
    from handsynth.eval import protocol_headline

    with pytest.raises(InvalidInputError, match="not a run_protocol result: KeyError 'hands'"):
        protocol_headline({"options": {"pose_sets": ["paper"]}})


def test_model_test_hands_with_segment_widths_and_flesh_offsets_are_the_same_hands_otherwise():
    plain = model_test_hands(3, seed=6, spread=1.5)
    wide = model_test_hands(3, seed=6, spread=1.5, segment_width_sd=0.1, flesh_offset_sd_mm=1.0)
    for p, w in zip(plain, wide):
        assert p.info["shape"] == w.info["shape"]
        pv, wv = p.info["variation"], w.info["variation"]
        new = ("segment_width", "flesh_offset_mm")
        assert {k: v for k, v in pv.items() if k not in new} == \
            {k: v for k, v in wv.items() if k not in new}
        assert pv["segment_width"] == [1.0] * 15 and len(set(wv["segment_width"])) == 15
        assert pv["flesh_offset_mm"] == [0.0] * 30 and len(set(wv["flesh_offset_mm"])) == 30


def test_model_test_hands_whose_breadths_follow_their_scale_are_the_same_hands_otherwise():
    plain = model_test_hands(3, seed=6, spread=1.5)
    scaled = model_test_hands(3, seed=6, spread=1.5, breadth_follows_scale=1.0)
    for p, w in zip(plain, scaled):
        pv, wv = p.info["variation"], w.info["variation"]
        breadths = ("digit_width", "palm_width", "palm_depth")
        assert {k: v for k, v in pv.items() if k not in breadths} == \
            {k: v for k, v in wv.items() if k not in breadths}
        ratio = np.r_[wv["digit_width"], wv["palm_width"], wv["palm_depth"]] / \
            np.r_[pv["digit_width"], pv["palm_width"], pv["palm_depth"]]
        assert np.allclose(ratio, ratio[0]) and ratio[0] != pytest.approx(1.0)


def test_describe_methods_names_every_learnt_option_and_refuses_unknown_names():
    from dataclasses import asdict

    from handsynth.db import LearningSetOptions
    from handsynth.errors import InvalidInputError
    from handsynth.estimate import LearnedOptions
    from handsynth.eval import describe_methods

    d = describe_methods(["standard", "fingers"], data=LearningSetOptions(hands=12))
    assert d["standard"] == {"lookup": "the paper's lookup, standard hand's 20,448-entry database"}
    assert d["fingers"] == {"learnt": asdict(LearnedOptions(kind="fingers"))}
    assert d["learning_set"] == asdict(LearningSetOptions(hands=12))
    assert "learning_set" not in describe_methods(["calibrated"])
    # the perceptrons alone: the ensemble's perceptron members at equal weights
    from handsynth.estimate import LEARNED_ENSEMBLE

    alone = describe_methods(["perceptrons"])["perceptrons"]["ensemble"]
    assert [(m["learnt"], m["learning_set_changes"]) for m in alone] == [
        (asdict(o), dict(c)) for o, _w, c in LEARNED_ENSEMBLE if o.kind == "mlp"]
    assert [m["weight"] for m in alone] == pytest.approx([1 / 3] * 3)
    with pytest.raises(InvalidInputError, match="got 'tree'"):
        describe_methods(["fingers", "tree"])


def test_a_glTF_file_of_ones_own_is_a_test_hand_named_by_its_stem(tmp_path):
    import shutil

    from handsynth.eval import mesh_test_hands
    from handsynth.testhands import shipped_hand_path

    mine = tmp_path / "my_hand.glb"
    shutil.copyfile(shipped_hand_path("mrtk"), mine)
    hands = mesh_test_hands(["godot_xr_tools", str(mine)])
    assert [h.name for h in hands] == ["godot_xr_tools", "my_hand"]
    assert hands[1].kind == "mesh" and hands[1].info == {"file": "my_hand.glb"}
    rest = relaxed_rest_posture(np.random.default_rng(0))
    np.testing.assert_array_equal(hands[1].make().mask(rest),
                                  mesh_test_hands(["mrtk"])[0].make().mask(rest))


def test_test_hands_that_are_not_glTF_hands_are_refused_by_name(tmp_path):
    from handsynth.eval import mesh_test_hands

    with pytest.raises(InvalidInputError, match="one of .* or a .gltf/.glb file, got 'hand.obj'"):
        mesh_test_hands(["hand.obj"])
    with pytest.raises(InvalidInputError, match="test hand file .*missing.glb' does not exist"):
        mesh_test_hands([str(tmp_path / "missing.glb")])
    broken = tmp_path / "broken.gltf"
    broken.write_text("not json")
    with pytest.raises(InvalidInputError, match="broken.gltf"):
        mesh_test_hands([broken])


def test_two_test_hands_of_one_name_are_refused():
    twice = model_test_hands(1, seed=4) * 2
    with pytest.raises(InvalidInputError, match="distinct names, got model0 twice"):
        run_protocol({"skip": lambda rest, hand: None}, twice, ProtocolOptions(frames=2))


def test_mesh_test_hands_scaled_say_so_and_refuse_a_bad_scale():
    from handsynth.eval import mesh_test_hands

    hands = mesh_test_hands(["mrtk"], scale=0.9)
    assert hands[0].info == {"file": "hand_r.glb", "scale": 0.9}
    assert hands[0].make().hand_length_mm == pytest.approx(
        0.9 * mesh_test_hands(["mrtk"])[0].make().hand_length_mm)
    with pytest.raises(InvalidInputError, match=r"scale must be a number in \[0.5, 2\], got 4"):
        mesh_test_hands(scale=4)


def test_a_damaged_glTF_hand_is_refused_with_its_file_before_any_work(tmp_path):
    # before: a .glb whose mesh was zero-filled in the middle loaded, and failed, without
    # naming the file, only when the protocol measured it (after the estimators had learnt)
    from handsynth.eval import mesh_test_hands
    from handsynth.testhands import shipped_hand_path

    data = bytearray(shipped_hand_path("mrtk").read_bytes())
    data[len(data) // 2:len(data) // 2 + 20000] = bytes(20000)
    damaged = tmp_path / "damaged.glb"
    damaged.write_bytes(bytes(data))
    with pytest.raises(InvalidInputError, match=r"damaged\.glb"):
        mesh_test_hands([damaged])
    cut = tmp_path / "cut.glb"
    cut.write_bytes(shipped_hand_path("mrtk").read_bytes()[:5000])
    with pytest.raises(InvalidInputError, match=r"cut\.glb"):
        mesh_test_hands([cut])
    hands = mesh_test_hands(["mrtk"])  # measured once here, not again by run_protocol
    assert hands[0].measurements is not None


def test_two_glTF_hands_of_one_name_are_refused_before_any_work(tmp_path):
    from handsynth.eval import mesh_test_hands

    with pytest.raises(InvalidInputError, match="two test hands named 'mrtk'"):
        mesh_test_hands(["mrtk", "mrtk"])


@pytest.mark.parametrize("args, kwargs, named", [
    ((-3,), {}, "n must be an integer >= 0 and <= 1000, got -3"),
    ((1.5,), {}, "n must be an integer >= 0 and <= 1000, got 1.5"),
    ((True,), {}, "n must be an integer >= 0 and <= 1000, got True (bool)"),
    (("2",), {}, "n must be an integer >= 0 and <= 1000, got '2' (str)"),
    ((1,), {"spread": -1.0}, "spread must be a finite number >= 0, got -1.0"),
    ((1,), {"spread": float("nan")}, "spread must be a finite number >= 0, got nan"),
    ((1,), {"spread": float("inf")}, "spread must be a finite number >= 0, got inf"),
    ((1,), {"spread": "1.5"}, "spread must be a finite number >= 0, got '1.5' (str)"),
    ((1,), {"spread": None}, "spread must be a finite number >= 0, got None (NoneType)"),
    ((1,), {"seed": -1}, "seed must be an integer >= 0, got -1"),
    ((10**6,), {}, "n must be an integer >= 0 and <= 1000, got 1000000"),
    ((0,), {"breadth_follows_scale": 3}, "breadth_follows_scale must be a finite number >= 0 and "
                                         "<= 2, got 3"),
])
def test_model_test_hands_refuses_a_bad_count_spread_or_seed_by_name(args, kwargs, named):
    # once numpy's "scale < 0", an error about an internal field, or [] for n < 0
    import re

    with pytest.raises(InvalidInputError, match=f"^{re.escape(named)}$"):
        model_test_hands(*args, **kwargs)


def test_model_test_hands_may_be_none_and_a_spread_of_0_leaves_each_shape_unvaried():
    assert model_test_hands(0) == []  # the command line's glTF-only run (--hands 0 --mesh ...)
    plain = model_test_hands(2, seed=4, spread=0)
    varied = model_test_hands(2, seed=4, spread=1.0)
    for p, v in zip(plain, varied):
        assert p.info["shape"] == v.info["shape"]
        var = p.info["variation"]
        assert var["segment_length"] == [1.0] * 15 and var["mcp_offset_mm"] == [0.0] * 8
        assert var["palm_length"] == 1.0 and v.info["variation"] != var
