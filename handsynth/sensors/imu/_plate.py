"""The forearm plate as one rigid body (an addition to seed 003).

The three forearm sensors sit on one rigid plate (seed 003 Fig. 2.15), so the
rotation between any two of them is constant.  The thesis gives each its own
attitude and chain (sensor 1 for the index/middle fingers, 2 for ring/little,
3 for the thumb).  Here the constant rotations are read from the
calibration's static start -- the same attitudes (eqs. 2.9-2.11 with the
azimuth alignment of eqs. 4.18-4.22) that give the forearm link vectors
(eq. 3.6) -- and every plate sensor's attitude estimate is turned into the
first sensor's frame and averaged, sample by sample; the average, turned back
into each sensor's frame, replaces the three estimates.

With R_k the estimated attitude of plate sensor k and C_k its static-start
attitude in the calibration, the fused elbow-to-wrist vector of every chain
is mean_k(R_k C_k^T) applied to the same world vector of the calibration's
static pose: the plate's rotation since that pose, averaged over the three
sensors, instead of one sensor's.  The forearm link vectors need no change:
they were computed from the same static-start attitudes, so the three chains
place the wrist at one point.

The average is the quaternion mean of Markley et al., "Averaging
quaternions", J. Guidance, Control, and Dynamics 30(4), 2007: the unit
eigenvector of the largest eigenvalue of sum_k q_k q_k^T, which does not
depend on the quaternions' signs.  A mean is not robust: where one of three
sensors strays from the mean by more than ``disagree_deg`` (a failing or
disturbed sensor; the filters agree to a few degrees), it is left out of
that sample's average and a warning names it.
"""

from __future__ import annotations

import warnings

import numpy as np

from ..._checks import check_number
from ...errors import InvalidInputError
from ._attitude import StaticStart, initial_attitude
from ._quat import angle_deg, check_quats, mat_to_quat, qconj, qmul, quat_to_mat
from ._recording import ImuRecording

__all__ = ["PLATE_SENSORS", "fuse_plate", "plate_rotations"]

#: The sensors on the forearm plate, the reference sensor first.
PLATE_SENSORS: tuple[str, ...] = ("forearm_1", "forearm_2", "forearm_3")


def plate_rotations(cal: ImuRecording, *, sensors=PLATE_SENSORS,
                    static: StaticStart | None = None) -> dict:
    """Constant rotations between the plate's sensors from a calibration's static start.

    Parameters
    ----------
    cal : ImuRecording
        The calibration recording (sensor-corrected, as for the link vectors),
        with a labelled ``static`` stretch and an ``elbow_flex`` rotation
        (the azimuth alignment), or the stretches given by `static`.
    sensors : sequence of str, keyword-only
        The plate's sensors, the reference first (at least two).
    static : StaticStart, keyword-only
        The static start and common rotation; default: the calibration's
        labelled ones, as :func:`link_vectors` takes them.

    Returns
    -------
    dict
        sensor -> (3, 3) rotation from that sensor's frame to the reference
        sensor's frame (the identity for the reference).
    """
    from ._vectors import _calibration_static

    sensors = tuple(sensors)
    if len(sensors) < 2:
        raise InvalidInputError(f"a plate needs at least two sensors, got {sensors!r}")
    missing = [s for s in sensors if s not in cal.sensors]
    if missing:
        raise InvalidInputError(f"the calibration recording lacks plate sensor(s) "
                                f"{', '.join(missing)}")
    q0 = initial_attitude(cal, static or _calibration_static(cal))
    r = quat_to_mat(q0[[cal.index(s) for s in sensors]])
    return {s: r[0].T @ r[k] for k, s in enumerate(sensors)}


def _markley_mean(q: np.ndarray, weight: np.ndarray) -> np.ndarray:
    """Weighted quaternion mean (N, 4) of `q` (K, N, 4) with weights (K, N), sign of q[0]."""
    m = np.einsum("kn,kni,knj->nij", weight, q, q)                      # (N, 4, 4)
    _, vec = np.linalg.eigh(m)
    mean = vec[..., -1]                                                  # largest eigenvalue
    return mean * np.where(np.sum(mean * q[0], axis=-1) < 0, -1.0, 1.0)[:, None]


def fuse_plate(quats, sensors, rotations: dict, *, disagree_deg: float = 10.0) -> np.ndarray:
    """One attitude for the plate's sensors from their separate estimates.

    Parameters
    ----------
    quats : ndarray, shape (S, N, 4)
        Sensor-to-world quaternions of every sensor (any filter's output).
    sensors : sequence of str, length S
    rotations : dict
        From :func:`plate_rotations`: plate sensor -> rotation from its frame
        to the reference sensor's.  Plate sensors absent from `sensors` are
        left out of the average.
    disagree_deg : float, keyword-only
        With three or more plate sensors, a sensor farther than this from the
        plate's mean attitude in a sample is left out of that sample's mean
        (with a warning naming it and the share of samples); with two, a
        warning says where they are farther apart than twice this.

    Returns
    -------
    ndarray, shape (S, N, 4)
        A copy of `quats` in which every plate sensor's attitude is the
        averaged plate attitude turned into its own frame; other sensors
        unchanged.  With fewer than two plate sensors present, an unchanged
        copy.

    Raises
    ------
    InvalidInputError
        `quats` not unit quaternions of shape (S, N, 4) (see
        :func:`check_quats`), a rotation that is not one, `disagree_deg` not
        a finite number > 0.
    """
    sensors = tuple(sensors)
    quats = check_quats(quats, sensors)
    check_number(disagree_deg, "disagree_deg", above=0)
    if not isinstance(rotations, dict):
        raise InvalidInputError(f"rotations must be a dict (from plate_rotations), got "
                                f"{type(rotations).__name__}")
    out = quats.copy()
    present = [s for s in rotations if s in sensors]
    if len(present) < 2:
        return out
    for s in present:
        r = np.asarray(rotations[s], dtype=float)
        if r.shape != (3, 3) or not np.allclose(r.T @ r, np.eye(3), atol=1e-6):
            raise InvalidInputError(f"plate rotation of {s!r} is not a rotation matrix")
    rel = dict(zip(present, mat_to_quat(np.stack([np.asarray(rotations[s], dtype=float)
                                                  for s in present]))))  # ref <- sensor
    # each sensor's estimate of the reference frame's attitude, world <- ref
    ref = np.stack([qmul(quats[sensors.index(s)], qconj(rel[s])) for s in present])
    weight = np.ones(ref.shape[:2])
    mean = _markley_mean(ref, weight)
    if len(present) >= 3:
        dev = angle_deg(ref, mean[None])                                     # (K, N)
        worst = np.argmax(dev, axis=0)
        stray = dev[worst, np.arange(dev.shape[1])] > disagree_deg
        if stray.any():
            weight[worst[stray], np.flatnonzero(stray)] = 0.0
            mean = _markley_mean(ref, weight)
            counts = np.bincount(worst[stray], minlength=len(present))
            named = ", ".join(f"{present[k]} in {c} samples" for k, c in enumerate(counts) if c)
            warnings.warn(f"forearm plate: a sensor's attitude strayed more than "
                          f"{disagree_deg:g} deg from the other plate sensors' ({named} of "
                          f"{dev.shape[1]}); left out of the plate's attitude there",
                          UserWarning, stacklevel=2)
    else:
        apart = angle_deg(ref[0], ref[1]) > 2 * disagree_deg     # each is disagree_deg off the mean
        if apart.any():
            warnings.warn(f"forearm plate: {present[0]} and {present[1]} disagree by more than "
                          f"{2 * disagree_deg:g} deg in {int(apart.sum())} of {len(apart)} "
                          "samples; with two sensors the stray one cannot be told, so their mean "
                          "is kept", UserWarning, stacklevel=2)
    for s in present:
        out[sensors.index(s)] = qmul(mean, rel[s])
    return out
