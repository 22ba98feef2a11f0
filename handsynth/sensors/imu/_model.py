"""The IMU hand: the handsynth hand on a moving forearm, with 20 MEMS IMUs.

The hand of :func:`handsynth.models.hand_mjcf` is copied (its MJCF is read, not
changed) and placed on a kinematic arm: three elbow translations and a
humeral rotation (the elbow moving or fixed), elbow flexion and forearm
rotation, then wrist flexion and deviation.  The ring/little side of the palm
is a separate body on a carpometacarpal (CM) hinge, the two-part hand that the
thesis found best ("Type 3", seed 003 section 3.4.2-3.4.3).

Twenty sites carry MuJoCo ``accelerometer``, ``gyro`` and ``magnetometer``
sensors, laid out as the thesis' system (seed 003 section 2.4.3, Fig. 2.15,
Table 3.6): three on a plate on the distal forearm, two on the back of the
hand (index/middle side, plane IM2; ring/little side, plane RP3) and one on
the back of every phalanx.  Sensor order is the thesis numbering SN1-SN20.

World frame: z up (gravity -z), x horizontal magnetic north, y = z cross x
(west), the global frame of seed 003 section 2.3.1.  At the zero pose the
hand frame of :mod:`handsynth.models` is the world frame rotated to the
elbow's position: forearm horizontal along +y, palm facing down.
Lengths in metres inside the model; the magnetic field in microtesla.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

from ..._checks import check_instance, check_number, check_options, short_repr
from ...errors import InvalidInputError
from ...models import (
    FINGERS,
    JOINT_NAMES,
    SEGMENT_BODIES,
    HandShape,
    compile_mjcf,
    hand_mjcf,
)

__all__ = [
    "ARM_JOINTS",
    "EARTH_FIELD_UT",
    "GRAVITY_MPS2",
    "MODEL_JOINTS",
    "SENSOR_BODIES",
    "SENSOR_NAMES",
    "ImuHand",
    "ImuPlacement",
    "imu_hand_mjcf",
]

#: Standard gravity (CGPM 1901), m/s^2.
GRAVITY_MPS2 = 9.80665

#: Geomagnetic field at Kyotanabe, Japan (where the thesis was measured),
#: from the World Magnetic Model 2020 (NOAA/BGS): horizontal intensity about
#: 30.7 uT toward magnetic north, vertical 35.6 uT downward (inclination
#: about 49 deg).  World-frame components (north, west, up), microtesla.
EARTH_FIELD_UT = (30.7, 0.0, -35.6)

#: Joints of the arm and of the ring/little CM hinge, before the 20 canonical
#: finger joints.  Slides in metres, hinges in degrees.
ARM_JOINTS: tuple[str, ...] = (
    "elbow_x", "elbow_y", "elbow_z",      # elbow translation (0 when fixed)
    "humeral_rot",                         # upper-arm rotation about vertical
    "elbow_flex",                          # + lifts the hand
    "forearm_rot",                         # + supination about the forearm axis
    "wrist_flex",                          # + palmar flexion
    "wrist_dev",                           # + radial deviation
    "ulnar_cm_flex",                       # ring/little CM flexion (palm cupping)
)

#: Every driven joint of the IMU hand, in the order of motion arrays.
MODEL_JOINTS: tuple[str, ...] = ARM_JOINTS + JOINT_NAMES

#: Sensor names in the thesis numbering SN1..SN20 (Table 3.6).
SENSOR_NAMES: tuple[str, ...] = (
    "forearm_1", "forearm_2", "forearm_3", "hand_ulnar",
    "little_proximal", "little_middle", "little_distal",
    "ring_proximal", "ring_middle", "ring_distal",
    "hand_radial",
    "middle_proximal", "middle_middle", "middle_distal",
    "index_proximal", "index_middle", "index_distal",
    "thumb_metacarpal", "thumb_proximal", "thumb_distal",
)

#: Temporary fingertip sensors of the calibration (seed 003 Table 3.5, "Tip"),
#: on the distal phalanges, used only to find the distal link vectors.
TIP_SENSORS: tuple[str, ...] = tuple(f"{f}_tip" for f in FINGERS)

#: Body (rigid segment) each sensor is fixed to.
SENSOR_BODIES: Mapping[str, str] = MappingProxyType({
    "forearm_1": "forearm", "forearm_2": "forearm", "forearm_3": "forearm",
    "hand_ulnar": "palm_ulnar", "hand_radial": "palm",
    **{b: b for f in FINGERS for b in SEGMENT_BODIES[f]},
    **{f"{f}_tip": SEGMENT_BODIES[f][-1] for f in FINGERS},
})

_LIMITS = {
    "humeral_rot": (-90.0, 90.0), "elbow_flex": (-10.0, 140.0), "forearm_rot": (-90.0, 90.0),
    # wrist: AAOS (1965) flexion 80, extension 70, radial 20, ulnar 30 deg
    "wrist_flex": (-70.0, 80.0), "wrist_dev": (-30.0, 20.0),
    # 4th/5th CM flexion: Kapandji (2007) "the hand", up to about 20-30 deg
    "ulnar_cm_flex": (-5.0, 25.0),
}


@dataclass(frozen=True)
class ImuPlacement:
    """Where the IMUs sit on the segments (all keyword-only, frozen).

    Parameters
    ----------
    height_mm : float
        Sensor centre above the dorsal skin: flexible board 1.5 mm plus half
        the 1 mm package (seed 003 section 3.3.3) plus a 2 mm curved plate.
    along : float
        Position along each phalanx as a fraction of its length.
    forearm_length_mm : float
        Elbow to wrist joint centre.  Default 250 mm: an assumption, not a
        measured figure.  The thesis' subjects averaged 270 mm (seed 003
        section 2.4.2, the discussion of Fig. 2.14); 250 mm is the forearm
        of a somewhat smaller adult: the segment proportions of Winter,
        *Biomechanics and Motor Control of Human Movement*, Fig. 4.1 (after
        Drillis & Contini 1966), give the forearm as 0.146 of stature, i.e.
        250 mm at a stature of 1.71 m.  Both simulator configurations
        (docs/imu.md, "Figures") use it; the held-out one changes the hand,
        not the forearm.
    offsets_mm : mapping of str to (3,) float
        Extra displacement of named sensors in their body frame, mm.
    tilts_deg : mapping of str to (3,) float
        Extra rotation of named sensors (x, y, z rotation vector, degrees).

    Raises
    ------
    InvalidInputError
        A field that is not a finite number in its range (`height_mm` in [0, 50),
        `along` in (0, 1), `forearm_length_mm` in [100, 400]), `offsets_mm` or
        `tilts_deg` not a mapping of names of :data:`SENSOR_NAMES` to 3 finite numbers.
    """

    height_mm: float = 4.0
    along: float = 0.5
    forearm_length_mm: float = 250.0
    offsets_mm: Mapping[str, tuple[float, float, float]] = field(default_factory=dict)
    tilts_deg: Mapping[str, tuple[float, float, float]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        check_number(self.height_mm, "ImuPlacement.height_mm", minimum=0.0, below=50.0)
        check_number(self.along, "ImuPlacement.along", above=0.0, below=1.0)
        check_number(self.forearm_length_mm, "ImuPlacement.forearm_length_mm", minimum=100.0,
                     maximum=400.0)
        for what in ("offsets_mm", "tilts_deg"):
            value = getattr(self, what)
            check_instance(value, Mapping, name=f"ImuPlacement.{what}",  # type: ignore[type-abstract]
                           hint=" (a mapping of sensor name to (x, y, z))")
            for name, vec in value.items():
                if name not in SENSOR_NAMES:
                    raise InvalidInputError(
                        f"unknown sensor {name!r} in placement; expected one of {', '.join(SENSOR_NAMES)}")
                _check_vector(vec, f"ImuPlacement.{what}[{name!r}]")


def _check_vector(vec, name: str) -> None:
    """Refuse anything but 3 finite numbers (a text, a number, a wrong length, NaN)."""
    try:
        v = None if isinstance(vec, (str, bytes)) else np.asarray(vec, dtype=np.float64)
    except (TypeError, ValueError):
        v = None
    if v is None or v.shape != (3,) or not np.isfinite(v).all():
        raise InvalidInputError(f"{name} must be 3 finite numbers (x, y, z), got "
                                f"{type(vec).__name__} {short_repr(vec)}")


def _fmt(v) -> str:
    return " ".join(f"{float(x):.9g}" for x in np.ravel(v))


def _rotvec_quat(rv_deg) -> np.ndarray:
    rv = np.radians(np.asarray(rv_deg, dtype=float))
    ang = np.linalg.norm(rv)
    if ang < 1e-12:
        return np.array([1.0, 0.0, 0.0, 0.0])
    ax = rv / ang
    return np.r_[np.cos(ang / 2), np.sin(ang / 2) * ax]


def _find(el: ET.Element, path: str) -> ET.Element:
    found = el.find(path)
    if found is None:
        raise InvalidInputError(f"the hand MJCF has no element {path!r}")
    return found


def _attr(el: ET.Element, name: str) -> str:
    value = el.get(name)
    if value is None:
        raise InvalidInputError(f"the hand MJCF element {el.tag!r} has no attribute {name!r}")
    return value


def _mesh_top(root: ET.Element, mesh: str) -> float:
    el = _find(root, f"./asset/mesh[@name='{mesh}']")
    v = np.array(_attr(el, "vertex").split(), dtype=float).reshape(-1, 3)
    return float(v[:, 2].max())


def imu_hand_mjcf(shape: HandShape | None = None, *, side: str = "right",
                  placement: ImuPlacement | None = None,
                  field_ut=EARTH_FIELD_UT, elbow_pos_m=(0.0, 0.0, 0.8),
                  tip_sensors: bool = False) -> str:
    """MJCF of the hand on a kinematic arm with 20 IMU sites and sensors.

    Parameters
    ----------
    shape : HandShape, optional
    side : {"right", "left"}, keyword-only
    placement : ImuPlacement, keyword-only
    field_ut : (3,) float, keyword-only
        Earth field in the world frame, microtesla.
    elbow_pos_m : (3,) float, keyword-only
        Elbow joint centre in the world at zero elbow translation, metres.
    tip_sensors : bool, keyword-only
        Add the five calibration-only fingertip sensors :data:`TIP_SENSORS`,
        `height_mm` above each fingertip point (the thesis' "offset").

    Returns
    -------
    str
        MJCF document; sensors are named ``<sensor>_acc``, ``_gyr``, ``_mag``.
    """
    placement = check_options(placement, ImuPlacement, name="placement")
    root = ET.fromstring(hand_mjcf(shape, side=side, forearm=True))
    sgn = 1.0 if side == "right" else -1.0
    la = placement.forearm_length_mm * 1e-3
    h = placement.height_mm * 1e-3

    wb = _find(root, "worldbody")
    stub = _find(wb, "./body[@name='forearm']")
    fa_top = _mesh_top(root, "forearm")
    wb.remove(stub)
    frame = _find(wb, "frame")
    wb.remove(frame)
    kf = root.find("keyframe")
    if kf is not None:
        root.remove(kf)
    ET.SubElement(root, "option", gravity=f"0 0 {-GRAVITY_MPS2}", magnetic=_fmt(field_ut))
    root.set("model", f"handsynth_{side}_imu_arm")
    root.insert(0, ET.Comment(" Generated by handsynth.sensors.imu.imu_hand_mjcf: the hand of "
                              "handsynth.models.hand_mjcf on a kinematic arm with IMUs; do not "
                              "edit. "))
    # the arm and the IMU sites as default classes beside the hand's (Menagerie layout)
    hand_class = _find(root, "./default/default[@class='hand']")
    arm = ET.SubElement(hand_class, "default", {"class": "arm"})
    ET.SubElement(arm, "geom", type="capsule", size="0.022", contype="0", conaffinity="0",
                  group="2", material="skin")
    imu = ET.SubElement(hand_class, "default", {"class": "imu"})
    ET.SubElement(imu, "site", size="0.004", group="4")

    def inertial(el: ET.Element) -> None:
        ET.SubElement(el, "inertial", pos="0 0 0", mass="0.05", diaginertia="1e-5 1e-5 1e-5")

    def hinge(el, name, axis):
        lo, hi = _LIMITS[name]
        ET.SubElement(el, "joint", name=name, type="hinge", axis=_fmt(axis), range=f"{lo:g} {hi:g}")

    base = ET.SubElement(wb, "body", name="upper_arm", pos=_fmt(elbow_pos_m))
    inertial(base)
    for n, ax in zip(("elbow_x", "elbow_y", "elbow_z"), np.eye(3)):
        ET.SubElement(base, "joint", name=n, type="slide", axis=_fmt(ax), range="-1 1")
    hinge(base, "humeral_rot", (0, 0, 1))
    fore = ET.SubElement(base, "body", name="forearm")
    inertial(fore)
    hinge(fore, "elbow_flex", (1, 0, 0))
    hinge(fore, "forearm_rot", (0, -sgn, 0))
    ET.SubElement(fore, "geom", {"class": "arm", "fromto": f"0 0 0 0 {la:.6g} 0"})
    wrist = ET.SubElement(fore, "body", name="hand_root", pos=f"0 {la:.6g} 0")
    inertial(wrist)
    hinge(wrist, "wrist_flex", (-1, 0, 0))
    hinge(wrist, "wrist_dev", (0, 0, sgn))
    wrist.append(frame)
    palm = _find(frame, "body")

    # two-part hand (Type 3): ring and little on a CM hinge near the wrist
    mcp = {f: np.array(_attr(_find(palm, f"./body[@name='{f}_proximal']"), "pos").split(), float)
           for f in FINGERS[1:]}
    cm_pos = np.array([0.5 * (mcp["ring"][0] + mcp["little"][0]), 0.2 * mcp["middle"][1], 0.0])
    ulnar = ET.Element("body", name="palm_ulnar", pos=_fmt(cm_pos))
    inertial(ulnar)
    axis = np.array([-1.0, 0.35 * sgn, 0.0])
    hinge(ulnar, "ulnar_cm_flex", axis / np.linalg.norm(axis))
    for f in ("ring", "little"):
        b = _find(palm, f"./body[@name='{f}_proximal']")
        palm.remove(b)
        b.set("pos", _fmt(mcp[f] - cm_pos))
        ulnar.append(b)
    palm.append(ulnar)

    bodies = {_attr(b, "name"): b for b in root.iter("body")}
    palm_top = _mesh_top(root, "palm")
    sites: dict[str, np.ndarray] = {
        # plate on the distal forearm (Fig. 2.15): two across, one proximal
        "forearm_1": np.array([-0.012 * sgn, la - 0.050, fa_top + h]),
        "forearm_2": np.array([0.012 * sgn, la - 0.050, fa_top + h]),
        "forearm_3": np.array([0.0, la - 0.075, fa_top + h]),
        # plane IM2 (index/middle, central) and RP3 (ring/little, distal), Fig. 2.12
        "hand_radial": np.array([0.5 * mcp["index"][0], 0.5 * mcp["middle"][1], palm_top + h]),
        "hand_ulnar": np.array([0.5 * (mcp["ring"][0] + mcp["little"][0]),
                                0.72 * 0.5 * (mcp["ring"][1] + mcp["little"][1]),
                                palm_top + h]) - cm_pos,
    }
    for f in FINGERS:
        for seg in SEGMENT_BODIES[f]:
            b = bodies[seg]
            kids = b.findall("body")
            if kids:
                length = float(_attr(kids[0], "pos").split()[1])
            else:
                length = float(_attr(b.findall("site")[-1], "pos").split()[1])
            sites[seg] = np.array([0.0, placement.along * length, _mesh_top(root, seg) + h])
            if not kids:
                sites[f"{f}_tip"] = np.array([0.0, length, h])
    sensors = ET.SubElement(root, "sensor")
    for name in SENSOR_NAMES + (TIP_SENSORS if tip_sensors else ()):
        pos = sites[name] + 1e-3 * np.asarray(placement.offsets_mm.get(name, (0, 0, 0)), float)
        q = _rotvec_quat(placement.tilts_deg.get(name, (0, 0, 0)))
        body = bodies[SENSOR_BODIES[name]] if SENSOR_BODIES[name] != "forearm" else fore
        ET.SubElement(body, "site", {"name": f"imu_{name}", "class": "imu", "pos": _fmt(pos),
                                     "quat": _fmt(q)})
        for kind, tag in (("acc", "accelerometer"), ("gyr", "gyro"), ("mag", "magnetometer")):
            ET.SubElement(sensors, tag, name=f"{name}_{kind}", site=f"imu_{name}")
    return ET.tostring(root, encoding="unicode")


class ImuHand:
    """A compiled IMU hand (see :func:`imu_hand_mjcf`).

    Parameters
    ----------
    shape : HandShape, optional
    side, placement, field_ut, elbow_pos_m : keyword-only
        As :func:`imu_hand_mjcf`.

    Attributes
    ----------
    model, data : mujoco.MjModel, mujoco.MjData
    """

    def __init__(self, shape: HandShape | None = None, *, side: str = "right",
                 placement: ImuPlacement | None = None, field_ut=EARTH_FIELD_UT,
                 elbow_pos_m=(0.0, 0.0, 0.8), tip_sensors: bool = False) -> None:
        import mujoco

        self._mj = mujoco
        self.shape = check_options(shape, HandShape, name="shape")
        self.side = side
        self.placement = check_options(placement, ImuPlacement, name="placement")
        self.field_ut = np.asarray(field_ut, dtype=float)
        self.model = compile_mjcf(imu_hand_mjcf(self.shape, side=side, placement=self.placement,
                                                field_ut=field_ut, elbow_pos_m=elbow_pos_m,
                                                tip_sensors=tip_sensors))
        self.sensors = SENSOR_NAMES + (TIP_SENSORS if tip_sensors else ())
        self.data = mujoco.MjData(self.model)
        m = self.model
        self.qadr = np.array([m.joint(n).qposadr[0] for n in MODEL_JOINTS], dtype=np.intp)
        self.dadr = np.array([m.joint(n).dofadr[0] for n in MODEL_JOINTS], dtype=np.intp)
        self.hinge = np.array([m.joint(n).type[0] == mujoco.mjtJoint.mjJNT_HINGE
                               for n in MODEL_JOINTS])
        self.site_ids = np.array([m.site(f"imu_{n}").id for n in self.sensors], dtype=np.intp)
        self.sensor_adr = {
            (n, k): m.sensor(f"{n}_{k}").adr[0] for n in self.sensors for k in ("acc", "gyr", "mag")
        }
        self.body_ids = {n: m.body(n).id for n in
                         ("forearm", "hand_root", "palm", "palm_ulnar",
                          *(b for f in FINGERS for b in SEGMENT_BODIES[f]))}

    def body_id(self, name: str) -> int:
        """MuJoCo id of body `name` (raises InvalidInputError naming the body)."""
        b = self._mj.mj_name2id(self.model, self._mj.mjtObj.mjOBJ_BODY, name)
        if b < 0:
            raise InvalidInputError(f"unknown body {name!r} in the IMU hand")
        return b

    def joint_id(self, name: str) -> int:
        j = self._mj.mj_name2id(self.model, self._mj.mjtObj.mjOBJ_JOINT, name)
        if j < 0:
            raise InvalidInputError(f"unknown joint {name!r}; expected one of {', '.join(MODEL_JOINTS)}")
        return j

    def set_state(self, q, qd=None, qdd=None) -> None:
        """Set positions, velocities and accelerations of :data:`MODEL_JOINTS`.

        Hinges in degrees (deg/s, deg/s^2), slides in metres; then run MuJoCo's
        inverse dynamics so that every sensor reads the kinematic state.
        """
        scale = np.where(self.hinge, np.pi / 180.0, 1.0)
        d = self.data
        d.qpos[self.qadr] = np.asarray(q, float) * scale
        d.qvel[self.dadr] = 0.0 if qd is None else np.asarray(qd, float) * scale
        d.qacc[self.dadr] = 0.0 if qdd is None else np.asarray(qdd, float) * scale
        self._mj.mj_inverse(self.model, d)
