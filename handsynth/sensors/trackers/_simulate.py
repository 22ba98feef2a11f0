"""Simulated two-sensor recordings of a finger joint.

Set-up of the patent (JP2010-88628, para. 0103): one receiver in the middle
of each phalanx either side of the joint, tilted so that the two do not
collide (para. 0101), transmitter on the wrist.  The transmitter frame is
the hand frame (origin at the wrist joint centre, ``+y`` toward the
middle-finger MCP, ``+z`` dorsal, metres).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from ...errors import InvalidInputError
from ..common import axis_angle_matrix
from ._checks import check_number
from ._geometry import joint_geometry
from ._joint_models import ArcJoint, FingerJoint, HingeJoint
from ._motion import FlexionMotion
from ._noise import LIBERTY, FieldDistortion, SensorNoise
from ._recording import GroundTruth, Recording

__all__ = ["SensorMount", "simulate_recording"]


@dataclass(frozen=True, kw_only=True)
class SensorMount:
    """Where a receiver sits on its segment.

    Parameters
    ----------
    along : float
        Position along the segment, 0 = proximal joint, 1 = distal end.
        The patent centres the receivers on the phalanges (para. 0103).
    height_mm : float
        Height of the receiver's centre above the bone axis (dorsal), mm:
        half the finger's thickness plus half the 9.6 mm receiver (para. 0094).
    lateral_mm : float
        Sideways offset from the finger's midline (``+x``), mm.
    pitch_deg, roll_deg, yaw_deg : float
        Tilt of the receiver about the segment's ``x``, ``y`` and ``z`` axes
        (applied in that order, intrinsic), degrees.
    """

    along: float = 0.5
    height_mm: float = 9.0
    lateral_mm: float = 0.0
    pitch_deg: float = 0.0
    roll_deg: float = 0.0
    yaw_deg: float = 0.0

    def __post_init__(self) -> None:
        for name, v in asdict(self).items():
            check_number(v, name)

    def frame(self, length: float) -> tuple[np.ndarray, np.ndarray]:
        """Receiver pose in the segment frame: position (3,) m, rotation (3, 3)."""
        pos = np.array([self.lateral_mm * 1e-3, self.along * length, self.height_mm * 1e-3])
        rot = Rotation.from_euler(
            "XYZ", [self.pitch_deg, self.roll_deg, self.yaw_deg], degrees=True
        ).as_matrix()
        return pos, rot


def simulate_recording(
    joint: str = "index_dip",
    *,
    model: HingeJoint | FingerJoint | ArcJoint | str = "finger",
    motion: FlexionMotion = FlexionMotion(),  # noqa: B008 - frozen dataclass, never mutated
    upper_mount: SensorMount = SensorMount(pitch_deg=15.0),
    lower_mount: SensorMount = SensorMount(pitch_deg=-15.0),
    noise: SensorNoise | FieldDistortion = LIBERTY,
    seed: int | None = 0,
    geometry_source: str = "auto",
    hand=None,
) -> Recording:
    """Simulate a Liberty recording of two receivers across `joint`.

    Parameters
    ----------
    joint : str
        ``"index_dip"``, ``"middle_pip"``, ... (see
        :data:`~handsynth.sensors._geometry.SUPPORTED_JOINTS`).
    model : HingeJoint, FingerJoint, ArcJoint, "hinge", "finger" or "arc"
        Joint kinematics; the strings give the default-parameter models.
    motion : FlexionMotion
        Trial protocol (duration, rate, range, wobble).
    upper_mount, lower_mount : SensorMount
        Receiver placement on the upper and lower segment.  The default
        +/-15 deg pitch tilts the receivers away from each other (para. 0101).
    noise : SensorNoise or FieldDistortion
        Measurement error; default :data:`~handsynth.sensors.LIBERTY`.
    seed : int or None
        Seed of the random generator (motion variability and noise).
    geometry_source : {"auto", "model", "table"}
        Passed to :func:`~handsynth.sensors._geometry.joint_geometry`.
    hand : handsynth.models.HandModel, optional
        A hand of a particular shape.

    Returns
    -------
    Recording
        With :attr:`Recording.truth` set.
    """
    jm: HingeJoint | FingerJoint | ArcJoint
    if isinstance(model, str):
        models: dict[str, type[HingeJoint | FingerJoint | ArcJoint]] = {
            "hinge": HingeJoint, "finger": FingerJoint, "arc": ArcJoint}
        if model not in models:
            raise InvalidInputError(
                f"model: expected 'hinge', 'finger' or 'arc', got {model!r}")
        jm = models[model]()
    else:
        jm = model
    rng = np.random.default_rng(seed)
    geo = joint_geometry(joint, source=geometry_source, hand=hand)
    m = motion.sample(rng)

    # upper segment: rotates about its own proximal joint (centre = origin)
    r_up = axis_angle_matrix(
        np.broadcast_to(geo.proximal_axis, m.times.shape + (3,)), m.proximal
    ) @ geo.upper_rotation
    o_up = np.broadcast_to(geo.upper_origin, r_up.shape[:1] + (3,))
    # lower segment from the joint model, composed on the upper pose
    r_rel, offset = jm.pose(m.flexion, m.wobble)
    c0 = np.array([0.0, geo.upper_length, 0.0])
    centre_up = c0 + offset  # joint centre in the upper segment frame, (n, 3)
    r_lo = r_up @ r_rel
    o_lo = o_up + np.einsum("nij,nj->ni", r_up, centre_up)

    mu_p, mu_r = upper_mount.frame(geo.upper_length)
    ml_p, ml_r = lower_mount.frame(geo.lower_length)
    positions = np.stack(
        [o_up + r_up @ mu_p, o_lo + r_lo @ ml_p], axis=1
    )
    rotations = np.stack([r_up @ mu_r, r_lo @ ml_r], axis=1)

    centre_sensor = np.stack(
        [
            (centre_up - mu_p) @ mu_r,  # mu_r^T (c - p), row-wise
            np.broadcast_to(-ml_p @ ml_r, centre_up.shape),
        ],
        axis=1,
    )
    reference = np.stack([(c0 - mu_p) @ mu_r, -ml_p @ ml_r])
    truth = GroundTruth(
        centre_world=o_lo,
        centre_sensor=centre_sensor,
        reference_centre=reference,
        joint_kind=jm.kind,
    )
    positions, rotations = noise.apply(positions, rotations, m.times, rng=rng)
    # re-orthonormalise after the noise product to machine precision
    rotations = Rotation.from_matrix(rotations.reshape(-1, 3, 3)).as_matrix().reshape(
        rotations.shape
    )
    metadata = {
        "source": "simulation",
        "joint_model": jm.describe(),
        "motion": {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(motion).items()},
        "upper_mount": asdict(upper_mount),
        "lower_mount": asdict(lower_mount),
        "noise": {"model": type(noise).__name__, **asdict(noise)},
        "seed": seed,
        "geometry_source": geo.source,
        # finger width direction (segment +x) in the transmitter frame at the
        # standard state, for AxisAngleFilter(lateral_axis="recording")
        "lateral_axis": r_up[0][:, 0].tolist(),
        "upper_length_mm": geo.upper_length * 1e3,
        "lower_length_mm": geo.lower_length * 1e3,
    }
    return Recording(
        times=m.times,
        positions=positions,
        rotations=rotations,
        labels=(geo.upper, geo.lower),
        joint=joint,
        metadata=metadata,
        truth=truth,
    )
