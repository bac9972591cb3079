"""The public API is what `lerobot_contrast` exports: the list is pinned, every name resolves, and importing the
package loads none of the heavy libraries until a name that needs them is used."""

import subprocess
import sys

import lerobot_contrast

EXPORTED = [
    "DistanceCost",
    "Evaluation",
    "Instance",
    "Judgement",
    "Outcome",
    "Perturbation",
    "PerturbationRegistry",
    "PlannedTrial",
    "PolicyArgs",
    "Pose",
    "ResetTimeCost",
    "Results",
    "Scene",
    "Task",
    "TrialContext",
    "TrialRecord",
    "UserError",
    "format_summary",
    "load_task",
    "make_plan",
    "make_policy",
    "perturb",
    "preview",
    "read_journal",
    "run",
    "stats",
    "task_names",
]


def test_exported_members():
    assert lerobot_contrast.__all__ == EXPORTED
    for name in EXPORTED:
        member = getattr(lerobot_contrast, name)
        assert getattr(member, "__module__", member.__name__).startswith("lerobot_contrast."), name


def test_importing_the_package_loads_no_heavy_library():
    code = "import sys, lerobot_contrast; print(sorted({n.split('.')[0] for n in sys.modules} & {'torch', 'lerobot'}))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
