"""The twin process's parts, started in order and stopped in reverse: the servo bank with its calibration file, the
physics, the placement socket, the camera publisher and the serial bus."""

from __future__ import annotations

import socket
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.domains.task_file import load_task_file
from lerobot_contrast.domains.task_file.world import sample_scene
from lerobot_contrast.twin.faults import FaultsConfig

CAMERA_NAME = "front"
CLOCKS = ("wall", "sim")


def joint_offsets(names: tuple[str, ...], degrees: float, seed: int) -> dict[str, float]:
    """Each motor's calibration error (radians): `degrees` in size, its sign drawn per joint."""
    signs = np.random.default_rng([seed, 3]).choice([-1.0, 1.0], len(names))
    return {name: float(sign * np.radians(degrees)) for name, sign in zip(names, signs, strict=True)}


@dataclass
class TwinConfig:
    """Start a virtual SO-101 bench: LeRobot's `so101_follower` connects to its serial port and LeRobot's `zmq`
    camera to its webcam as to the real arm's; objects are placed with `python -m lerobot_contrast.twin.place`.
    Runs until Ctrl-C."""

    # The task file whose table, objects and bins the twin builds: a path or a shipped example's name.
    task: str = "so101_blocks"
    # The robot id LeRobot is given (--robot.id): the calibration file is written under this name.
    robot_id: str = "twin"
    # Where to write the calibration file (default: LeRobot's own calibration folder); give eval the same
    # --robot.calibration_dir.
    calibration_dir: Path | None = None
    # Frames per second the camera publishes: the control rate.
    fps: int = 30
    # wall: the world runs in real time, as a real arm does (what shows LeRobot's deadlines are met). sim: it moves
    # only when a client advances it (give eval the --clock it prints): as fast as the machine allows, and the same
    # results however busy the machine is.
    clock: str = "wall"
    # The port of the simulated clock's socket on 127.0.0.1 (--clock=sim).
    clock_port: int = 5557
    # Camera frame width in pixels.
    width: int = 640
    # Camera frame height in pixels.
    height: int = 480
    # The lens's radial distortion k1 (-0.3: a wide-angle USB webcam; 0: a perfect pinhole).
    lens_k1: float = -0.3
    # The port of the camera's ZMQ publisher on 127.0.0.1.
    camera_port: int = 5555
    # The port of the placement command socket on 127.0.0.1.
    control_port: int = 5556
    # Seed of the objects' first placement and of the camera's sensor noise.
    seed: int = 0
    # Each joint's calibration off the arm's model by this many degrees (its sign drawn per joint from --seed), as a
    # user's calibration leaves a real arm a few degrees from the kinematic model's zero.
    joint_offset_deg: float = 0.0
    faults: FaultsConfig = field(default_factory=FaultsConfig)

    def check(self) -> None:
        """Raise one line for a flag no twin can start with (checked before anything binds or loads)."""
        if self.clock not in CLOCKS:
            raise UserError(f"--clock={self.clock}: give wall (real time) or sim (advanced by its clients)")
        ports = (
            ("camera_port", "control_port", "clock_port") if self.clock == "sim" else ("camera_port", "control_port")
        )
        for flag in ports:
            port = getattr(self, flag)
            if not 1 <= port <= 65535:
                raise UserError(f"--{flag}={port} is not a port: give one from 1 to 65535")
        if not 0 <= self.joint_offset_deg <= 10:
            raise UserError(f"--joint_offset_deg={self.joint_offset_deg:g}: give degrees from 0 to 10")
        for k, first in enumerate(ports):
            for second in ports[k + 1 :]:
                if getattr(self, first) == getattr(self, second):
                    raise UserError(f"--{first} and --{second} are both {getattr(self, first)}: give two ports")
        for flag in ("fps", "width", "height"):
            if getattr(self, flag) < 1:
                raise UserError(f"--{flag}={getattr(self, flag)}: give a whole number above 0")


def check_port(port: int, what: str, flag: str) -> None:
    """Raise one line if `port` on 127.0.0.1 cannot be bound (as ZMQ binds it: reusing a port in TIME_WAIT)."""
    with socket.socket() as probe:
        probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            probe.bind(("127.0.0.1", port))
        except OSError as error:
            raise UserError(f"{what} {port} on 127.0.0.1: {error.strerror}; choose a free one with {flag}") from None


class Twin:
    """The running bench of `config`; `camera=False` leaves the webcam out (tests of the arm alone)."""

    def __init__(self, config: TwinConfig, camera: bool = True) -> None:
        from lerobot_contrast.so101 import arm  # MuJoCo loads here, after the caller chose its GL backend
        from lerobot_contrast.so101.scene import build_spec
        from lerobot_contrast.twin.camera import view_hulls
        from lerobot_contrast.twin.physics import Physics
        from lerobot_contrast.twin.servos import ServoBank

        config.check()
        self.config = config
        self.task = load_task_file(config.task).spec
        # Before MuJoCo loads and compiles (seconds): a twin already running is the usual reason a port is taken.
        check_port(config.control_port, "control port", "--control_port")
        if config.clock == "sim":
            check_port(config.clock_port, "clock port", "--clock_port")
        if camera:
            check_port(config.camera_port, "camera port", "--camera_port")
        scene = sample_scene(self.task, np.random.default_rng(config.seed))
        self.bank = ServoBank(arm.MOTORS, arm.rest_raw(), limits=arm.raw_limits())
        # The camera draws the arm's meshes as light hulls (a third of the render time); contacts are unchanged.
        spec = build_spec(self.task, scene, extras=[view_hulls] if camera else [])
        self.physics = Physics(
            spec, self.bank, self.task.objects, joint_offsets(arm.MOTOR_NAMES, config.joint_offset_deg, config.seed)
        )
        self.with_camera = camera
        self.simulated = config.clock == "sim"
        self.camera = None
        self.endpoints: dict[str, str] = {}
        self.cameras_flag = ""
        self._running: list = []

    def start(self) -> dict[str, str]:
        """Start every part; a part that cannot start stops the ones before it and raises one line."""
        from lerobot_contrast.twin.bus_server import BusServer
        from lerobot_contrast.twin.calibration_file import write_calibration_file
        from lerobot_contrast.twin.placement import PlacementServer

        try:
            path = write_calibration_file(self.bank, self.config.robot_id, self.config.calibration_dir)
        except OSError as error:
            raise UserError(str(error)) from None
        self.endpoints["calibration"] = str(path)
        try:
            placement = PlacementServer(self.physics, self.task, self.config.control_port)
            self.endpoints["placement"] = placement.start()
            self._running.append(placement)
            if self.with_camera:
                self.endpoints["camera"] = self._start_camera()
            # On the simulated clock the bus is served here, its servos stepped with the physics: nothing else
            # runs while a client waits on the bus, so its replies meet LeRobot's deadlines without a process.
            bus = BusServer(self.bank, self.config.faults, process=not self.simulated)
            self.endpoints["bus"] = bus.start()
            self._running.append(bus)
            if self.simulated:
                self.endpoints["clock"] = self._start_clock(bus)
            else:
                self.physics.start()
                self._running.append(self.physics)
        except BaseException:
            self.stop()
            raise
        return self.endpoints

    def _start_clock(self, bus) -> str:
        from lerobot_contrast.twin.clock_server import ClockServer

        clock = ClockServer(self.physics, bus, self.camera, self.config.fps, self.config.clock_port)
        address = clock.start()
        self._running.append(clock)
        return address

    def _start_camera(self) -> str:
        from lerobot_contrast.twin.camera import CameraArgs
        from lerobot_contrast.twin.camera_server import robot_cameras, serve_camera
        from lerobot_contrast.twin.lens import LensArgs

        config = self.config
        (x0, x1), (y0, y1) = self.task.workspace.area.box
        args = CameraArgs(config.width, config.height)
        lens = LensArgs(k1=config.lens_k1, seed=config.seed)
        target = ((x0 + x1) / 2, (y0 + y1) / 2, 0.0)
        server = serve_camera(self.physics.read, target, args, lens, CAMERA_NAME, config.camera_port, config.fps,
                              paced=not self.simulated)  # fmt: skip
        self._running.append(server)
        self.camera = server
        self.cameras_flag = robot_cameras(server, args)
        return server.address

    @property
    def failure(self) -> str | None:
        """Why a part stopped on its own (its thread printed it already), or None while all run."""
        return next((part.error for part in self._running if getattr(part, "error", None)), None)

    def stop(self) -> None:
        while self._running:
            self._running.pop().stop()

    def eval_flags(self) -> str:
        """The flags that point `python -m lerobot_contrast.eval` (or any LeRobot command) at this twin."""
        config = self.config
        flags = [
            "--robot.type=so101_follower",
            f"--robot.port={self.endpoints['bus']}",
            f"--robot.id={config.robot_id}",
        ]
        if config.calibration_dir is not None:
            flags.append(f"--robot.calibration_dir={config.calibration_dir}")
        if "camera" in self.endpoints:
            flags.append(f"--robot.cameras='{self.cameras_flag}'")
        if "clock" in self.endpoints:
            flags.append(f"--clock={self.endpoints['clock']}")
        return " ".join(flags)
