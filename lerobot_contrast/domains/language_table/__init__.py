"""Language-Table task domain: the benchmark's five evaluation families, their wording and perturbations."""

from lerobot_contrast.domains.language_table.families import FAMILIES, is_achieved, push_target, rebase
from lerobot_contrast.domains.language_table.perturbations import PERTURBATIONS
from lerobot_contrast.domains.language_table.task import LanguageTableTask, enumerate_conditions, instruction_to_array

__all__ = [
    "FAMILIES",
    "PERTURBATIONS",
    "LanguageTableTask",
    "enumerate_conditions",
    "instruction_to_array",
    "is_achieved",
    "push_target",
    "rebase",
]
