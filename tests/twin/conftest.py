"""MuJoCo fixes its GL backend when first imported: these tests import it at collection, before the twin's camera
module can choose offscreen EGL, so choose it here (a display-less CI machine has no GLFW)."""

import os

os.environ.setdefault("MUJOCO_GL", "egl")
