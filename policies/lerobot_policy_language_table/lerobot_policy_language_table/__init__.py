"""LeRobot policy plugin for Language-Table. LeRobot imports this distribution at start-up (name prefix
`lerobot_policy_`); the model, processors and checkpoint converter arrive with the policy issue."""

__version__ = "0.1.0"
