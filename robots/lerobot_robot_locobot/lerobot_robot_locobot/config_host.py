"""`python -m lerobot_robot_locobot.host` settings (draccus flags such as --backend=sim --sim.collision=stop),
their checks, and parsing with one-line errors."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path

import draccus

from lerobot_robot_locobot.protocol import DEFAULT_PORTS

BACKENDS = ("sim", "ros2")
WILDCARDS = ("*", "0.0.0.0", "::", "")


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


class HostConfigError(ValueError):
    pass


def validate(config: HostConfig) -> None:
    if config.bind in WILDCARDS:
        raise HostConfigError(
            f"--bind={config.bind!r} would listen on every interface; give the one address the workstation "
            "reaches the robot at (or 127.0.0.1 for a local simulator)"
        )
    if config.backend not in BACKENDS:
        raise HostConfigError(f"--backend must be one of {list(BACKENDS)}, got {config.backend!r}")
    if not 0.05 <= config.watchdog_s <= 5.0:
        raise HostConfigError(f"--watchdog_s must be between 0.05 and 5 seconds, got {config.watchdog_s}")
    if config.publish_hz <= 0:
        raise HostConfigError(f"--publish_hz must be positive, got {config.publish_hz}")
    if config.sim.collision not in ("slide", "stop"):
        raise HostConfigError(f"--sim.collision must be slide or stop, got {config.sim.collision!r}")
    if config.ros2.base_type not in ("create3", "kobuki"):
        raise HostConfigError(f"--ros2.base_type must be create3 or kobuki, got {config.ros2.base_type!r}")
    if config.authorized_keys is not None and config.server_secret_key is None:
        raise HostConfigError("--authorized_keys needs --server_secret_key (the host's own CurveZMQ key)")


def _flag_names(cls: type, prefix: str = "") -> set[str]:
    names = set()
    for f in dataclasses.fields(cls):
        names.add(prefix + f.name)
        if f.default_factory is not dataclasses.MISSING and dataclasses.is_dataclass(f.default_factory):
            names |= _flag_names(f.default_factory, f"{prefix}{f.name}.")
    return names


def parse_config(argv: list[str]) -> HostConfig:
    """Draccus flags with a one-line error for an unknown flag or a bad value."""
    known = _flag_names(HostConfig) | {"help", "config_path"}
    for arg in argv:
        if arg != "-h" and (not arg.startswith("--") or arg[2:].split("=", 1)[0] not in known):
            raise HostConfigError(f"unknown flag {arg!r}; see --help for the flags the host takes")
    try:
        return draccus.parse(config_class=HostConfig, args=argv)
    except SystemExit:
        raise
    except Exception as error:  # draccus explains bad values over several lines
        raise HostConfigError(f"invalid flag value: {' '.join(str(error).split())}") from None
