"""IMU finger tracking: a simulated 20-IMU system and its estimators (seed 003).

Simulation (:func:`simulate_imu`) of MPU-9250-like IMUs on the forearm (3),
the back of the hand (2) and every phalanx (15) of the handsynth hand, noise
as Allan-deviation figures; Allan variance; orientation estimators sharing
one :class:`OrientationEstimator` protocol (gyro integration, the thesis'
Filter 1 and EKF "Filter 4", and the VQF, Madgwick, Mahony and ahrs-EKF
baselines); sensor-to-joint vectors; joint angles and fingertip positions.
"""

from ._attitude import StaticStart, azimuth_correction, gyro_bias, initial_attitude
from ._ekf import ChainEKF, ChainEKFOptions, sensor_tree
from ._filters import (
    AhrsEKFEstimator,
    ConstantEstimator,
    Filter1,
    Filter1Options,
    MadgwickEstimator,
    MahonyEstimator,
    OrientationEstimator,
    RawIntegration,
    VQFEstimator,
    integrate_gyro,
)
from ._layout import CHAINS, FLEX_JOINT, LINKS, POINTS
from ._model import (
    ARM_JOINTS,
    EARTH_FIELD_UT,
    GRAVITY_MPS2,
    MODEL_JOINTS,
    SENSOR_BODIES,
    SENSOR_NAMES,
    TIP_SENSORS,
    ImuHand,
    ImuPlacement,
    imu_hand_mjcf,
)
from ._motion import (
    CALIBRATION_PLAN,
    GRASP_POSES,
    Motion,
    calibration_motion,
    concat_motions,
    free_motion,
    grasp_motion,
    static_motion,
)
from ._noise import (
    EVAL_NOISE,
    MPU9250_DATASHEET,
    AxisNoise,
    ImuNoise,
    MagDisturbance,
    MagNoise,
    apply_axis_noise,
)
from ._recording import (
    UNITS,
    ImuRecording,
    ImuTruth,
    check_recording,
    read_imu_csv,
    write_imu_csv,
)
from ._simulate import SkinMotion, simulate_imu
from ._vectors import (
    ROTATIONS,
    ChainModel,
    VectorEstimate,
    calibrate_vectors,
    chain_model,
    link_vectors,
    rotation_vector,
    seel_joint_positions,
    truth_chain_model,
)

__all__ = [
    "ARM_JOINTS",
    "CALIBRATION_PLAN",
    "CHAINS",
    "EARTH_FIELD_UT",
    "EVAL_NOISE",
    "FLEX_JOINT",
    "GRASP_POSES",
    "GRAVITY_MPS2",
    "LINKS",
    "MODEL_JOINTS",
    "MPU9250_DATASHEET",
    "POINTS",
    "ROTATIONS",
    "SENSOR_BODIES",
    "SENSOR_NAMES",
    "TIP_SENSORS",
    "UNITS",
    "AhrsEKFEstimator",
    "AxisNoise",
    "ChainEKF",
    "ChainEKFOptions",
    "ChainModel",
    "ConstantEstimator",
    "Filter1",
    "Filter1Options",
    "ImuHand",
    "ImuNoise",
    "ImuPlacement",
    "ImuRecording",
    "ImuTruth",
    "MadgwickEstimator",
    "MagDisturbance",
    "MagNoise",
    "MahonyEstimator",
    "Motion",
    "OrientationEstimator",
    "RawIntegration",
    "SkinMotion",
    "StaticStart",
    "VQFEstimator",
    "VectorEstimate",
    "apply_axis_noise",
    "azimuth_correction",
    "calibrate_vectors",
    "calibration_motion",
    "chain_model",
    "check_recording",
    "concat_motions",
    "free_motion",
    "grasp_motion",
    "gyro_bias",
    "imu_hand_mjcf",
    "initial_attitude",
    "integrate_gyro",
    "link_vectors",
    "read_imu_csv",
    "rotation_vector",
    "seel_joint_positions",
    "sensor_tree",
    "simulate_imu",
    "static_motion",
    "truth_chain_model",
    "write_imu_csv",
]
