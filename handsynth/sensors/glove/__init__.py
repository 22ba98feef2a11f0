"""Few-sensor data glove: simulated bend sensors and joint-angle estimators.

A cheap glove has one bend sensor per finger; this package simulates such
gloves (DG5-VHand-like over the PIP joint, 5DT-like over MCP and PIP) on
simulated users, and estimates all 20 joint angles of
:data:`handsynth.models.JOINT_NAMES` from the five readings with the models
of seed 004 (SPEC.md section 4): DIP = 2/3 PIP, models 1-4 per
representative motion, likelihood mixing over motions (eqs. 4-6), a pooled
model, a postural-synergy baseline and the constant answer.

Units: readings in ADC counts, angles in degrees, times in seconds.
"""

from ._apply import apply_calibration
from ._calibrate import (
    RANGE_LABELS,
    CalibrationOptions,
    calibrate,
    default_synergies,
    load_calibration,
    range_readings,
    save_calibration,
)
from ._checks import SensorCheck, check_reading_range, check_sensors
from ._cyberglove import CYBERGLOVE_COLUMNS, read_cyberglove_csv
from ._estimators import (
    ConstantEstimator,
    GatedEstimator,
    GloveEstimator,
    RangeNormalizer,
    RegressionEstimator,
    SynergyEstimator,
    estimator_from_dict,
)
from ._eval import (
    CONDITIONS,
    LATER_CONDITIONS,
    MOTION_SETS,
    EvalOptions,
    EvalSetup,
    EvalTestData,
    eval_setup,
    evaluate,
)
from ._mixing import MotionMixer, fit_mixer
from ._models import (
    DIP_PIP_RATIO,
    MODELS,
    GloveWarning,
    JointFit,
    MotionModel,
    finger_joints,
    fit_motion_model,
)
from ._motions import (
    MOTIONS,
    NAMED_MOTIONS,
    OTHER_MOTIONS,
    REPRESENTATIVE_MOTIONS,
    grasp_posture,
    motions_for,
)
from ._recording import (
    GloveRecording,
    read_glove_csv,
    write_angles_csv,
    write_glove_csv,
)
from ._sensors import (
    GLOVE_KINDS,
    SENSOR_NAMES,
    SensorParams,
    bend_angle_deg,
    play_operator,
    play_operator_reference,
    sensor_joints,
    simulate_sensors,
)
from ._simulate import (
    GLOVE_HELDOUT,
    GLOVE_TUNING,
    GloveConfig,
    GloveUser,
    don_glove,
    make_user,
    simulate_poses,
    simulate_range_holds,
    simulate_session,
)
from ._stream import STUCK_LINES, stream_glove_csv
from ._synergy import Synergies, fit_synergies

__all__ = [
    "CONDITIONS",
    "CYBERGLOVE_COLUMNS",
    "DIP_PIP_RATIO",
    "GLOVE_HELDOUT",
    "GLOVE_KINDS",
    "GLOVE_TUNING",
    "LATER_CONDITIONS",
    "MODELS",
    "MOTIONS",
    "MOTION_SETS",
    "NAMED_MOTIONS",
    "OTHER_MOTIONS",
    "RANGE_LABELS",
    "REPRESENTATIVE_MOTIONS",
    "SENSOR_NAMES",
    "STUCK_LINES",
    "CalibrationOptions",
    "ConstantEstimator",
    "EvalOptions",
    "EvalSetup",
    "EvalTestData",
    "GatedEstimator",
    "GloveConfig",
    "GloveEstimator",
    "GloveRecording",
    "GloveUser",
    "GloveWarning",
    "JointFit",
    "MotionMixer",
    "MotionModel",
    "RangeNormalizer",
    "RegressionEstimator",
    "SensorCheck",
    "SensorParams",
    "Synergies",
    "SynergyEstimator",
    "apply_calibration",
    "bend_angle_deg",
    "calibrate",
    "check_reading_range",
    "check_sensors",
    "default_synergies",
    "don_glove",
    "estimator_from_dict",
    "eval_setup",
    "evaluate",
    "finger_joints",
    "fit_mixer",
    "fit_motion_model",
    "fit_synergies",
    "grasp_posture",
    "load_calibration",
    "make_user",
    "motions_for",
    "play_operator",
    "play_operator_reference",
    "range_readings",
    "read_cyberglove_csv",
    "read_glove_csv",
    "save_calibration",
    "sensor_joints",
    "simulate_poses",
    "simulate_range_holds",
    "simulate_sensors",
    "simulate_session",
    "stream_glove_csv",
    "write_angles_csv",
    "write_glove_csv",
]
