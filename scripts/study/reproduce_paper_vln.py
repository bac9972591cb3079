"""Reproduce the paper's real-robot navigation study (Section 6, Figure 4, appendix Figures 7-8) in the simulated
apartment, with the learned default navigator (vln_navigator).

Two designs, both run by the sweep engine (lerobot_contrast.sweep):
- the paper's exact design: its five participant arrangements (--task=vln_paper) x (original + ΔL, ΔLB, ΔS, ΔSB)
  x 3 repeats = 75 trials, metric progress to two subgoals, cost metres of furniture moved;
- the same design at scale (lerobot_contrast/sweep/studies/paper_vln.yaml): 3 seeds x 100 sampled arrangements (--task=vln), standard
  against contrast (all four, and each axis pair), cost as metres and, for standard and all four, as reset seconds.
  Each axis pair is the all-four run kept to its originals and that pair's trials, every trial charged what staging
  it costs from the scene the previous kept trial left: the pairs are then the very perturbations the all-four set
  ran (their differences are not a fresh draw's noise), and the study runs 200 fewer episodes a seed.
The scripted route follower runs both as a calibration row: it reads the goal from the instance, so ΔL cannot change
what it does and the other perturbations only give it a new route (it runs without rendering the camera it does not
read).

Usage: python scripts/study/reproduce_paper_vln.py [--output_dir outputs/paper_vln] [--seeds 0 1 2] [--n_instances 100]
       [--num_cpus N] [--paper_only] [--repeats 3] [--max_episode_steps N]
Writes OUTPUT_DIR/runs/... (a run per cell) and OUTPUT_DIR/reproduction.md (the table beside the paper's
figures, and a verdict per finding). Re-running resumes or skips finished runs. The last line is
`wall_s=... standard_cost_per_instance_m=... perturbation_cost_per_base_m=... ...` name=value pairs.
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

import numpy as np
from rich.console import Console

from lerobot_contrast.sweep.cells import flatten, read_sweep_file, studies_dir, sweep_cells
from lerobot_contrast.sweep.command import SweepConfig, execute
from lerobot_contrast.sweep.ray_pool import RayArgs

SWEEP = studies_dir() / "paper_vln.yaml"
PERTURBATIONS = ("L", "LB", "S", "SB")
# The paper's navigation figures (Section 6.2 and appendix C).
PAPER_STANDARD_COST_PER_INSTANCE_M = 8.8
PAPER_PERTURBATION_COST_PER_BASE_M = 1.0
PAPER_BUDGET_M = 35.0
PAPER_HIGHER_LB_SB = 0.13
AXIS_PAIRS = {"contrast_language": ("L", "LB"), "contrast_scene": ("S", "SB")}  # kept from contrast_all4
CEILING_GAP = 0.05  # the route follower's perturbations may score this far below its originals and count as unchanged
ERROR_BAR = 0.05  # |progress error| at which an estimate counts as reaching the standard's (the paper: "nearly")
ERROR_FRACTIONS = (0.1, 0.25, 0.5, 1.0)
ERROR_DESIGNS = {  # shown name: (the standard run that sets the full value and the cost, the design)
    "standard": ("standard", "standard"),
    "contrast, all four": ("standard", "contrast_all4"),
    "contrast, ΔL + ΔLB": ("standard", "contrast_language"),
    "contrast, ΔS + ΔSB": ("standard", "contrast_scene"),
    "standard, reset seconds": ("standard_reset", "standard_reset"),
    "contrast, all four, reset seconds": ("standard_reset", "contrast_all4_reset"),
}
TABLE_HEAD = ("| perturbation | trials | progress | paired against the same base's original |", "|---|---|---|---|")


def paper_spec(base: dict, repeats: int = 3) -> dict:
    """The paper's exact design: one run of 5 arrangements x 5 trials x 3 repeats, for each policy, and the
    standard evaluation of the same arrangements (its cost per instance is the paper's 8.8 m)."""
    contrast = {"strategy": "contrast", "perturbations": list(PERTURBATIONS)}
    return {
        "eval": {**base, "task": "vln_paper", "n_instances": 5, "repeats": repeats},
        "grid": {"seed": [0]},
        "cells": [
            {"name": "paper_standard", "strategy": "standard"},
            {"name": "paper_contrast", **contrast},
            {"name": "paper_route_follower", **contrast, "policy.type": "route_follower", "robot.camera": False},
        ],
    }


def run_spec(spec: dict, sweep: Path, runs_dir: Path, num_cpus: int | None) -> dict[tuple[str, int], Path]:
    cfg = SweepConfig(sweep=sweep, output_dir=runs_dir, resume=True, ray=RayArgs(None, num_cpus))
    outcomes = execute(cfg, spec, Console())
    failed = [name for name, outcome in outcomes.items() if outcome.status != "complete"]
    if failed:
        raise SystemExit(f"error: {len(failed)} runs failed ({', '.join(failed)}); see the lines above")
    return {(c.label, c.config.seed): Path(c.config.output_dir) for c in sweep_cells(sweep, spec, runs_dir)}


def load(dirs: dict[tuple[str, int], Path], design: str) -> list:
    from lerobot_contrast.reporting import load_run

    if design in AXIS_PAIRS:
        return [kept_to(run, AXIS_PAIRS[design]) for run in load(dirs, "contrast_all4")]
    return [load_run(str(path)) for (d, _), path in sorted(dirs.items()) if d == design]


def kept_to(run, axes: tuple[str, ...]):
    """`run` (a contrast run) as the contrast set of `axes` alone: its originals and those axes' trials in plan
    order, each charged what staging it costs from the scene the previous kept trial left (a language pair's
    resets then undo no scene perturbation it never made)."""
    from lerobot_contrast.contrast.cost import make_cost_model
    from lerobot_contrast.record.journal import read_journal
    from lerobot_contrast.reporting.stats import frame

    cost_model = make_cost_model(run.config.get("cost", "distance"))
    kept, scene, spent = [], None, 0.0
    for record in read_journal(run.path / "journal.jsonl"):
        if record.axis is not None and record.axis not in axes:
            continue
        cost = record.cost if scene is None or record.instance is None else cost_model(scene, record.instance.scene)
        spent += cost
        kept.append(dataclasses.replace(record, cost=cost, cumulative_cost=spent))
        if record.scene_after is not None:
            scene = record.scene_after
    return dataclasses.replace(run, results=frame(kept))


def progress_by_perturbation(runs: list) -> tuple[dict, dict]:
    """Progress per perturbation pooled over seeds, and each perturbation paired against its own bases."""
    import pandas as pd

    from lerobot_contrast.reporting import stats
    from lerobot_contrast.reporting.analysis import rng

    pooled = pd.concat([stats.frame(run.results) for run in runs], ignore_index=True)
    return stats.grouped_estimates(pooled, "perturbation", "progress"), stats.paired_sensitivity(
        pooled, "progress", rng()
    )


def costs(runs_standard: list, runs_contrast: list) -> dict[str, float]:
    """Standard cost per instance, perturbation cost per base, and trials within the paper's 35 m budget."""
    from lerobot_contrast.reporting import stats

    # Per instance and per base, not per trial: a repeat restages the same scene for nothing.
    per_instance = [
        stats.total_cost(r.results) / max(1, stats.frame(r.results)["base_id"].nunique()) for r in runs_standard
    ]
    per_base = []
    for run in runs_contrast:
        df = stats.done(stats.frame(run.results))
        perturbed = df[df["perturbation"].notna()]
        per_base.append(perturbed["cost"].sum() / max(1, df["base_id"].nunique()))
    return {
        "standard_per_instance": float(np.mean(per_instance)),
        "perturbation_per_base": float(np.mean(per_base)),
        "standard_in_budget": float(np.mean([stats.trials_at_cost(r.results, PAPER_BUDGET_M) for r in runs_standard])),
        "contrast_in_budget": float(np.mean([stats.trials_at_cost(r.results, PAPER_BUDGET_M) for r in runs_contrast])),
    }


def cost_rows(cost: dict[str, float]) -> list[str]:
    ratio = cost["contrast_in_budget"] / max(1.0, cost["standard_in_budget"])
    return [
        "| figure | this study | the paper |",
        "|---|---|---|",
        f"| standard evaluation's cost per instance | {cost['standard_per_instance']:.1f} m "
        f"| {PAPER_STANDARD_COST_PER_INSTANCE_M} m |",
        f"| cost of the four perturbations per base | {cost['perturbation_per_base']:.2f} m "
        f"| about {PAPER_PERTURBATION_COST_PER_BASE_M:.0f} m |",
        f"| trials within {PAPER_BUDGET_M:.0f} m: contrast / standard | {cost['contrast_in_budget']:.0f} / "
        f"{cost['standard_in_budget']:.0f} ({ratio:.1f}x) | nearly 3x |",
    ]


def error_at_cost(runs_standard: list, runs_other: list, fraction: float = 1.0) -> tuple[float, float, float]:
    """|estimate - full value| of `runs_other` at `fraction` of the standard run's total cost (mean over seeds),
    the trials it ran within that cost, and the standard's trials."""
    from lerobot_contrast.reporting import stats

    errors, trials, reference = [], [], []
    for standard, other in zip(runs_standard, runs_other, strict=True):
        truth, budget = stats.full_value(standard.results, "progress"), fraction * stats.total_cost(standard.results)
        errors.append(
            abs(stats.running_estimate(stats.frame(other.results), "progress", np.array([budget]))[0] - truth)
        )
        trials.append(stats.trials_at_cost(other.results, budget))
        reference.append(len(stats.done(standard.results)))
    affordable = [e for e in errors if not np.isnan(e)]  # NaN: no trial within the budget yet
    return float(np.mean(affordable)) if affordable else float("nan"), float(np.mean(trials)), float(np.mean(reference))


def error_table(dirs: dict, pairs: dict[str, tuple[str, str]]) -> list[str]:
    """The estimate's error against the standard evaluation as cost grows: one row per design, one column per
    share of the standard run's total cost (NaN: no trial affordable yet)."""
    head = " | ".join(f"{f:.0%} of its cost" for f in ERROR_FRACTIONS)
    lines = [f"| design | {head} |", "|---|" + "---|" * len(ERROR_FRACTIONS)]
    for shown, (ref, name) in pairs.items():
        standard, other = load(dirs, ref), load(dirs, name)  # read once a row: an axis pair re-reads the journals
        cells = []
        for fraction in ERROR_FRACTIONS:
            err, n, _ = error_at_cost(standard, other, fraction)
            cells.append(f"{err:.3f} ({n:.0f} trials)")
        lines.append(f"| {shown} | {' | '.join(cells)} |")
    return lines


def interval(e) -> str:
    return f"{e.mean:.3f} [{e.low:.3f}, {e.high:.3f}]"


def perturbation_table(runs: list) -> tuple[list[str], dict, dict]:
    from lerobot_contrast.contrast.perturbation import perturbation_label

    progress, paired = progress_by_perturbation(runs)
    rows = []
    for name, e in progress.items():
        shown = "original" if name == "original" else perturbation_label(name)
        d = paired.get(name)
        versus = "–" if d is None else f"{d.mean:+.3f} [{d.low:+.3f}, {d.high:+.3f}] ({d.n_clusters} bases)"
        rows.append(f"| {shown} | {e.n_trials} | {interval(e)} | {versus} |")
    return rows, progress, paired


def pooled_progress(runs: list) -> float:
    """The full contrast set's progress: the mean over all its trials (originals and perturbations), all seeds."""
    from lerobot_contrast.reporting import stats

    return float(np.mean([v for run in runs for v in stats.metric_values(run.results, "progress")["value"]]))


def holds(ok: bool) -> str:
    return "**holds**" if ok else "**does not hold**"


def side(progress: dict, paired: dict, contrast: float, names: tuple[str, ...], above: bool) -> str:
    """Whether each of `names` scores above (or below) the full contrast set, and why. It counts only where the
    full set's score lies outside the perturbation's own 95 % interval: a tie is not a finding. Its paired change
    against the same bases' originals is given beside it."""
    present = [n for n in names if n in progress]
    ok = bool(present) and all(
        (progress[n].low > contrast) if above else (progress[n].high < contrast) for n in present
    )
    parts = []
    for n in present:
        d, rel = paired.get(n), (progress[n].mean / contrast - 1) if contrast > 0 else float("nan")
        resolved = d is not None and (d.low > 0 or d.high < 0)
        why = (
            ""
            if d is None
            else (
                f"; against its originals {d.mean:+.3f} [{d.low:+.3f}, {d.high:+.3f}], "
                f"{'resolved' if resolved else 'within the interval of no change'}"
            )
        )
        parts.append(f"Δ{n} {interval(progress[n])} ({rel:+.0%}{why})")
    return f"{holds(ok)}: {'; '.join(parts)}; the full contrast set {contrast:.3f}"


def verdicts(progress: dict, paired: dict, contrast: float, found: dict, reset: dict, calibration: dict) -> list[str]:
    """The paper's navigation findings, each judged from this study's numbers, with the reason."""
    cheaper = found["trials_all4"] > found["trials_standard"]
    close = found["error_all4"] <= ERROR_BAR
    cheaper_s, close_s = reset["trials_all4"] > reset["trials_standard"], reset["error_all4"] <= ERROR_BAR
    original = progress["original"].mean if "original" in progress else float("nan")
    perturbed = float(np.mean([progress[p].mean for p in PERTURBATIONS if p in progress]))
    why = (
        f"it ran {found['trials_all4']:.0f} trials against {found['trials_standard']:.0f} for the standard's cost; "
        f"|progress error| {found['error_all4']:.3f} against the bar of {ERROR_BAR} "
        f"(its originals score {original:.3f}, its perturbations {perturbed:.3f} on average"
        + ("" if close else ": the perturbations move the estimate away from the i.i.d. value")
        + ")"
    )
    unchanged = "L" in calibration and max(abs(calibration["L"].low), abs(calibration["L"].high)) < 1e-9
    near = all(abs(calibration[p].mean) <= CEILING_GAP for p in PERTURBATIONS if p in calibration)
    return [
        f"1. Contrast sets reach the standard evaluation's estimate at less cost: {holds(cheaper and close)}: {why}.",
        f"2. ΔL and ΔS score below the full contrast set: {side(progress, paired, contrast, ('L', 'S'), False)}.",
        f"3. ΔLB and ΔSB score above it (the paper: {PAPER_HIGHER_LB_SB:.0%} higher): "
        f"{side(progress, paired, contrast, ('LB', 'SB'), True)}.",
        f"4. Reset seconds as the cost give the same conclusions as metres: "
        f"{holds(cheaper_s == cheaper and close_s == close)}: with reset seconds the contrast set ran "
        f"{reset['trials_all4']:.0f} trials against {reset['trials_standard']:.0f} for the standard's cost, "
        f"|progress error| {reset['error_all4']:.3f}.",
        f"5. Calibration: the route follower reads the goal, not the words, so ΔL (same goal) changes nothing, and "
        f"the perturbations with a new goal or scene leave it within {CEILING_GAP} of its originals: "
        f"{holds(unchanged and near)} (paired changes "
        + ", ".join(f"Δ{p} {calibration[p].mean:+.3f}" for p in PERTURBATIONS if p in calibration)
        + ").",
    ]


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--output_dir", type=Path, default=Path("outputs/paper_vln"))
    p.add_argument("--seeds", type=int, nargs="+", default=None)
    p.add_argument("--n_instances", type=int, default=None)
    p.add_argument("--repeats", type=int, default=3, help="repeats of the paper's exact design (the paper: 3)")
    p.add_argument("--max_episode_steps", type=int, default=None, help="steps per episode (default: the yaml's)")
    p.add_argument("--num_cpus", type=int, default=None, help="runs at once on this machine (default: its cores)")
    p.add_argument("--paper_only", action="store_true", help="run only the paper's exact 75-trial design")
    return p.parse_args(argv)


def paper_section(dirs: dict, repeats: int) -> tuple[list[str], list[str]]:
    rows, progress, _ = perturbation_table(load(dirs, "paper_contrast"))
    calibration, _, _ = perturbation_table(load(dirs, "paper_route_follower"))
    cost = costs(load(dirs, "paper_standard"), load(dirs, "paper_contrast"))
    lines = [
        f"## The paper's exact design: 5 arrangements x (original + 4 perturbations) x {repeats} repeats "
        f"= {25 * repeats} trials",
        "",
        f"Cost in metres of furniture moved (the standard evaluation of the same five arrangements, {repeats} "
        "repeats):",
        "",
        *cost_rows(cost),
        "",
        "Learned navigator (vln_navigator), progress to two subgoals (95 % intervals clustered by base):",
        "",
        *TABLE_HEAD,
        *rows,
        "",
        "Calibration, the scripted route follower (reads the goal, not the words):",
        "",
        *TABLE_HEAD,
        *calibration,
        "",
    ]
    figures = [f"paper_standard_cost_per_instance_m={cost['standard_per_instance']:.2f}"]
    return lines, [*figures, *(f"paper_progress_{k}={v.mean:.3f}" for k, v in progress.items())]


def scaled_section(dirs: dict) -> tuple[list[str], list[str]]:
    from lerobot_contrast.reporting import stats

    standard, all4 = load(dirs, "standard"), load(dirs, "contrast_all4")
    cost = costs(standard, all4)
    found, reset = {}, {}
    for key, name in {"all4": "contrast_all4", "standard": "standard"}.items():
        found[f"error_{key}"], found[f"trials_{key}"], _ = error_at_cost(standard, load(dirs, name))
    reset["error_all4"], reset["trials_all4"], reset["trials_standard"] = error_at_cost(
        load(dirs, "standard_reset"), load(dirs, "contrast_all4_reset")
    )
    rows, progress, paired = perturbation_table(all4)
    rf_rows, _, rf_paired = perturbation_table(load(dirs, "route_follower_contrast_all4"))
    contrast = pooled_progress(all4)
    lines = [
        f"## At scale: {len(standard)} seeds x {len(stats.done(stats.frame(standard[0].results)))} sampled arrangements, standard "
        "against contrast",
        "",
        *cost_rows(cost),
        "",
        "|progress error| against the standard evaluation's full value as cost grows (mean over seeds; the "
        "standard's own row converges to 0 at 100 %):",
        "",
        *error_table(dirs, ERROR_DESIGNS),
        "",
        "Progress per perturbation, learned navigator, all four, pooled over seeds:",
        "",
        *TABLE_HEAD,
        *rows,
        "",
        "Calibration, the route follower:",
        "",
        *TABLE_HEAD,
        *rf_rows,
        "",
        "The paper's navigation findings:",
        "",
        *verdicts(progress, paired, contrast, found, reset, rf_paired),
        "",
    ]
    figures = [
        f"standard_cost_per_instance_m={cost['standard_per_instance']:.2f}",
        f"perturbation_cost_per_base_m={cost['perturbation_per_base']:.2f}",
        f"trials_in_35m_contrast={cost['contrast_in_budget']:.0f}",
        f"trials_in_35m_standard={cost['standard_in_budget']:.0f}",
        f"abs_err_all4={found['error_all4']:.3f}",
        f"abs_err_all4_reset={reset['error_all4']:.3f}",
        f"progress_standard={np.mean([stats.full_value(r.results, 'progress') for r in standard]):.3f}",
        f"progress_contrast={contrast:.3f}",
    ]
    return lines, figures


def main(argv: list[str] | None = None) -> None:
    args = parse_args(argv)
    spec = read_sweep_file(SWEEP)
    spec["eval"] = flatten(spec.get("eval") or {})
    if args.n_instances is not None:
        spec["eval"]["n_instances"] = args.n_instances
    if args.max_episode_steps is not None:
        spec["eval"]["max_episode_steps"] = args.max_episode_steps
    if args.seeds is not None:
        spec["grid"] = {**(spec.get("grid") or {}), "seed": args.seeds}
    start = time.perf_counter()
    runs_dir = args.output_dir / "runs"
    paper = {**paper_spec(spec["eval"], args.repeats), "share_episodes": spec.get("share_episodes", False)}
    lines, figures = paper_section(run_spec(paper, SWEEP, runs_dir, args.num_cpus), args.repeats)
    if not args.paper_only:
        scaled, more = scaled_section(run_spec(spec, SWEEP, runs_dir, args.num_cpus))
        lines, figures = [*lines, *scaled], [*figures, *more]
    wall_s = time.perf_counter() - start
    text = "\n".join(["# The paper's navigation study in the simulated apartment", "", *lines])
    args.output_dir.mkdir(parents=True, exist_ok=True)
    (args.output_dir / "reproduction.md").write_text(text, encoding="utf-8")
    print(text)
    print(" ".join([f"wall_s={wall_s:.0f}", *figures]))


if __name__ == "__main__":
    main()
