"""LeRobot robot plugin for the LoCoBot. LeRobot imports this distribution at start-up (name prefix
`lerobot_robot_`); the robot, host and wire protocol arrive with the LoCoBot issue."""

__version__ = "0.1.0"
