"""The arm's operator reads no truth: staging, seeing and labelling import nothing of the twin (its placement client
above all), only LeRobot's robot, the camera calibration and the arm's model."""

import subprocess
import sys

MODULES = ("lerobot_contrast.operators.arm.operator", "lerobot_contrast.operators.arm.setup", "lerobot_contrast.staging.seeing",
           "lerobot_contrast.so101.motion", "lerobot_contrast.operators.arm.verdict")  # fmt: skip


def test_the_arm_operator_imports_nothing_of_the_twin():
    code = (
        f"import sys, importlib; [importlib.import_module(m) for m in {MODULES!r}]; "
        "print(sorted(m for m in sys.modules if m.startswith('lerobot_contrast.twin')))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
