"""Finger joint centres from two 6-DOF magnetic trackers.

Simulated and real recordings of two receivers glued on the phalanges either
side of a finger joint (patent JP2010-88628, SPEC section 2), the patent's
plane-constrained variance estimator with its axis-angle frame filter, the
classic baselines (3-D variance, O'Brien et al. 2000, SCoRE), and segment
lengths L1..L14 from the estimated centres.  Every estimate first asks what
the data determine (rotation spread, expected error): it refuses, warns, or
reports a single-axis motion as its axis; readers detect the PiMgr CSV and
Liberty ASCII exports and say what they dropped.

Units: metres and seconds in arrays, millimetres in reported errors and
lengths, degrees at option interfaces.
"""

from ._axis_filter import AxisAngleFilter, AxisFilterResult
from ._determinability import Determinability, assess_determinability, linear_centre
from ._estimators import (
    JointCentreEstimator,
    OBrienEstimator,
    PlaneVarianceEstimator,
    VarianceEstimator,
)
from ._eval import (
    CONFIGS,
    ESTIMATORS,
    estimate_all,
    evaluate,
    make_estimator,
    midpoint_baseline,
    rom_sweep,
)
from ._geometry import SUPPORTED_JOINTS, JointGeometry, joint_geometry
from ._hdf5 import load_recording, save_recording
from ._joint_models import ArcJoint, FingerJoint, HingeJoint
from ._lengths import SEGMENT_NAMES, segment_length_mm, segment_lengths_mm
from ._motion import FlexionMotion
from ._noise import (
    DISTORTED_FIELD,
    LIBERTY,
    LIBERTY_RESOLUTION,
    NO_NOISE,
    FieldDistortion,
    SensorNoise,
)
from ._plane import foot_of_perpendicular, plane_coordinates, plane_normal, plane_point
from ._plot import plot_axis_histogram
from ._quality import MotionQuality, motion_quality
from ._readers import read_polhemus, read_recording
from ._recording import GroundTruth, Recording
from ._result import JointCentreResult
from ._score import ScoreEstimator
from ._simulate import SensorMount, simulate_recording

__all__ = [
    "CONFIGS",
    "DISTORTED_FIELD",
    "ESTIMATORS",
    "LIBERTY",
    "LIBERTY_RESOLUTION",
    "NO_NOISE",
    "SEGMENT_NAMES",
    "SUPPORTED_JOINTS",
    "ArcJoint",
    "AxisAngleFilter",
    "AxisFilterResult",
    "Determinability",
    "FieldDistortion",
    "FingerJoint",
    "FlexionMotion",
    "GroundTruth",
    "HingeJoint",
    "JointCentreEstimator",
    "JointCentreResult",
    "JointGeometry",
    "MotionQuality",
    "OBrienEstimator",
    "PlaneVarianceEstimator",
    "Recording",
    "ScoreEstimator",
    "SensorMount",
    "SensorNoise",
    "VarianceEstimator",
    "assess_determinability",
    "estimate_all",
    "evaluate",
    "foot_of_perpendicular",
    "joint_geometry",
    "linear_centre",
    "load_recording",
    "make_estimator",
    "midpoint_baseline",
    "motion_quality",
    "plane_coordinates",
    "plane_normal",
    "plane_point",
    "plot_axis_histogram",
    "read_polhemus",
    "read_recording",
    "rom_sweep",
    "save_recording",
    "segment_length_mm",
    "segment_lengths_mm",
    "simulate_recording",
]
