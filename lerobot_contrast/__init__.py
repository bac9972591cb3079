"""lerobot-contrast: contrast-set evaluation of language-guided robot policies for LeRobot."""

__version__ = "0.1.0"
