"""The sweep command's flags (light: read and checked before Ray, LeRobot or torch load)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from lerobot_contrast.contrast.errors import UserError


@dataclass
class RayArgs:
    # The Ray cluster to join: auto (the one `ray start --head` runs on this machine), HOST:6379 (a head's port, from
    # a node of the cluster) or ray://HOST:10001 (a head's client port, from any machine). This project's code is
    # shipped to its nodes. Default: start a Ray for this sweep on this machine only.
    address: str | None = None
    # CPUs of the Ray started on this machine, which is how many cells run at once (default: all its cores).
    num_cpus: int | None = None
    # GPUs each cell whose policy.device is cuda asks Ray for: 1 gives it a GPU of its own, a fraction (0.25) lets
    # that many cells (4) share one; a cell on the CPU asks for none.
    gpus_per_cell: float = 1.0
    # GPUs of the Ray started on this machine (default: those Ray finds).
    num_gpus: int | None = None
    # On a node that cannot see the sweep folder (no shared storage), whether a cell's Rerun recordings and dataset
    # come back to it with the cell's journal, results and summary.
    bring_back_recordings: bool = True

    def check(self) -> None:
        """Refuse a GPU request Ray cannot express (draccus would hide why, so it is checked after parsing)."""
        whole = float(self.gpus_per_cell).is_integer()
        if not (0 < self.gpus_per_cell <= 1 or (self.gpus_per_cell > 1 and whole)):
            raise UserError(
                f"--ray.gpus_per_cell must be a fraction of one GPU (0.25) or a whole number of GPUs, "
                f"got {self.gpus_per_cell:g}"
            )
        if self.num_gpus is not None and self.num_gpus < 0:
            raise UserError(f"--ray.num_gpus must be 0 or more, got {self.num_gpus}")


@dataclass
class SweepConfig:
    """Run a sweep of contrast-set evaluations on Ray: every cell a simulated evaluation in its own run directory."""

    # The sweep file (YAML, also given as the first argument): `eval` (settings every cell shares), `grid` (lists
    # of values; every combination is a cell), `cells` (a list of settings to override, each with an optional
    # `name` standing for them in the cell's directory name), and optionally `output_dir`.
    sweep: Path | None = None
    # The sweep folder, which holds one run directory per cell (default: the sweep file's output_dir, else
    # outputs/sweeps/<sweep file name>). On a cluster, nodes that do not see it write each cell on their own disk
    # and send its run directory back here as the cell ends.
    output_dir: Path | None = None
    # Continue the sweep in the sweep folder: skip complete cells and resume the others from their journals.
    resume: bool = False
    # Times Ray reruns a cell whose worker process dies; each attempt resumes from the cell's journal.
    max_retries: int = 3
    # List the cells and their planned trials, then exit without running anything.
    dry_run: bool = False
    ray: RayArgs = field(default_factory=RayArgs)
