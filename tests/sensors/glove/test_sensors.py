import dataclasses
import re

import numpy as np
import pytest

from handsynth.errors import InvalidInputError
from handsynth.models import JOINT_NAMES, named_pose
from handsynth.sensors.glove import (
    SensorParams,
    bend_angle_deg,
    play_operator,
    play_operator_reference,
    sensor_joints,
    simulate_sensors,
)


def _poses(**joints):
    a = np.zeros((len(next(iter(joints.values()))), 20))
    for name, v in joints.items():
        a[:, JOINT_NAMES.index(name)] = v
    return a


def test_dg5_sees_pip_not_mcp_and_5dt_sees_both():
    mcp_only = _poses(index_mcp_flex=[0.0, 60.0])
    pip_only = _poses(index_pip_flex=[0.0, 60.0])
    dg5, fdt = SensorParams(kind="dg5"), SensorParams(kind="5dt")
    assert np.ptp(bend_angle_deg(mcp_only, dg5)[:, 1]) == 0
    assert np.ptp(bend_angle_deg(pip_only, dg5)[:, 1]) == pytest.approx(60.0)
    # 5DT manual: "average of knuckle and first joint"
    assert np.ptp(bend_angle_deg(mcp_only, fdt)[:, 1]) == pytest.approx(30.0)
    assert np.ptp(bend_angle_deg(pip_only, fdt)[:, 1]) == pytest.approx(30.0)
    # slip onto the knuckle makes a DG5 sensor see some MCP
    slipped = SensorParams(kind="dg5", crosstalk=0.1)
    assert np.ptp(bend_angle_deg(mcp_only, slipped)[:, 1]) == pytest.approx(6.0)


def test_sensor_joints_cover_each_finger_once():
    j = sensor_joints("dg5")
    names = [JOINT_NAMES[i] for i in j["distal"]]
    assert names == ["thumb_mcp_flex", "index_pip_flex", "middle_pip_flex", "ring_pip_flex",
                     "little_pip_flex"]
    with pytest.raises(InvalidInputError, match="cyberglove"):
        sensor_joints("cyberglove")


def test_play_operator_matches_reference_and_shows_hysteresis():
    rng = np.random.default_rng(0)
    x = np.cumsum(rng.normal(0, 1, (500, 5)), axis=0)
    w = np.array([0.0, 1.0, 2.0, 4.0, 8.0])
    np.testing.assert_allclose(play_operator(x, w), play_operator_reference(x, w))
    np.testing.assert_allclose(play_operator(x, np.zeros(5)), x)
    # up then down through the same input: outputs differ by the band width
    ramp = np.concatenate([np.linspace(0, 50, 51), np.linspace(50, 0, 51)])[:, None]
    y = play_operator(ramp, [4.0])[:, 0]
    assert y[-26] - y[25] == pytest.approx(4.0)  # lags: reads high on the way down


def test_readings_gain_offset_noise_saturation():
    fist = np.stack([named_pose("open"), named_pose("fist")])
    p = SensorParams(kind="dg5", gain=4.0, offset=1000.0, nonlinearity=0.0,
                     hysteresis_deg=0.0, noise_counts=0.0)
    s = simulate_sensors(fist, p)
    np.testing.assert_allclose(s[0], 1000.0)
    assert s[1, 1] == 1000.0 + 4.0 * 95.0
    # nonlinearity reads a large bend high
    s_nl = simulate_sensors(fist, p.replace(nonlinearity=0.2))
    assert s_nl[1, 1] == pytest.approx(1000 + 4 * (95 + 0.2 * 95**2 / 100), abs=0.5)
    # full scale clips
    sat = simulate_sensors(fist, p.replace(gain=50.0))
    assert sat[1, 1] == 4095
    # noise is there and of the asked size
    many = np.repeat(fist[:1], 4000, axis=0)
    noisy = simulate_sensors(many, p.replace(noise_counts=3.0), rng=np.random.default_rng(1))
    assert 2.7 < noisy[:, 1].std() < 3.3


def test_params_validate_and_are_frozen():
    with pytest.raises(InvalidInputError, match="gain"):
        SensorParams(gain=0.0)
    with pytest.raises(InvalidInputError, match="noise_counts"):
        SensorParams(noise_counts=[1, 1, -1, 1, 1])
    with pytest.raises(TypeError):
        SensorParams().replace(gian=3.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        SensorParams().gain = 3.0


@pytest.mark.parametrize("angles", [np.zeros((100, 29)), np.zeros((20, 300)), np.zeros(20),
                                    np.zeros((4, 20, 1))])
def test_angles_must_be_n_by_20(angles):
    # any array with >= 20 columns was read, a (20,) vector failed with an IndexError
    p = SensorParams()
    for fn in (simulate_sensors, bend_angle_deg):
        with pytest.raises(InvalidInputError, match=r"angles must have shape \(N, 20\), got "
                                                    + re.escape(str(angles.shape))):
            fn(angles, p)


def test_angles_must_be_finite_and_params_sensor_params():
    a = np.zeros((5, 20))
    a[2, 4] = np.nan
    with pytest.raises(InvalidInputError, match=r"angles holds nan at index \(2, 4\)"):
        simulate_sensors(a, SensorParams())
    with pytest.raises(InvalidInputError, match="params must be SensorParams, got str"):
        bend_angle_deg(np.zeros((5, 20)), "dg5")
