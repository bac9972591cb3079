"""`--robot.type=vln_sim`: the simulated studio apartment as an in-process LeRobot robot (no LoCoBot host)."""

from __future__ import annotations

from dataclasses import dataclass

from lerobot.robots import RobotConfig

from lerobot_contrast.contrast.errors import UserError


@RobotConfig.register_subclass("vln_sim")
@dataclass(kw_only=True)
class VLNSimConfig(RobotConfig):
    # Render the ray-cast camera `front`. Scripted policies that read the scene need no image.
    camera: bool = True
    # With the camera, also give its aligned depth `front_depth` (H, W, 1) in metres, as the LoCoBot's
    # --robot.use_depth=true does (the learned default of --task=vln reads it).
    depth: bool = True
    camera_width: int = 640
    camera_height: int = 480
    # One discrete step: forward this many metres, or turn this many degrees (VLN-CE RxR and the paper: 30).
    forward_m: float = 0.25
    turn_deg: float = 30.0
    # On contact the robot "slide"s along the obstacle (Habitat's ALLOW_SLIDING) or "stop"s where it touched.
    collision: str = "slide"
    robot_radius: float = 0.18
    # The camera: horizontal field of view and height above the floor (RealSense D435 on a LoCoBot).
    hfov_deg: float = 69.0
    camera_height_m: float = 0.55

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.collision not in ("slide", "stop"):
            raise UserError(f"--robot.collision must be slide or stop, got {self.collision!r}")
        if not 0 < self.forward_m <= 1.0 or not 0 < self.turn_deg <= 90.0:
            raise UserError(
                f"--robot.forward_m must be in (0, 1] and --robot.turn_deg in (0, 90], got {self.forward_m}, {self.turn_deg}"
            )
