"""Rig files: surveil YAML round trip and errors, importers, aniposelib export, CLI."""

from __future__ import annotations

import logging
from pathlib import Path

import cv2
import numpy as np
import pytest

from surveil import cli
from surveil.camera import Rig
from surveil.cli import ExitCode
from surveil.errors import InputError
from surveil.io.calibration import (
    detect_format,
    export_aniposelib,
    import_rig,
    load_rig,
    save_rig,
)
from surveil.rigs import lab4_rig, make_corner_rig

REPO = Path(__file__).resolve().parents[2]


def assert_rigs_equal(a: Rig, b: Rig, atol: float = 0.0) -> None:
    assert a.names == b.names
    for ca, cb in zip(a, b, strict=True):
        assert (ca.width, ca.height) == (cb.width, cb.height), ca.name
        for attr in ("K", "dist", "R", "t"):
            np.testing.assert_allclose(
                getattr(ca, attr), getattr(cb, attr), rtol=0, atol=atol, err_msg=attr
            )


@pytest.fixture
def rig() -> Rig:
    """Five cameras with distortion vectors of 5, 4, 8, 14 and 12 coefficients."""
    base = make_corner_rig(5, room_m=(7.0, 4.5), height_m=2.4)
    lengths = (5, 4, 8, 14, 12)
    cams = []
    for cam, n in zip(base, lengths, strict=True):
        dist = np.linspace(-0.1, 0.05, n) / 3.0  # non-round values, exercise every digit
        cams.append(type(cam)(cam.name, cam.width, cam.height, cam.K, dist, cam.R, cam.t))
    return Rig(tuple(cams))


# ---------------------------------------------------------------------------------------------
# surveil rig YAML


def test_save_load_round_trip_is_exact(rig, tmp_path):
    path = tmp_path / "sub" / "rig.yaml"
    save_rig(rig, path)
    assert_rigs_equal(load_rig(path), rig, atol=0.0)


def test_saved_file_has_the_contract_layout(rig, tmp_path):
    path = tmp_path / "rig.yaml"
    save_rig(rig, path)
    fs = cv2.FileStorage(str(path), cv2.FileStorage_READ)
    assert fs.getNode("units").string() == "m"
    cam = fs.getNode("cameras").at(1)
    assert set(cam.keys()) == {"name", "image_width", "image_height", "K", "dist", "R", "t"}
    assert cam.getNode("image_width").isInt()
    assert cam.getNode("K").mat().shape == (3, 3)
    assert cam.getNode("dist").mat().shape == (1, 4)
    assert cam.getNode("t").mat().shape == (3, 1)
    fs.release()


def test_load_accepts_the_yaml_1_0_header(rig, tmp_path):
    path = tmp_path / "rig.yaml"
    save_rig(rig, path)
    text = path.read_text()
    first, rest = text.split("\n", 1)
    assert first.startswith("%YAML")
    path.write_text("%YAML:1.0\n" + rest)
    assert_rigs_equal(load_rig(path), rig)


def test_bundled_lab4_rig_is_its_generator_saved():
    rig = load_rig(REPO / "calibration" / "lab4.yaml")
    assert_rigs_equal(rig, lab4_rig(), atol=0.0)
    assert rig.names == ("cam0", "cam1", "cam2", "cam3")
    centre = np.array([[3.0, 2.5, 0.9]])
    for cam in rig:
        assert cam.size == (640, 480)
        assert cam.centre_m[2] == pytest.approx(2.6)
        px, depth = cam.project(centre)
        # the room centre is near the image centre (distortion moves it off the principal
        # point only slightly) and in front of every camera
        assert depth[0] > 0 and np.abs(px[0] - [319.5, 239.5]).max() < 1.0


def write_rig_yaml(path: Path, cameras: list[dict], units: object = "m") -> Path:
    """Write a rig-like FileStorage file with arbitrary (possibly wrong) camera values."""
    fs = cv2.FileStorage(str(path), cv2.FileStorage_WRITE)
    if units is not None:
        fs.write("units", units)
    fs.startWriteStruct("cameras", cv2.FileNode_SEQ)
    for cam in cameras:
        fs.startWriteStruct("", cv2.FileNode_MAP)
        for key, value in cam.items():
            fs.write(key, value)
        fs.endWriteStruct()
    fs.endWriteStruct()
    fs.release()
    return path


def camera_dict(cam_name: str, /, **overrides: object) -> dict:
    d = {
        "name": cam_name,
        "image_width": 640,
        "image_height": 480,
        "K": np.array([[500.0, 0, 319.5], [0, 500, 239.5], [0, 0, 1]]),
        "dist": np.zeros((1, 5)),
        "R": np.eye(3),
        "t": np.array([[0.0], [0.0], [2.0]]),
    }
    for key, value in overrides.items():
        if value is None:
            del d[key]
        else:
            d[key] = value
    return d


@pytest.mark.parametrize(
    "second_camera, match",
    [
        (camera_dict("cam1", K=None), r"camera 'cam1' \(index 1\): key 'K': missing"),
        (camera_dict("cam1", t=None), r"camera 'cam1' \(index 1\): key 't': missing"),
        (
            camera_dict("cam1", image_height=None),
            r"camera 'cam1' \(index 1\): key 'image_height': missing",
        ),
        (camera_dict("cam1", name=None), r"camera index 1: key 'name': missing"),
        (
            camera_dict("cam1", K=np.eye(3)[:2]),
            r"camera 'cam1' \(index 1\): key 'K': expected a 3x3 matrix, found 2x3",
        ),
        (
            camera_dict("cam1", dist=np.zeros((1, 6))),
            r"camera 'cam1' \(index 1\): key 'dist': expected 1xN .*4, 5, 8, 12, 14, found 1x6",
        ),
        (
            camera_dict("cam1", dist=np.zeros((2, 5))),
            r"camera 'cam1' \(index 1\): key 'dist': expected 1xN .*found 2x5",
        ),
        (
            camera_dict("cam1", R=np.diag([1.0, 1.0, 1.01])),
            r"camera 'cam1' \(index 1\): key 'R': expected a rotation matrix",
        ),
        (
            camera_dict("cam1", R=np.diag([1.0, 1.0, -1.0])),
            r"camera 'cam1' \(index 1\): key 'R': expected a rotation .*det = -1",
        ),
        (
            camera_dict("cam1", t=np.zeros((4, 1))),
            r"camera 'cam1' \(index 1\): key 't': expected a 3x1 translation, found 4x1",
        ),
        (
            camera_dict("cam1", K=np.array([[0.0, 0, 1], [0, 5, 1], [0, 0, 1]])),
            r"camera 'cam1' \(index 1\): key 'K': expected positive focal lengths",
        ),
        (
            camera_dict("cam1", image_width="640"),
            r"camera 'cam1' \(index 1\): key 'image_width': expected an integer, found the "
            r"string '640'",
        ),
        (
            camera_dict("cam1", image_width=0),
            r"camera 'cam1' \(index 1\): key 'image_width': expected a positive integer",
        ),
        (
            camera_dict("cam1", R="identity"),
            r"camera 'cam1' \(index 1\): key 'R': expected an opencv-matrix, found the string",
        ),
        (
            camera_dict("cam 1"),
            r"camera index 1: key 'name': expected a camera name .*found 'cam 1'",
        ),
        (
            camera_dict("cam0"),
            r"camera 'cam0' \(index 1\): key 'name': expected a unique name, found 'cam0' "
            r"again \(already camera index 0\)",
        ),
    ],
)
def test_malformed_camera_names_file_camera_and_key(tmp_path, second_camera, match):
    path = write_rig_yaml(tmp_path / "bad_rig.yaml", [camera_dict("cam0"), second_camera])
    with pytest.raises(InputError, match=r"bad_rig\.yaml: " + match):
        load_rig(path)


@pytest.mark.parametrize(
    "units, match",
    [
        ("mm", r"bad_rig\.yaml: key 'units': expected \"m\", found 'mm'"),
        (None, r"bad_rig\.yaml: key 'units': missing"),
        (1, r"bad_rig\.yaml: key 'units': expected a string, found the integer 1"),
    ],
)
def test_units_must_be_metres(tmp_path, units, match):
    path = write_rig_yaml(tmp_path / "bad_rig.yaml", [camera_dict("cam0")], units=units)
    with pytest.raises(InputError, match=match):
        load_rig(path)


def test_missing_cameras_and_empty_rig(tmp_path):
    path = tmp_path / "bad_rig.yaml"
    fs = cv2.FileStorage(str(path), cv2.FileStorage_WRITE)
    fs.write("units", "m")
    fs.release()
    with pytest.raises(InputError, match=r"bad_rig\.yaml: key 'cameras': missing"):
        load_rig(path)
    write_rig_yaml(path, [])
    with pytest.raises(InputError, match=r"bad_rig\.yaml: .*at least one camera"):
        load_rig(path)


def test_broken_matrix_data_is_an_input_error(tmp_path):
    path = write_rig_yaml(tmp_path / "bad_rig.yaml", [camera_dict("cam0")])
    text = path.read_text()
    # cut the K data to 8 of its 9 numbers
    path.write_text(text.replace("data: [ 500., 0., 319.5,", "data: [ 0., 319.5,", 1))
    with pytest.raises(InputError, match=r"camera 'cam0' \(index 0\): key 'K': .*broken"):
        load_rig(path)


def test_yaml_syntax_error_is_an_input_error_naming_the_file(tmp_path):
    path = tmp_path / "broken.yaml"
    path.write_text("%YAML:1.0\n---\nunits: [m\ncameras: {\n")
    with pytest.raises(InputError, match=r"broken\.yaml: not a readable OpenCV FileStorage"):
        load_rig(path)


def test_missing_file_is_an_input_error(tmp_path):
    with pytest.raises(InputError, match=r"nowhere\.yaml: file not found"):
        load_rig(tmp_path / "nowhere.yaml")


# ---------------------------------------------------------------------------------------------
# OpenCV multiview sample


def write_multiview_file(
    path: Path, rig: Rig, scale: float, fisheye: list[int] | None = None, **overrides
):
    """Write ``rig`` as samples/python/multiview_calibration.py's saveToFile does: poses
    relative to the first camera, lengths multiplied by ``scale`` (the board unit)."""
    R0, t0 = rig.cameras[0].R, rig.cameras[0].t
    rvecs, ts = [], []
    for cam in rig:
        R = cam.R @ R0.T  # camera i from camera 0: x_i = R x_0 + t
        rvecs.append(cv2.Rodrigues(R)[0])
        ts.append(((cam.t - R @ t0) * scale).reshape(3, 1))
    entries = {
        "rvecs": np.array(rvecs),
        "distortions": np.array([cam.dist.reshape(1, -1) for cam in rig]),
        "Ks": np.array([cam.K for cam in rig]),
        "Ts": np.array(ts),
        "rvecs0": np.zeros((2, 3, 1)),
        "errors_per_frame": np.zeros((len(rig), 2)),
        "is_fisheye": np.array(fisheye or [0] * len(rig), dtype=int),
        "image_sizes": np.array([cam.size for cam in rig]),
        "cam_ids": ",".join(str(i + 1) for i in range(len(rig))),
    }
    entries.update(overrides)
    fs = cv2.FileStorage(str(path), cv2.FileStorage_WRITE)
    for key, value in entries.items():
        fs.write(key, value)
    fs.release()
    return R0, t0


def test_import_opencv_multiview_in_camera0_frame(tmp_path, caplog):
    rig = lab4_rig()
    path = tmp_path / "multiview.yaml"
    R0, t0 = write_multiview_file(path, rig, scale=1000.0)  # board measured in mm
    assert detect_format(path) == "opencv-multiview"
    with caplog.at_level(logging.INFO, logger="surveil.io.calibration"):
        imported = import_rig(path, units="mm")
    assert "world frame = camera 1's frame" in caplog.text
    assert "translations in mm" in caplog.text
    assert imported.names == ("1", "2", "3", "4")
    # world points seen in camera 0's frame project identically
    pts_world = np.array([[3.0, 2.5, 0.9], [1.0, 4.0, 1.7], [5.0, 1.0, 0.2]])
    pts_cam0 = pts_world @ R0.T + t0
    for orig, imp in zip(rig, imported, strict=True):
        assert imp.size == orig.size
        np.testing.assert_allclose(imp.K, orig.K)
        np.testing.assert_allclose(imp.dist, orig.dist)
        np.testing.assert_allclose(imp.project(pts_cam0)[0], orig.project(pts_world)[0])


def test_import_opencv_multiview_requires_units(tmp_path):
    path = tmp_path / "multiview.yaml"
    write_multiview_file(path, lab4_rig(), scale=1.0)
    with pytest.raises(InputError, match=r"multiview\.yaml: .*pass --units m\|mm\|cm"):
        import_rig(path)


def test_import_opencv_multiview_refuses_fisheye(tmp_path):
    path = tmp_path / "multiview.yaml"
    write_multiview_file(path, lab4_rig(), scale=1.0, fisheye=[0, 0, 1, 0])
    with pytest.raises(InputError, match=r"camera '3' \(index 2\): key 'is_fisheye'"):
        import_rig(path, units="m")


def test_import_opencv_multiview_wrong_count_names_the_key(tmp_path):
    path = tmp_path / "multiview.yaml"
    write_multiview_file(path, lab4_rig(), scale=1.0, Ks=np.array([np.eye(3)] * 3))
    with pytest.raises(InputError, match=r"multiview\.yaml: key 'Ks': expected 4 x 9 values"):
        import_rig(path, fmt="opencv-multiview", units="m")


# ---------------------------------------------------------------------------------------------
# aniposelib / Pose2Sim TOML


def test_export_aniposelib_round_trip(rig, tmp_path):
    path = tmp_path / "calibration.toml"
    export_aniposelib(rig, path)
    text = path.read_text()
    assert "[cam_0]" in text and "[metadata]" in text and "fisheye = false" in text
    assert detect_format(path) == "aniposelib"
    # rotations go through a Rodrigues vector: equal to float precision, not bit for bit
    assert_rigs_equal(import_rig(path, units="m"), rig, atol=1e-12)


def test_aniposelib_requires_units(rig, tmp_path):
    path = tmp_path / "calibration.toml"
    export_aniposelib(rig, path)
    with pytest.raises(InputError, match=r"calibration\.toml: the aniposelib format .*--units"):
        import_rig(path)


POSE2SIM_TOML = """\
[int_cam1_img]
name = "int_cam1_img"
size = [ 1920.0, 1080.0]
matrix = [ [ 1100.5, 0.0, 959.5], [ 0.0, 1101.25, 539.5], [ 0.0, 0.0, 1.0]]
distortions = [ -0.05, 0.01, 0.0002, -0.0001]
rotation = [ 1.2, -0.3, 0.1]
translation = [ 0.5, 1.25, 4.0]
fisheye = false

[int_cam2_img]
name = "int_cam2_img"
size = [ 1920.0, 1080.0]
matrix = [ [ 1200.0, 0.0, 955.0], [ 0.0, 1200.0, 545.0], [ 0.0, 0.0, 1.0]]
distortions = [ 0.0025, -0.0008, -0.0010, 0.0009]
rotation = [ 0.0, 0.0, 0.0]
translation = [ -3.8731, -0.7154, 5.3564]
fisheye = false

[metadata]
adjusted = false
error = 0.0
"""


def test_import_pose2sim_toml_ignores_metadata(tmp_path):
    path = tmp_path / "Calib.toml"
    path.write_text(POSE2SIM_TOML)
    rig = import_rig(path, units="m")
    assert rig.names == ("int_cam1_img", "int_cam2_img")
    cam = rig["int_cam1_img"]
    assert cam.size == (1920, 1080)
    np.testing.assert_allclose(cam.K, [[1100.5, 0, 959.5], [0, 1101.25, 539.5], [0, 0, 1]])
    np.testing.assert_allclose(cam.dist, [-0.05, 0.01, 0.0002, -0.0001])
    np.testing.assert_allclose(cam.R, cv2.Rodrigues(np.array([1.2, -0.3, 0.1]))[0])
    np.testing.assert_allclose(cam.t, [0.5, 1.25, 4.0])
    np.testing.assert_allclose(rig["int_cam2_img"].R, np.eye(3))


def test_units_mm_are_scaled_to_metres(tmp_path):
    path = tmp_path / "Calib.toml"
    path.write_text(POSE2SIM_TOML)
    in_m = import_rig(path, units="m")
    in_mm = import_rig(path, units="mm")
    in_cm = import_rig(path, units="cm")
    for a, b, c in zip(in_m, in_mm, in_cm, strict=True):
        np.testing.assert_allclose(b.t, a.t / 1000)
        np.testing.assert_allclose(c.t, a.t / 100)
        np.testing.assert_array_equal(b.K, a.K)
        np.testing.assert_array_equal(b.R, a.R)


@pytest.mark.parametrize(
    "old, new, match",
    [
        ("rotation = [ 1.2, -0.3, 0.1]", "", r"camera 'int_cam1_img' \(index 0\): key 'rotation'"),
        (
            "size = [ 1920.0, 1080.0]",
            "size = [ 1920.5, 1080.0]",
            r"camera 'int_cam1_img' \(index 0\): key 'size': expected a positive integer",
        ),
        (
            "distortions = [ -0.05, 0.01, 0.0002, -0.0001]",
            "distortions = [ -0.05, 0.01, 0.0002]",
            r"camera 'int_cam1_img' \(index 0\): key 'distortions': .*found 3",
        ),
        (
            "matrix = [ [ 1200.0, 0.0, 955.0], [ 0.0, 1200.0, 545.0], [ 0.0, 0.0, 1.0]]",
            "matrix = [ [ 1200.0, 0.0, 955.0], [ 0.0, 1200.0, 545.0]]",
            r"camera 'int_cam2_img' \(index 1\): key 'matrix': expected a 3x3 matrix, found 2x3",
        ),
        (
            'name = "int_cam2_img"',
            'name = "int cam2"',
            r"camera 'int_cam2_img' \(index 1\): key 'name': .*found 'int cam2'",
        ),
        (
            'name = "int_cam2_img"',
            'name = "int_cam1_img"',
            r"camera 'int_cam1_img' \(index 1\): key 'name': expected a unique name",
        ),
        (
            "fisheye = false\n\n[metadata]",
            "fisheye = true\n\n[metadata]",
            r"camera 'int_cam2_img' \(index 1\): key 'fisheye'",
        ),
        ("[metadata]", "[metadata", r"invalid TOML"),
    ],
)
def test_malformed_toml_names_file_camera_and_key(tmp_path, old, new, match):
    assert old in POSE2SIM_TOML
    path = tmp_path / "Calib.toml"
    path.write_text(POSE2SIM_TOML.replace(old, new, 1))
    with pytest.raises(InputError, match=r"Calib\.toml: " + match):
        import_rig(path, units="m")


# ---------------------------------------------------------------------------------------------
# EasyMocap intri.yml + extri.yml


def write_easymocap(
    folder: Path, rig: Rig, scale: float = 1.0, sizes: bool = True, **extri_overrides
) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    intri = cv2.FileStorage(str(folder / "intri.yml"), cv2.FileStorage_WRITE)
    extri = cv2.FileStorage(str(folder / "extri.yml"), cv2.FileStorage_WRITE)
    for fs in (intri, extri):
        fs.startWriteStruct("names", cv2.FileNode_SEQ)
        for cam in rig:
            fs.write("", cam.name)
        fs.endWriteStruct()
    for cam in rig:
        intri.write(f"K_{cam.name}", cam.K)
        intri.write(f"dist_{cam.name}", cam.dist.reshape(1, -1))
        if sizes:
            intri.write(f"H_{cam.name}", cam.height)
            intri.write(f"W_{cam.name}", cam.width)
        extri.write(f"R_{cam.name}", cam.rvec.reshape(3, 1))
        extri.write(f"Rot_{cam.name}", cam.R)
        t_key = f"T_{cam.name}"
        extri.write(t_key, extri_overrides.get(t_key, cam.t.reshape(3, 1) * scale))
    intri.release()
    extri.release()
    return folder / "intri.yml"


def test_import_easymocap_pair(tmp_path):
    rig = lab4_rig()
    intri = write_easymocap(tmp_path / "mocap", rig, scale=100.0)
    assert detect_format(intri) == "easymocap"
    imported = import_rig(intri, units="cm", extri=tmp_path / "mocap" / "extri.yml")
    assert_rigs_equal(imported, rig, atol=1e-12)
    # extri.yml beside intri.yml is found without --extri
    assert_rigs_equal(import_rig(intri, fmt="easymocap", units="cm"), rig, atol=1e-12)


def test_easymocap_without_size_infers_it_from_principal_point_with_a_warning(tmp_path, caplog):
    intri = write_easymocap(tmp_path, lab4_rig(), sizes=False)
    with caplog.at_level(logging.WARNING, logger="surveil.io.calibration"):
        imported = import_rig(intri, units="m")
    assert all(cam.size == (640, 480) for cam in imported)
    assert "has no W_cam0/H_cam0" in caplog.text and "640x480" in caplog.text


def test_easymocap_as_written_by_easymocap(tmp_path):
    """EasyMocap writes its files by hand: '%YAML:1.0', CRLF, 6 decimals, names quoted."""
    crlf = "\r\n"
    intri = crlf.join(
        [
            "%YAML:1.0",
            "---",
            "names:",
            '  - "01"',
            "K_01: !!opencv-matrix",
            "  rows: 3",
            "  cols: 3",
            "  dt: d",
            "  data: [1000.000000, 0.000000, 512.000000, 0.000000, 1000.000000, 384.000000, "
            "0.000000, 0.000000, 1.000000]",
            "dist_01: !!opencv-matrix",
            "  rows: 1",
            "  cols: 5",
            "  dt: d",
            "  data: [-0.100000, 0.020000, 0.000000, 0.000000, 0.000000]",
            "",
        ]
    )
    c, s = np.cos(0.3), np.sin(0.3)
    rot = f"{1:.6f}, 0.000000, 0.000000, 0.000000, {c:.6f}, {-s:.6f}, 0.000000, {s:.6f}, {c:.6f}"
    extri = crlf.join(
        [
            "%YAML:1.0",
            "---",
            "names:",
            '  - "01"',
            "Rot_01: !!opencv-matrix",
            "  rows: 3",
            "  cols: 3",
            "  dt: d",
            f"  data: [{rot}]",
            "T_01: !!opencv-matrix",
            "  rows: 3",
            "  cols: 1",
            "  dt: d",
            "  data: [0.100000, -0.200000, 3.000000]",
            "",
        ]
    )
    (tmp_path / "intri.yml").write_bytes(intri.encode())
    (tmp_path / "extri.yml").write_bytes(extri.encode())
    cam = import_rig(tmp_path / "intri.yml", units="m")["01"]
    assert cam.size == (1024, 768)
    np.testing.assert_allclose(cam.R, cv2.Rodrigues(np.array([0.3, 0.0, 0.0]))[0], atol=1e-6)
    np.testing.assert_allclose(cam.t, [0.1, -0.2, 3.0])


def test_easymocap_errors_name_file_camera_and_key(tmp_path):
    rig = lab4_rig()
    intri = write_easymocap(tmp_path, rig)
    with pytest.raises(InputError, match=r"intri\.yml: the easymocap format .*--units"):
        import_rig(intri)
    write_easymocap(tmp_path, rig, T_cam2=np.zeros((2, 1)))
    with pytest.raises(
        InputError, match=r"extri\.yml: camera 'cam2' \(index 2\): key 'T_cam2': .*found 2x1"
    ):
        import_rig(intri, units="m")
    with pytest.raises(InputError, match=r"extri\.yml: looks like an EasyMocap extri\.yml"):
        import_rig(tmp_path / "extri.yml", units="m")


def test_easymocap_needs_its_extri(tmp_path):
    intri = write_easymocap(tmp_path, lab4_rig())
    (tmp_path / "extri.yml").unlink()
    with pytest.raises(InputError, match=r"intri\.yml: .*extri\.yml.*pass --extri"):
        import_rig(intri, units="m")


def test_unknown_layout_lists_the_keys(tmp_path):
    path = tmp_path / "other.yaml"
    fs = cv2.FileStorage(str(path), cv2.FileStorage_WRITE)
    fs.write("camera_matrix", np.eye(3))
    fs.release()
    with pytest.raises(
        InputError, match=r"other\.yaml: unknown calibration layout.*camera_matrix"
    ):
        import_rig(path, units="m")


def test_surveil_format_through_import(tmp_path, rig):
    path = tmp_path / "rig.yaml"
    save_rig(rig, path)
    assert detect_format(path) == "surveil"
    assert_rigs_equal(import_rig(path), rig)
    with pytest.raises(InputError, match=r"rig\.yaml: key 'units': surveil rig files are in"):
        import_rig(path, units="mm")


# ---------------------------------------------------------------------------------------------
# CLI


@pytest.fixture
def restore_logging():
    """cli.main installs a root handler on the (captured) stderr; put the old ones back."""
    root = logging.getLogger()
    handlers, level = root.handlers[:], root.level
    yield
    root.handlers[:] = handlers
    root.setLevel(level)


def test_cli_rig_import_then_export(tmp_path, capsys, restore_logging):
    src = tmp_path / "Calib.toml"
    src.write_text(POSE2SIM_TOML)
    out = tmp_path / "rig.yaml"
    code = cli.main(["rig", "import", str(src), "--units", "m", "--out", str(out)])
    captured = capsys.readouterr()
    assert code == int(ExitCode.OK)
    assert "2 cameras (int_cam1_img, int_cam2_img)" in captured.out
    assert "aniposelib TOML" in captured.err and "translations in m" in captured.err
    assert_rigs_equal(load_rig(out), import_rig(src, units="m"))

    toml_out = tmp_path / "again.toml"
    code = cli.main(["rig", "export", str(out), "--out", str(toml_out)])
    assert code == int(ExitCode.OK)
    assert "aniposelib TOML, metres" in capsys.readouterr().out
    assert_rigs_equal(import_rig(toml_out, units="m"), load_rig(out), atol=1e-12)


def test_cli_rig_import_without_units_is_bad_input(tmp_path, capsys, restore_logging):
    src = tmp_path / "Calib.toml"
    src.write_text(POSE2SIM_TOML)
    out = tmp_path / "rig.yaml"
    code = cli.main(["rig", "import", str(src), "--out", str(out)])
    err = capsys.readouterr().err
    assert code == int(ExitCode.BAD_INPUT)
    assert "Calib.toml" in err and "pass --units m|mm|cm" in err
    assert not out.exists()


def test_cli_rig_export_of_a_bad_rig_is_bad_input(tmp_path, capsys, restore_logging):
    bad = write_rig_yaml(tmp_path / "bad_rig.yaml", [camera_dict("cam0", R=np.eye(3) * 2)])
    code = cli.main(["rig", "export", str(bad), "--out", str(tmp_path / "x.toml")])
    assert code == int(ExitCode.BAD_INPUT)
    assert "bad_rig.yaml: camera 'cam0' (index 0): key 'R'" in capsys.readouterr().err
