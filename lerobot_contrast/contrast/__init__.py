"""The contrast-set core: scenes, instances, perturbations, costs, strategies and metrics (pure Python + numpy)."""

from lerobot_contrast.contrast.cost import CostModel, DistanceCost, ResetTimeCost, make_cost_model
from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.metrics import spl, subgoal_progress
from lerobot_contrast.contrast.perturbation import AXES, Perturbation, PerturbationRegistry
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.contrast.staging import materialize, staging_moves
from lerobot_contrast.contrast.strategy import STRATEGIES, PlannedTrial, make_plan
from lerobot_contrast.contrast.task import Judgement, Task, perturb
from lerobot_contrast.contrast.trial import Outcome, TrialRecord

__all__ = [
    "AXES",
    "STRATEGIES",
    "CostModel",
    "DistanceCost",
    "Instance",
    "Judgement",
    "Outcome",
    "Perturbation",
    "PerturbationRegistry",
    "PlannedTrial",
    "Pose",
    "ResetTimeCost",
    "Scene",
    "Task",
    "TrialRecord",
    "UserError",
    "make_cost_model",
    "make_plan",
    "materialize",
    "perturb",
    "spl",
    "staging_moves",
    "subgoal_progress",
]
