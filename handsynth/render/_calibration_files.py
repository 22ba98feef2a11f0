"""Camera calibration files read as :class:`~handsynth.render.CameraIntrinsics`.

:func:`read_intrinsics` reads a calibration file as the usual tools write it:
OpenCV's ``FileStorage`` (YAML, XML or JSON: ``camera_matrix``,
``distortion_coefficients``, ``image_width``, ``image_height``; its calibration
sample's ``fisheye_model: 1`` for a fisheye), ROS ``camera_calibration``'s
``ost.yaml`` and ``camera_info`` messages (``plumb_bob``,
``rational_polynomial``, ``equidistant``), Kalibr's camera chain of one pinhole
camera (``cam0: {intrinsics: [fu, fv, pu, pv], distortion_coeffs,
distortion_model, resolution}``), Basalt's ``calibration.json`` of one camera
(``pinhole``, ``pinhole-radtan8``, ``kb4``), ORB-SLAM2/3 settings (``PinHole``,
``KannalaBrandt8``) and plain JSON or YAML with those names.  Cameras of other
projections (Kalibr's ``omni``, ``ds``, ``eucm``; Basalt's ``ds``, ``eucm``,
``fov``) and files of several cameras are refused by name, not read as a pinhole.
"""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

import numpy as np

from .._checks import check_path, short_repr
from ..errors import InvalidCameraError, InvalidInputError
from ._lens import _PINHOLE_COUNTS, CameraIntrinsics

__all__ = ["read_intrinsics"]

#: ``distortion_model`` spellings (ROS, Kalibr, OpenCV users) and the model each is.
_MODEL_NAMES = {"plumb_bob": "pinhole", "rational_polynomial": "pinhole", "radtan": "pinhole",
                "pinhole": "pinhole", "brown": "pinhole", "brown_conrady": "pinhole",
                "none": "pinhole", "equidistant": "fisheye", "fisheye": "fisheye",
                "kannala_brandt": "fisheye", "kb4": "fisheye"}
#: Field names read by :func:`read_intrinsics` (lower case), in order of preference.
_MATRIX_KEYS = ("camera_matrix", "cameramatrix", "k", "intrinsic_matrix", "intrinsics")
_DISTORTION_KEYS = ("distortion_coefficients", "dist_coeffs", "distcoeffs", "distortion_coeffs",
                    "dist_coeff", "distortion", "d")
_SIZE_KEYS = (("image_width", "image_height"), ("width", "height"))
_SIZE_PAIR_KEYS = ("image_size", "imagesize", "resolution", "size")
#: Sequences longer than this in an OpenCV ``FileStorage`` file are left unread: none is a
#: field read here, and OpenCV's Python binding walks a sequence from its start for each item.
_LONG_SEQUENCE = 1000
#: Camera types of Basalt (``camera_type``) and ORB-SLAM3 (``Camera.type``) read: the model,
#: and the names of its coefficients in OpenCV's order, required and optional.
_CameraType = tuple[str, tuple[str, ...], tuple[str, ...]]
_BASALT_TYPES: dict[str, _CameraType] = {
    "pinhole": ("pinhole", (), ()),
    "pinhole-radtan8": ("pinhole", ("k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"), ()),
    "kb4": ("fisheye", ("k1", "k2", "k3", "k4"), ())}
_ORBSLAM_TYPES: dict[str, _CameraType] = {
    "PinHole": ("pinhole", ("k1", "k2", "p1", "p2"), ("k3",)),
    "KannalaBrandt8": ("fisheye", ("k1", "k2", "k3", "k4"), ())}


def _node_value(node):
    """An OpenCV ``FileNode`` as Python: a number, text, list, dict, or an array for a matrix."""
    if node.isMap():
        keys = node.keys()
        if "dt" in keys and "data" in keys:  # an !!opencv-matrix (None: an empty one)
            m = node.mat()
            return np.zeros(0) if m is None else m
        return {k: _node_value(node.getNode(k)) for k in keys}
    if node.isSeq():
        if node.size() > _LONG_SEQUENCE:
            return f"<a sequence of {node.size()} values, not read>"
        return [_node_value(node.at(i)) for i in range(node.size())]
    if node.isInt():
        return int(node.real())
    if node.isReal():
        return node.real()
    return node.string() if node.isString() else None


def _load_opencv(path: Path, text: str) -> dict:
    """The top-level fields of an OpenCV ``FileStorage`` file (YAML, XML or JSON)."""
    import cv2

    if text.lstrip().startswith("<") and not text.lstrip().startswith("<?xml"):
        text = '<?xml version="1.0"?>' + text  # read from memory, XML is known by its declaration
    try:
        fs = cv2.FileStorage(text, cv2.FILE_STORAGE_READ | cv2.FILE_STORAGE_MEMORY)
    except (cv2.error, SystemError) as exc:
        said = str(exc.__cause__ or exc.__context__ or exc)
        m = re.search(r"\((\d+)\): ([^'\n]*)", said)
        where = f" at line {m[1]} ({m[2].strip()})" if m else f" ({said.strip().splitlines()[-1][:120]})"
        raise InvalidInputError(f"camera intrinsics {path}: not a readable OpenCV FileStorage "
                                f"file{where}") from None
    try:
        root = fs.root()
        names = root.keys() if root.isMap() else ()  # a FileNode's keys, not a dict's
        return {key: _node_value(root.getNode(key)) for key in names}
    finally:
        fs.release()


def _load_yaml(path: Path, text: str):
    """A YAML file's one document (None when it holds none)."""
    import yaml

    # OpenCV's YAML: a "%YAML:1.0" directive PyYAML refuses (emptied: line numbers kept),
    # and !!opencv-matrix tags
    text = re.sub(r"\A(\s*)%YAML[^\n]*", r"\1", text)
    text = re.sub(r"!!opencv-(matrix|nd-matrix)", "", text)
    try:
        docs = [d for d in yaml.load_all(text, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
                if d is not None]
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        problem = getattr(exc, "problem", None) or str(exc)
        lines = text.splitlines()
        if mark is not None and mark.line < len(lines) and "\t" in lines[mark.line][:mark.column + 1]:
            problem += "; YAML does not allow tabs there: indent with spaces"
        where = f" at line {mark.line + 1}" if mark is not None else ""
        raise InvalidInputError(f"camera intrinsics {path}: not valid YAML{where} ({problem})") \
            from None
    if len(docs) > 1:
        raise InvalidInputError(f"camera intrinsics {path}: holds {len(docs)} YAML documents "
                                f"(separated by '---'); give one camera's calibration")
    return docs[0] if docs else None


def _load_document(path: Path) -> dict:
    """A calibration file's fields, as a dict (keys as written)."""
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise InvalidInputError(f"camera intrinsics {path}: cannot be read ({exc})") from None
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InvalidInputError(f"camera intrinsics {path}: not a text file (byte "
                                f"{data[exc.start]:#04x} at offset {exc.start} is not UTF-8); a "
                                f"calibration is YAML, XML or JSON text") from None
    head = text.lstrip()
    if not head:
        raise InvalidInputError(f"camera intrinsics {path}: the file is empty")
    if head.startswith("# oST version"):
        raise InvalidInputError(f"camera intrinsics {path}: is ROS camera_calibration's ost.txt; "
                                f"give the ost.yaml (or left.yaml, right.yaml) written with it")
    doc = None
    if head.startswith("<"):
        doc = _load_opencv(path, text)
    elif head.startswith("%YAML"):  # OpenCV's own YAML (OpenCV, ORB-SLAM): read by OpenCV, fast
        try:
            doc = _load_opencv(path, text)
        except InvalidInputError:
            doc = _load_yaml(path, text)
    elif path.suffix.lower() == ".json":
        try:
            doc = json.loads(text)
        except json.JSONDecodeError as exc:
            try:  # OpenCV's JSON: "//" comments (its calibration sample writes the flags so)
                doc = _load_opencv(path, text)
            except InvalidInputError:
                raise InvalidInputError(f"camera intrinsics {path}: not valid JSON ({exc})") \
                    from None
    else:
        doc = _load_yaml(path, text)
    if not isinstance(doc, dict):
        raise InvalidInputError(f"camera intrinsics {path}: must be a map of fields "
                                f"(camera_matrix, distortion_coefficients, image_width, "
                                f"image_height), got {'nothing' if doc is None else type(doc).__name__}")
    return doc


def _lower(fields: dict) -> dict:
    """`fields` with its keys as lower-case text."""
    return {str(k).lower(): v for k, v in fields.items()}


def _numbers(value, path: Path, key: str) -> np.ndarray:
    """A field's numbers, flat: a list, nested lists or a ``{rows, cols, data}`` matrix map."""
    if isinstance(value, dict):
        lower = _lower(value)
        if "data" not in lower:
            raise InvalidInputError(f"camera intrinsics {path}: field {key!r} is a map without "
                                    f"'data' (got {', '.join(map(str, value))})")
        value = lower["data"]
    try:
        arr = np.asarray(value, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise InvalidInputError(f"camera intrinsics {path}: field {key!r} must hold numbers, "
                                f"got {short_repr(value)}") from None
    if not np.isfinite(arr).all():
        raise InvalidInputError(f"camera intrinsics {path}: field {key!r} holds NaN or "
                                f"infinity: {short_repr(value)}")
    return arr


def _find(fields: dict, keys, path: Path, what: str):
    for k in keys:
        if k in fields:
            return k, fields[k]
    raise InvalidInputError(f"camera intrinsics {path}: no {what} (looked for "
                            f"{', '.join(keys)}; found {', '.join(fields) or 'nothing'})")


def _several_cameras(path: Path, names) -> InvalidInputError:
    return InvalidInputError(f"camera intrinsics {path}: holds {len(names)} cameras "
                             f"({', '.join(names)}); give a file of the one on the hand")


def _named_camera(params, kind, types: dict[str, _CameraType], path: Path, type_field: str,
                  prefix: str) -> dict:
    """The fields read of a camera given as named parameters (``fx``, ``fy``, ``cx``, ``cy``,
    ``k1``...) and a camera type of `types` (Basalt, ORB-SLAM3).

    `type_field` names the type's field and `prefix` the parameters' in messages.
    """
    found = next((t for t in types if t.lower() == str(kind).strip().lower()), None)
    if found is None:
        raise InvalidInputError(f"camera intrinsics {path}: {type_field} {short_repr(kind)} is not "
                                f"a camera handsynth reads (it reads {', '.join(types)})")
    if not isinstance(params, dict):
        raise InvalidInputError(f"camera intrinsics {path}: {prefix.rstrip('.')} must be a map of "
                                f"parameters (fx, fy, cx, cy...), got {short_repr(params)}")
    model, names, optional = types[found]
    params = _lower(params)
    missing = [f"{prefix}{n}" for n in ("fx", "fy", "cx", "cy", *names) if n not in params]
    if missing:
        raise InvalidInputError(f"camera intrinsics {path}: a {found} camera needs "
                                f"{', '.join(missing)} (found {', '.join(params) or 'nothing'})")
    value = {n: _numbers(params[n], path, f"{prefix}{n}") for n in (*names, *optional)
             if n in params}
    for n, v in value.items():
        if v.size != 1:
            raise InvalidInputError(f"camera intrinsics {path}: field {prefix}{n!r} must be one "
                                    f"number, got {short_repr(params[n])}")
    return {"camera_matrix": [params[n] for n in ("fx", "fy", "cx", "cy")],
            "distortion_coefficients": [float(v[0]) for v in value.values()],
            "distortion_model": model}


def _basalt_fields(root: dict, path: Path) -> dict:
    """The fields read of Basalt's ``calibration.json`` (``value0`` of cereal's JSON)."""
    cameras = root["intrinsics"]
    if len(cameras) > 1:
        raise _several_cameras(path, [f"value0.intrinsics[{i}]" for i in range(len(cameras))])
    cam = _lower(cameras[0])
    fields = _named_camera(cam.get("intrinsics"), cam.get("camera_type"), _BASALT_TYPES, path,
                           "value0.intrinsics[0].camera_type", "value0.intrinsics[0].intrinsics.")
    if "resolution" not in root:
        raise InvalidInputError(f"camera intrinsics {path}: no frame size (looked for "
                                f"value0.resolution; found {', '.join(root)})")
    res = root["resolution"]
    fields["resolution"] = res[0] if isinstance(res, list) and res and isinstance(res[0], list) \
        else res
    return fields


def _orbslam_fields(fields: dict, prefix: str, path: Path) -> dict:
    """The fields read of an ORB-SLAM settings file (``Camera.type``, ``Camera1.fx``... or, in
    older files, ``Camera.fx``...; ``Camera.width``, ``Camera.height``)."""
    if "camera2.fx" in fields:
        raise _several_cameras(path, ["Camera1", "Camera2"])
    size = [fields.get(k) for k in ("camera.width", "camera.height")]
    if None in size:
        raise InvalidInputError(f"camera intrinsics {path}: no frame size (looked for "
                                f"Camera.width and Camera.height; found {', '.join(fields)})")
    shown = "Camera1." if prefix == "camera1." else "Camera."
    params = {k[len(prefix):]: v for k, v in fields.items() if k.startswith(prefix)}
    out = _named_camera(params, fields.get("camera.type", "PinHole"), _ORBSLAM_TYPES, path,
                        "Camera.type", shown)
    return {**out, "image_width": size[0], "image_height": size[1]}


def _camera_fields(doc: dict, path: Path) -> dict:
    """The fields of the one camera a file describes (lower-case keys), in the generic names:
    a Basalt, ORB-SLAM or Kalibr file, or one camera's map in a file of several, is read so."""
    fields = _lower(doc)
    root = _lower(fields["value0"]) if isinstance(fields.get("value0"), dict) else fields
    cams = root.get("intrinsics")
    if isinstance(cams, list) and cams and all(isinstance(c, dict) for c in cams):
        return _basalt_fields(root, path)
    orbslam = next((p for p in ("camera1.", "camera.") if f"{p}fx" in fields), None)
    if orbslam and not fields.keys() & set(_MATRIX_KEYS):
        return _orbslam_fields(fields, orbslam, path)
    where = ""
    cameras = [k for k, v in fields.items()
               if isinstance(v, dict) and _lower(v).keys() & set(_MATRIX_KEYS)]
    if cameras and not fields.keys() & set(_MATRIX_KEYS):  # Kalibr's cam0, cam1...
        if len(cameras) > 1:
            raise _several_cameras(path, cameras)
        where, fields = f"{cameras[0]}.", _lower(fields[cameras[0]])
    projection = str(fields.get("camera_model", "pinhole")).strip().lower()
    if "intrinsics" in fields and projection != "pinhole":  # Kalibr's omni, ds, eucm
        raise InvalidInputError(f"camera intrinsics {path}: {where}camera_model {projection!r} is "
                                f"not a pinhole camera; handsynth reads Kalibr's pinhole cameras "
                                f"(distortion radtan or equidistant) only")
    return fields


def _distortion_model(fields: dict, path: Path) -> str:
    """``"pinhole"`` or ``"fisheye"``: from ``distortion_model`` (or ``model``) and OpenCV's
    calibration sample's ``fisheye_model`` (1: calibrated with ``cv::fisheye``)."""
    key = next((k for k in ("distortion_model", "model") if k in fields), None)
    name = str(fields[key]).strip().lower() if key else "pinhole"
    if name not in _MODEL_NAMES:
        raise InvalidInputError(f"camera intrinsics {path}: {key} {name!r} is not one "
                                f"handsynth knows ({', '.join(sorted(_MODEL_NAMES))})")
    model = _MODEL_NAMES[name]
    if "fisheye_model" in fields:
        flag = fields["fisheye_model"]
        if isinstance(flag, str) or flag not in (0, 1):
            raise InvalidInputError(f"camera intrinsics {path}: field 'fisheye_model' must be 0 "
                                    f"or 1, got {short_repr(flag)}")
        flagged = "fisheye" if flag else "pinhole"
        if key and flagged != model:
            raise InvalidInputError(f"camera intrinsics {path}: fisheye_model {flag:g} and {key} "
                                    f"{name!r} contradict each other")
        model = flagged
    return model


def _focal_and_centre(fields: dict, path: Path) -> tuple[float, float, float, float]:
    """``fx, fy, cx, cy`` of the camera matrix (3x3) or Kalibr's ``[fu, fv, pu, pv]``."""
    key, raw = _find(fields, _MATRIX_KEYS, path, "camera matrix")
    m = _numbers(raw, path, key)
    if m.size == 4:  # Kalibr: fu, fv, pu, pv
        return m[0], m[1], m[2], m[3]
    if m.size != 9:
        raise InvalidInputError(f"camera intrinsics {path}: field {key!r} must hold 9 numbers (a "
                                f"3x3 matrix) or 4 (fu, fv, pu, pv), got {m.size}")
    k = m.reshape(3, 3)
    if not np.allclose(k[2], [0.0, 0.0, 1.0]) or k[1, 0] != 0.0:
        raise InvalidInputError(f"camera intrinsics {path}: field {key!r} must be a camera "
                                f"matrix [[fx, 0, cx], [0, fy, cy], [0, 0, 1]], got {k.tolist()}")
    if abs(k[0, 1]) > 1e-9 * k[0, 0]:
        raise InvalidInputError(f"camera intrinsics {path}: field {key!r} has a skew of "
                                f"{k[0, 1]:g}; only cameras without skew are supported")
    return k[0, 0], k[1, 1], k[0, 2], k[1, 2]


def _frame_size(fields: dict, path: Path) -> tuple[int, int]:
    """The calibration's frame size, whole pixels."""
    size = next(((fields[a], fields[b]) for a, b in _SIZE_KEYS if a in fields and b in fields),
                None)
    if size is None:
        pair = next((fields[k] for k in _SIZE_PAIR_KEYS if k in fields), None)
        if pair is None:
            raise InvalidInputError(
                f"camera intrinsics {path}: no frame size (looked for image_width and "
                f"image_height, width and height, {', '.join(_SIZE_PAIR_KEYS)}; found "
                f"{', '.join(fields)})")
        size = tuple(_numbers(pair, path, "image size"))
        if len(size) != 2:
            raise InvalidInputError(f"camera intrinsics {path}: the frame size must be [width, "
                                    f"height], got {short_repr(pair)}")
    dims = [_numbers(v, path, "frame size") for v in size]
    if any(d.size != 1 or not float(d[0]).is_integer() for d in dims):
        raise InvalidInputError(f"camera intrinsics {path}: the frame size must be whole pixels, "
                                f"got {short_repr(size[0])} x {short_repr(size[1])}")
    w, h = (int(d[0]) for d in dims)
    return int(w), int(h)


def read_intrinsics(path: str | os.PathLike) -> CameraIntrinsics:
    """A camera calibration file as :class:`CameraIntrinsics`.

    Parameters
    ----------
    path : str or os.PathLike
        One camera's calibration as these tools write it:

        - OpenCV ``FileStorage`` YAML, XML or JSON, as its calibration sample
          saves it (``out_camera_data.yml``; ``fisheye_model: 1`` for a
          fisheye calibration) or ``cv2.FileStorage`` writes it;
        - ROS ``camera_calibration``'s ``ost.yaml`` (or ``left.yaml``) and
          ``camera_info`` messages as ``rostopic echo`` / ``ros2 topic echo``
          print them (``K``, ``D``, ``width``, ``height``);
        - a Kalibr camera chain of one camera (``camera_model: pinhole``,
          ``intrinsics: [fu, fv, pu, pv]``, ``distortion_model: radtan`` or
          ``equidistant``, ``resolution``);
        - Basalt's ``calibration.json`` of one camera (``camera_type``
          ``pinhole``, ``pinhole-radtan8`` or ``kb4``);
        - an ORB-SLAM2/3 settings file (``Camera.type: PinHole`` or
          ``KannalaBrandt8``; ``Camera1.fx``... or ``Camera.fx``...;
          ``Camera.width``, ``Camera.height``);
        - JSON or YAML with the fields ``camera_matrix`` (3x3, nested or
          flat, or a ``{rows, cols, data}`` map; also ``cameraMatrix``,
          ``K``), ``distortion_coefficients`` (also ``dist_coeffs``,
          ``distCoeffs``, ``distortion_coeffs``, ``D``; empty for none), the
          frame size (``image_width`` and ``image_height``, ``width`` and
          ``height``, or ``image_size`` / ``resolution`` as ``[w, h]``) and
          optionally ``distortion_model`` (``plumb_bob``,
          ``rational_polynomial``, ``radtan``: the pinhole model;
          ``equidistant``, ``fisheye``: the fisheye model), alone or as the
          one camera's map in the file.

    Returns
    -------
    CameraIntrinsics

    Raises
    ------
    InvalidInputError
        No such file, an empty or binary file, one that cannot be parsed
        (naming the line where the parser says), a field missing (naming
        those looked for and those found), a camera matrix that is not 3x3
        with a last row ``0 0 1`` and no skew, a distortion model not known,
        a camera that is not a pinhole one (Kalibr's ``omni``, ``ds``,
        ``eucm``; Basalt's ``ds``, ``eucm``...), a file of several cameras,
        or values out of range (:class:`CameraIntrinsics`), each naming the
        file.
    """
    p = check_path(path, "camera intrinsics", kind="file")
    if not p.is_file():
        raise InvalidInputError(f"camera intrinsics {str(p)!r}: no such file")
    fields = _camera_fields(_load_document(p), p)
    fx, fy, cx, cy = _focal_and_centre(fields, p)
    dkey, draw = _find(fields, _DISTORTION_KEYS, p, "distortion coefficients")
    dist = _numbers(draw, p, dkey) if draw is not None else np.zeros(0)
    model = _distortion_model(fields, p)
    if model == "pinhole" and dist.size and not dist.any():
        dist = np.zeros(0)
    if model == "pinhole" and dist.size in (1, 2, 3, 6, 7):
        # ROS and Kalibr write fewer where the rest are zero: k1, k2[, p1, p2]...
        dist = np.concatenate([dist, np.zeros(next(c for c in _PINHOLE_COUNTS if c >= dist.size)
                                              - dist.size)])
    w, h = _frame_size(fields, p)
    try:
        return CameraIntrinsics(w, h, float(fx), float(fy), float(cx), float(cy),
                                distortion=tuple(float(v) for v in dist), model=model)
    except InvalidCameraError as exc:
        raise InvalidCameraError(f"camera intrinsics {p}: {exc}") from None
