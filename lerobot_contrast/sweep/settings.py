"""The sweep command's flags (light: read and checked before Ray, LeRobot or torch load)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path


@dataclass
class RayArgs:
    # The Ray cluster to join: auto (the one `ray start --head` runs on this machine) or ray://HOST:10001 (a
    # remote head's client port). Default: start a Ray for this sweep on this machine only.
    address: str | None = None
    # CPUs of the Ray started on this machine, which is how many cells run at once (default: all its cores).
    num_cpus: int | None = None


@dataclass
class SweepConfig:
    """Run a sweep of contrast-set evaluations on Ray: every cell a simulated evaluation in its own run directory."""

    # The sweep file (YAML, also given as the first argument): `eval` (settings every cell shares), `grid` (lists
    # of values; every combination is a cell), `cells` (a list of settings to override, each with an optional
    # `name` standing for them in the cell's directory name), and optionally `output_dir`.
    sweep: Path | None = None
    # The sweep folder, which holds one run directory per cell (default: the sweep file's output_dir, else
    # outputs/sweeps/<sweep file name>). On a cluster it must be storage every node mounts at the same path.
    output_dir: Path | None = None
    # Continue the sweep in the sweep folder: skip complete cells and resume the others from their journals.
    resume: bool = False
    # Times Ray reruns a cell whose worker process dies; each attempt resumes from the cell's journal.
    max_retries: int = 3
    # List the cells and their planned trials, then exit without running anything.
    dry_run: bool = False
    ray: RayArgs = field(default_factory=RayArgs)
