import warnings

import pytest

from handsynth.sensors.imu import (
    ImuHand,
    SkinMotion,
    calibrate,
    calibration_motion,
    free_motion,
    simulate_imu,
)


@pytest.fixture(scope="session")
def imu_hand():
    return ImuHand()


@pytest.fixture(scope="session")
def free_rec(imu_hand):
    """12 s of free motion, elbow fixed, datasheet noise."""
    return simulate_imu(free_motion(12.0, seed=5), hand=imu_hand, seed=6)


@pytest.fixture(scope="session")
def ideal_rec(imu_hand):
    """The same motion without noise."""
    return simulate_imu(free_motion(12.0, seed=5), hand=imu_hand, noise=None)


@pytest.fixture(scope="session")
def worn():
    """A calibration and a free motion of the same sensors, with skin motion."""
    skin = SkinMotion(2.0, 4.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the simulated disturbance and still-start notes
        cal = calibrate(simulate_imu(calibration_motion(), hand=ImuHand(tip_sensors=True),
                                     skin=skin, seed=1, device_seed=2), sensor_calibration=False)
        rec = simulate_imu(free_motion(12.0, seed=3), hand=ImuHand(), skin=skin, seed=4,
                           device_seed=2)
    return cal, rec
