"""Reader and benchmark run for the BROAD dataset (Laidig et al., Data 6(7):72, 2021).

BROAD (Berlin Robust Orientation Estimation Assessment Dataset, CC-BY-4.0,
github.com/dlaidig/broad) has 39 trials of one 9-axis IMU with optical
ground truth.  Each trial is a ``.mat`` file (``data_mat/``) or an HDF5 file
(``data_hdf5/``) with the same fields, as read by the dataset's own example
code:

- ``imu_acc`` (N, 3) m/s^2, ``imu_gyr`` (N, 3) rad/s, ``imu_mag`` (N, 3) uT;
- ``opt_quat`` (N, 4) the optical reference orientation (w, x, y, z),
  IMU-to-earth, earth frame ENU (the example code turns estimates into ENU
  before comparing); NaN where the markers were lost;
- ``movement`` (N,) bool: the samples the error metric uses;
- ``sampling_rate`` scalar, Hz.

The HDF5 files store the arrays as top-level datasets of the same names
and the sampling rate as the file's attribute ``sampling_rate`` (read off
the dataset's own files; a dataset of that name is accepted too).  The
metric is
the dataset's: RMSE over the movement phases of the total error angle, the
heading error (rotation about the vertical of the earth-frame error
quaternion q_imu q_opt^-1) and the inclination error.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...errors import RecordingError
from ._attitude import StaticStart
from ._filters import _Q_NWU_FROM_ENU
from ._quat import qconj, qmul
from ._recording import ImuRecording

__all__ = ["BROAD_FILTERS", "broad_errors", "find_broad_trials", "read_broad_trial", "run_broad"]

BROAD_FILTERS: tuple[str, ...] = ("constant", "raw", "filter1", "gated", "vqf", "vqf_online",
                                  "madgwick", "mahony", "ahrs_ekf")
_FIELDS = ("imu_acc", "imu_gyr", "imu_mag", "opt_quat", "movement", "sampling_rate")


def _load(path: Path) -> dict:
    if path.suffix == ".mat":
        from scipy.io import loadmat

        try:
            raw = loadmat(path)
        except Exception as exc:  # scipy raises several types on bad files
            raise RecordingError(f"{path}: not a readable .mat file ({exc})") from None
        return {k: raw[k] for k in _FIELDS if k in raw}
    import h5py

    try:
        with h5py.File(path, "r") as f:
            d = {}
            for k in _FIELDS:
                if k not in f:
                    continue
                if not isinstance(f[k], h5py.Dataset):
                    raise RecordingError(f"{path}: field {k} is an HDF5 "
                                         f"{type(f[k]).__name__.lower()}, not a dataset (array)")
                d[k] = np.asarray(f[k])
            if "sampling_rate" not in d and "sampling_rate" in f.attrs:
                d["sampling_rate"] = np.asarray(f.attrs["sampling_rate"])
            return d
    except OSError as exc:
        raise RecordingError(f"{path}: not a readable HDF5 file ({exc})") from None


def _rate(path: Path, value) -> float:
    """The ``sampling_rate`` field as a finite float > 0 (one value, any array shape)."""
    a = np.asarray(value)
    if a.size != 1:
        raise RecordingError(f"{path}: field sampling_rate must be one number (Hz), got "
                             f"{a.size} values of shape {a.shape}")
    v = a.reshape(-1)[0]
    if isinstance(v, bytes):
        v = v.decode(errors="replace")
    if isinstance(v, str):
        v = str(v)
    if isinstance(v, (str, bool, np.bool_)) or a.dtype.kind not in "iuf":
        raise RecordingError(f"{path}: field sampling_rate is {v!r}, not a number (Hz)")
    rate = float(v)
    if not (np.isfinite(rate) and rate > 0):
        raise RecordingError(f"{path}: field sampling_rate is {rate!r}; expected a finite "
                             "number > 0 (Hz)")
    return rate


def read_broad_trial(path) -> tuple[ImuRecording, np.ndarray, np.ndarray]:
    """Read one BROAD trial.

    Parameters
    ----------
    path : str or os.PathLike
        A ``.mat`` file (read with scipy); any other suffix is read as HDF5.

    Returns
    -------
    rec : ImuRecording
        One sensor named after the file's stem.
    opt_quat : ndarray, shape (N, 4)
        Reference orientation, ENU earth frame (NaN rows allowed).
    movement : ndarray of bool, shape (N,)

    Raises
    ------
    RecordingError
        A missing field, a field that is not an array (an HDF5 group), wrong
        shapes, NaN in the IMU data, no movement phase, a sampling rate that
        is not one finite number > 0.
    """
    path = Path(path)
    if not path.is_file():
        raise RecordingError(f"{path}: no such file")
    d = _load(path)
    missing = [k for k in _FIELDS if k not in d]
    if missing:
        raise RecordingError(f"{path}: missing BROAD field(s) {', '.join(missing)}")
    rate = _rate(path, d["sampling_rate"])
    arr = {}
    for k in ("imu_acc", "imu_gyr", "imu_mag", "opt_quat"):
        try:
            arr[k] = np.asarray(d[k], dtype=float)
        except (TypeError, ValueError):
            raise RecordingError(f"{path}: field {k} is not numeric") from None
    a0 = arr["imu_acc"]
    n = a0.shape[0] if a0.ndim == 2 and a0.shape[1] == 3 else max(a0.shape, default=0)
    for k, w in (("imu_acc", 3), ("imu_gyr", 3), ("imu_mag", 3), ("opt_quat", 4)):
        if arr[k].shape != (n, w):
            hint = (" (stored transposed?)" if arr[k].shape == (w, n) else "")
            raise RecordingError(f"{path}: field {k} has shape {arr[k].shape}, expected "
                                 f"(N, {w}) with N = {n} samples{hint}")
        if k != "opt_quat" and not np.all(np.isfinite(arr[k])):
            i = int(np.argwhere(~np.isfinite(arr[k]))[0, 0])
            raise RecordingError(f"{path}: field {k} is not finite at sample {i}")
    movement = np.asarray(d["movement"]).reshape(-1).astype(bool)
    if movement.shape != (n,):
        raise RecordingError(f"{path}: field movement has {movement.size} values, expected {n}")
    if not movement.any():
        raise RecordingError(f"{path}: field movement marks no sample")
    rec = ImuRecording(rate, (path.stem,), arr["imu_acc"][None], arr["imu_gyr"][None],
                       arr["imu_mag"][None])
    return rec, arr["opt_quat"], movement


def broad_errors(q_enu: np.ndarray, opt_quat: np.ndarray, movement: np.ndarray) -> dict:
    """BROAD's total, heading and inclination RMSE (degrees) over the movement phases.

    Parameters
    ----------
    q_enu : ndarray, shape (N, 4), float
        Estimated IMU-to-earth quaternions (w, x, y, z), earth frame ENU;
        normalised here.
    opt_quat : ndarray, shape (N, 4), float
        The reference of :func:`read_broad_trial`; NaN rows are left out of
        the means.
    movement : ndarray, shape (N,), bool
        The samples the metric uses (a boolean mask: integers would index).

    Returns
    -------
    dict
        ``"total_rmse_deg"``, ``"heading_rmse_deg"`` and
        ``"inclination_rmse_deg"``, floats in degrees: the RMS over the
        movement samples of the angle of the earth-frame error
        ``q_enu opt_quat^-1``, of its rotation about the vertical and of the
        rest.  NaN (with numpy's warning) when the reference is NaN over the
        whole movement phase.
    """
    q = q_enu / np.linalg.norm(q_enu, axis=1, keepdims=True)
    o = opt_quat / np.linalg.norm(opt_quat, axis=1, keepdims=True)
    e = qmul(q, qconj(o))
    e /= np.linalg.norm(e, axis=1, keepdims=True)
    total = 2 * np.arccos(np.clip(np.abs(e[:, 0]), 0, 1))
    heading = 2 * np.arctan(np.abs(e[:, 3] / e[:, 0]))
    incl = 2 * np.arccos(np.clip(np.sqrt(e[:, 0] ** 2 + e[:, 3] ** 2), 0, 1))

    def rmse(x):
        return float(np.degrees(np.sqrt(np.nanmean(x[movement] ** 2))))

    return {"total_rmse_deg": rmse(total), "heading_rmse_deg": rmse(heading),
            "inclination_rmse_deg": rmse(incl)}


def find_broad_trials(directory) -> list[Path]:
    """BROAD trial files in `directory` (or its data_mat/data_hdf5), one per trial name.

    Parameters
    ----------
    directory : str or os.PathLike
        Searched, then its ``data_mat`` and ``data_hdf5`` subfolders, for
        ``.mat``, ``.hdf5`` and ``.h5`` files whose names start with two
        digits.  Of files with the same stem, the first found is kept (in
        that folder order, names sorted within a folder).

    Returns
    -------
    list of pathlib.Path
        Sorted by stem.

    Raises
    ------
    RecordingError
        `directory` is not a directory, or holds no trial file.
    """
    directory = Path(directory)
    if not directory.is_dir():
        raise RecordingError(f"{directory}: not a directory")
    files: dict[str, Path] = {}
    for sub in (directory, directory / "data_mat", directory / "data_hdf5"):
        if sub.is_dir():
            for p in sorted(sub.iterdir()):
                if p.suffix in (".mat", ".hdf5", ".h5") and p.stem[:2].isdigit():
                    files.setdefault(p.stem, p)
    if not files:
        raise RecordingError(f"{directory}: no BROAD trial files (NN_name.mat or .hdf5)")
    return [files[k] for k in sorted(files)]


def run_broad(directory, *, filters=BROAD_FILTERS, progress=None) -> dict:
    """Run every filter on every trial present; the dataset's error metric per trial.

    The static start for the thesis' estimators is the rest before the first
    movement sample (at most 2 s); BROAD has no common rotation, so there is
    no azimuth alignment.

    Parameters
    ----------
    directory : path-like
        The dataset's folder (or its ``data_mat`` / ``data_hdf5``).
    filters : sequence of str, keyword-only
        Names from :data:`BROAD_FILTERS`.
    progress : callable, keyword-only, optional
        Called with a line of text after each trial (the ahrs filters take
        seconds per trial).

    Each trial gets :func:`check_recording`'s checks (raising on unusable
    data, its warnings issued with :func:`warnings.warn` naming the file); a
    trial whose reference is NaN over the whole movement phase, or where a
    filter gives no finite error, is skipped with a warning, so the means
    and the result never hold NaN.

    Raises
    ------
    RecordingError
        A bad trial (see :func:`read_broad_trial`, :func:`check_recording`),
        or no usable trial at all.
    """
    import warnings

    from ._eval import make_filter
    from ._recording import check_recording

    out: dict = {"trials": {}, "mean": {}}
    for path in find_broad_trials(directory):
        rec, opt, movement = read_broad_trial(path)
        first = int(np.argmax(movement))
        static_s = max(2.0 / rec.rate_hz, min(2.0, first / rec.rate_hz))
        for w in check_recording(rec, static_s=static_s, source=str(path)):
            warnings.warn(f"{path}: {w}", stacklevel=2)
        if not np.isfinite(opt[movement]).all(axis=1).any():
            warnings.warn(f"{path}: the reference opt_quat is NaN over the whole movement phase; "
                          "trial skipped", stacklevel=2)
            continue
        static = StaticStart(static_s=static_s, align_start_s=None, align_end_s=None)
        res = {}
        for name in filters:
            est = make_filter(name)
            if hasattr(est, "static"):
                import dataclasses

                est = dataclasses.replace(est, static=static)
            q = est.run(rec)[0]
            q_enu = qmul(qconj(_Q_NWU_FROM_ENU), q)
            res[name] = broad_errors(q_enu, opt, movement)
        bad = sorted({n for n, m in res.items() if not all(np.isfinite(v) for v in m.values())})
        if bad:
            warnings.warn(f"{path}: filter(s) {', '.join(bad)} give no finite error; trial "
                          "skipped", stacklevel=2)
            continue
        out["trials"][path.stem] = res
        if progress is not None:
            best = min(res, key=lambda k: res[k]["total_rmse_deg"])
            progress(f"{path.stem}: best {best} {res[best]['total_rmse_deg']:.2f} deg")
    if not out["trials"]:
        raise RecordingError(f"{directory}: no usable BROAD trial (every one was skipped)")
    for name in filters:
        out["mean"][name] = {m: float(np.mean([t[name][m] for t in out["trials"].values()]))
                             for m in ("total_rmse_deg", "heading_rmse_deg", "inclination_rmse_deg")}
    out["anchor"] = "VQF over all 39 BROAD trials: 2.9 deg mean total RMSE (Laidig & Seel 2023)"
    return out
