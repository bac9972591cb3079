"""lerobot-contrast: contrast-set evaluation of language-guided robot policies for LeRobot.

The public API: load a task, perturb its instances, plan, evaluate and summarise. Names are imported on first
use, so `import lerobot_contrast` stays light (the simulators and LeRobot load only when an evaluation runs)."""

import importlib.metadata
from importlib import import_module
from typing import Any

__version__ = importlib.metadata.version("lerobot_contrast")

_EXPORTS = {
    "Instance": "lerobot_contrast.contrast.instance",
    "Pose": "lerobot_contrast.contrast.scene",
    "Scene": "lerobot_contrast.contrast.scene",
    "Perturbation": "lerobot_contrast.contrast.perturbation",
    "PerturbationRegistry": "lerobot_contrast.contrast.perturbation",
    "Task": "lerobot_contrast.contrast.task",
    "Judgement": "lerobot_contrast.contrast.task",
    "perturb": "lerobot_contrast.contrast.task",
    "DistanceCost": "lerobot_contrast.contrast.cost",
    "ResetTimeCost": "lerobot_contrast.contrast.cost",
    "make_plan": "lerobot_contrast.contrast.strategy",
    "PlannedTrial": "lerobot_contrast.contrast.strategy",
    "Outcome": "lerobot_contrast.contrast.trial",
    "TrialContext": "lerobot_contrast.contrast.trial",
    "TrialRecord": "lerobot_contrast.contrast.trial",
    "UserError": "lerobot_contrast.contrast.errors",
    "load_task": "lerobot_contrast.domains",
    "task_names": "lerobot_contrast.domains",
    "Evaluation": "lerobot_contrast.spine.evaluation",
    "Results": "lerobot_contrast.spine.evaluation",
    "run": "lerobot_contrast.spine.evaluation",
    "preview": "lerobot_contrast.spine.evaluation",
    "PolicyArgs": "lerobot_contrast.policies",
    "make_policy": "lerobot_contrast.policies",
    "read_journal": "lerobot_contrast.record.journal",
    "format_summary": "lerobot_contrast.record.summary",
}
_MODULES = {"stats": "lerobot_contrast.reporting.stats"}

__all__ = [
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


def __getattr__(name: str) -> Any:
    if name in _MODULES:
        return import_module(_MODULES[name])
    if name in _EXPORTS:
        return getattr(import_module(_EXPORTS[name]), name)
    raise AttributeError(f"module 'lerobot_contrast' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *__all__])
