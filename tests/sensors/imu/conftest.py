import pytest

from handsynth.sensors.imu import ImuHand, free_motion, simulate_imu


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
