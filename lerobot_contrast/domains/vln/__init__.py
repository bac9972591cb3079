"""Vision-and-language navigation in the simulated studio apartment: the paper's real-robot study as a task
(five arrangements, two-subgoal instructions, ΔL/ΔLB/ΔS/ΔSB) and a scripted baseline navigator."""

from lerobot_contrast.domains.vln.examples import ARRANGEMENTS, FAMILY, example_instances, storage_scene
from lerobot_contrast.domains.vln.perturbations import PERTURBATIONS
from lerobot_contrast.domains.vln.task import SUCCESS_RADIUS_M, VLNTask

__all__ = [
    "ARRANGEMENTS",
    "FAMILY",
    "PERTURBATIONS",
    "SUCCESS_RADIUS_M",
    "VLNTask",
    "example_instances",
    "storage_scene",
]
