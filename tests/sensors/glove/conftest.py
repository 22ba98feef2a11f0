import pytest

from handsynth.sensors.glove import (
    calibrate,
    don_glove,
    make_user,
    motions_for,
    simulate_session,
)


@pytest.fixture(scope="session")
def user():
    return make_user(0, hand_length=1.04)


@pytest.fixture(scope="session")
def dg5(user):
    return don_glove(user, "dg5", seed=1)


@pytest.fixture(scope="session")
def cal_rec(user, dg5):
    """Calibration session: 4 trials of the 3 DG5 motions."""
    return simulate_session(user, dg5, motions_for("dg5"), trials=4, seed=10)


@pytest.fixture(scope="session")
def estimators(cal_rec):
    return calibrate(cal_rec)
