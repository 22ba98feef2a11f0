"""Input checks of the public API: what a library call refuses, warns about or accepts."""

import dataclasses
import warnings

import numpy as np
import pytest

from handsynth.errors import InvalidInputError, RecordingError
from handsynth.sensors.imu import (
    EVAL_NOISE,
    SENSOR_NAMES,
    ChainEKF,
    ChainEKFOptions,
    Filter1Options,
    GatedOptions,
    ImuRecording,
    KalmanDenoiser,
    MadgwickEstimator,
    MagDisturbance,
    MagNoise,
    NoiseCoefficients,
    SkinMotion,
    StaticStart,
    VQFEstimator,
    allan_deviation,
    check_recording,
    fingertip_positions,
    free_motion,
    fuse_plate,
    integrate_gyro,
    joint_angles,
    make_filter,
    noise_coefficients,
    read_imu_csv,
    simulate_imu,
    truth_chain_model,
    truth_link_frames,
    write_imu_csv,
    zero_offsets,
)

# every single-sensor estimator; Filter 4 (needs a link model) is tested apart
SINGLE = ("constant", "raw", "filter1", "gated", "vqf", "vqf_online", "madgwick", "mahony",
          "ahrs_ekf")


@pytest.fixture(scope="module")
def one(free_rec):
    """Two sensors, 6 s (still start, common rotation, motion)."""
    return free_rec.subset(("forearm_1", "index_distal")).slice(0, 600)


# 1. sampling rate ---------------------------------------------------------------------------

@pytest.mark.parametrize("rate", [-100.0, 0.0, float("nan"), float("inf"), None])
def test_a_rate_that_is_not_a_positive_number_is_refused_by_name(one, rate):
    with pytest.raises(InvalidInputError, match="rate_hz"):
        VQFEstimator(online=True).run(dataclasses.replace(one, rate_hz=rate))


def test_every_estimator_refuses_a_bad_rate_before_running(one):
    # the recording is refused when made, so no filter (VQF's C++ included) sees it
    for rate in (-100.0, 0.0):
        for name in SINGLE:
            with pytest.raises(InvalidInputError, match="rate_hz"):
                make_filter(name).run(dataclasses.replace(one, rate_hz=rate))


@pytest.mark.parametrize("rate", [-100.0, 0.0, float("nan"), None])
def test_integrate_gyro_refuses_a_bad_rate(rate):
    with pytest.raises(InvalidInputError, match="rate_hz"):
        integrate_gyro(np.array([[1.0, 0, 0, 0]]), np.zeros((1, 10, 3)), rate)


def test_integrate_gyro_checks_its_arrays():
    q0, gyr = np.array([[1.0, 0, 0, 0]]), np.zeros((1, 10, 3))
    with pytest.raises(InvalidInputError, match="gyr must have shape"):
        integrate_gyro(q0, np.zeros((10, 3)), 100.0)
    with pytest.raises(InvalidInputError, match="q0 must have shape"):
        integrate_gyro(np.array([1.0, 0, 0, 0]), gyr, 100.0)
    with pytest.raises(InvalidInputError, match="unit quaternions"):
        integrate_gyro(2 * q0, gyr, 100.0)
    out = integrate_gyro(q0.tolist(), gyr.astype(np.float32), 100)
    assert out.dtype == np.float64 and np.allclose(out, [1.0, 0, 0, 0])


# 2. the recording's content ---------------------------------------------------------------

@pytest.mark.parametrize("name", SINGLE)
def test_run_refuses_gyro_in_deg_per_s(one, name):
    with pytest.raises(RecordingError, match="deg/s"):
        make_filter(name).run(dataclasses.replace(one, gyr=np.degrees(one.gyr)))


def test_run_refuses_a_nan_sample_naming_it(one):
    gyr = one.gyr.copy()
    gyr[1, 321, 2] = np.nan
    for name in ("raw", "gated", "vqf", "madgwick"):
        with pytest.raises(RecordingError, match=r"'index_distal' gyr axis z .* sample 321"):
            make_filter(name).run(dataclasses.replace(one, gyr=gyr))


def test_filter4_runs_the_same_checks(free_rec):
    est = ChainEKF(truth_chain_model(free_rec))
    with pytest.raises(RecordingError, match="deg/s"):
        est.run(dataclasses.replace(free_rec, gyr=np.degrees(free_rec.gyr)))
    with pytest.raises(InvalidInputError, match="rate_hz"):
        est.run(dataclasses.replace(free_rec, rate_hz=0.0))


def test_a_static_start_longer_than_the_recording_is_refused(one):
    for name in ("raw", "vqf", "madgwick"):
        est = dataclasses.replace(make_filter(name), static=StaticStart(static_s=10.0))
        with pytest.raises(RecordingError, match="static start static_s=10 s is longer"):
            est.run(one)
    # a common rotation cut by the end is used as far as it goes; one wholly after it is refused
    assert make_filter("raw").run(one.slice(0, 300)).shape == (2, 300, 4)     # 3 s; 2-4 s
    with pytest.raises(InvalidInputError, match="common rotation 2.0-4.0 s is outside"):
        make_filter("raw").run(one.slice(0, 201))


def test_run_warns_what_check_recording_warns_about_once(imu_hand):
    rec = simulate_imu(free_motion(20.0, seed=1), hand=imu_hand, noise=EVAL_NOISE, seed=1)
    rec = rec.subset(("forearm_1", "index_distal"))
    with pytest.warns(UserWarning, match="magnetic disturbance"):
        make_filter("vqf").run(rec)
    # the same recording again, or after check_recording returned the warnings: no repeat
    again = dataclasses.replace(rec)
    assert check_recording(again)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        make_filter("vqf").run(again)


def test_sensor_names_must_be_unique_strings(one):
    acc = np.repeat(one.acc[:1], 20, axis=0)
    with pytest.raises(RecordingError, match="'forearm_1' given more than once"):
        ImuRecording(100.0, ("forearm_1",) * 20, acc, acc, acc)
    with pytest.raises(RecordingError, match="sensor names"):
        ImuRecording(100.0, "ab", one.acc, one.gyr, one.mag)


# 3. layout and dtype ----------------------------------------------------------------------

def test_wrong_layouts_are_named(one):
    first = one.subset(("forearm_1",))
    with pytest.raises(RecordingError, match=r"acc has shape \(600, 3\), expected \(S, N, 3\) "
                                             r"with S = len\(sensors\) = 1 .*a\[None\]"):
        ImuRecording(100.0, ("forearm_1",), first.acc[0], first.gyr, first.mag)
    with pytest.raises(RecordingError, match=r"gyr has shape \(2, 3, 600\).*transpose"):
        dataclasses.replace(one, gyr=one.gyr.transpose(0, 2, 1))
    with pytest.raises(RecordingError, match="as many samples"):
        dataclasses.replace(one, mag=one.mag[:, :-1])
    with pytest.raises(RecordingError, match="mag must be an array of numbers"):
        dataclasses.replace(one, mag=object())


@pytest.mark.parametrize("name", SINGLE)
def test_float32_fortran_and_list_input_agree_with_float64(one, name):
    est = make_filter(name)
    ref = est.run(one)
    variants = {
        "float32": dataclasses.replace(one, acc=one.acc.astype(np.float32),
                                       gyr=one.gyr.astype(np.float32),
                                       mag=one.mag.astype(np.float32)),
        "fortran": dataclasses.replace(one, acc=np.asfortranarray(one.acc),
                                       gyr=np.asfortranarray(one.gyr),
                                       mag=np.asfortranarray(one.mag)),
        "list": dataclasses.replace(one, acc=one.acc.tolist(), gyr=one.gyr.tolist(),
                                    mag=one.mag.tolist()),
    }
    for kind, rec in variants.items():
        assert rec.gyr.dtype == np.float64 and rec.gyr.flags.c_contiguous
        q = est.run(rec)
        dot = np.abs(np.sum(q * ref, axis=-1))
        tol = 1e-3 if kind == "float32" else 1e-9        # float32 rounding of the samples
        assert q.shape == ref.shape and np.all(1 - dot < tol), (kind, float(1 - dot.min()))


def test_a_recording_without_samples_is_refused(one):
    empty = one.slice(0, 0)
    for name in ("madgwick", "vqf", "raw"):
        est = dataclasses.replace(make_filter(name), static=StaticStart(static_s=0.01))
        with pytest.raises(RecordingError):
            est.run(empty)


# 4. joint angles, fingertips, plate -------------------------------------------------------

@pytest.fixture(scope="module")
def kin(imu_hand, ideal_rec):
    model = truth_chain_model(ideal_rec)
    frames = truth_link_frames(ideal_rec, model, imu_hand)
    return ideal_rec.truth.quat[:, :50], ideal_rec.sensors, frames, model


def test_joint_angles_refuse_quaternions_that_are_not_unit(kin):
    q, sensors, frames, model = kin
    for call in (lambda x: joint_angles(x, sensors, frames),
                 lambda x: fingertip_positions(x, sensors, model)):
        with pytest.raises(InvalidInputError, match="quats must be unit quaternions.*norm 2"):
            call(2 * q)
    ref, _ = joint_angles(q, sensors, frames)
    with pytest.warns(UserWarning, match="normalised"):
        close, _ = joint_angles(q * 1.005, sensors, frames)
    assert np.allclose(close, ref, equal_nan=True, atol=1e-9)
    tiny, _ = joint_angles((q * (1 + 1e-6)).astype(np.float32), sensors, frames)
    assert np.nanmax(np.abs(tiny - ref)) < 1e-2


def test_joint_angles_refuse_a_transposed_array_and_name_missing_sensors(kin):
    q, sensors, frames, model = kin
    with pytest.raises(InvalidInputError, match=r"\(N, S, 4\) given"):
        joint_angles(q.transpose(1, 0, 2), sensors, frames)
    with pytest.raises(InvalidInputError, match=r"\(N, S, 4\) given"):
        fingertip_positions(q.transpose(1, 0, 2), sensors, model)
    with pytest.raises(InvalidInputError, match=r"\(N, S, 4\) given"):
        fuse_plate(q.transpose(1, 0, 2), sensors, {})
    without = [k for k, s in enumerate(sensors) if s != "ring_middle"]
    with pytest.raises(InvalidInputError, match="'ring_middle' .joint ring_pip"):
        joint_angles(q[without], [sensors[k] for k in without], frames)
    partial = {s: f for s, f in frames.items() if s != "index_middle"}
    with pytest.raises(InvalidInputError, match="frames has no link frame of sensor 'index_middle'"):
        joint_angles(q, sensors, partial)


@pytest.mark.parametrize("side", ["Right", "rigth", "", None])
def test_joint_angles_refuse_an_unknown_side(kin, side, ideal_rec):
    q, sensors, frames, _ = kin
    with pytest.raises(InvalidInputError, match="side must be 'right' or 'left'"):
        joint_angles(q, sensors, frames, side=side)
    with pytest.raises(InvalidInputError, match="side must be 'right' or 'left'"):
        zero_offsets(ideal_rec, frames, side=side)


def test_joint_angles_refuse_a_zero_of_another_shape(kin):
    q, sensors, frames, _ = kin
    for zero in (np.ones(1), np.ones(19), np.ones((1, 20))):
        with pytest.raises(InvalidInputError, match=r"zero must have shape \(20,\)"):
            joint_angles(q, sensors, frames, zero=zero)
    a, _ = joint_angles(q, sensors, frames, zero=np.ones(20))
    b, _ = joint_angles(q, sensors, frames)
    assert np.allclose(a, b - 1.0, equal_nan=True)


def test_fuse_plate_checks_its_arguments(kin):
    q, sensors, _, _ = kin
    rot = {"forearm_1": np.eye(3), "forearm_2": np.eye(3), "forearm_3": np.eye(3)}
    with pytest.raises(InvalidInputError, match="unit quaternions"):
        fuse_plate(3 * q, sensors, rot)
    with pytest.raises(InvalidInputError, match="disagree_deg"):
        fuse_plate(q, sensors, rot, disagree_deg=float("nan"))
    with pytest.raises(InvalidInputError, match="more than once"):
        fuse_plate(q[:2], ("forearm_1", "forearm_1"), rot)


# 5. options -------------------------------------------------------------------------------

@pytest.mark.parametrize("make, field", [
    (lambda: Filter1Options(obs_noise=float("nan")), "obs_noise"),
    (lambda: Filter1Options(gyro_noise=-0.01), "gyro_noise"),
    (lambda: VQFEstimator(online="no"), "online"),
    (lambda: MadgwickEstimator(gain=-1.0), "gain"),
    (lambda: MadgwickEstimator(gain=float("inf")), "gain"),
    (lambda: ChainEKFOptions(switch_dps=-5.0), "switch_dps"),
    (lambda: ChainEKFOptions(use_h2="yes"), "use_h2"),
    (lambda: ChainEKFOptions(acc_sd="1"), "acc_sd"),
    (lambda: StaticStart(align_start_s=None, align_end_s=6.0), "align_start_s"),
    (lambda: StaticStart(align_start_s=3.0, align_end_s=None), "align_end_s"),
    (lambda: StaticStart(align_start_s="2", align_end_s=4.0), "align_start_s"),
    (lambda: GatedOptions(rest_s=-1.0), "rest_s"),
    (lambda: MagDisturbance(start_s=1.5, end_s=0.5), "end_s"),
    (lambda: MagDisturbance(start_s=float("nan"), end_s=0.5), "start_s"),
    (lambda: MagDisturbance(0.0, 1.0, field_ut=(1.0, 2.0)), "field_ut"),
    (lambda: MagDisturbance(0.0, 1.0, sensors=("index_prox",)), "index_prox"),
    (lambda: MagDisturbance(0.0, 1.0, sensors="index_proximal"), "sensors"),
    (lambda: MagNoise(white_ut=-1.0), "white_ut"),
    (lambda: MagNoise(soft_iron=float("nan")), "soft_iron"),
    (lambda: MagNoise(full_scale_ut=0.0), "full_scale_ut"),
    (lambda: SkinMotion(slide_mm=-2.0), "slide_mm"),
    (lambda: SkinMotion(tilt_deg=float("inf")), "tilt_deg"),
])
def test_options_refuse_bad_values_by_name(make, field):
    with pytest.raises(InvalidInputError, match=field):
        make()


def test_static_start_none_turns_the_alignment_off():
    assert StaticStart(align_start_s=None).align_end_s is None
    assert StaticStart(align_end_s=None).align_start_s is None


def test_a_disturbance_of_a_sensor_the_hand_lacks_is_refused(imu_hand):
    noise = dataclasses.replace(EVAL_NOISE, disturbances=(
        MagDisturbance(0.5, 1.0, sensors=("index_tip",)),))
    with pytest.raises(InvalidInputError, match="'index_tip', not on this hand"):
        simulate_imu(free_motion(6.0, seed=1), hand=imu_hand, noise=noise)


# 6. Allan variance ------------------------------------------------------------------------

def test_allan_functions_are_public():
    import handsynth.sensors.imu as imu

    for name in ("allan_deviation", "noise_coefficients", "KalmanDenoiser", "NoiseCoefficients"):
        assert name in imu.__all__
    assert NoiseCoefficients(1.0, 2.0, 3.0).bias_instability == 3.0


def test_allan_deviation_refuses_taus_instead_of_dropping_them():
    x = np.random.default_rng(0).normal(size=1000)
    for taus in ([0.1, float("nan")], [0.1, -0.5], [0.1, 0.0], [0.001], [6.0], []):
        with pytest.raises(InvalidInputError, match="taus"):
            allan_deviation(x, 100.0, taus)
    for rate in (0.0, -1.0, float("nan"), "100"):
        with pytest.raises(InvalidInputError, match="rate_hz"):
            allan_deviation(x, rate)
    t, _ = allan_deviation(x, 100.0, [0.01, 0.1, 4.99])
    assert np.allclose(t, [0.01, 0.1, 4.99])


def test_noise_coefficients_refuse_non_positive_or_non_finite_input():
    taus, adev = np.array([0.01, 0.1, 1.0]), np.array([1.0, 0.3, 0.1])
    with pytest.raises(InvalidInputError, match="adev must be finite and > 0.*index 1"):
        noise_coefficients(taus, [1.0, np.nan, 0.1])
    with pytest.raises(InvalidInputError, match="adev must be finite and > 0"):
        noise_coefficients(taus, [1.0, 0.0, 0.1])
    with pytest.raises(InvalidInputError, match="taus must be finite and > 0"):
        noise_coefficients([-0.01, 0.1, 1.0], adev)
    assert noise_coefficients(taus, adev).random_walk > 0


def test_kalman_denoiser_refuses_empty_or_non_finite_samples():
    den = KalmanDenoiser(1e-3, 1e-5)
    for z in ([], np.zeros((0, 3)), [1.0, np.nan]):
        with pytest.raises(InvalidInputError, match="z "):
            den.apply(z)
    with pytest.raises(InvalidInputError, match="KalmanDenoiser.rate_hz"):
        KalmanDenoiser(1e-3, 1e-5, rate_hz="100")
    assert den.apply([1.0]).shape == (1,)


# 7. the CSV writer and check_recording's arguments ----------------------------------------

@pytest.mark.parametrize("bad", ["index,distal", "a;b", "tab\there", "", " padded", 'q"uote'])
def test_write_imu_csv_refuses_names_it_cannot_read_back(tmp_path, one, bad):
    rec = dataclasses.replace(one, sensors=("forearm_1", bad))
    path = tmp_path / "rec.csv"
    with pytest.raises(RecordingError, match="cannot be written as a CSV column"):
        write_imu_csv(rec, path)
    assert not path.exists()


def test_written_names_read_back(tmp_path, one):
    rec = dataclasses.replace(one, sensors=("forearm 1", "index-distal.2"))
    write_imu_csv(rec, tmp_path / "rec.csv")
    assert read_imu_csv(tmp_path / "rec.csv").sensors == rec.sensors


@pytest.mark.parametrize("kw", [{"gyr_full_scale": float("nan")}, {"acc_full_scale": 0.0},
                                {"acc_full_scale": -1.0}, {"gyr_full_scale": "2000"},
                                {"acc_full_scale": float("inf")}])
def test_check_recording_refuses_bad_full_scales(one, kw):
    with pytest.raises(RecordingError, match=next(iter(kw))):
        check_recording(one, **kw)


def test_the_sensor_names_are_the_model_s():
    # MagDisturbance takes every sensor of the hand, tip sensors included
    MagDisturbance(0.0, 1.0, sensors=SENSOR_NAMES[:2] + ("index_tip",))


def test_helpers_name_an_argument_of_the_wrong_kind(one):
    # before: AttributeError ('float' object has no attribute 'static_s') and KeyError
    from handsynth.sensors.imu import azimuth_correction, chain_model, gyro_bias, initial_attitude

    for fn in (gyro_bias, azimuth_correction, initial_attitude):
        with pytest.raises(InvalidInputError, match=r"^static must be a StaticStart, got float 2\.0$"):
            fn(one, 2.0)
    with pytest.raises(InvalidInputError, match=r"^rec must be an ImuRecording, got"):
        gyro_bias(np.zeros((3, 10, 3)))
    with pytest.raises(InvalidInputError,
                       match=r"^vectors lacks (\d+) of the \1 sensor-to-joint vectors .*forearm_3->elbow"):
        chain_model(one, {})


def test_a_link_model_missing_only_a_next_links_vector_is_named(one):
    # before: a bare KeyError from link_vectors once each link's own vector was there
    from handsynth.sensors.imu import chain_model
    from handsynth.sensors.imu._layout import LINKS
    from handsynth.sensors.imu._vectors import _needed_vector_keys

    own = {(s1, j1) for s1, j1, _ in LINKS}
    vectors = {k: np.zeros(3) for k in _needed_vector_keys()}
    gone = next(k for k in vectors if k not in own)
    del vectors[gone]
    with pytest.raises(InvalidInputError,
                       match=rf"^vectors lacks 1 of the \d+ .*: {gone[0]}->{gone[1]} "):
        chain_model(one, vectors)


def test_a_gyro_at_zero_is_dead_only_where_its_accelerometer_lives():
    # a noise-free simulation of a still hand reads gyros of exactly 0 and a constant
    # gravity: taken; a gyro at 0 beside an accelerometer whose readings change: dead
    from handsynth.sensors.imu import ImuHand, check_recording, simulate_imu, static_motion

    ideal = simulate_imu(static_motion(3.0), hand=ImuHand(), noise=None)
    assert not ideal.gyr.any()
    assert check_recording(ideal) == []
    acc = ideal.acc.copy()
    acc[0] += 0.01 * np.random.default_rng(0).standard_normal(acc[0].shape)
    with pytest.raises(RecordingError, match=r"the gyro of sensor\(s\) 'forearm_1' reads exactly 0 "
                                             r"on every axis in all 300 samples while"):
        check_recording(dataclasses.replace(ideal, acc=acc))
