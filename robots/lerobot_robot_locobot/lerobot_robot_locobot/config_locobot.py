"""`--robot.type=locobot`: the workstation side of the LoCoBot, talking to `python -m lerobot_robot_locobot.host`."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from lerobot.robots import RobotConfig

from lerobot_robot_locobot.actions import ACTION_MODES
from lerobot_robot_locobot.protocol import DEFAULT_PORTS


@RobotConfig.register_subclass("locobot")
@dataclass
class LocobotConfig(RobotConfig):
    # Address of the robot running `python -m lerobot_robot_locobot.host` (its --bind address).
    host: str = "127.0.0.1"
    port_command: int = DEFAULT_PORTS["command"]
    port_observation: int = DEFAULT_PORTS["observation"]
    port_rpc: int = DEFAULT_PORTS["rpc"]
    # Seconds to wait for the host's first answer before giving up with an error naming the address.
    connect_timeout_s: float = 5.0
    # Seconds one discrete step may take on the robot before send_action fails.
    step_timeout_s: float = 15.0
    # The host counts as gone once no observation has arrived for this long, while get_observation waits for a
    # fresh one (published within the last three publishing periods; a stale image is never returned) or while a
    # step runs. Default: 60 of the host's publishing periods (2 s at its default 30 Hz).
    observation_timeout_s: float | None = None
    # Camera image size the host sends (it resizes or renders to it), and whether it adds aligned depth.
    camera_width: int = 640
    camera_height: int = 480
    use_depth: bool = False
    # "discrete": VLN-CE actions forward.vel/turn_left.vel/turn_right.vel/stop.vel (the largest positive one
    # runs, exactly once, and send_action returns when it finished); "velocity": x.vel (m/s), theta.vel (rad/s).
    action_mode: str = "discrete"
    forward_m: float = 0.25
    # VLN-CE's RxR setting and the paper's policy turn 30 degrees; R2R turns 15.
    turn_deg: float = 30.0
    # Velocity limits applied here; the host clamps again to its own limits.
    max_x_vel: float = 0.3
    max_theta_vel: float = 1.0
    # CurveZMQ: this client's secret key file and the host's public key file (see lerobot_robot_locobot.keys).
    client_secret_key: Path | None = None
    server_public_key: Path | None = None

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.action_mode not in ACTION_MODES:
            raise ValueError(f"--robot.action_mode must be one of {list(ACTION_MODES)}, got {self.action_mode!r}")
        if self.camera_width < 16 or self.camera_height < 16:
            raise ValueError(
                f"--robot.camera_width/height must be at least 16, got {self.camera_width}x{self.camera_height}"
            )
        if not 0 < self.forward_m <= 1.0 or not 0 < self.turn_deg <= 90.0:
            raise ValueError(
                f"--robot.forward_m must be in (0, 1] and --robot.turn_deg in (0, 90], got {self.forward_m}, {self.turn_deg}"
            )
        if self.observation_timeout_s is not None and not self.observation_timeout_s > 0:
            raise ValueError(f"--robot.observation_timeout_s must be positive, got {self.observation_timeout_s}")
        if (self.client_secret_key is None) != (self.server_public_key is None):
            raise ValueError("--robot.client_secret_key and --robot.server_public_key go together: set both or neither")
