import dataclasses

import numpy as np
import pytest

from handsynth.sensors.imu import (
    AhrsEKFEstimator,
    ConstantEstimator,
    Filter1,
    GatedFilter,
    MadgwickEstimator,
    MahonyEstimator,
    OrientationEstimator,
    RawIntegration,
    StaticStart,
    VQFEstimator,
    azimuth_correction,
    initial_attitude,
    simulate_imu,
    static_motion,
)
from handsynth.sensors.imu._quat import angle_deg, heading_inclination_deg

ALL = [ConstantEstimator(), RawIntegration(), Filter1(), GatedFilter(), VQFEstimator(),
       VQFEstimator(online=True, name="vqf_online"), MadgwickEstimator(),
       MahonyEstimator(), AhrsEKFEstimator()]


@pytest.mark.parametrize("est", ALL, ids=lambda e: e.name)
def test_every_estimator_satisfies_the_protocol(est):
    assert isinstance(est, OrientationEstimator)


@pytest.fixture(scope="module")
def static_rec(imu_hand):
    pose = np.zeros(29)
    pose[4] = 30.0  # elbow flexed: forearm and hand tilted
    pose[9 + 4 * 2] = 50.0  # index MCP flexed
    return simulate_imu(static_motion(4.0, pose=pose), hand=imu_hand, seed=3)


@pytest.mark.parametrize("est", ALL, ids=lambda e: e.name)
def test_world_frame_convention_on_a_static_hand(est, static_rec):
    """Every estimator reports the same world frame (z up, x north): a wrong
    ENU/NED conversion shows up as a 90 or 180 deg error here."""
    sub = static_rec.subset(("forearm_1", "hand_radial", "index_proximal", "thumb_distal"))
    truth = static_rec.truth.quat[[0, 10, 14, 19]]
    # no common rotation in a static recording: no azimuth alignment
    q = dataclasses.replace(est, static=StaticStart(align_start_s=None)).run(sub)
    heading, incl = heading_inclination_deg(q[:, -50:], truth[:, -50:])
    assert incl.max() < 3.0
    assert heading.max() < 20.0  # azimuth spread 4.5 deg s.d. per sensor, unaligned


def test_initial_attitude_matches_truth(free_rec):
    q0 = initial_attitude(free_rec)
    err = angle_deg(q0, free_rec.truth.quat[:, 0])
    assert np.median(err) < 2.5


def test_azimuth_alignment_shrinks_the_spread(free_rec):
    q_raw = initial_attitude(free_rec, align=False)
    q_al = initial_attitude(free_rec)
    h_raw, _ = heading_inclination_deg(q_raw, free_rec.truth.quat[:, 0])
    h_al, _ = heading_inclination_deg(q_al, free_rec.truth.quat[:, 0])
    assert np.std(h_al) < 0.5 * np.std(h_raw)
    assert azimuth_correction(free_rec).shape == (20,)


def test_raw_integration_beats_constant_on_moving_segments(free_rec):
    e_raw = angle_deg(RawIntegration().run(free_rec), free_rec.truth.quat)
    e_const = angle_deg(ConstantEstimator().run(free_rec), free_rec.truth.quat)

    def rmse(e):
        return np.sqrt(np.mean(e[:, 400:] ** 2, axis=1))

    assert np.all(rmse(e_raw) < rmse(e_const))
    assert np.median(rmse(e_raw)) < 5.0


def test_online_vqf_is_causal_and_the_offline_one_is_not(free_rec):
    """The offline VQF uses future samples (its bias estimate); the online one cannot."""
    half = free_rec.slice(0, free_rec.n // 2)
    online = VQFEstimator(online=True)
    np.testing.assert_allclose(online.run(half), online.run(free_rec)[:, :half.n], atol=1e-12)
    offline = VQFEstimator()
    assert angle_deg(offline.run(half), offline.run(free_rec)[:, :half.n]).max() > 1e-3


@pytest.mark.parametrize("n", [0, 1, 2, 500])
def test_compiled_gyro_chain_equals_the_plain_one(n):
    from handsynth.sensors.imu._filters import _chain_reference
    from handsynth.sensors.imu._quat import qexp, qnormalize
    from handsynth.sensors.imu._quat_numba import _chain

    rng = np.random.default_rng(n)
    q0 = qnormalize(rng.normal(size=(3, 4)))
    dq = qexp(rng.normal(scale=0.05, size=(3, n, 3)))
    fast, plain = _chain(q0, dq), _chain_reference(q0, dq)
    assert fast.shape == plain.shape == (3, n, 4)
    np.testing.assert_allclose(fast, plain, rtol=0, atol=1e-14)
    if n:
        np.testing.assert_array_equal(fast[:, 0], q0)
