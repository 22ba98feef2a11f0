import numpy as np
import pytest

from handsynth.errors import InvalidInputError
from handsynth.models import JOINT_LIMITS_DEG, JOINT_NAMES
from handsynth.sensors.glove import (
    don_glove,
    make_user,
    motions_for,
    simulate_session,
)


def test_session_shapes_labels_and_limits(cal_rec):
    assert cal_rec.sensors.shape == (cal_rec.n_samples, 5)
    assert set(cal_rec.motion) == set(motions_for("dg5"))
    assert set(cal_rec.trial) == {0, 1, 2, 3}
    assert (cal_rec.truth >= JOINT_LIMITS_DEG[:, 0] - 1e-9).all()
    assert (cal_rec.truth <= JOINT_LIMITS_DEG[:, 1] + 1e-9).all()
    # the reference glove is not the truth
    err = cal_rec.angles - cal_rec.truth
    assert 1.2 < err.std() < 1.8


def test_trials_vary_and_users_differ(user, dg5):
    rec = simulate_session(user, dg5, ["standard"], trials=3, seed=5)
    j = JOINT_NAMES.index("index_mcp_flex")
    peaks = [rec.truth[rec.trial == k, j].max() for k in range(3)]
    lengths = [(rec.trial == k).sum() for k in range(3)]
    assert np.ptp(peaks) > 1.0 and len(set(lengths)) > 1
    other = make_user(99)
    rec2 = simulate_session(other, don_glove(other, "dg5", seed=1), ["standard"], trials=3,
                            seed=5)
    assert abs(rec2.truth[:, j].max() - max(peaks)) > 0.5 or \
        not np.allclose(other.dip_ratio, user.dip_ratio)


def test_dip_is_not_exactly_two_thirds_pip(cal_rec):
    p, d = JOINT_NAMES.index("middle_pip_flex"), JOINT_NAMES.index("middle_dip_flex")
    big = cal_rec.truth[:, p] > 30
    ratio = cal_rec.truth[big, d] / cal_rec.truth[big, p]
    assert abs(np.median(ratio) - 2 / 3) > 0.005


def test_parallel_extension_barely_moves_a_dg5_sensor(user):
    """Seed 004 section 3.1 / Fig. 5: why Parallel Extension is dropped for DG5."""
    dg5, fdt = don_glove(user, "dg5", seed=1), don_glove(user, "5dt", seed=1)
    r_dg5 = simulate_session(user, dg5, ["parallel_extension"], trials=1, seed=3)
    r_5dt = simulate_session(user, fdt, ["parallel_extension"], trials=1, seed=3)
    span_dg5 = np.ptp(r_dg5.sensors[:, 1:], axis=0) / dg5.gain[1:]
    span_5dt = np.ptp(r_5dt.sensors[:, 1:], axis=0) / fdt.gain[1:]
    assert span_5dt.mean() > 2.5 * span_dg5.mean()


def test_bad_arguments():
    with pytest.raises(InvalidInputError, match="unknown motion 'wave'"):
        simulate_session(make_user(0), don_glove(make_user(0), "dg5", seed=0), ["wave"])
    with pytest.raises(InvalidInputError, match="seed"):
        make_user(-1)


@pytest.mark.parametrize("length", [0, -1.0, 0.2, 3.0, float("nan"), "1.0"])
def test_hand_length_is_checked(user, length):
    with pytest.raises(InvalidInputError, match="hand_length"):
        make_user(1, hand_length=length)
    with pytest.raises(InvalidInputError, match="hand_length"):
        user.replace(hand_length=length)
    assert make_user(1, hand_length=0.9).hand_length == 0.9


def test_user_fields_are_checked(user):
    with pytest.raises(InvalidInputError, match=r"GloveUser.dip_ratio must have shape \(5,\)"):
        user.replace(dip_ratio=np.ones(20))
    with pytest.raises(InvalidInputError, match="name must be a string"):
        make_user(1, name=7)


def test_range_holds_are_labelled_timed_and_read_as_a_range(user, dg5):
    from handsynth.sensors.glove import RANGE_LABELS, range_readings, simulate_range_holds

    holds = simulate_range_holds(user, dg5, seed=3, start_s=10.0, hold_samples=20)
    assert holds.n_samples == 40 and holds.angles is not None
    assert list(holds.motion[[0, 19, 20, 39]]) == [RANGE_LABELS[0]] * 2 + [RANGE_LABELS[1]] * 2
    np.testing.assert_allclose(holds.time_s[[0, 1]], [10.0, 10.0 + 1 / 60])
    open_, fist = range_readings(holds)
    assert (fist > open_).all()  # every sensor bends further in a fist
    assert simulate_range_holds(user, dg5, with_angles=False).angles is None
    with pytest.raises(InvalidInputError, match="rate_hz must be > 0"):
        simulate_range_holds(user, dg5, rate_hz=0)


def test_a_motion_given_twice_or_none_is_refused(user, dg5):
    # its trials shared numbers and were read back as one trial of two grasps
    with pytest.raises(InvalidInputError, match="'tripod' is given twice"):
        simulate_session(user, dg5, ["tripod", "tripod"], trials=1)
    with pytest.raises(InvalidInputError, match="at least one motion"):
        simulate_session(user, dg5, [], trials=1)


def test_the_held_out_configuration_draws_other_gloves():
    from handsynth.sensors.glove import GLOVE_HELDOUT, GLOVE_TUNING

    user = make_user(3, hand_length=1.0)
    # the tuning configuration is the default, draw for draw
    plain, tuning = don_glove(user, "dg5", seed=4), don_glove(user, "dg5", seed=4,
                                                             config=GLOVE_TUNING)
    np.testing.assert_array_equal(plain.gain, tuning.gain)
    np.testing.assert_array_equal(plain.hysteresis_deg, tuning.hysteresis_deg)
    held = [don_glove(user, "5dt", seed=s, glove_seed=s, config=GLOVE_HELDOUT) for s in range(20)]
    hyst = np.concatenate([h.hysteresis_deg for h in held])
    noise = np.concatenate([h.noise_counts for h in held])
    nonlin = np.concatenate([h.nonlinearity for h in held])
    assert hyst.min() >= 4.0 and hyst.max() <= 8.0 and hyst.max() > 5.0  # beyond tuning's 2-5
    assert noise.min() >= 3.0 and noise.max() <= 6.0
    assert nonlin.min() >= 0.1 and nonlin.max() > 0.2
    assert GLOVE_HELDOUT.label == "heldout" and GLOVE_TUNING.label == "tuning"
    # and other users: the tuning configuration's draw for draw, the held-out's wider
    a, b = make_user(5), make_user(5, config=GLOVE_TUNING)
    np.testing.assert_array_equal(a.style_scale, b.style_scale)
    np.testing.assert_array_equal(a.dip_ratio, b.dip_ratio)
    users = [make_user(s, config=GLOVE_HELDOUT) for s in range(40)]
    dip = np.concatenate([u.dip_ratio for u in users])
    assert dip.min() >= 0.45 and dip.max() <= 0.85 and (dip.min() < 0.55 or dip.max() > 0.80)
    style = np.concatenate([u.style_offset_deg for u in users])
    assert 5.0 < style.std() < 7.0  # 6 deg s.d. (tuning 4)


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"hysteresis_deg": (5.0, 2.0)}, r"GloveConfig.hysteresis_deg must be a range"),
    ({"noise_counts": 3.0}, r"GloveConfig.noise_counts must be two numbers"),
    ({"slip": (0.1, float("nan"))}, r"GloveConfig.slip"),
    ({"gain_donning_sd": -0.1}, r"GloveConfig.gain_donning_sd must be >= 0"),
    ({"gain_counts_per_deg": (0.0, 4.0)}, r"GloveConfig.gain_counts_per_deg must be above 0"),
    ({"dip_ratio": (0.0, 0.8)}, r"GloveConfig.dip_ratio must be above 0"),
    ({"style_offset_sd_deg": float("inf")}, r"GloveConfig.style_offset_sd_deg"),
])
def test_glove_config_refuses_what_is_no_spread(kwargs, match):
    from handsynth.sensors.glove import GloveConfig

    with pytest.raises(InvalidInputError, match=match):
        GloveConfig(**kwargs)
    with pytest.raises(InvalidInputError, match="config"):
        don_glove(make_user(0), "dg5", seed=0, config={"label": "heldout"})
