"""6-axis sensors (no magnetometer): read, checked, calibrated and tracked."""

import dataclasses

import numpy as np
import pytest

from handsynth.errors import EstimationError, RecordingError
from handsynth.sensors.imu import (
    AhrsEKFEstimator,
    Filter1,
    GatedFilter,
    MadgwickEstimator,
    MahonyEstimator,
    RawIntegration,
    StaticStart,
    VQFEstimator,
    bridge_lost,
    check_recording,
    free_motion,
    initial_attitude,
    simulate_imu,
)
from handsynth.sensors.imu._ekf import ChainEKF
from handsynth.sensors.imu._quat import angle_deg, qconj, qmul
from handsynth.sensors.imu._vectors import truth_chain_model


def _six(rec):
    return dataclasses.replace(rec, mag=None)


def _headings_deg(q, q_true):
    d = qmul(q_true, qconj(q))
    return np.degrees(2 * np.arctan2(d[..., 3], d[..., 0]))


def _turned(q, psi_deg):
    h = np.radians(psi_deg) / 2
    return qmul(np.array([np.cos(h), 0.0, 0.0, np.sin(h)]), q)


def test_headings_come_from_the_common_rotation(free_rec):
    six = _six(free_rec)
    q6, q9 = initial_attitude(six), initial_attitude(free_rec)
    truth = free_rec.truth.quat[:, 0]
    psi = _headings_deg(q6, truth)
    # one heading for the whole hand (the common rotation's direction, not north), the
    # sensors within a fraction of a degree of one another, as the compass aligned by it
    assert np.ptp(psi) < 1.5 and np.std(psi) <= np.std(_headings_deg(q9, truth)) + 0.05
    assert abs(np.mean(psi)) > 10  # not north: nothing here reads the field
    # the inclination is the accelerometer's either way
    err = angle_deg(_turned(q6, np.mean(psi)), truth)
    assert err.max() < 3.0
    with pytest.raises(EstimationError, match=r"6-axis sensors \(no magnetometer\) takes the "
                                              r"sensors' headings from the common rotation, and it "
                                              r"is off \(--align none\)"):
        initial_attitude(six, StaticStart(align_start_s=None))


def test_one_sensor_without_a_common_rotation_takes_its_own_x_axis(free_rec):
    off = StaticStart(align_start_s=None)
    for name in ("index_proximal", "hand_radial"):
        one = _six(free_rec.subset((name,)))
        q = initial_attitude(one, off)
        truth = free_rec.truth.quat[free_rec.index(name), 0]
        # its heading is its own (not the truth's), its inclination the accelerometer's
        err = angle_deg(_turned(q, _headings_deg(q, truth)[0]), truth[None])
        assert err.max() < 3.0
        # the world's x is the sensor's x axis made horizontal: x has no sideways part
        from handsynth.sensors.imu._quat import qrot

        x_world = qrot(q[0], np.array([1.0, 0.0, 0.0]))
        assert abs(x_world[1]) < 1e-9 and x_world[0] > 0
        assert GatedFilter(static=off).run(one).shape == (1, one.n, 4)

@pytest.mark.parametrize("est", [RawIntegration(), GatedFilter(), VQFEstimator(),
                                 VQFEstimator(online=True, name="vqf_online")],
                         ids=lambda e: e.name)
def test_single_sensor_filters_track_without_the_magnetometer(est, free_rec):
    q9 = est.run(free_rec)
    q6 = est.run(_six(free_rec))
    truth = free_rec.truth.quat
    psi = np.mean(_headings_deg(q6[:, 0], truth[:, 0]))
    err6 = angle_deg(_turned(q6, psi), truth)[:, 400:]
    err9 = angle_deg(q9, truth)[:, 400:]
    # 12 s: the gyros hold the headings the common rotation gave
    assert np.sqrt(np.mean(err6**2)) < 3.0
    assert np.sqrt(np.mean(err6**2)) < np.sqrt(np.mean(err9**2)) + 1.0
    # the relative headings are what joint angles need: adjacent sensors as in the truth
    rel6 = angle_deg(qmul(qconj(q6[14]), q6[15]), qmul(qconj(truth[14]), truth[15]))
    assert np.sqrt(np.mean(rel6[400:] ** 2)) < 3.0


@pytest.mark.parametrize("est", [Filter1(), MadgwickEstimator(), MahonyEstimator(),
                                 AhrsEKFEstimator()], ids=lambda e: e.name)
def test_filters_that_need_the_compass_say_so(est, free_rec):
    with pytest.raises(EstimationError, match=rf"^{est.name} .*6-axis sensors has no "
                                              r"magnetometer.*: use filter4, gated, raw or vqf"):
        est.run(_six(free_rec.slice(0, 500)))


def test_filter4_tracks_without_the_magnetometer(imu_hand):
    rec = simulate_imu(free_motion(6.0, seed=1, elbow="moving"), hand=imu_hand, seed=2)
    model = truth_chain_model(rec)
    six = _six(rec)
    fast = ChainEKF(model).run(six)
    # the compiled loop and the plain reference agree on the zero field too (the slice's
    # last sample aside: its angular acceleration is a one-sided difference there)
    plain = ChainEKF(model, fast=False).run(six.slice(0, 450))
    assert angle_deg(fast[:, :449], plain[:, :449]).max() < 1e-4  # deg: arccos rounding
    truth = rec.truth.quat
    psi = np.mean(_headings_deg(fast[:, 0], truth[:, 0]))
    err6 = angle_deg(_turned(fast, psi), truth)[:, 400:]
    err9 = angle_deg(ChainEKF(model).run(rec), truth)[:, 400:]
    assert np.sqrt(np.mean(err6**2)) < 3.0
    assert np.sqrt(np.mean(err6**2)) < np.sqrt(np.mean(err9**2)) + 0.5


def test_checks_and_bridging_read_six_axis_recordings(free_rec):
    six = _six(free_rec)
    assert check_recording(six) == []
    bad = six.acc.copy()
    bad[3, 700, 1] = np.nan
    with pytest.raises(RecordingError, match=r"sensor 'hand_ulnar' acc axis y is not finite at "
                                             r"sample 700"):
        check_recording(dataclasses.replace(six, acc=bad))
    # a reading held by the logger for 0.2 s is found and bridged without a magnetometer
    acc, gyr = six.acc.copy(), six.gyr.copy()
    acc[14, 600:620], gyr[14, 600:620] = acc[14, 599], gyr[14, 599]
    held = dataclasses.replace(six, acc=acc, gyr=gyr)
    with pytest.raises(RecordingError, match=r"'index_proximal'.*samples lost"):
        check_recording(held)
    bridged, found = bridge_lost(held)
    assert bridged.mag is None and [h.sensor for h in found] == ["index_proximal"]
    assert check_recording(bridged) == []
