import numpy as np
import pytest

from handsynth.sensors.imu import (
    OrientationEstimator,
    RawIntegration,
    free_motion,
    simulate_imu,
)
from handsynth.sensors.imu._ekf import ChainEKF, ChainEKFOptions, _tree, observe
from handsynth.sensors.imu._ekf_numba import observe_fast
from handsynth.sensors.imu._quat import angle_deg, qexp, qmul, quat_to_mat
from handsynth.sensors.imu._vectors import truth_chain_model


@pytest.fixture(scope="module")
def moving_rec(imu_hand):
    return simulate_imu(free_motion(8.0, seed=1, elbow="moving"), hand=imu_hand, seed=2)


def _args(rec, i, rng):
    r = quat_to_mat(rec.truth.quat[:, i])
    return r, rec.gyr[:, i], rng.normal(0, 5, (20, 3)), rec.acc[:, i], rec.mag[:, i]


def test_protocol(moving_rec):
    assert isinstance(ChainEKF(truth_chain_model(moving_rec)), OrientationEstimator)


@pytest.mark.slow  # the first call compiles the EKF (10-40 s on a fresh checkout)
@pytest.mark.parametrize("opts", [ChainEKFOptions(), ChainEKFOptions(use_h2=False, switch_dps=None)])
def test_compiled_observation_equals_reference(moving_rec, opts):
    rng = np.random.default_rng(0)
    tree = _tree(moving_rec.sensors, truth_chain_model(moving_rec))
    kw = dict(mh=np.full(20, 30.0), fnorm0=np.full(20, 47.0),
              rz=np.tile(np.eye(3)[:2], (20, 1, 1)), fast=rng.random(20) > 0.5)
    args = _args(moving_rec, 450, rng)
    ref = observe(tree, *args, options=opts, **kw)
    got = observe_fast(tree, *args, kw["mh"], kw["fnorm0"], kw["rz"], kw["fast"], opts)
    for a, b in zip(ref, got):
        assert np.allclose(a, b, atol=1e-12)


def test_jacobian_matches_finite_differences(moving_rec):
    rng = np.random.default_rng(1)
    tree = _tree(moving_rec.sensors, truth_chain_model(moving_rec))
    kw = dict(mh=np.full(20, 30.0), fnorm0=np.full(20, 47.0),
              rz=np.tile(np.eye(3)[:2], (20, 1, 1)), fast=np.zeros(20, bool),
              options=ChainEKFOptions())
    r, w, dw, a, m = _args(moving_rec, 500, rng)
    _, hx, h, _ = observe(tree, r, w, dw, a, m, **kw)
    q = moving_rec.truth.quat[:, 500]
    eps = 1e-6
    for k in (0, 10, 3, 16, 19):
        for ax in range(3):
            d = np.zeros((20, 3))
            d[k, ax] = eps
            _, hx2, _, _ = observe(tree, quat_to_mat(qmul(qexp(d), q)), w, dw, a, m, **kw)
            assert np.allclose((hx2 - hx) / eps, h[:, 3 * k + ax], atol=1e-3)


def test_noise_free_recording_is_tracked(imu_hand):
    rec = simulate_imu(free_motion(8.0, seed=3, elbow="moving"), hand=imu_hand, noise=None)
    err = angle_deg(ChainEKF(truth_chain_model(rec)).run(rec), rec.truth.quat)
    assert err.max() < 0.2


def test_white_noise_only_beats_raw_integration(imu_hand):
    from handsynth.sensors.imu import MPU9250_DATASHEET, AxisNoise, ImuNoise, MagNoise

    d = MPU9250_DATASHEET
    white = ImuNoise(AxisNoise(d.gyro.white, 0, 0), AxisNoise(d.accel.white, 0, 0),
                     MagNoise(0.3, 0, 0, 0, 0))
    rec = simulate_imu(free_motion(12.0, seed=4), hand=imu_hand, noise=white, seed=5)

    def rmse(q):
        return np.sqrt(np.mean(angle_deg(q, rec.truth.quat)[:, 400:] ** 2))

    assert rmse(ChainEKF(truth_chain_model(rec)).run(rec)) < rmse(RawIntegration().run(rec))


@pytest.mark.parametrize("bias_tau_s", [None, 20.0])
def test_compiled_loop_equals_reference_loop(moving_rec, bias_tau_s):
    model = truth_chain_model(moving_rec)
    short = moving_rec.slice(0, 450)
    options = ChainEKFOptions(bias_tau_s=bias_tau_s)
    fast = ChainEKF(model, options=options).run(short)
    ref = ChainEKF(model, options=options, fast=False).run(short)
    assert angle_deg(fast, ref).max() < 1e-4  # arccos resolution near 0



def test_compiled_loop_equals_reference_loop_over_filled_samples(moving_rec):
    import dataclasses

    model = truth_chain_model(moving_rec)
    filled = np.zeros((20, 450), bool)
    filled[14, 250:300] = filled[3, 260:280] = True
    short = dataclasses.replace(moving_rec.slice(0, 450), filled=filled)
    fast = ChainEKF(model).run(short)
    ref = ChainEKF(model, fast=False).run(short)
    assert angle_deg(fast, ref).max() < 1e-4  # arccos resolution near 0
    # the mark changes the filter only where it loosens: before the first filled sample,
    # the same attitudes as without it
    plain = ChainEKF(model).run(moving_rec.slice(0, 450))
    assert angle_deg(fast[:, :250], plain[:, :250]).max() < 1e-4
    assert angle_deg(fast[:, 250:], plain[:, 250:]).max() > 1e-3


def test_a_sensor_bridged_comes_back_after_the_gap(imu_hand):
    """A sensor held 0.5 s, bridged: with its attitude loosened over the filled samples the
    readings after the gap pull it back; held tight (as before) it stays off."""
    import dataclasses

    from handsynth.sensors.imu import bridge_lost

    rec = simulate_imu(free_motion(9.0, seed=4, elbow="moving"), hand=imu_hand, seed=8)
    k, start, n = rec.index("index_middle"), 560, 50
    arrays = {name: getattr(rec, name).copy() for name in ("acc", "gyr", "mag")}
    for a in arrays.values():
        a[k, start:start + n] = a[k, start - 1]
    out, _ = bridge_lost(dataclasses.replace(rec, **arrays))
    model = truth_chain_model(rec)
    after = slice(start + n + 100, None)  # from 1 s after the gap on
    truth = rec.truth.quat[k, after]
    loose = angle_deg(ChainEKF(model).run(out)[k, after], truth)
    tight = angle_deg(ChainEKF(model).run(dataclasses.replace(out, filled=None))[k, after], truth)
    recorded = angle_deg(ChainEKF(model).run(rec)[k, after], truth)
    rms = [float(np.sqrt(np.mean(e**2))) for e in (loose, tight, recorded)]
    assert rms[0] < 0.5 * rms[1] and rms[0] < rms[2] + 1.0, rms

@pytest.mark.slow
def test_filter4b_learns_a_gyro_bias_that_drifts(imu_hand):
    """A gyro bias drifting by up to 1 deg/s per minute: Filter 4 drifts with it, filter4b much less."""
    from dataclasses import replace

    from handsynth.sensors.imu import MPU9250_DATASHEET, make_filter

    d = MPU9250_DATASHEET
    noise = replace(d, gyro=replace(d.gyro, bias_drift_rate=np.radians(1.0) / 60.0))
    rec = simulate_imu(free_motion(40.0, seed=6), hand=imu_hand, noise=noise, seed=7)
    model = truth_chain_model(rec)

    def rmse(name):
        return np.sqrt(np.mean(angle_deg(make_filter(name, model).run(rec), rec.truth.quat)[:, 400:] ** 2))

    assert rmse("filter4b") < 0.75 * rmse("filter4")  # 3.8 against 5.9 deg
