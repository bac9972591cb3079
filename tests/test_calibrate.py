"""Calibrating the table plane through the tabletop simulator, whose camera geometry is known: the printed board
rendered lying on its table is found, and the fitted homography matches the simulator's own."""

import json
import shutil
import types

import cv2
import numpy as np
import pytest
from lerobot.utils import constants

from lerobot_contrast.calibrate import main
from lerobot_contrast.domains.language_table.render import TabletopRenderer
from lerobot_contrast.domains.task_file.loader import examples_dir, load_task_file
from lerobot_contrast.staging import board, homography
from lerobot_contrast.staging.args import StagingArgs
from lerobot_contrast.staging.setup import default_calibration, make_bench
from tests.staging.sim_camera import WHERE, board_frame, sim_pixels

# The so101_blocks workspace (metres), where staging needs the homography to hold.
SO101_WORKSPACE = ((0.15, -0.25), (0.45, 0.25))
WORKSPACE = np.array([[x, y] for x in np.linspace(0.15, 0.45, 7) for y in np.linspace(-0.25, 0.25, 7)])
BOARD_FLAGS = [f"--board.x={WHERE.x}", f"--board.y={WHERE.y}", f"--board.yaw_deg={WHERE.yaw_deg}"]


@pytest.fixture(scope="module")
def renderer():
    return TabletopRenderer()


def test_the_board_rendered_on_the_table_gives_the_simulators_homography_within_a_pixel(renderer):
    calibration = homography.fit("top", board_frame(renderer), WHERE, 1.0, SO101_WORKSPACE)
    assert calibration.markers >= homography.MIN_MARKERS
    assert np.abs(calibration.to_pixels(WORKSPACE) - sim_pixels(renderer, WORKSPACE)).max() < 1.0
    # Back from pixels to the table, and lifted off it through the camera pose the homography implies.
    assert np.abs(calibration.to_table(sim_pixels(renderer, WORKSPACE)) - WORKSPACE).max() < 0.005
    raised = renderer.project(np.column_stack([WORKSPACE, np.full(len(WORKSPACE), 0.04)])) - 0.5
    assert np.abs(calibration.lift(WORKSPACE, 0.04) - raised).max() < 1.5


def test_the_command_writes_the_calibration_beside_the_task_file(renderer, tmp_path, capsys):
    task = tmp_path / "my_table.yaml"
    shutil.copy(examples_dir() / "so101_blocks.yaml", task)
    frame = tmp_path / "frame.png"
    cv2.imwrite(str(frame), cv2.cvtColor(board_frame(renderer), cv2.COLOR_RGB2BGR))
    assert main([f"--task={task}", f"--image={frame}", *BOARD_FLAGS]) == 0
    out = capsys.readouterr().out
    assert "camera top:" in out and "reprojection error" in out
    stored = json.loads((tmp_path / "my_table.calibration.json").read_text())
    assert stored["board"]["printed"] == board.printed_size_text()
    loaded = homography.load(tmp_path / "my_table.calibration.json")["top"]
    assert np.abs(loaded.to_pixels(WORKSPACE) - sim_pixels(renderer, WORKSPACE)).max() < 1.0


def test_a_shipped_examples_calibration_goes_to_the_users_folder_where_evals_staging_finds_it(
    renderer, tmp_path, monkeypatch, capsys
):
    monkeypatch.setattr(constants, "HF_LEROBOT_CALIBRATION", tmp_path / "calibration")
    shipped = sorted(examples_dir().iterdir())
    frame = tmp_path / "frame.png"
    cv2.imwrite(str(frame), cv2.cvtColor(board_frame(renderer), cv2.COLOR_RGB2BGR))
    assert main(["--task=so101_blocks", f"--image={frame}", *BOARD_FLAGS]) == 0
    written = tmp_path / "calibration" / "tables" / "so101_blocks.calibration.json"
    assert capsys.readouterr().out.splitlines()[-1] == f"wrote {written}; eval --task=so101_blocks finds it there"
    assert sorted(examples_dir().iterdir()) == shipped  # nothing written into the installed package
    assert default_calibration(str(examples_dir() / "so101_blocks.yaml")) == written  # named by its path too
    robot = types.SimpleNamespace(observation_features={"top": (480, 640, 3)})
    task = load_task_file("so101_blocks")
    bench = make_bench(StagingArgs(viewer="none"), "so101_blocks", task, robot, "measured", lambda: None)
    expected = homography.load(written)["top"]
    assert np.allclose(bench.calibration.to_pixels(WORKSPACE), expected.to_pixels(WORKSPACE))


def test_a_calibration_that_cannot_be_written_is_one_line(renderer, tmp_path, monkeypatch, capsys):
    (tmp_path / "a_file").write_text("")
    monkeypatch.setattr(constants, "HF_LEROBOT_CALIBRATION", tmp_path / "a_file" / "calibration")
    frame = tmp_path / "frame.png"
    cv2.imwrite(str(frame), cv2.cvtColor(board_frame(renderer), cv2.COLOR_RGB2BGR))
    assert main(["--task=so101_blocks", f"--image={frame}", *BOARD_FLAGS]) == 2
    error = capsys.readouterr().err
    assert error.startswith(f"error: cannot write {tmp_path / 'a_file' / 'calibration' / 'tables'}") and (
        error.endswith("; name another file with --output=PATH\n") and error.count("\n") == 1
    )


def test_the_printable_board_states_its_printed_size(tmp_path, capsys):
    assert main([f"--write_board={tmp_path / 'board.png'}"]) == 0
    assert "markers 50 mm" in capsys.readouterr().out and "print at 100%" in board.printed_size_text()
    page = cv2.imread(str(tmp_path / "board.png"), cv2.IMREAD_GRAYSCALE)
    _, _, markers = homography.detect_board(page)
    assert markers == board.COLUMNS * board.ROWS
    width_m = page.shape[1] / (board.DPI / 0.0254)
    assert width_m == pytest.approx(board.board_size_m()[0] + 2 * board.MARGIN_M, abs=0.001)


def test_no_board_in_view_or_a_poor_fit_is_one_line(renderer, tmp_path, capsys):
    bare, boarded = tmp_path / "bare.png", tmp_path / "board.png"
    cv2.imwrite(str(bare), renderer.render({}))
    cv2.imwrite(str(boarded), cv2.cvtColor(board_frame(renderer), cv2.COLOR_RGB2BGR))
    out = tmp_path / "cal.json"
    assert main([f"--image={bare}", f"--output={out}"]) == 2
    error = capsys.readouterr().err.strip()
    assert error.startswith("error: camera top: board not found") and "\n" not in error
    assert main([f"--image={boarded}", f"--output={out}", "--max_error_px=0.01", *BOARD_FLAGS]) == 2
    error = capsys.readouterr().err.strip()
    assert "reprojection error" in error and "--max_error_px=0.01" in error and "\n" not in error
    assert not out.exists()


@pytest.mark.slow  # ~30 s alone: loading every LeRobot robot type, which the suite's eval tests load anyway
def test_the_robots_cameras_are_read_with_evals_robot_flags(tmp_path, capsys):
    # The simulated table's camera through the robot path (connect, a frame per camera, disconnect): no board on it.
    assert main(["--robot.type=language_table_sim", f"--output={tmp_path / 'cal.json'}"]) == 2
    error = capsys.readouterr().err.strip()
    assert error.startswith("error: camera top: board not found") and "\n" not in error


@pytest.mark.parametrize(
    ("flag", "said"),
    [
        ("--max_error_px=-1", "error: --max_error_px=-1: give a positive number of pixels"),
        ("--max_error_px=0", "error: --max_error_px=0: give a positive number of pixels"),
        ("--write_board={tmp}/board.jpg", "error: --write_board={tmp}/board.jpg: writes a .pdf or a .png, not .jpg"),
        ("--write_board={tmp}/a_file/board.pdf", "error: --write_board={tmp}/a_file/board.pdf: cannot write it ("),
    ],
)
def test_calibrates_bad_input_is_one_line_and_writes_nothing(flag, said, tmp_path, capsys):
    (tmp_path / "a_file").write_text("")  # a file where the board's folder should be: no folder can be made there
    frame = tmp_path / "frame.png"
    cv2.imwrite(str(frame), np.full((48, 64, 3), 128, np.uint8))
    before = sorted(tmp_path.rglob("*"))
    assert main([flag.format(tmp=tmp_path), f"--image={frame}", f"--output={tmp_path / 'cal.json'}"]) == 2
    error = capsys.readouterr().err
    assert error.startswith(said.format(tmp=tmp_path)) and error.count("\n") == 1
    assert sorted(tmp_path.rglob("*")) == before
