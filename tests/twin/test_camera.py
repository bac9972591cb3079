"""The twin's webcam: LeRobot's unmodified `ZMQCamera` reads its frames, in RGB as LeRobot's cameras give them; the
printed board lying on the twin's table is found by the project's calibration under the default lens, where the true
camera model puts it; a busy port or a broken renderer is one line."""

import json
import threading

import cv2
import numpy as np
import pytest
import zmq

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.ports import free_port
from lerobot_contrast.twin.board import NAME, add_board, remove_board
from lerobot_contrast.twin.camera import CameraArgs, TwinCamera
from lerobot_contrast.twin.camera_server import CameraServer, robot_cameras, serve_camera
from lerobot_contrast.twin.lens import LensArgs

TARGET = (0.30, 0.0, 0.0)  # so101_blocks' workspace centre
BOARD = {"x": 0.32, "y": -0.02, "yaw_deg": 12.0}
RED_CUBE = (0.40, 0.15, 0.0125)  # centre of a 2.5 cm cube on the table


def table(with_board: bool):
    """A table top with a lamp, a red cube and (if asked) the board; MuJoCo imported after the twin chose EGL."""
    import mujoco

    spec = mujoco.MjSpec()
    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_PLANE, size=[1, 1, 0.01], rgba=[0.55, 0.45, 0.35, 1])
    spec.worldbody.add_light(pos=[0.3, 0, 1.5], dir=[0, 0, -1], diffuse=[0.6, 0.6, 0.6])
    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.0125] * 3, pos=RED_CUBE, rgba=[0.9, 0.1, 0.1, 1])
    if with_board:
        add_board(spec, **BOARD)
    return spec


@pytest.fixture(scope="module")
def world():
    import mujoco

    model = table(with_board=True).compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return model, data


def test_lerobot_zmq_camera_reads_rgb_frames_from_the_twin(world):
    """The --robot.cameras flag the twin prints, parsed as eval parses it, gives LeRobot's own ZMQCamera, which reads
    the twin's frames."""
    import draccus
    import lerobot.cameras.zmq  # noqa: F401  (registers the zmq camera type, as eval's robot registry does)
    from lerobot.cameras.utils import make_cameras_from_configs
    from lerobot.robots.so_follower import SO101FollowerConfig

    model, data = world
    lock = threading.Lock()

    def read(view):
        with lock:
            return view(model, data)

    args = CameraArgs()
    server = serve_camera(read, TARGET, args, LensArgs(), name="front", port=free_port(), fps=30)
    try:
        flag = robot_cameras(server, args)
        config = draccus.parse(SO101FollowerConfig, args=["--port=/dev/null", f"--cameras={flag}"])
        reader = make_cameras_from_configs(config.cameras)["front"]
        reader.connect()
        try:
            frames = [reader.read() for _ in range(3)]
        finally:
            reader.disconnect()
    finally:
        server.stop()
    assert all(frame.shape == (480, 640, 3) and frame.dtype == np.uint8 for frame in frames)
    assert not np.array_equal(frames[0], frames[1])  # fresh frames, each with its own sensor noise
    camera = TwinCamera(TARGET, args, LensArgs())  # the same pose: where the cube's top shows
    col, row = np.round(camera.project(np.array([RED_CUBE[:2] + (0.025,)]))[0]).astype(int)
    red, green, blue = frames[-1][row - 2 : row + 3, col - 2 : col + 3].reshape(-1, 3).mean(axis=0)
    assert red > 2 * green and red > 2 * blue  # the red cube arrives red in RGB order
    assert server.times.frames >= 3 and server.error is None


def test_the_board_is_found_under_the_default_lens_where_the_camera_model_says(world, tmp_path):
    from lerobot_contrast.calibrate import main as calibrate
    from lerobot_contrast.staging import board

    model, data = world
    camera = TwinCamera(TARGET, CameraArgs(), LensArgs())
    try:
        frame = camera.frame(model, data)
    finally:
        camera.close()
    grey = cv2.cvtColor(frame, cv2.COLOR_RGB2GRAY)
    parameters = cv2.aruco.DetectorParameters()
    parameters.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
    corners, ids, _ = cv2.aruco.ArucoDetector(board.dictionary(), parameters).detectMarkers(grey)
    objects, pixels = board.grid_board().matchImagePoints(corners, ids)
    on_table = board.board_to_table(objects.reshape(-1, 3)[:, :2], board.BoardArgs(**BOARD))
    expected = camera.project(np.column_stack([on_table, np.full(len(on_table), 0.0005)]))
    assert len(ids) == board.COLUMNS * board.ROWS
    offsets = pixels.reshape(-1, 2) - expected
    # The board shows where the true model puts it: no shift (half a pixel would be a convention slip), and each
    # corner within the detector's scatter on an unsmoothed render.
    assert np.abs(offsets.mean(axis=0)).max() < 0.15
    assert np.sqrt(np.mean(np.sum(offsets**2, axis=1))) < 0.6

    image, output = tmp_path / "front.png", tmp_path / "table.calibration.json"
    cv2.imwrite(str(image), cv2.cvtColor(frame, cv2.COLOR_RGB2BGR))
    flags = [f"--board.{key}={value}" for key, value in BOARD.items()]
    assert calibrate([f"--image={image}", "--camera=front", f"--output={output}", *flags]) == 0
    assert json.loads(output.read_text())["cameras"]["front"]["markers"] == board.COLUMNS * board.ROWS


@pytest.mark.parametrize(("full_meshes", "hole_shows"), [(True, "table"), (False, "ring")])
def test_meshes_with_a_hull_are_drawn_as_their_hull_unless_asked_for_in_full(full_meshes, hole_shows):
    """The arm's links are drawn as the convex hulls MuJoCo computes for contacts (a CPU renderer cannot draw the
    SO-101's 320k CAD triangles 30 times a second): a blue ring's hole is filled by its hull, open in full."""
    import mujoco

    spec = table(with_board=False)
    ring = spec.add_mesh(name="ring")
    ring.make_supertorus(24, 0.3, 1.0, 1.0)
    ring.scale = [0.2, 0.2, 0.2]
    body = spec.worldbody.add_body(pos=[0.3, 0.0, 0.03])
    for group, collides in ((2, 0), (3, 1)):  # as the SO-101 model has them: a visual geom and a collision twin
        body.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname="ring", group=group, contype=collides,
                      conaffinity=collides, rgba=[0.1, 0.2, 0.9, 1])  # fmt: skip
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    camera = TwinCamera(TARGET, CameraArgs(width=320, height=240, full_meshes=full_meshes), LensArgs(noise=0.0))
    try:
        frame = camera.frame(model, data)
    finally:
        camera.close()
    col, row = np.round(camera.project(np.array([[0.3, 0.0, 0.03]]))[0]).astype(int)
    red, _, blue = frame[row - 1 : row + 2, col - 1 : col + 2].reshape(-1, 3).mean(axis=0)
    assert ("ring" if blue > 2 * red else "table") == hole_shows


def test_view_hulls_give_the_camera_light_meshes_and_leave_the_physics_alone():
    import mujoco

    from lerobot_contrast.twin.camera import view_hulls

    def spec_with_rings():
        spec = table(with_board=False)
        ring = spec.add_mesh(name="ring")
        ring.make_supertorus(48, 0.3, 1.0, 1.0)
        ring.scale = [0.2, 0.2, 0.2]
        weighed = spec.worldbody.add_body(name="weighed", pos=[0.3, 0.0, 0.05], mass=0.2, inertia=[1e-4] * 3,
                                          explicitinertial=True)  # fmt: skip
        weighed.add_freejoint()
        weighed.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname="ring", contype=0, conaffinity=0, group=2)
        weighed.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname="ring", group=3)
        loose = spec.worldbody.add_body(name="loose", pos=[0.3, 0.2, 0.05])  # its mass comes from its geoms
        loose.add_freejoint()
        loose.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname="ring", contype=0, conaffinity=0, group=2)
        return spec

    plain = spec_with_rings().compile()
    edited_spec = spec_with_rings()
    view_hulls(edited_spec, vertices=24)
    edited = edited_spec.compile()
    assert np.allclose(plain.body_mass, edited.body_mass) and np.allclose(plain.body_inertia, edited.body_inertia)
    meshes = [mujoco.mj_id2name(edited, mujoco.mjtObj.mjOBJ_MESH, edited.geom_dataid[g]) for g in range(edited.ngeom)
              if edited.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH]  # fmt: skip
    assert meshes == ["ring_view", "ring", "ring"]  # the weighed body's visual geom only
    view = mujoco.mj_name2id(edited, mujoco.mjtObj.mjOBJ_MESH, "ring_view")
    assert 0 < edited.mesh_graph[edited.mesh_graphadr[view]] <= 24  # a hull of at most 24 vertices to draw


def test_the_board_moves_and_comes_off_the_table():
    import mujoco

    spec = table(with_board=False)
    add_board(spec, 0.3, 0.0, 0.0)
    add_board(spec, 0.25, 0.05, 30.0)
    model = spec.compile()
    boards = [i for i in range(model.ngeom) if mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, i) == NAME]
    assert len(boards) == 1 and np.allclose(model.geom_pos[boards[0]][:2], (0.25, 0.05), atol=0.02)
    assert remove_board(spec) and not remove_board(spec)
    assert spec.compile().ntex == 0


def test_a_busy_port_is_one_line():
    context = zmq.Context()
    taken = context.socket(zmq.PUB)
    port = taken.bind_to_random_port("tcp://127.0.0.1")
    try:
        with pytest.raises(UserError) as error:
            CameraServer(lambda: np.zeros((4, 4, 3), np.uint8), port=port).start()
    finally:
        taken.close()
        context.term()
    message = str(error.value)
    assert "\n" not in message and f"camera port {port}" in message and "--camera_port" in message


def test_a_renderer_that_fails_stops_the_feed_with_one_line(capsys):
    def broken() -> np.ndarray:
        raise RuntimeError("the GL context was lost")

    closed_on = []
    server = CameraServer(broken, name="front", port=free_port(),
                          close=lambda: closed_on.append(threading.current_thread().name))  # fmt: skip
    server.start()
    server._thread.join(timeout=5)
    server.stop()
    assert server.error == "twin camera front stopped: the GL context was lost"
    assert capsys.readouterr().err.strip() == server.error
    assert closed_on == ["twin camera front"]  # what render made (a GL context) is freed on the thread that made it


@pytest.mark.parametrize(("args", "says"), [(CameraArgs(elevation_deg=5), "camera elevation 5 degrees: give 10 to 85"),
                                            (CameraArgs(width=8), "camera size 8x480"),
                                            (CameraArgs(focal=0), "camera distance 0.85 m, focal 0")])  # fmt: skip
def test_bad_camera_flags_are_one_line(args, says):
    with pytest.raises(UserError, match=says):
        TwinCamera(TARGET, args, LensArgs())


def test_points_behind_or_beside_the_view_have_no_pixel():
    camera = TwinCamera(TARGET, CameraArgs(width=320, height=240), LensArgs())
    behind = camera.position + (camera.position - np.array(TARGET))
    far_side = np.array([0.3, -3.0, 0.0])  # 3 m to the robot's right: outside a 60-degree view
    pixels = camera.project(np.array([TARGET, behind, far_side]))
    assert np.allclose(pixels[0], (159.5, 119.5)) and np.isnan(pixels[1:]).all()
