"""The dataset card (README.md) of a published run: what was evaluated, the method, the results and figures,
and how to load, review, compare and re-run it. Its YAML `configs` make the Hub viewer show the results table."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

from huggingface_hub import DatasetCardData

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.perturbation import perturbation_label

PAPER = "https://arxiv.org/abs/2406.13636"
CITATION = """@InProceedings{anwar2024contrast,
  title     = {Contrast Sets for Evaluating Language-Guided Robot Policies},
  author    = {Anwar, Abrar and Gupta, Rohan and Thomason, Jesse},
  booktitle = {Proceedings of The 8th Conference on Robot Learning},
  series    = {Proceedings of Machine Learning Research},
  volume    = {270},
  pages     = {2205--2219},
  year      = {2025}
}"""
AXES = (
    ("ΔL", "wording", "same"),
    ("ΔLB", "wording", "different"),
    ("ΔS", "scene", "same"),
    ("ΔSB", "scene", "different"),
)


def _get(data: dict[str, Any], dotted: str) -> Any:
    for part in dotted.split("."):
        data = data.get(part) if isinstance(data, dict) else None
    return data


def _evaluated(config: dict[str, Any]) -> list[tuple[str, str]]:
    policy = _get(config, "policy.path") or _get(config, "policy.type") or "oracle"  # PolicyArgs' default
    revision = _get(config, "policy.revision") or "-"
    robot = f"`{_get(config, 'robot.type') or '?'}`"
    families = ", ".join(config.get("families") or []) or "all"
    settings = {k: v for k, v in (config.get("policy") or {}).items() if k not in ("type", "path", "revision")}
    return [
        ("policy", f"`{policy}`"),
        ("policy revision", f"`{revision}`"),
        ("policy settings", ", ".join(f"`{k}={v}`" for k, v in settings.items()) or "-"),
        ("robot", robot),
        ("task", f"`{config.get('task', '?')}` (families: {families})"),
    ]


def _perturbations(config: dict[str, Any], names: list[str]) -> list[str]:
    """One line per perturbation the run applied, with its axis and description from the task when known."""
    described: dict[str, tuple[str, str]] = {}
    try:
        from lerobot_contrast.domains import load_task

        task = load_task(config.get("task", ""))
        described = {p.name: (p.axis, p.description) for p in task.perturbations}
    except (UserError, ImportError):  # a task this installation does not know: list the names alone
        described = {}
    lines = []
    for name in names:
        axis, description = described.get(name, ("?", ""))
        lines.append(f"  - {perturbation_label(name)} (Δ{axis}){': ' + description if description else ''}")
    return lines or ["  - none (an i.i.d. evaluation)"]


def _summary_table(summary: dict[str, Any]) -> list[str]:
    unit = _get(summary, "settings.cost_unit") or ""

    def fmt(value: Any, pattern: str = "{:.3f}") -> str:
        return "-" if value is None else pattern.format(value)

    lines = [f"| perturbation | trials | n/a | success | SPL | cost ({unit}) |", "|---|---:|---:|---:|---:|---:|"]
    rows = summary.get("per_perturbation", {})
    for name in ["original", *(n for n in rows if n != "original")]:
        if name in rows:
            s = rows[name]
            label = perturbation_label(None if name == "original" else name)
            lines.append(
                f"| {label} | {s['trials']} | {s['not_applicable']} | {fmt(s['success_rate'])} | {fmt(s['spl'])} "
                f"| {fmt(s['cost'], '{:.2f}')} |"
            )
    total = summary.get("overall", {})
    lines.append(
        f"| **all** | {total.get('trials')} | {total.get('not_applicable')} | {fmt(total.get('success_rate'))} "
        f"| {fmt(total.get('spl'))} | {fmt(total.get('cumulative_cost'), '{:.2f}')} |"
    )
    return lines


def _report(run_dir: Path) -> tuple[list[str], list[str]]:
    """report/report.md with headings nested under the card's and its links pointing into report/; plus
    the figures it does not show itself."""
    report_dir = run_dir / "report"
    text = (report_dir / "report.md").read_text(encoding="utf-8") if (report_dir / "report.md").is_file() else ""
    text = re.sub(r"^(#{1,4}) ", r"##\1 ", text, flags=re.MULTILINE)
    text = re.sub(r"\]\((?!https?:|/|#|report/)([^)]+)\)", r"](report/\1)", text)
    figures = sorted(p.name for p in report_dir.glob("*.png")) if report_dir.is_dir() else []
    extra = [f"![{Path(name).stem}](report/{name})" for name in figures if f"report/{name}" not in text]
    return (text.strip().splitlines() if text else []), extra


def _configs(has_frames: bool) -> list[dict[str, Any]]:
    configs = [
        {"config_name": "results", "data_files": [{"split": "train", "path": "results.parquet"}], "default": True}
    ]
    if has_frames:
        configs.append(
            {"config_name": "frames", "data_files": [{"split": "train", "path": "dataset/data/*/*.parquet"}]}
        )
    return configs


def _method(config: dict[str, Any], summary: dict[str, Any]) -> list[str]:
    budget, unit = config.get("budget"), _get(summary, "settings.cost_unit") or ""
    spent = summary.get("overall", {}).get("cumulative_cost", 0.0)
    names = [n for n in summary.get("per_perturbation", {}) if n != "original"]
    return [
        f"Contrast sets ([Anwar, Gupta and Thomason, CoRL 2024]({PAPER})): each i.i.d. test instance is followed by",
        "small, specific perturbations run in the scene the robot left behind, within an experimenter-cost budget.",
        "",
        "| axis | changes | expected behaviour |",
        "|---|---|---|",
        *(f"| {a} | {c} | {b} |" for a, c, b in AXES),
        "",
        f"- strategy: `{config.get('strategy', '?')}`, order `{config.get('order', 'iid')}`, "
        f"{config.get('n_instances', '?')} base instances, {config.get('repeats', 1)} repeat(s), seed {config.get('seed', '?')}",
        f"- budget: {'none' if budget is None else f'{budget:g} {unit}'} (cost model `{config.get('cost', '?')}`); "
        f"spent {spent:.2f} {unit}; run {'complete' if summary.get('complete') else 'incomplete'}",
        "- perturbations:",
        *_perturbations(config, names),
    ]


def _files(has_frames: bool) -> list[str]:
    lines = [
        "- `results.parquet` (config `results`): one row per trial: instance, perturbation, staging, cost, metrics",
        "- `summary.json`, `config.json`, `journal.jsonl`: the summary, every setting (rebuilds the plan), the journal",
        "- `rerun/episode_NNNNNN.rrd`: one Rerun recording per episode (camera, scene map, instruction, actions,"
        " outcome); `rerun/episode_layout.rbl` lays several out alike",
    ]
    if has_frames:
        lines.append("- `dataset/`: the episodes as a LeRobotDataset v3 (config `frames`), with `eval.*` columns")
    return lines


def _usage(repo_id: str, episode_url: str | None) -> list[str]:
    return [
        "```python",
        "from datasets import load_dataset",
        "",
        f'results = load_dataset("{repo_id}", "results", split="train").to_pandas()',
        'print(results.groupby("perturbation", dropna=False)[["success", "spl", "cost"]].mean())',
        "```",
        "",
        "```bash",
        "# compare with a local run; run the same contrast set against another policy",
        f"python -m lerobot_contrast.report hub:{repo_id} my_run/",
        f"python -m lerobot_contrast.eval --plan hub:{repo_id} --policy.path=...",
        "# review episodes: each base instance beside its perturbations",
        f"hf download {repo_id} --repo-type dataset --local-dir run",
        "python -m lerobot_contrast.review run --perturbation=original,LB1 --web",
        *([f"rerun {episode_url}  # or open one episode directly"] if episode_url else []),
        "```",
    ]


def dataset_card(run_dir: Path, repo_id: str, endpoint: str, has_frames: bool) -> str:
    """README.md for the run's dataset repo: YAML metadata (viewer configs, tags), then the sections."""
    config = json.loads((run_dir / "config.json").read_text(encoding="utf-8"))
    summary = json.loads((run_dir / "summary.json").read_text(encoding="utf-8"))
    evaluated = _evaluated(config)
    task, policy = config.get("task", "?"), evaluated[0][1].strip("`")
    data = DatasetCardData(
        pretty_name=f"Contrast-set evaluation: {policy} on {task}",
        task_categories=["robotics"],
        tags=["LeRobot", "lerobot-contrast", "contrast-sets", "evaluation"],
        configs=_configs(has_frames),
    )
    report, figures = _report(run_dir)
    episodes = sorted(p.relative_to(run_dir).as_posix() for p in run_dir.glob("rerun/episode_*.rrd"))
    episode_url = f"{endpoint}/datasets/{repo_id}/resolve/main/{episodes[0]}" if episodes else None
    sections = [
        (f"# Contrast-set evaluation of `{policy}` on `{task}`", [
            "Made with lerobot-contrast, a LeRobot plugin. One row of `results.parquet` per trial; every episode",
            "can be replayed in Rerun.",
        ]),
        ("## What was evaluated", ["| | |", "|---|---|", *(f"| {k} | {v} |" for k, v in evaluated)]),
        ("## Method", _method(config, summary)),
        ("## Results", [*(report or _summary_table(summary)), *(line for f in figures for line in ("", f))]),
        ("## Files", _files(has_frames)),
        ("## Use it", _usage(repo_id, episode_url)),
        ("## Citation", ["```bibtex", CITATION, "```"]),
    ]  # fmt: skip
    body = "\n\n".join(heading + "\n\n" + "\n".join(lines) for heading, lines in sections)
    return f"---\n{data.to_yaml()}\n---\n\n{body}\n"
