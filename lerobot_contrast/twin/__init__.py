"""A virtual SO-101 bench: LeRobot's unmodified `so101_follower` driver and camera classes connect to it as to the arm
(a Feetech bus on a pseudo-terminal, a MuJoCo arm and table, a camera publisher, a scripted operator)."""

import os

# MuJoCo fixes its GL backend when first imported: every twin module that renders imports this package first, so the
# camera draws offscreen through EGL with or without a display (MUJOCO_GL set by the user still wins).
os.environ.setdefault("MUJOCO_GL", "egl")
