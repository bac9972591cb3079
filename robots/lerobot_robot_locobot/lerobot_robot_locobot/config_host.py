"""`python -m lerobot_robot_locobot.host` settings (draccus flags such as --backend=sim --sim.collision=stop)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from lerobot_robot_locobot.protocol import DEFAULT_PORTS


@dataclass
class SimConfig:
    # On contact the robot "slide"s along the obstacle (Habitat's ALLOW_SLIDING) or "stop"s where it touched.
    collision: str = "slide"
    robot_radius: float = 0.18
    # The camera: horizontal field of view and height above the floor (RealSense D435 on a LoCoBot).
    hfov_deg: float = 69.0
    camera_height_m: float = 0.55


@dataclass
class Ros2Config:
    # Interbotix model and namespace, as given to the xslocobot control launch file.
    robot_model: str = "locobot_base"
    robot_name: str = "locobot"
    base_type: str = "create3"  # or "kobuki"
    color_topic: str = "/locobot/camera/color/image_raw"
    # Launch the camera with depth aligned to colour (rs_camera_align_depth:=true) for this topic.
    depth_topic: str = "/locobot/camera/aligned_depth_to_color/image_raw"
    # Create 3 bump/cliff events (irobot_create_msgs/HazardDetectionVector); empty to ignore.
    hazard_topic: str = "/mobile_base/hazard_detection"
    # Closed-loop discrete steps: cruising speeds and how close to the target counts as reached.
    step_x_vel: float = 0.2
    step_theta_vel: float = 0.6
    tolerance_m: float = 0.01
    tolerance_deg: float = 1.5
    step_timeout_s: float = 10.0


@dataclass
class HostConfig:
    # "sim": the simulated apartment (tests, demos); "ros2": an Interbotix LoCoBot under ROS 2.
    backend: str = "sim"
    # The one interface to listen on, e.g. the robot's Wi-Fi address; never all interfaces.
    bind: str = "127.0.0.1"
    port_command: int = DEFAULT_PORTS["command"]
    port_observation: int = DEFAULT_PORTS["observation"]
    port_rpc: int = DEFAULT_PORTS["rpc"]
    # Stop the base when no command arrived for this long (a lost or crashed client).
    watchdog_s: float = 0.5
    # Observations are published at this rate, and at once after every step.
    publish_hz: float = 30.0
    # Limits on what a client may ask for: velocities, and the size of one discrete step.
    max_x_vel: float = 0.3
    max_theta_vel: float = 1.0
    max_step_m: float = 1.0
    max_turn_deg: float = 90.0
    jpeg_quality: int = 90
    # CurveZMQ: the host's secret key file, and a directory of the public keys of clients allowed in.
    server_secret_key: Path | None = None
    authorized_keys: Path | None = None
    sim: SimConfig = field(default_factory=SimConfig)
    ros2: Ros2Config = field(default_factory=Ros2Config)
