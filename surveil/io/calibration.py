"""Rig calibration files: surveil's own rig YAML, importers from other tools, and an exporter.

surveil's rig file (``calibration/<rig>.yaml``, described for users in docs/calibration.md and
fixed by the formats contract) is an OpenCV FileStorage YAML file, read and written only with
``cv2.FileStorage``::

    units: m
    cameras:
      - name: cam0              # [A-Za-z0-9_.-]+, unique
        image_width: 640        # pixels
        image_height: 480
        K: !!opencv-matrix      # 3x3 intrinsics, pixels
        dist: !!opencv-matrix   # 1xN OpenCV distortion, N in 4, 5, 8, 12, 14
        R: !!opencv-matrix      # 3x3 rotation world -> camera
        t: !!opencv-matrix      # 3x1 translation world -> camera, metres

so that a world point ``X`` is at ``R @ X + t`` in the camera frame. Both the ``%YAML:1.0``
header (OpenCV <= 4) and ``%YAML 1.2`` (what OpenCV 5 writes) are read; files are written with
whatever header the installed OpenCV writes, which every OpenCV version reads.

Importers (:func:`import_rig`), each world -> camera:

``opencv-multiview``
    The file of OpenCV's ``samples/python/multiview_calibration.py`` (keys ``cam_ids``,
    ``Ks``, ``distortions``, ``rvecs``, ``Ts``, ``image_sizes``). Its world frame is the
    frame of the first camera (x right, y down, z forward -- *not* Z up) and its lengths are
    in the unit of the calibration board's ``--pattern_distance``: ``units`` is required.
``aniposelib``
    The TOML of anipose / aniposelib, Pose2Sim (``Calib.toml``), Caliscope, FreeMoCap: one
    table per camera with ``name``, ``size``, ``matrix``, ``distortions``, ``rotation``
    (Rodrigues), ``translation``; ``[metadata]`` is ignored. Units differ between these tools
    (Pose2Sim metres, anipose board units): ``units`` is required.
``easymocap``
    EasyMocap's ``intri.yml`` (``names``, ``K_<name>``, ``dist_<name>`` or ``D_<name>``,
    optional ``H_<name>``/``W_<name>``) with ``extri.yml`` (``R_<name>`` Rodrigues or
    ``Rot_<name>`` 3x3, ``T_<name>``). ``units`` is required. Without ``H_``/``W_`` the image
    size is inferred from the principal point, with a warning.

Every problem is an :class:`~surveil.errors.InputError` whose message names the file, the
camera (name and index) and the key, and says what was expected and what was found.
"""

from __future__ import annotations

import logging
import re
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from surveil.camera import CAMERA_NAME_RE, DIST_LENGTHS, Camera, Rig
from surveil.errors import InputError

log = logging.getLogger(__name__)

FORMATS = ("surveil", "opencv-multiview", "aniposelib", "easymocap")
UNITS_TO_M = {"m": 1.0, "cm": 0.01, "mm": 0.001}
ROTATION_TOL = 1e-6  # max |R R^T - I| of a rotation read from a rig file (as Camera checks)
REORTHONORMALISE_TOL = 1e-4  # imported 3x3 rotations written with few decimals are repaired
_DIST_TEXT = ", ".join(map(str, DIST_LENGTHS))


# ---------------------------------------------------------------------------------------------
# error messages


@dataclass(frozen=True)
class _Where:
    """Where a value comes from, to build messages: a file, optionally one of its cameras."""

    path: Path
    index: int | None = None
    name: str | None = None

    def cam(self, index: int, name: str | None = None) -> _Where:
        return _Where(self.path, index, name)

    def error(self, key: str | None, message: str) -> InputError:
        parts = [str(self.path)]
        if self.index is not None:
            parts.append(
                f"camera {self.name!r} (index {self.index})"
                if self.name is not None
                else f"camera index {self.index}"
            )
        if key is not None:
            parts.append(f"key {key!r}")
        return InputError(": ".join(parts) + ": " + message)

    def missing(self, key: str) -> InputError:
        return self.error(key, "missing (required)")


def _shape_text(arr: np.ndarray) -> str:
    return "x".join(map(str, arr.shape)) if arr.ndim else "a scalar"


# ---------------------------------------------------------------------------------------------
# checks shared by every format: arrays -> Camera, with messages naming the key


def _as_float_array(where: _Where, key: str, value: Any) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise where.error(key, f"expected numbers, found {value!r}") from None
    if not np.isfinite(arr).all():
        raise where.error(key, "expected finite numbers, found NaN or infinity")
    return arr


def _matrix33(where: _Where, key: str, value: Any) -> np.ndarray:
    arr = _as_float_array(where, key, value)
    if arr.shape != (3, 3):
        raise where.error(key, f"expected a 3x3 matrix, found {_shape_text(arr)}")
    return arr


def _vector(
    where: _Where, key: str, value: Any, lengths: tuple[int, ...], what: str
) -> np.ndarray:
    """A 1xN, Nx1 or flat vector with N in ``lengths``, returned flat."""
    arr = _as_float_array(where, key, value)
    if arr.ndim > 2 or (arr.ndim == 2 and 1 not in arr.shape) or arr.size not in lengths:
        raise where.error(key, f"expected {what}, found {_shape_text(arr)}")
    return arr.reshape(-1)


def _intrinsics(where: _Where, key: str, value: Any) -> np.ndarray:
    K = _matrix33(where, key, value)
    if K[0, 0] <= 0 or K[1, 1] <= 0:
        raise where.error(
            key, f"expected positive focal lengths, found fx={K[0, 0]}, fy={K[1, 1]}"
        )
    if not np.allclose(K[2], [0, 0, 1]):
        raise where.error(key, f"expected last row [0, 0, 1], found {K[2].tolist()}")
    return K


def _distortion(where: _Where, key: str, value: Any) -> np.ndarray:
    return _vector(where, key, value, DIST_LENGTHS, f"1xN coefficients with N in {_DIST_TEXT}")


def _rotation(where: _Where, key: str, value: Any, *, repair: bool = False) -> np.ndarray:
    """A 3x3 rotation matrix (orthonormal, det +1). ``repair``: project a nearly orthonormal
    matrix (written with few decimals by another tool) onto the nearest rotation."""
    R = _matrix33(where, key, value)
    err = float(np.abs(R @ R.T - np.eye(3)).max())
    det = float(np.linalg.det(R))
    if repair and err <= REORTHONORMALISE_TOL and det > 0:
        u, _, vt = np.linalg.svd(R)
        R = u @ vt
        err, det = float(np.abs(R @ R.T - np.eye(3)).max()), float(np.linalg.det(R))
    if err > ROTATION_TOL or det < 0:
        raise where.error(
            key,
            f"expected a rotation matrix (R R^T = I within {ROTATION_TOL:g}, det +1), "
            f"found max |R R^T - I| = {err:.3g}, det = {det:.6f}",
        )
    return R


def _rodrigues(where: _Where, key: str, value: Any) -> np.ndarray:
    rvec = _vector(where, key, value, (3,), "a Rodrigues rotation vector of 3 numbers")
    return cv2.Rodrigues(rvec)[0]


def _translation(where: _Where, key: str, value: Any, scale: float) -> np.ndarray:
    return _vector(where, key, value, (3,), "a 3x1 translation") * scale


def _camera_name(where: _Where, key: str, value: Any) -> str:
    if not isinstance(value, str) or not CAMERA_NAME_RE.match(value):
        raise where.error(
            key, f"expected a camera name of letters, digits, '_', '.', '-', found {value!r}"
        )
    return value


def _image_size(where: _Where, key: str, value: Any) -> int:
    if isinstance(value, float) and value.is_integer():
        value = int(value)
    if isinstance(value, bool) or not isinstance(value, int) or value <= 0:
        raise where.error(key, f"expected a positive integer number of pixels, found {value!r}")
    return value


def _build_rig(where: _Where, cameras: list[Camera], names_key: str = "name") -> Rig:
    seen: dict[str, int] = {}
    for i, cam in enumerate(cameras):
        if cam.name in seen:
            raise where.cam(i, cam.name).error(
                names_key,
                f"expected a unique name, found {cam.name!r} again "
                f"(already camera index {seen[cam.name]})",
            )
        seen[cam.name] = i
    if not cameras:
        raise where.error(None, "expected at least one camera, found none")
    return Rig(tuple(cameras))


def _camera(where: _Where, name: str, width: int, height: int, K, dist, R, t) -> Camera:
    try:
        return Camera(name, width, height, K, dist, R, t)
    except (ValueError, TypeError) as exc:  # every field was checked above; belt and braces
        raise where.error(None, str(exc)) from None


def _units_scale(where: _Where, units: str | None, fmt: str, why: str) -> float:
    if units is None:
        raise where.error(
            None,
            f"the {fmt} format does not say which unit its translations are in ({why}); "
            "pass --units m|mm|cm (units='m', 'mm' or 'cm')",
        )
    if units not in UNITS_TO_M:
        raise where.error(None, f"units must be one of m, mm, cm; got {units!r}")
    return UNITS_TO_M[units]


# ---------------------------------------------------------------------------------------------
# cv2.FileStorage helpers


def _first_line_of_cv_error(exc: BaseException) -> str:
    cause = exc.__cause__ if exc.__cause__ is not None else exc
    text = str(cause).strip().splitlines()[0] if str(cause).strip() else type(cause).__name__
    return re.sub(r"^OpenCV\([^)]*\)\s*\S+:\d+:\s*error:\s*", "", text)


def _open_storage(path: Path) -> cv2.FileStorage:
    """Open a FileStorage file for reading; any failure is an InputError naming the file."""
    if not path.is_file():
        raise InputError(f"{path}: file not found")
    try:
        fs = cv2.FileStorage(str(path), cv2.FileStorage_READ)
    except (cv2.error, SystemError) as exc:  # a parse error surfaces as SystemError in Python
        raise InputError(
            f"{path}: not a readable OpenCV FileStorage (YAML/XML) file: "
            f"{_first_line_of_cv_error(exc)}"
        ) from None
    if not fs.isOpened():
        raise InputError(f"{path}: cannot be opened as an OpenCV FileStorage (YAML/XML) file")
    return fs


def _keys(node: cv2.FileNode) -> tuple[str, ...]:
    return tuple(node.keys()) if node.isMap() else ()


def _node_matrix(where: _Where, parent: cv2.FileNode, key: str) -> np.ndarray:
    if key not in _keys(parent):
        raise where.missing(key)
    node = parent.getNode(key)
    if not node.isMap():
        raise where.error(key, f"expected an opencv-matrix, found {_node_kind(node)}")
    try:
        mat = node.mat()
    except cv2.error as exc:
        raise where.error(
            key, f"expected an opencv-matrix, found a broken one: {_first_line_of_cv_error(exc)}"
        ) from None
    if mat is None:
        raise where.error(key, "expected an opencv-matrix, found a map without matrix data")
    return np.asarray(mat, dtype=np.float64)


def _node_kind(node: cv2.FileNode) -> str:
    if node.isString():
        return f"the string {node.string()!r}"
    if node.isInt():
        return f"the integer {int(node.real())}"
    if node.isReal():
        return f"the number {node.real()}"
    if node.isSeq():
        return f"a sequence of {node.size()} items"
    if node.isMap():
        return "a map"
    return "nothing"


def _node_string(where: _Where, parent: cv2.FileNode, key: str) -> str:
    if key not in _keys(parent):
        raise where.missing(key)
    node = parent.getNode(key)
    if not node.isString():
        raise where.error(key, f"expected a string, found {_node_kind(node)}")
    return node.string()


def _node_int(where: _Where, parent: cv2.FileNode, key: str) -> int:
    if key not in _keys(parent):
        raise where.missing(key)
    node = parent.getNode(key)
    if not node.isInt():
        raise where.error(key, f"expected an integer, found {_node_kind(node)}")
    return _image_size(where, key, int(node.real()))


# ---------------------------------------------------------------------------------------------
# surveil rig YAML


def load_rig(path: Path) -> Rig:
    """Read a surveil rig YAML file (formats contract, "Rig calibration").

    Parameters
    ----------
    path : Path
        ``calibration/<rig>.yaml``: OpenCV FileStorage with ``units: m`` and a ``cameras``
        sequence of maps (``name``, ``image_width``, ``image_height``, ``K`` 3x3, ``dist``
        1xN, ``R`` 3x3 world -> camera, ``t`` 3x1 world -> camera in metres).

    Returns
    -------
    Rig
        The cameras in file order.

    Raises
    ------
    InputError
        Unreadable file, ``units`` not ``"m"``, or a camera with a missing key, a matrix of the
        wrong shape, ``dist`` length not in 4/5/8/12/14, ``R`` not a rotation, a duplicate or
        invalid name; the message names the file, the camera and the key.
    """
    path = Path(path)
    where = _Where(path)
    fs = _open_storage(path)
    try:
        root = fs.root()
        units = _node_string(where, root, "units")
        if units != "m":
            raise where.error("units", f'expected "m", found {units!r}')
        if "cameras" not in _keys(root):
            raise where.missing("cameras")
        seq = fs.getNode("cameras")
        if not seq.isSeq():
            raise where.error("cameras", f"expected a sequence of maps, found {_node_kind(seq)}")
        cameras = [_read_rig_camera(where, seq.at(i), i) for i in range(seq.size())]
    finally:
        fs.release()
    rig = _build_rig(where, cameras)
    log.debug("%s: %d cameras (%s)", path, len(rig), ", ".join(rig.names))
    return rig


def _read_rig_camera(where: _Where, node: cv2.FileNode, index: int) -> Camera:
    w = where.cam(index)
    if not node.isMap():
        raise w.error(None, f"expected a map of camera keys, found {_node_kind(node)}")
    name = _camera_name(w, "name", _node_string(w, node, "name"))
    w = where.cam(index, name)
    width = _node_int(w, node, "image_width")
    height = _node_int(w, node, "image_height")
    K = _intrinsics(w, "K", _node_matrix(w, node, "K"))
    dist = _distortion(w, "dist", _node_matrix(w, node, "dist"))
    R = _rotation(w, "R", _node_matrix(w, node, "R"))
    t = _translation(w, "t", _node_matrix(w, node, "t"), 1.0)
    return _camera(w, name, width, height, K, dist, R, t)


def save_rig(rig: Rig, path: Path) -> None:
    """Write ``rig`` as a surveil rig YAML file (read back exactly by :func:`load_rig`).

    Parameters
    ----------
    rig : Rig
        Cameras with ``K`` (3, 3), ``dist`` (N,), ``R`` (3, 3) world -> camera and ``t`` (3,)
        world -> camera in metres.
    path : Path
        Output file; its parent directory is created. Written by ``cv2.FileStorage`` (17
        significant digits, so the round trip is exact).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fs = cv2.FileStorage(str(path), cv2.FileStorage_WRITE)
    if not fs.isOpened():
        raise InputError(f"{path}: cannot be opened for writing")
    try:
        fs.write("units", "m")
        fs.startWriteStruct("cameras", cv2.FileNode_SEQ)
        for cam in rig:
            fs.startWriteStruct("", cv2.FileNode_MAP)
            fs.write("name", cam.name)
            fs.write("image_width", int(cam.width))
            fs.write("image_height", int(cam.height))
            fs.write("K", np.ascontiguousarray(cam.K))
            fs.write("dist", cam.dist.reshape(1, -1).copy())
            fs.write("R", np.ascontiguousarray(cam.R))
            fs.write("t", cam.t.reshape(3, 1).copy())
            fs.endWriteStruct()
        fs.endWriteStruct()
    finally:
        fs.release()
    log.debug("wrote %s: %d cameras", path, len(rig))


# ---------------------------------------------------------------------------------------------
# import


def detect_format(path: Path) -> str:
    """Guess the calibration format of ``path`` from its content (one of :data:`FORMATS`).

    ``.toml`` -> ``aniposelib``; a FileStorage file with ``cameras`` -> ``surveil``; with
    ``cam_ids`` or ``Ks``/``rvecs``/``Ts`` -> ``opencv-multiview``; with ``names`` and
    ``K_<name>`` keys -> ``easymocap`` (the ``intri.yml``).

    Raises
    ------
    InputError
        Unreadable file or unknown layout (the message lists the keys found).
    """
    path = Path(path)
    if path.suffix.lower() == ".toml":
        return "aniposelib"
    fs = _open_storage(path)
    try:
        keys = set(_keys(fs.root()))
    finally:
        fs.release()
    if "cameras" in keys:
        return "surveil"
    if "cam_ids" in keys or {"Ks", "rvecs", "Ts"} <= keys:
        return "opencv-multiview"
    if "names" in keys and any(k.startswith("K_") for k in keys):
        return "easymocap"
    if "names" in keys and any(k.startswith(("R_", "Rot_", "T_")) for k in keys):
        raise InputError(
            f"{path}: looks like an EasyMocap extri.yml; pass the intri.yml as the source and "
            "this file with --extri"
        )
    raise InputError(
        f"{path}: unknown calibration layout (top-level keys: {', '.join(sorted(keys)) or '-'}); "
        f"expected one of the formats {', '.join(FORMATS)} -- pass --format"
    )


def import_rig(
    path: Path,
    fmt: str | None = None,
    units: str | None = None,
    extri: Path | None = None,
) -> Rig:
    """Read a rig calibrated by another tool (or a surveil rig file).

    Parameters
    ----------
    path : Path
        The calibration file; for EasyMocap the ``intri.yml``.
    fmt : str, optional
        ``"surveil"``, ``"opencv-multiview"``, ``"aniposelib"`` or ``"easymocap"``; default:
        :func:`detect_format`.
    units : str, optional
        ``"m"``, ``"cm"`` or ``"mm"``: the unit of the source's translations, which are scaled
        to metres. Required for every format but ``surveil`` (whose files say ``units: m``):
        these formats do not record their unit, and surveil never guesses it.
    extri : Path, optional
        EasyMocap ``extri.yml``; default ``extri.yml`` beside ``path``.

    Returns
    -------
    Rig
        ``R``/``t`` world -> camera, ``t`` in metres. The world frame is the source's; for
        ``opencv-multiview`` that is the first camera's frame, not a Z-up floor frame.

    Raises
    ------
    InputError
        Unknown format, missing ``units``, or any bad value; the message names the file, the
        camera and the key.
    """
    path = Path(path)
    where = _Where(path)
    if not path.is_file():
        raise InputError(f"{path}: file not found")
    if fmt is None:
        fmt = detect_format(path)
        log.info("%s: detected format %s", path, fmt)
    match fmt:
        case "surveil":
            if units not in (None, "m"):
                raise where.error("units", f"surveil rig files are in metres; got units={units!r}")
            rig = load_rig(path)
            log.info("%s: surveil rig, world -> camera, metres", path)
            return rig
        case "opencv-multiview":
            return _import_opencv_multiview(path, units)
        case "aniposelib":
            return _import_aniposelib(path, units)
        case "easymocap":
            return _import_easymocap(path, units, extri)
    raise InputError(f"{path}: unknown calibration format {fmt!r}; expected one of {FORMATS}")


def _import_opencv_multiview(path: Path, units: str | None) -> Rig:
    where = _Where(path)
    scale = _units_scale(
        where, units, "opencv-multiview", "the unit of the board's --pattern_distance"
    )
    fs = _open_storage(path)
    try:
        root = fs.root()
        sizes = _node_matrix(where, root, "image_sizes")
        n = sizes.shape[0] if sizes.ndim == 2 and sizes.shape[1] == 2 else 0
        if n == 0:
            raise where.error(
                "image_sizes",
                f"expected an Nx2 matrix (width, height), found {_shape_text(sizes)}",
            )
        names = _multiview_names(where, root, n)
        per_cam: dict[str, np.ndarray] = {}
        for key, count in (("Ks", 9), ("rvecs", 3), ("Ts", 3), ("distortions", None)):
            arr = _node_matrix(where, root, key)
            if count is None:
                count = arr.size // n
                if arr.size % n or count not in DIST_LENGTHS:
                    raise where.error(
                        key,
                        f"expected {n} rows of N coefficients (N in {_DIST_TEXT}) for {n} "
                        f"cameras, found {arr.size} values",
                    )
            if arr.size != n * count:
                raise where.error(
                    key,
                    f"expected {n} x {count} values for {n} cameras (image_sizes has {n} "
                    f"rows), found {_shape_text(arr)}",
                )
            per_cam[key] = arr.reshape(n, count)
        fisheye = np.zeros(n)
        if "is_fisheye" in _keys(root) and fs.getNode("is_fisheye").isMap():
            fisheye = _node_matrix(where, root, "is_fisheye").reshape(-1)
    finally:
        fs.release()
    cameras = []
    for i, name in enumerate(names):
        w = where.cam(i, name)
        if i < fisheye.size and fisheye[i]:
            raise w.error(
                "is_fisheye",
                "expected a pinhole camera, found a fisheye one (surveil uses the "
                "OpenCV pinhole distortion model only)",
            )
        width = _image_size(w, "image_sizes", float(sizes[i, 0]))
        height = _image_size(w, "image_sizes", float(sizes[i, 1]))
        K = _intrinsics(w, "Ks", per_cam["Ks"][i].reshape(3, 3))
        dist = _distortion(w, "distortions", per_cam["distortions"][i])
        R = _rodrigues(w, "rvecs", per_cam["rvecs"][i])
        t = _translation(w, "Ts", per_cam["Ts"][i], scale)
        cameras.append(_camera(w, name, width, height, K, dist, R, t))
    rig = _build_rig(where, cameras, "cam_ids")
    log.info(
        "%s: OpenCV multiview calibration, %d cameras; rvecs/Ts taken as world -> camera with "
        "the world frame = camera %s's frame (z forward, y down: not Z-up, no floor at Z = 0); "
        "translations in %s, scaled to metres",
        path,
        len(rig),
        rig.names[0],
        units,
    )
    log.warning(
        "%s: this rig's world frame is camera %s's frame, not a Z-up floor frame: re-express "
        "it in a floor frame before tracking (docs/calibration.md)",
        path,
        rig.names[0],
    )
    return rig


def _multiview_names(where: _Where, root: cv2.FileNode, n: int) -> list[str]:
    if "cam_ids" not in _keys(root):
        log.info("%s: no cam_ids; naming the cameras cam0..cam%d", where.path, n - 1)
        return [f"cam{i}" for i in range(n)]
    node = root.getNode("cam_ids")
    if node.isString():
        ids = [s.strip() for s in node.string().split(",")]
    elif node.isSeq():
        ids = [
            node.at(i).string() if node.at(i).isString() else str(int(node.at(i).real()))
            for i in range(node.size())
        ]
    else:
        raise where.error("cam_ids", f"expected comma-separated ids, found {_node_kind(node)}")
    if len(ids) != n:
        raise where.error(
            "cam_ids", f"expected {n} ids (image_sizes has {n} rows), found {len(ids)}: {ids}"
        )
    return [_camera_name(where.cam(i), "cam_ids", s) for i, s in enumerate(ids)]


def _import_aniposelib(path: Path, units: str | None) -> Rig:
    where = _Where(path)
    scale = _units_scale(where, units, "aniposelib", "Pose2Sim writes metres, anipose board units")
    try:
        with open(path, "rb") as f:
            doc = tomllib.load(f)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{path}: invalid TOML: {exc}") from None
    tables = [(k, v) for k, v in doc.items() if isinstance(v, dict) and k != "metadata"]
    cameras = []
    for i, (table_key, table) in enumerate(tables):
        w = where.cam(i, table_key)
        name = _camera_name(w, "name", table.get("name", table_key))
        w = where.cam(i, name)

        def get(key: str, w: _Where = w, table: dict = table) -> Any:
            if key not in table:
                raise w.missing(key)
            return table[key]

        if table.get("fisheye", False):
            raise w.error(
                "fisheye",
                "expected false, found true (surveil uses the OpenCV pinhole "
                "distortion model only)",
            )
        size = get("size")
        if not isinstance(size, list) or len(size) != 2:
            raise w.error("size", f"expected [width, height], found {size!r}")
        width = _image_size(w, "size", size[0])
        height = _image_size(w, "size", size[1])
        K = _intrinsics(w, "matrix", get("matrix"))
        dist = _distortion(w, "distortions", get("distortions"))
        R = _rodrigues(w, "rotation", get("rotation"))
        t = _translation(w, "translation", get("translation"), scale)
        cameras.append(_camera(w, name, width, height, K, dist, R, t))
    rig = _build_rig(where, cameras)
    log.info(
        "%s: aniposelib TOML, %d cameras; rotation (Rodrigues) / translation taken as world -> "
        "camera, translations in %s, scaled to metres",
        path,
        len(rig),
        units,
    )
    return rig


def export_aniposelib(rig: Rig, path: Path) -> None:
    """Write ``rig`` as an aniposelib calibration TOML (anipose, Pose2Sim), in metres.

    One table ``[cam_<i>]`` per camera with ``name``, ``size`` ``[width, height]``, ``matrix``
    (3x3), ``distortions``, ``rotation`` (Rodrigues vector, world -> camera), ``translation``
    (world -> camera, metres) and ``fisheye = false``, then ``[metadata]``. Floats are written
    with ``repr`` (shortest exact form), so ``import_rig(path, units="m")`` gives the rig back.

    Parameters
    ----------
    rig : Rig
        The cameras to write.
    path : Path
        Output ``.toml`` file; its parent directory is created.
    """

    def floats(values: np.ndarray) -> str:
        return "[" + ", ".join(repr(float(v)) for v in values) + "]"

    lines = [
        "# camera calibration written by surveil: aniposelib / Pose2Sim layout,",
        "# rotation (Rodrigues) and translation world -> camera, translation in metres",
        "",
    ]
    for i, cam in enumerate(rig):
        lines += [
            f"[cam_{i}]",
            f'name = "{cam.name}"',
            f"size = [{cam.width}, {cam.height}]",
            "matrix = [" + ", ".join(floats(row) for row in cam.K) + "]",
            f"distortions = {floats(cam.dist)}",
            f"rotation = {floats(cam.rvec)}",
            f"translation = {floats(cam.t)}",
            "fisheye = false",
            "",
        ]
    lines += ["[metadata]", "adjusted = false", "error = 0.0", ""]
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines), encoding="utf-8")
    log.debug("wrote %s: %d cameras (aniposelib TOML, metres)", path, len(rig))


def _import_easymocap(path: Path, units: str | None, extri: Path | None) -> Rig:
    where = _Where(path)
    scale = _units_scale(where, units, "easymocap", "EasyMocap does not record it")
    if extri is None:
        extri = path.parent / "extri.yml"
        if not extri.is_file():
            raise where.error(
                None, f"EasyMocap needs its extri.yml too; none found at {extri}: pass --extri"
            )
        log.info("%s: using extrinsics from %s", path, extri)
    extri = Path(extri)
    ewhere = _Where(extri)
    intri_fs = _open_storage(path)
    try:
        extri_fs = _open_storage(extri)
    except InputError:
        intri_fs.release()
        raise
    cameras = []
    try:
        names = _easymocap_names(where, intri_fs.root())
        ikeys, ekeys = _keys(intri_fs.root()), _keys(extri_fs.root())
        for i, name in enumerate(names):
            w, ew = where.cam(i, name), ewhere.cam(i, name)
            K = _intrinsics(w, f"K_{name}", _node_matrix(w, intri_fs.root(), f"K_{name}"))
            dist_key = (
                f"dist_{name}"
                if f"dist_{name}" in ikeys or f"D_{name}" not in ikeys
                else f"D_{name}"
            )
            dist = _distortion(w, dist_key, _node_matrix(w, intri_fs.root(), dist_key))
            width, height = _easymocap_size(w, intri_fs.root(), name, K)
            if f"R_{name}" in ekeys:
                R = _rodrigues(ew, f"R_{name}", _node_matrix(ew, extri_fs.root(), f"R_{name}"))
            elif f"Rot_{name}" in ekeys:
                R = _rotation(
                    ew,
                    f"Rot_{name}",
                    _node_matrix(ew, extri_fs.root(), f"Rot_{name}"),
                    repair=True,
                )
            else:
                raise ew.error(f"R_{name}", f"missing (required, or Rot_{name})")
            t = _translation(
                ew, f"T_{name}", _node_matrix(ew, extri_fs.root(), f"T_{name}"), scale
            )
            cameras.append(_camera(w, name, width, height, K, dist, R, t))
    finally:
        intri_fs.release()
        extri_fs.release()
    rig = _build_rig(where, cameras, "names")
    log.info(
        "%s + %s: EasyMocap intri/extri, %d cameras; R_/T_ taken as world -> camera, "
        "translations in %s, scaled to metres",
        path,
        extri,
        len(rig),
        units,
    )
    return rig


def _easymocap_names(where: _Where, root: cv2.FileNode) -> list[str]:
    if "names" not in _keys(root):
        raise where.missing("names")
    node = root.getNode("names")
    if not node.isSeq():
        raise where.error("names", f"expected a sequence of strings, found {_node_kind(node)}")
    names = []
    for i in range(node.size()):
        item = node.at(i)
        value: Any = (
            item.string()
            if item.isString()
            else (str(int(item.real())) if item.isInt() else _node_kind(item))
        )
        names.append(_camera_name(where.cam(i), "names", value))
    return names


def _easymocap_size(
    where: _Where, root: cv2.FileNode, name: str, K: np.ndarray
) -> tuple[int, int]:
    """(width, height): from ``W_<name>``/``H_<name>`` if present, else from the principal
    point (the even size nearest to 2 c, with a warning)."""
    keys = _keys(root)
    if f"W_{name}" in keys or f"H_{name}" in keys:
        return _node_int(where, root, f"W_{name}"), _node_int(where, root, f"H_{name}")
    width, height = (2 * int(np.round(c + 0.25)) for c in (K[0, 2], K[1, 2]))
    log.warning(
        "%s: camera %r has no W_%s/H_%s; image size inferred from the principal point as "
        "%dx%d -- check it against the videos",
        where.path,
        name,
        name,
        name,
        width,
        height,
    )
    return width, height
