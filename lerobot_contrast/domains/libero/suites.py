"""LIBERO's suites as data: each task's instruction, BDDL goal, objects and the object poses of its init states,
read from the installed LIBERO package (BDDL files and init-state files), with no simulator."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.scene import Pose
from lerobot_contrast.domains.libero import runtime

SUITES = ("libero_spatial", "libero_object", "libero_goal", "libero_10")
# qpos of the Panda arm (7 joints) and its gripper (2), which come first; then one free joint (7 numbers: x y z and
# the quaternion w x y z) per BDDL object, in the BDDL's order. The simulator checks this layout when it loads a task.
ROBOT_QPOS = 9
FREE_JOINT = 7


@dataclass(frozen=True)
class LiberoTaskInfo:
    suite: str
    task_id: int
    name: str
    language: str
    bddl_file: Path
    objects: dict[str, str]  # object name -> category, in the BDDL's order (the model's free-joint order)
    fixtures: dict[str, str]
    goal: tuple[tuple[str, ...], ...]  # BDDL goal predicates, e.g. ("in", "alphabet_soup_1", "basket_1_contain_region")
    n_init_states: int


def check_suite(suite: str) -> str:
    if suite not in SUITES:
        raise UserError(f"--task: unknown LIBERO suite {suite!r}; choose from: {', '.join(SUITES)}")
    return suite


@cache
def benchmark(suite: str):
    runtime.load()
    from libero.libero import benchmark as bench

    return bench.get_benchmark_dict()[check_suite(suite)]()


@cache
def tasks(suite: str) -> tuple[LiberoTaskInfo, ...]:
    """The suite's tasks, in LIBERO's order (task ids 0..n-1)."""
    bench = benchmark(suite)
    from libero.libero import get_libero_path
    from libero.libero.envs.bddl_utils import robosuite_parse_problem

    out = []
    for task_id in range(bench.n_tasks):
        task = bench.get_task(task_id)
        bddl = Path(get_libero_path("bddl_files")) / task.problem_folder / task.bddl_file
        problem = robosuite_parse_problem(str(bddl))
        out.append(
            LiberoTaskInfo(
                suite=suite,
                task_id=task_id,
                name=task.name,
                language=task.language,
                bddl_file=bddl,
                objects={name: category for category, names in problem["objects"].items() for name in names},
                fixtures={name: category for category, names in problem["fixtures"].items() for name in names},
                goal=tuple(tuple(predicate) for predicate in problem["goal_state"]),
                n_init_states=len(init_states(suite, task_id)),
            )
        )
    return tuple(out)


def task_info(suite: str, task_id: int) -> LiberoTaskInfo:
    known = tasks(suite)
    if not 0 <= task_id < len(known):
        raise UserError(f"--families: {suite} has no task {task_id}; its task ids are 0 to {len(known) - 1}")
    return known[task_id]


@cache
def init_states(suite: str, task_id: int) -> np.ndarray:
    """LIBERO's init states of the task (MuJoCo states: time, qpos, qvel), loaded as LeRobot loads them."""
    from lerobot.envs.libero import get_task_init_states

    return np.asarray(get_task_init_states(benchmark(suite), task_id))


def planar(qpos7: np.ndarray) -> Pose:
    """The planar pose of a free joint's (x, y, z, qw, qx, qy, qz): position and heading about the vertical."""
    x, y, _, w, qx, qy, qz = (float(v) for v in qpos7)
    return Pose(x, y, math.atan2(2.0 * (w * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz)))


def object_qpos(info: LiberoTaskInfo, state: np.ndarray) -> dict[str, np.ndarray]:
    """Each object's free-joint qpos in a flattened MuJoCo state (time first, then qpos)."""
    return {
        name: state[1 + ROBOT_QPOS + FREE_JOINT * k : 1 + ROBOT_QPOS + FREE_JOINT * (k + 1)]
        for k, name in enumerate(info.objects)
    }


def init_poses(info: LiberoTaskInfo, index: int) -> dict[str, Pose]:
    state = init_states(info.suite, info.task_id)[index]
    return {name: planar(q) for name, q in object_qpos(info, state).items()}


def world_key(objects) -> frozenset[str]:
    """Tasks whose objects are the same share a world: one LIBERO scene the simulator can stage any of them in."""
    return frozenset(objects)
