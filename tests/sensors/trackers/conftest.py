import pytest
from scipy.spatial.transform import Rotation

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


def _liberty_lines(rec, *, scale, counter, quaternion, decimal_comma=False):
    """Liberty ASCII lines, written here by hand (not by the library)."""
    out = []
    for i in range(rec.n_frames):
        for s in (0, 1):
            p = rec.positions[i, s] * scale
            r = Rotation.from_matrix(rec.rotations[i, s])
            a = r.as_quat()[[3, 0, 1, 2]] if quaternion else r.as_euler("ZYX", degrees=True)
            head = f"{s + 1:3d}" + (f"{1000 + i:8d}" if counter else "")
            line = head + "".join(f" {v:10.4f}" for v in p) + "".join(f" {v:10.5f}" for v in a)
            out.append(line.replace(".", ",") if decimal_comma else line)
    return out


def _pimgr_lines(rec, *, scale, t0=0.0, duplicate_every=0):
    """PiMgr CSV lines with header; every `duplicate_every`-th sample written twice."""
    out = ["Time,w1,x1,y1,z1,w2,x2,y2,z2,loc1_x,loc1_y,loc1_z,loc2_x,loc2_y,loc2_z"]
    for i in range(rec.n_frames):
        q = [Rotation.from_matrix(rec.rotations[i, s]).as_quat()[[3, 0, 1, 2]] for s in (0, 1)]
        if i % 7 == 3:
            q[0] = -q[0]  # a quaternion sign flip: the same rotation
        p = rec.positions[i] * scale
        vals = [*q[0], *q[1], *p[0], *p[1]]
        t = t0 + rec.times[i]
        out.append(f"{t:.4f}," + ",".join(f"{v:.6f}" for v in vals))
        if duplicate_every and i % duplicate_every == 0:
            out.append(f"{t + 0.5 / 240:.4f}," + ",".join(f"{v:.6f}" for v in vals))
    return out


@pytest.fixture(scope="session")
def liberty_lines():
    return _liberty_lines


@pytest.fixture(scope="session")
def pimgr_lines():
    return _pimgr_lines
