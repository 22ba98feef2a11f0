import pytest

from handsynth.sensors.trackers import FlexionMotion, simulate_recording


@pytest.fixture(scope="session")
def finger_rec():
    """Short finger-like DIP recording at Liberty-like noise (table geometry)."""
    return simulate_recording(
        "index_dip", model="finger", motion=FlexionMotion(duration_s=12.0),
        seed=3, geometry_source="table",
    )


@pytest.fixture(scope="session")
def hinge_rec():
    """Mock (pure hinge) recording without wobble."""
    return simulate_recording(
        "index_dip", model="hinge",
        motion=FlexionMotion(duration_s=12.0, wobble_deg=0.0, proximal_coupling=0.0),
        seed=4, geometry_source="table",
    )
