"""The sweep's cells as Ray tasks: one CPU each (and --ray.gpus_per_cell GPUs for a policy on cuda), retried on
another worker when theirs dies, watched through their journals for the progress view; on a cluster, with this
run directory brought back from nodes that do not see the sweep folder."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from pathlib import Path

import ray
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.sweep.carry import Carry, pack, unpack
from lerobot_contrast.sweep.cells import Cell, sharing_predecessors
from lerobot_contrast.sweep.settings import RayArgs as RayArgs  # where the scripts import it
from lerobot_contrast.sweep.shipping import ONE_THREAD
from lerobot_contrast.sweep.worker import CellOutcome, run_cell, wants_gpu

POLL_S = 0.5


def trials_recorded(cells: Sequence[Cell], finished: dict[str, int]) -> int:
    """Trials so far: a finished cell's count, else its journal's lines (on the driver's file system, which the
    workers share)."""
    return sum(finished.get(c.name, _journal_lines(Path(c.config.output_dir))) for c in cells)


def _journal_lines(run_dir: Path) -> int:
    try:
        with (run_dir / "journal.jsonl").open("rb") as handle:
            return sum(block.count(b"\n") for block in iter(lambda: handle.read(1 << 20), b""))
    except FileNotFoundError:
        return 0


def cell_gpus(cell: Cell, gpus_per_cell: float) -> float:
    """The GPUs `cell` asks Ray for: `gpus_per_cell` for a policy on cuda, none for one on the CPU."""
    return gpus_per_cell if wants_gpu(cell.config.policy) else 0.0


def check_gpus(cells: Sequence[Cell], gpus_per_cell: float) -> None:
    """Refuse GPU cells that no node of the joined Ray cluster can hold (Ray would leave them waiting forever)."""
    wanting = [cell for cell in cells if cell_gpus(cell, gpus_per_cell)]
    if not wanting:
        return
    most = max((node["Resources"].get("GPU", 0.0) for node in ray.nodes() if node["Alive"]), default=0.0)
    if most >= gpus_per_cell:
        return
    has = "has no GPU" if most == 0 else f"has at most {most:g} GPUs on one node"
    more = f" (and {len(wanting) - 1} more)" if len(wanting) > 1 else ""
    raise UserError(
        f"cell {wanting[0].name}{more} runs its policy on {wanting[0].config.policy.device} and asks Ray for "
        f"{gpus_per_cell:g} GPU, but the Ray cluster {has}; "
        "run the sweep where Ray has GPUs (ray start --num-gpus=N, or --ray.num_gpus=N for this machine's Ray), "
        "lower --ray.gpus_per_cell, or set policy.device: cpu"
    )


def run_cells(
    cells: Sequence[Cell],
    planned: dict[str, int],
    max_retries: int,
    report: Callable[[CellOutcome], None],
    console: Console,
    gpus_per_cell: float = 1.0,
    carry: Carry | None = None,
) -> list[CellOutcome]:
    """Run every cell as a Ray task and return their outcomes in the cells' order, calling `report` as each ends.
    A cell that would share episodes with an earlier one (`sharing_predecessors`) waits for it to end, so it takes
    that cell's episodes rather than running them beside it, unless a CPU would otherwise stand idle: then the
    earliest waiting cell starts at once (sharing what it finds), and the sweep takes no longer than without
    waiting. `carry` (on a cluster) takes the driver's copy of a started cell's run directory to a node that does
    not see the sweep folder; what such a node sends back lands there as the cell ends."""
    task = ray.remote(run_cell)
    cpus = max(1, int(ray.cluster_resources().get("CPU", 1)))

    def submit(cell: Cell) -> None:
        ref = task.options(
            num_cpus=1,
            num_gpus=cell_gpus(cell, gpus_per_cell),
            max_retries=max_retries,
            name=f"cell {cell.name}",
            runtime_env={"env_vars": ONE_THREAD},
        ).remote(cell.name, cell.config, cell.shared, _carried(carry, Path(cell.config.output_dir)))
        refs[ref] = cell
        pending.append(ref)

    predecessor = sharing_predecessors(list(cells))
    waiting = [cell for cell in cells if predecessor[cell.name] is not None]
    refs: dict[ray.ObjectRef, Cell] = {}
    pending: list[ray.ObjectRef] = []
    for cell in cells:
        if predecessor[cell.name] is None:
            submit(cell)
    finished: dict[str, int] = {}  # complete cells count as their whole plan (a budget may stop one earlier)
    outcomes = {}
    with _progress(console) as progress:
        cell_bar = progress.add_task("cells", total=len(cells))
        trial_bar = progress.add_task("trials", total=sum(planned.values()))
        while pending or waiting:
            while waiting and len(pending) < cpus:  # an idle CPU: the earliest waiting cell need not wait
                submit(waiting.pop(0))
            ready, pending[:] = ray.wait(pending, num_returns=len(pending), timeout=POLL_S)
            for ref in ready:
                outcome = _outcome(refs[ref], ref, max_retries)
                if outcome.run_dir is not None:
                    unpack(outcome.run_dir, Path(refs[ref].config.output_dir))
                    outcome = dataclasses.replace(outcome, run_dir=None)
                outcomes[outcome.name] = outcome
                if outcome.status == "complete":
                    finished[outcome.name] = planned[outcome.name]
                report(outcome)
                # Whatever its outcome, the cell waiting for it starts: it runs what it does not find shared.
                for follower in [c for c in waiting if predecessor[c.name] == outcome.name]:
                    waiting.remove(follower)
                    submit(follower)
            progress.update(cell_bar, completed=len(outcomes))
            progress.update(trial_bar, completed=trials_recorded(cells, finished))
    return [outcomes[cell.name] for cell in cells]


def _carried(carry: Carry | None, run_dir: Path) -> Carry | None:
    """`carry` with the driver's copy of a started cell's run directory, which a node without the folder resumes."""
    if carry is None or not (run_dir / "config.json").is_file():
        return carry
    return dataclasses.replace(carry, run_dir=pack(run_dir))


def _outcome(cell: Cell, ref: ray.ObjectRef, max_retries: int) -> CellOutcome:
    try:
        return ray.get(ref)
    except ray.exceptions.RayError as error:  # its worker died on every attempt, or its node is gone
        reason = " ".join(str(error).split())[:300]
        return CellOutcome(cell.name, "failed", error=f"lost after {max_retries + 1} attempts ({reason})")


def _progress(console: Console) -> Progress:
    return Progress(
        TextColumn("{task.description:>6}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=console,
        disable=not console.is_terminal,
    )
