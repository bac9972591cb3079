"""`python -m lerobot_contrast.sweep SWEEP.yaml`: many evaluations (a grid or list of eval settings) run as Ray
tasks, on this machine or a cluster, each into its own run directory under one sweep folder."""

from __future__ import annotations

import sys
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rich.console import Console

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.eval import planned_evaluation
from lerobot_contrast.extras import require_extra
from lerobot_contrast.record.journal import read_journal
from lerobot_contrast.spine.config import ConfigError
from lerobot_contrast.spine.flags import parse_config, usage_text, wants_help
from lerobot_contrast.sweep.cells import Cell, read_sweep_file, sweep_cells, sweep_file_path
from lerobot_contrast.sweep.settings import SweepConfig as SweepConfig  # where the scripts import it

if TYPE_CHECKING:
    from lerobot_contrast.sweep.worker import CellOutcome

COMMAND = "python -m lerobot_contrast.sweep SWEEP.yaml|STUDY"


def sweep_folder(cfg: SweepConfig, spec: dict) -> Path:
    from lerobot_contrast.record.sweep_dir import is_sweep_dir  # pandas: after the flags are checked

    given = cfg.output_dir or spec.get("output_dir")
    folder = Path(given) if given else Path("outputs/sweeps") / cfg.sweep.stem
    if folder.exists() and any(folder.iterdir()) and not cfg.resume and not cfg.dry_run:
        what = "a sweep folder" if is_sweep_dir(folder) else "not empty"
        raise ConfigError(f"--output_dir: {folder} is {what}; pass --resume=true to continue it or choose another")
    return folder


def plan_cells(cells: list[Cell]) -> dict[str, int]:
    """Each cell's planned trials; planning every cell first reports a bad setting before anything runs."""
    planned = {}
    for cell in cells:
        try:
            planned[cell.name] = len(planned_evaluation(cell.config).plan)
        except UserError as error:
            raise ConfigError(f"cell {cell.name}: {error}") from None
    return planned


def outcome_line(outcome: CellOutcome) -> str:
    if outcome.status == "complete":
        return f"{outcome.name}: complete, {outcome.trials} trials in {outcome.seconds:.0f} s"
    return f"{outcome.name}: failed: {outcome.error}"


def index_entries(cells: list[Cell], outcomes: dict[str, CellOutcome]) -> list[dict]:
    entries = []
    for cell in cells:
        outcome = outcomes.get(cell.name)
        entry = {"name": cell.name, "settings": cell.settings, "status": "pending"}
        if outcome is not None:
            entry |= {"status": outcome.status, "trials": outcome.trials, "seconds": round(outcome.seconds, 1)}
            entry |= {"cpu_s": round(outcome.cpu_s, 1), "node": outcome.node, "pid": outcome.pid}
            entry |= {"policy_loaded": outcome.policy_loaded, "error": outcome.error}
            entry |= {"gpus": outcome.gpus, "cuda_visible_devices": outcome.cuda_visible_devices}
        entries.append(entry)
    return entries


def run_sweep(cfg: SweepConfig, console: Console) -> int:
    """Run the sweep file cfg.sweep names; the exit code is 1 when any cell failed."""
    if cfg.sweep is None:
        raise ConfigError(f"give the sweep file: {COMMAND}")
    cfg.ray.check()
    cfg.sweep = sweep_file_path(cfg.sweep)
    outcomes = execute(cfg, read_sweep_file(cfg.sweep), console)
    return int(any(outcome.status != "complete" for outcome in outcomes.values()))


def execute(cfg: SweepConfig, spec: dict[str, Any], console: Console) -> dict[str, CellOutcome]:
    """Run the cells of `spec` (a sweep file's contents, read from cfg.sweep) that are not complete yet, then
    write the sweep index and results table; every cell's outcome by name (none with --dry_run)."""
    # Ray, pandas, LeRobot and torch load here, once the flags are known to be sound; a wrong address or token is
    # said before LeRobot and torch load.
    from lerobot_contrast.sweep.cluster import join, reach

    if cfg.ray.address and not cfg.dry_run:
        reach(cfg.ray.address)
    from lerobot_contrast.record.sweep_dir import is_complete, write_index, write_sweep_results
    from lerobot_contrast.sweep.carry import Carry, mark_folder
    from lerobot_contrast.sweep.ray_pool import check_gpus, run_cells

    folder = sweep_folder(cfg, spec)
    cells = sweep_cells(cfg.sweep, spec, folder)
    planned = plan_cells(cells)
    if cfg.dry_run:
        for cell in cells:
            console.print(f"{cell.name}: {planned[cell.name]} planned trials", highlight=False, soft_wrap=True)
        console.print(f"{len(cells)} cells into {folder}", highlight=False, soft_wrap=True)
        return {}
    outcomes = {c.name: _finished(c) for c in cells if is_complete(Path(c.config.output_dir))}
    todo = [cell for cell in cells if cell.name not in outcomes]
    if todo:  # Ray is joined, and its GPUs checked, before the sweep folder is written
        join(cfg.ray)
        check_gpus(todo, cfg.ray.gpus_per_cell)
    folder.mkdir(parents=True, exist_ok=True)
    write_index(folder, index_entries(cells, outcomes))
    if outcomes:
        console.print(f"{len(outcomes)} of {len(cells)} cells already complete", highlight=False, soft_wrap=True)
    if todo:
        report = partial(_report, console, folder)
        # On a cluster, nodes that do not find this folder's id in it run their cells on their own disk.
        carry = Carry(mark_folder(folder), folder.resolve(), None, cfg.ray.bring_back_recordings)
        carry = carry if cfg.ray.address else None
        ran = run_cells(todo, planned, cfg.max_retries, report, console, cfg.ray.gpus_per_cell, carry)
        outcomes |= {outcome.name: outcome for outcome in ran}
    entries = index_entries(cells, outcomes)
    write_index(folder, entries)
    table = write_sweep_results(folder, entries)
    failed = sum(outcome.status != "complete" for outcome in outcomes.values())
    console.print(
        f"sweep: {len(cells) - failed} of {len(cells)} cells complete, {failed} failed; results: {table}",
        highlight=False,
        soft_wrap=True,
    )
    return outcomes


def _finished(cell: Cell) -> CellOutcome:
    from lerobot_contrast.sweep.worker import CellOutcome

    return CellOutcome(cell.name, "complete", len(read_journal(Path(cell.config.output_dir) / "journal.jsonl")))


def _report(console: Console, folder: Path, outcome: CellOutcome) -> None:
    """One line per cell as it ends; an unexpected error's traceback goes to logs/<cell>.log."""
    line = outcome_line(outcome)
    if outcome.detail is not None:
        log = folder / "logs" / f"{outcome.name}.log"
        log.parent.mkdir(exist_ok=True)
        log.write_text(outcome.detail, encoding="utf-8")
        line += f" (traceback in {log})"
    console.print(line, highlight=False, soft_wrap=True)


def main(argv: list[str] | None = None) -> int:
    console = Console()
    try:
        argv = list(sys.argv[1:] if argv is None else argv)
        if wants_help(argv):
            print(usage_text(SweepConfig, f"{COMMAND} [--flag=value | --flag value] ..."))
            return 0
        require_extra("sweep", "python -m lerobot_contrast.sweep")
        # The sweep file as the first argument, or as --sweep=PATH.
        return run_sweep(parse_config(SweepConfig, argv, positional="sweep"), console)
    except KeyboardInterrupt:
        print(
            "\ninterrupted: every finished trial is in its cell's journal; continue with --resume=true", file=sys.stderr
        )
        return 130
    except UserError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
