"""The real LoCoBot under ROS 2: Interbotix's Python API for the base, camera topics for the images.

Needs ROS 2 (Galactic or Humble, Create 3 base) with `interbotix_xs_modules` and the LoCoBot control launch
running (`ros2 launch interbotix_xslocobot_control xslocobot_control.launch.py robot_model:=locobot_base
use_base:=true use_camera:=true rs_camera_align_depth:=true`). Imported only by `--backend=ros2`."""

from __future__ import annotations

import threading

import numpy as np

from lerobot_robot_locobot.config_host import Ros2Config
from lerobot_robot_locobot.odometry import Pose2

try:
    from interbotix_common_modules.common_robot.robot import robot_shutdown, robot_startup
    from interbotix_xs_modules.xs_robot.locobot import BaseType, InterbotixLocobotXS
    from sensor_msgs.msg import Image
except ImportError as error:
    raise ImportError(
        f"--backend=ros2 needs ROS 2 with the Interbotix LoCoBot packages ({error}); source the ROS 2 and "
        "interbotix workspaces (e.g. `source ~/interbotix_ws/install/setup.bash`) before starting the host"
    ) from None


class InterbotixDriver:
    def __init__(self, config: Ros2Config) -> None:
        base_type = BaseType.KOBUKI if config.base_type == "kobuki" else BaseType.CREATE3
        self.robot = InterbotixLocobotXS(
            robot_model=config.robot_model, robot_name=config.robot_name, use_base=True, base_type=base_type
        )
        self._lock = threading.Lock()
        self._color: tuple[int, np.ndarray] | None = None
        self._depth: np.ndarray | None = None
        self._bumped = False
        node = self.robot.get_node()
        node.create_subscription(Image, config.color_topic, self._on_color, 1)
        node.create_subscription(Image, config.depth_topic, self._on_depth, 1)
        if config.hazard_topic:
            from irobot_create_msgs.msg import HazardDetectionVector

            node.create_subscription(HazardDetectionVector, config.hazard_topic, self._on_hazard, 1)
        robot_startup()

    def command_velocity(self, x: float, theta: float) -> None:
        self.robot.base.command_velocity_xyaw(x=x, yaw=theta)

    def odometry(self) -> Pose2 | None:
        x, y, theta = self.robot.base.get_odom_xytheta()
        return float(x), float(y), float(theta)

    def bumper(self) -> bool:
        return self._bumped

    def color(self) -> tuple[int, np.ndarray] | None:
        with self._lock:
            return self._color

    def depth(self) -> np.ndarray | None:
        with self._lock:
            return self._depth

    def shutdown(self) -> None:
        self.robot.base.stop()
        robot_shutdown()

    def _on_color(self, msg: Image) -> None:
        image = _pixels(msg, 3)
        if msg.encoding == "bgr8":
            image = image[..., ::-1]
        with self._lock:
            count = 0 if self._color is None else self._color[0] + 1
            self._color = (count, np.ascontiguousarray(image))

    def _on_depth(self, msg: Image) -> None:
        raw = _pixels(msg, 1)[..., 0]
        depth = raw.astype(np.float32) / 1000.0 if msg.encoding == "16UC1" else raw.astype(np.float32)
        with self._lock:
            self._depth = depth

    def _on_hazard(self, msg) -> None:
        self._bumped = any(detection.type == detection.BUMP for detection in msg.detections)


def _pixels(msg: Image, channels: int) -> np.ndarray:
    """A sensor_msgs/Image as an (H, W, channels) array (rgb8/bgr8, 16UC1 millimetres, 32FC1 metres)."""
    dtype = {"16UC1": np.uint16, "32FC1": np.float32}.get(msg.encoding, np.uint8)
    itemsize = np.dtype(dtype).itemsize
    rows = np.frombuffer(msg.data, dtype=np.uint8).reshape(msg.height, msg.step)
    data = rows[:, : msg.width * channels * itemsize].copy().view(dtype)
    return data.reshape(msg.height, msg.width, channels)
