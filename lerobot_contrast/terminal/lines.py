"""Console output: one line per trial while running, and the dry-run plan an operator would follow."""

from __future__ import annotations

from lerobot_contrast.contrast.cost import CostModel
from lerobot_contrast.contrast.perturbation import perturbation_label as label
from lerobot_contrast.contrast.scene import Scene
from lerobot_contrast.contrast.staging import Move, staging_moves
from lerobot_contrast.contrast.trial import TrialRecord

# How an aborted episode ended (`extra["ended_by"]`), as the console says it.
ABORTED_BY = {"disconnected": "the robot disconnected", "estop": "emergency stop"}


def trial_line(record: TrialRecord, unit: str) -> str:
    head = f"[{record.index + 1:>4}] {label(record.perturbation):<9}"  # numbered from 1, as the console says
    if record.status == "not_applicable" or record.instance is None:
        return f"{head} not applicable here, skipped"
    if record.status == "skipped":
        return f"{head} skipped by the operator"
    if record.status == "aborted":
        ended_by = record.extra.get("ended_by")
        return (
            f"{head} aborted: {ABORTED_BY.get(ended_by, ended_by)} after {record.steps} steps; "
            f"cost={record.cost:.2f} {unit} total={record.cumulative_cost:.2f} {unit}  {record.instance.instruction!r}"
        )
    metric = f"success={int(bool(record.success))}"
    if record.spl is not None:
        metric += f" spl={record.spl:.2f}"
    return (
        f"{head} {metric:<22} cost={record.cost:6.2f} {unit} total={record.cumulative_cost:7.2f} {unit}"
        f"  steps={record.steps:<4} {record.instance.instruction!r}"
    )


def plan_lines(records: list[TrialRecord], initial_scene: Scene, cost: CostModel) -> list[str]:
    """The staging an operator follows, assuming the robot leaves each scene as it was staged."""
    unit = cost.unit
    lines = []
    scene = initial_scene
    for record in records:
        if record.status != "done" or record.instance is None:
            lines.append(
                f"[{record.index + 1:>4}] {label(record.perturbation):<9} {record.base_id}: not applicable, skipped"
            )
            continue
        target = record.instance.scene
        lines.append(
            f"[{record.index + 1:>4}] {label(record.perturbation):<9} {record.instance.id}  stage={record.staging:<8} "
            f"cost={record.cost:.2f} {unit} total={record.cumulative_cost:.2f} {unit}  {record.instance.instruction!r}"
        )
        for move in staging_moves(scene, target):
            start = "(off the table)" if move.start is None else f"({move.start.x:+.3f}, {move.start.y:+.3f})"
            end = "(off the table)" if move.end is None else f"({move.end.x:+.3f}, {move.end.y:+.3f})"
            lines.append(f"{'':>16}move {move.name:<16} {start} -> {end}  {_moved(move, scene, target, cost)}")
        scene = record.scene_after or target
    return lines


def _moved(move: Move, scene: Scene, target: Scene, cost: CostModel) -> str:
    """The distance moved; for an object brought in or taken away, what the cost model charges for it."""
    if move.start is not None and move.end is not None:
        return f"{move.distance:.3f} m"
    alone = cost(_only(scene, move.name), _only(target, move.name))
    return f"{'brought in' if move.start is None else 'taken away'}, charged {alone:.2f} {cost.unit}"


def _only(scene: Scene, name: str) -> Scene:
    return Scene({name: scene.objects[name]} if name in scene.objects else {})
