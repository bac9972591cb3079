"""LoCoBot link and apartment simulator speed: host-client round trip, 640x480 JPEG frames per second over
loopback, and ray-cast renders per second.

- rtt_ms: median time of a no-op discrete step (the client sends it, the host runs it and acknowledges it in
  its next observation, the client receives that), with 640x480 images on the wire.
- fps_640x480: observations per second a client receives when every one carries a new 640x480 JPEG (the host
  encodes each, as it does camera frames on the robot; the client decodes each), host publishing flat out.
- sim_render_fps: RGB-D ray-cast renders per second of the furnished studio at 640x480.
Usage: python scripts/bench/bench_locobot.py [--seconds 5] [--steps 200]. The last line is machine-readable.
"""

from __future__ import annotations

import argparse
import math
import statistics
import tempfile
import time
from pathlib import Path

from lerobot_robot_locobot import Locobot, LocobotConfig, one_hot
from lerobot_robot_locobot.config_host import HostConfig, SimConfig
from lerobot_robot_locobot.host import HostThread

from lerobot_contrast.contrast.scene import Pose
from lerobot_contrast.domains.vln.apartment import STUDIO, CameraSpec, Footprints, RayCaster, Room
from lerobot_contrast.domains.vln.locobot_sim import SimBackend


class FreshFrames(SimBackend):
    """The simulator, but every observation carries another of a few pre-rendered frames, as a camera would:
    the host encodes each and the client decodes each, and no render time is counted."""

    def __init__(self) -> None:
        super().__init__(SimConfig())
        self.count = 0
        self.configure_camera(640, 480, False)

    def configure_camera(self, width: int, height: int, depth: bool) -> None:
        super().configure_camera(width, height, depth)
        start = self.world.pose
        self.frames = []
        for _ in range(8):
            self.world.rotate(2 * math.pi / 8)
            self.frames.append(super().images()[1])
        self.world.place_robot(start)

    def images(self):
        self.count += 1
        return self.count, self.frames[self.count % len(self.frames)], None


def client(ports: dict[str, int], directory: Path) -> Locobot:
    robot = Locobot(
        LocobotConfig(
            port_command=ports["command"],
            port_observation=ports["observation"],
            port_rpc=ports["rpc"],
            calibration_dir=directory,
        )
    )
    robot.connect()
    return robot


def round_trip_ms(steps: int, directory: Path) -> tuple[float, float]:
    """Median no-op step round trip, and median forward step (render and encode included), in ms."""
    with HostThread(HostConfig(port_command=0, port_observation=0, port_rpc=0)) as host:
        robot = client(host.ports, directory)
        stop, forward = [], []
        for k in range(steps):
            start = time.perf_counter()
            robot.send_action(one_hot("stop"))
            stop.append(time.perf_counter() - start)
            start = time.perf_counter()
            robot.send_action(one_hot("turn_left" if k % 2 else "turn_right"))
            forward.append(time.perf_counter() - start)
        robot.disconnect()
    return 1000 * statistics.median(stop), 1000 * statistics.median(forward)


def frames_per_second(seconds: float, directory: Path) -> float:
    config = HostConfig(port_command=0, port_observation=0, port_rpc=0, publish_hz=1000.0)
    with HostThread(config, FreshFrames()) as host:
        robot = client(host.ports, directory)
        image = robot.get_observation()["front"]
        received, start = 0, time.perf_counter()
        while time.perf_counter() - start < seconds:
            latest = robot.get_observation()["front"]  # decoded once per new observation, so a new array
            received += latest is not image
            image = latest
        elapsed = time.perf_counter() - start
        robot.disconnect()
    return received / elapsed


def renders_per_second(seconds: float) -> float:
    caster = RayCaster(CameraSpec(640, 480))
    footprints = Footprints.from_objects({name: Pose(*pose) for name, pose in STUDIO.items()})
    count, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        caster.render(Room(), footprints, Pose(4.0, 2.6, 0.1 * count))
        count += 1
    return count / (time.perf_counter() - start)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=5.0, help="duration of each throughput measurement")
    parser.add_argument("--steps", type=int, default=200, help="discrete steps timed for the round trip")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        rtt, turn = round_trip_ms(args.steps, Path(tmp))
        fps = frames_per_second(args.seconds, Path(tmp))
    render = renders_per_second(args.seconds)
    print(
        f"no-op step round trip {rtt:.2f} ms; a turn step (render, JPEG encode and transfer at 640x480) {turn:.1f} ms"
    )
    print(f"640x480 JPEG observations received {fps:.1f}/s; apartment renders {render:.1f}/s (RGB-D, 640x480)")
    print(f"rtt_ms={rtt:.2f} fps_640x480={fps:.1f} sim_render_fps={render:.1f}")


if __name__ == "__main__":
    main()
