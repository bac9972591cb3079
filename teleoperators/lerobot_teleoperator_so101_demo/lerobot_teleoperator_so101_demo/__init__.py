"""LeRobot teleoperator plugin `so101_demo`: a scripted demonstrator for the virtual SO-101 of lerobot_contrast."""

from lerobot_teleoperator_so101_demo.config_so101_demo import SO101DemoConfig
from lerobot_teleoperator_so101_demo.so101_demo import SO101Demo

__all__ = ["SO101Demo", "SO101DemoConfig"]
