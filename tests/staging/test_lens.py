"""Calibrating through a wide-angle webcam's lens (k1 = -0.3), photographed by the synthetic oblique camera: the
workspace is located within 1 cm where the homography alone is past it, the live view's targets land where the camera
sees them, a board that cannot pin the lens is refused, and calibration files keep the lens (old ones still load)."""

import json

import cv2
import numpy as np
import pytest

from lerobot_contrast.calibrate import main
from lerobot_contrast.staging import board, homography, locate
from lerobot_contrast.staging.synthetic import ObliqueCamera, board_photo

WORKSPACE = ((0.15, -0.25), (0.45, 0.25))  # so101_blocks
GRID = np.array([[x, y] for x in np.linspace(0.15, 0.45, 7) for y in np.linspace(-0.25, 0.25, 11)])
WHERE = board.BoardArgs(0.30, 0.0, 0.0)
CUBE_CENTRE = 0.015  # a 3 cm cube is located where the ray through its centre meets the plane at half its height


def located_off_cm(calibration: homography.CameraCalibration, camera: ObliqueCamera) -> float:
    """The farthest that cube centres seen anywhere on the workspace are placed from where they are."""
    seen = camera.project(np.column_stack([GRID, np.full(len(GRID), CUBE_CENTRE)]))
    return float(np.max(np.linalg.norm(calibration.to_table(seen, CUBE_CENTRE) - GRID, axis=1)) * 100)


@pytest.mark.parametrize(("elevation", "azimuth"), [(58, 337), (74, 329), (76, 12)])
def test_a_wide_angle_lens_is_measured_and_the_workspace_located_within_1_cm(elevation, azimuth):
    camera = ObliqueCamera(elevation, azimuth, k1=-0.3)
    photo = board_photo(camera, WHERE, seed=1)
    calibration = homography.fit("front", photo, WHERE, 2.0, WORKSPACE)
    assert calibration.lens.k1 == pytest.approx(-0.3, abs=0.03)
    assert located_off_cm(calibration, camera) < 1.0
    # The homography alone fits the board as well, yet misplaces the workspace's edges (what calibrate did before).
    plain = homography.fit("front", photo, WHERE, 2.0, WORKSPACE, lens=False)
    assert plain.error_px < 1.0 and located_off_cm(plain, camera) > 1.4
    # Targets drawn on the live view are bent back through the lens: where the camera sees the table's points.
    assert np.abs(calibration.to_pixels(GRID) - camera.project(np.column_stack([GRID, np.zeros(len(GRID))]))).max() < 2
    raised = camera.project(np.column_stack([GRID, np.full(len(GRID), 0.03)]))
    assert np.abs(calibration.lift(GRID, 0.03) - raised).max() < 3


@pytest.mark.parametrize(("elevation", "azimuth"), [(85, 0), (88, 45)])
def test_a_camera_looking_nearly_straight_down_is_calibrated_at_a_webcams_focal_length(elevation, azimuth):
    # Square on, one view cannot tell the focal length: a typical webcam's is taken, and k1 fitted at it.
    camera = ObliqueCamera(elevation, azimuth, k1=-0.3)
    calibration = homography.fit("front", board_photo(camera, WHERE, seed=3), WHERE, 2.0, WORKSPACE)
    assert calibration.lens.focal == pytest.approx(0.8 * camera.width)
    assert located_off_cm(calibration, camera) < 1.0


def test_cubes_at_the_workspaces_corners_are_found_within_1_cm_through_the_lens():
    camera = ObliqueCamera(76, 12, k1=-0.3)
    photo = board_photo(camera, WHERE, seed=1)
    cubes = {"red": (0.175, 0.225), "green": (0.175, -0.225), "blue": (0.425, 0.225), "yellow": (0.425, -0.225)}
    table = board_photo(camera, None, seed=2, cubes=cubes)
    farthest = {}
    for lens in (True, False):
        calibration = homography.fit("front", photo, WHERE, 2.0, WORKSPACE, lens=lens)
        found = locate.find_objects(table, calibration, {colour: colour for colour in cubes}, WORKSPACE, 0.03)
        assert set(found) == set(cubes)
        farthest[lens] = max(np.hypot(x - cubes[c][0], y - cubes[c][1]) * 100 for c, (x, y) in found.items())
    assert farthest[True] < 1.0 and farthest[False] > 1.2  # the homography alone: past 1 cm at the corners


def hide_markers(image: np.ndarray, keep: set[int]) -> np.ndarray:
    """The photo with every marker but `keep` covered by paper, as by something lying on the board."""
    grey = cv2.cvtColor(image, cv2.COLOR_RGB2GRAY)
    corners, ids, _ = cv2.aruco.ArucoDetector(board.dictionary()).detectMarkers(grey)
    out = image.copy()
    for quad, marker in zip(corners, ids.ravel(), strict=True):
        if marker not in keep:
            quad = quad.reshape(4, 2)
            grown = quad.mean(axis=0) + 1.3 * (quad - quad.mean(axis=0))
            cv2.fillPoly(out, [np.round(grown).astype(np.int32)], (235, 235, 230))
    return out


def test_a_board_too_small_in_view_to_pin_the_lens_is_refused_in_one_line(tmp_path, capsys):
    camera = ObliqueCamera(40, 90, k1=-0.3)
    frame = tmp_path / "frame.png"
    photo = hide_markers(board_photo(camera, WHERE, seed=3), keep={0, 1, 4, 5})  # a 11 x 11 cm corner of the board
    cv2.imwrite(str(frame), cv2.cvtColor(photo, cv2.COLOR_RGB2BGR))
    out = tmp_path / "cal.json"
    assert main([f"--image={frame}", f"--output={out}", "--board.x=0.30"]) == 2
    error = capsys.readouterr().err
    assert error.startswith("error: camera top: the board covers too little of the view to measure the lens")
    assert "lay it nearer the image's edge" in error and error.count("\n") == 1
    assert not out.exists()


def test_the_lens_is_kept_in_the_calibration_file_and_version_1_files_still_load(tmp_path, capsys):
    camera = ObliqueCamera(60, 200, k1=-0.3)
    frame = tmp_path / "frame.png"
    cv2.imwrite(str(frame), cv2.cvtColor(board_photo(camera, WHERE, seed=2), cv2.COLOR_RGB2BGR))
    out = tmp_path / "cal.json"
    assert main([f"--image={frame}", f"--output={out}", "--camera=front"]) == 0
    printed = capsys.readouterr().out.split("lens k1 ")[1].split()[0]
    assert float(printed) == pytest.approx(-0.3, abs=0.03)
    stored = json.loads(out.read_text())
    assert stored["version"] == homography.CALIBRATION_VERSION == 2
    loaded = homography.load(out)["front"]
    assert located_off_cm(loaded, camera) < 1.0
    assert np.allclose(loaded.lens.undistort(loaded.lens.distort(loaded.to_pixels(GRID))), loaded.to_pixels(GRID))
    # A file written before the lens was measured: the homography alone, read as a lens-free camera.
    old = {**stored, "version": 1, "cameras": {"front": {**stored["cameras"]["front"]}}}
    del old["cameras"]["front"]["lens"]
    out.write_text(json.dumps(old))
    plain = homography.load(out)["front"]
    assert plain.lens is None
    expected = cv2.perspectiveTransform(GRID.reshape(-1, 1, 2), np.array(old["cameras"]["front"]["homography"]))
    assert np.allclose(plain.to_pixels(GRID), expected.reshape(-1, 2))


def test_a_workspace_out_of_the_cameras_view_is_refused():
    camera = ObliqueCamera(60, 200, k1=-0.3)
    photo = board_photo(camera, WHERE, seed=2)
    # Far to the robot's right, and behind the camera.
    for elsewhere in (((0.15, -3.0), (0.45, -2.5)), ((-2.0, -0.25), (-1.5, 0.25))):
        with pytest.raises(homography.CalibrationError, match="the task's workspace is not in view; aim the camera"):
            homography.fit("front", photo, WHERE, 2.0, elsewhere)
