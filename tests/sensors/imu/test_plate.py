import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from handsynth.errors import InvalidInputError, RecordingError
from handsynth.sensors.imu import (
    CALIBRATION_PLAN,
    PLATE_SENSORS,
    ImuCalibration,
    ImuHand,
    ImuPlacement,
    calibration_motion,
    fingertip_positions,
    fuse_plate,
    plate_rotations,
    simulate_imu,
    truth_chain_model,
)
from handsynth.sensors.imu._quat import angle_deg, mat_to_quat, qmul

SENSORS = ("index_distal", *PLATE_SENSORS, "hand_radial")


def _scalar_last(q):
    return np.roll(q, -1, axis=-1)


def _scalar_first(q):
    return np.roll(q, 1, axis=-1)


def _plate_case(n=200, seed=0, spread_deg=2.0):
    """Quaternions of a turning plate seen by three sensors with their own errors."""
    rng = np.random.default_rng(seed)
    mounts = Rotation.from_rotvec(np.radians(rng.normal(0, 8, (3, 3))))    # sensor -> plate
    plate = Rotation.from_rotvec(np.cumsum(rng.normal(0, 0.05, (n, 3)), axis=0))
    q = np.empty((len(SENSORS), n, 4))
    q[0] = _scalar_first(Rotation.random(n, random_state=seed).as_quat())
    q[4] = _scalar_first(Rotation.random(n, random_state=seed + 1).as_quat())
    errs = Rotation.from_rotvec(np.radians(rng.normal(0, spread_deg, (3, n, 3))))
    for k in range(3):
        q[1 + k] = _scalar_first((errs[k] * plate * mounts[k]).as_quat())
    # the plate rotations as plate_rotations gives them: sensor k -> sensor 1 (reference)
    rel = {s: (mounts[0].inv() * mounts[k]).as_matrix() for k, s in enumerate(PLATE_SENSORS)}
    return q, rel, plate, mounts, errs


def test_fused_plate_matches_the_plain_quaternion_mean():
    q, rel, _, mounts, _ = _plate_case()
    out = fuse_plate(q, SENSORS, rel)
    # reference: each sensor's estimate of the reference sensor's attitude, averaged
    # by scipy (Markley's mean), turned back into every plate sensor's frame
    ref = [Rotation.from_quat(_scalar_last(q[1 + k])) * Rotation.from_matrix(rel[s]).inv()
           for k, s in enumerate(PLATE_SENSORS)]
    for i in (0, 57, 199):
        mean = Rotation.concatenate([r[i] for r in ref]).mean()
        for k, s in enumerate(PLATE_SENSORS):
            want = _scalar_first((mean * Rotation.from_matrix(rel[s])).as_quat())
            assert angle_deg(out[1 + k, i], want) < 1e-4
    # the rotations between the plate's sensors are exactly the stored ones
    for k in (1, 2):
        r1 = Rotation.from_quat(_scalar_last(out[1]))
        rk = Rotation.from_quat(_scalar_last(out[1 + k]))
        d = (r1.inv() * rk * Rotation.from_matrix(rel[PLATE_SENSORS[k]]).inv()).magnitude()
        assert np.degrees(d).max() < 1e-6
    # the other sensors are untouched, the input too
    assert np.array_equal(out[0], q[0]) and np.array_equal(out[4], q[4])
    assert not np.array_equal(out[1], q[1])
    assert mounts is not None


def test_fusion_averages_the_sensors_errors_away():
    q, rel, plate, mounts, errs = _plate_case(n=2000, spread_deg=2.0)
    out = fuse_plate(q, SENSORS, rel)
    true = [_scalar_first((plate * mounts[k]).as_quat()) for k in range(3)]
    before = np.mean([np.sqrt(np.mean(angle_deg(q[1 + k], true[k]) ** 2)) for k in range(3)])
    after = np.mean([np.sqrt(np.mean(angle_deg(out[1 + k], true[k]) ** 2)) for k in range(3)])
    assert after == pytest.approx(before / np.sqrt(3), rel=0.1)
    # errors that cancel exactly give the truth
    q2 = q.copy()
    e = Rotation.from_rotvec(np.radians([[1.5, 0.0, 0.0]]))
    q2[1] = _scalar_first((e * plate * mounts[0]).as_quat())
    q2[2] = _scalar_first((e.inv() * plate * mounts[1]).as_quat())
    q2[3] = true[2]
    out2 = fuse_plate(q2, SENSORS, rel)
    for k in range(3):
        assert angle_deg(out2[1 + k], true[k]).max() < 1e-4
    assert errs is not None


def test_a_stray_sensor_is_left_out_with_a_warning():
    q, rel, plate, mounts, _ = _plate_case(n=300, spread_deg=1.0)
    true = [_scalar_first((plate * mounts[k]).as_quat()) for k in range(3)]
    bad = q.copy()
    off = Rotation.from_rotvec(np.radians([0.0, 40.0, 0.0]))
    bad[2, 100:160] = _scalar_first((off * Rotation.from_quat(_scalar_last(q[2, 100:160])))
                                    .as_quat())
    with pytest.warns(UserWarning, match="forearm_2 in 60 samples of 300"):
        out = fuse_plate(bad, SENSORS, rel)
    clean = fuse_plate(q, SENSORS, rel)
    for k in range(3):       # where it strayed, the other two carry the plate
        assert angle_deg(out[1 + k, 100:160], true[k][100:160]).max() < 4.0
    np.testing.assert_allclose(out[:, :100], clean[:, :100])
    # without the exclusion the stray sensor would have pulled every plate sensor off
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        loose = fuse_plate(bad, SENSORS, rel, disagree_deg=90.0)
    assert angle_deg(loose[1, 100:160], true[0][100:160]).min() > 8.0
    # two sensors: no telling which strayed; the mean is kept and the disagreement said
    with pytest.warns(UserWarning, match="forearm_1 and forearm_2 disagree by more than 20 deg "
                                         "in 60 of 300 samples"):
        two = fuse_plate(bad[:3], SENSORS[:3], rel)
    assert angle_deg(two[1, 100:160], true[0][100:160]).min() > 8.0


def test_fusion_ignores_quaternion_signs_and_absent_sensors():
    q, rel, *_ = _plate_case()
    flipped = q.copy()
    flipped[2, ::3] *= -1
    a, b = fuse_plate(q, SENSORS, rel), fuse_plate(flipped, SENSORS, rel)
    assert angle_deg(a[1:4], b[1:4]).max() < 1e-4
    # one plate sensor alone is left as it is; two are fused
    keep = (0, 1, 4)
    one = fuse_plate(q[list(keep)], [SENSORS[i] for i in keep], rel)
    assert np.array_equal(one, q[list(keep)])
    two = fuse_plate(q[:3], SENSORS[:3], rel)
    assert not np.array_equal(two[1], q[1])
    with pytest.raises(InvalidInputError, match="not a rotation matrix"):
        fuse_plate(q, SENSORS, {**rel, "forearm_2": 2 * np.eye(3)})
    with pytest.raises(InvalidInputError, match="must have shape"):
        fuse_plate(q[:, :, :3], SENSORS, rel)


@pytest.fixture(scope="module")
def plate_cal():
    """Static start and elbow rotation of a hand whose plate sensors are tilted differently."""
    tilts = {"forearm_1": (3.0, -2.0, 4.0), "forearm_2": (-5.0, 1.0, 2.0),
             "forearm_3": (2.0, 6.0, -3.0)}
    hand = ImuHand(placement=ImuPlacement(tilts_deg=tilts), tip_sensors=True)
    plan = tuple(p for p in CALIBRATION_PLAN if p[0] == "elbow_flex")
    return simulate_imu(calibration_motion(plan=plan), hand=hand, noise=None)


def test_plate_rotations_are_the_true_ones(plate_cal):
    rel = plate_rotations(plate_cal)
    assert set(rel) == set(PLATE_SENSORS) and np.allclose(rel["forearm_1"], np.eye(3))
    r = Rotation.from_quat(_scalar_last(plate_cal.truth.quat[:, 0]))
    for s in PLATE_SENSORS:
        want = (r[plate_cal.index("forearm_1")].inv() * r[plate_cal.index(s)]).as_matrix()
        assert angle_deg(mat_to_quat(rel[s]), mat_to_quat(want)) < 0.05
    with pytest.raises(InvalidInputError, match="at least two"):
        plate_rotations(plate_cal, sensors=("forearm_1",))
    with pytest.raises(InvalidInputError, match="lacks plate sensor"):
        plate_rotations(plate_cal.subset(("forearm_1", "forearm_2", "hand_radial")))


def test_every_chain_puts_the_wrist_at_one_point(plate_cal):
    """Link vectors from the same static start: fused, the three chains share the wrist."""
    from handsynth.sensors.imu import ChainModel, link_vectors

    rel = plate_rotations(plate_cal)
    truth = plate_cal.truth.joint_vectors
    model = ChainModel(truth_chain_model(plate_cal).own, link_vectors(plate_cal, truth))
    rng = np.random.default_rng(3)
    q = plate_cal.truth.quat.copy()
    for s in PLATE_SENSORS:        # each forearm sensor with its own attitude error
        k = plate_cal.index(s)
        e = _scalar_first(Rotation.from_rotvec(np.radians(rng.normal(0, 2, 3))).as_quat())
        q[k] = qmul(e, q[k])
    fused = fuse_plate(q, plate_cal.sensors, rel)
    for quats, same in ((q, False), (fused, True)):
        tips = fingertip_positions(quats, plate_cal.sensors, model)
        wrists = np.stack([tips[f"{f}_joints"][:, 0] for f in ("index", "ring", "thumb")])
        spread = np.abs(wrists - wrists[0]).max()
        assert (spread < 1e-9) if same else (spread > 1e-3)


def test_calibration_file_keeps_the_plate(tmp_path, ideal_rec):
    model = truth_chain_model(ideal_rec)
    sensors = tuple(model.own)
    rel = {s: Rotation.from_rotvec([0.0, 0.1 * k, 0.0]).as_matrix()
           for k, s in enumerate(PLATE_SENSORS)}
    cal = ImuCalibration(model, {s: np.eye(3) for s in sensors}, np.zeros(20), sensors, plate=rel)
    path = cal.save(tmp_path / "c.json")
    d = json.loads(path.read_text())
    assert d["version"] == 6 and set(d["plate"]) == set(PLATE_SENSORS)
    back = ImuCalibration.load(path)
    for s in PLATE_SENSORS:
        assert np.allclose(back.plate[s], rel[s])
    q = ideal_rec.truth.quat
    assert not np.array_equal(back.fuse(q, ideal_rec.sensors), q)
    assert back.fuse(q, ideal_rec.sensors, plate_fusion=False) is q
    # version 4 files load without the plate: each forearm sensor keeps its attitude
    del d["plate"]
    d["version"] = 4
    p4 = tmp_path / "v4.json"
    p4.write_text(json.dumps(d))
    old = ImuCalibration.load(p4)
    assert old.plate is None and old.fuse(q, ideal_rec.sensors) is q
    d["version"] = 5
    d["plate"] = {"forearm_1": np.eye(3).tolist(), "forearm_2": (2 * np.eye(3)).tolist()}
    p4.write_text(json.dumps(d))
    with pytest.raises(RecordingError, match="plate rotation\\(s\\) of forearm_2"):
        ImuCalibration.load(p4)
    d["plate"] = {"forearm_1": [1, 2]}
    p4.write_text(json.dumps(d))
    with pytest.raises(RecordingError, match="malformed plate rotations"):
        ImuCalibration.load(p4)
