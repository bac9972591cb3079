"""The report's PNG figures (matplotlib, no display needed): the paper's two panels and its appendix figure."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from lerobot_contrast.contrast.metrics import METRIC_NAMES
from lerobot_contrast.contrast.perturbation import perturbation_label
from lerobot_contrast.reporting import stats
from lerobot_contrast.reporting.analysis import VersusFull

COLORS = [f"C{k}" for k in range(10)]


def color_of(labels: list[str]) -> dict[str, str]:
    return {label: COLORS[k % len(COLORS)] for k, label in enumerate(labels)}


def save(fig: Figure, path: Path) -> Path:
    for ax in fig.axes:  # below the axes, where it hides no data
        ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2, frameon=False)
    fig.savefig(path, dpi=150, bbox_inches="tight")
    return path


def _name(name: str) -> str:
    return {"original": "original", "all": "all trials"}.get(name) or perturbation_label(name)


def perturbation_plot(
    table: dict[str, dict[str, stats.Estimate]],
    order: list[str],
    metric: str,
    full: dict[str, float] | None,
    colors: dict[str, str],
) -> Figure:
    """Mean metric per perturbation with 95% intervals, one bar per group (the paper's left panels).

    Each bar carries its n; a perturbation a group has no trials of reads "n/a" (a bar of 0 would be a score)."""
    names = [n for n in order if any(n in per for per in table.values())]
    width = 0.8 / max(len(table), 1)
    fig = Figure(figsize=(max(6.0, 1.1 * len(names) + 3.0), 4.2))
    ax = fig.add_subplot()
    for k, (label, per) in enumerate(table.items()):
        offset = (k - (len(table) - 1) / 2) * width
        shown = [(i + offset, per[n]) for i, n in enumerate(names) if n in per and per[n].n_trials > 0]
        for x in [i + offset for i, n in enumerate(names) if n not in per or per[n].n_trials == 0]:
            ax.text(x, 0.01, "n/a", ha="center", va="bottom", fontsize=7, color="dimgray")
        if not shown:
            ax.bar([], [], width, color=colors[label], label=label)  # the group keeps its legend entry
            continue
        xs, est = zip(*shown, strict=True)
        means = np.array([e.mean for e in est])
        err = np.array([[e.mean - e.low for e in est], [e.high - e.mean for e in est]])
        ax.bar(xs, means, width, yerr=np.nan_to_num(err), capsize=3, color=colors[label], label=label)
        for x, e in shown:  # at the bar's foot, where no interval covers it and a bar of 0 still shows its n
            ax.text(x, 0.01, f"n={e.n_trials}", ha="center", va="bottom", fontsize=7)
    for k, (policy, value) in enumerate((full or {}).items()):  # one line per policy: a mean of two is neither's
        whose = "" if len(full) == 1 else f", {policy}"
        style = ("--", ":", "-.")[k % 3]
        label = f"full i.i.d. evaluation{whose} ({value:.3f})"
        ax.axhline(value, color="black", linestyle=style, linewidth=1, label=label)
    ax.set_xticks(range(len(names)), [_name(n) for n in names])
    ax.set_xlim(-0.6, len(names) - 0.4)
    ax.set_xlabel("trials (original = the i.i.d. base instances; all trials = the strategy's estimate)")
    ax.set_ylabel(f"mean {METRIC_NAMES[metric]} (95% interval)")
    ax.set_ylim(0.0, 1.05)
    ax.set_title(f"{METRIC_NAMES[metric]} per perturbation")
    return fig


def error_figure(
    versus: list[VersusFull], metric: str, unit: str, colors: dict[str, str], path: Path, cap: float | None = None
) -> Path:
    """|estimate - full i.i.d. value| against cumulative cost, mean and std over seeds (the right panels)."""
    fig = Figure(figsize=(7.5, 4.5))
    ax = fig.add_subplot()
    for v in versus:
        c = v.curve
        upto = _until(c.costs, v.end_cost)
        seeds = f"{v.seeds} seed" + ("s" if v.seeds > 1 else "")
        ax.plot(c.costs[upto], c.mean[upto], color=colors[v.label], label=f"{v.label} ({seeds})")
        low, high = (c.mean - c.std)[upto], (c.mean + c.std)[upto]
        ax.fill_between(c.costs[upto], low, high, color=colors[v.label], alpha=0.15, linewidth=0)
    _mark_standard_cost(ax, float(np.mean([v.reference_costs.mean() for v in versus])), unit)
    ax.set_xlim(0.0, cap if cap is not None else max(v.curve.costs[-1] for v in versus))
    ax.set_ylim(bottom=0.0)
    ax.set_xlabel(f"cumulative cost ({unit} of staging)")
    ax.set_ylabel(f"|estimated − full i.i.d. {METRIC_NAMES[metric]}|")
    ax.set_title(f"Estimation error of {METRIC_NAMES[metric]} vs cost (mean ± std over seeds)")
    return save(fig, path)


def _mark_standard_cost(ax, cost: float, unit: str) -> None:
    ax.axvline(cost, color="black", linestyle=":", linewidth=1, label=f"standard evaluation's cost ({cost:.0f} {unit})")


def _until(costs: np.ndarray, end: float) -> np.ndarray:
    """Bins up to and including the first one past `end`: a curve stops where its longest run stopped."""
    return np.arange(len(costs)) <= np.searchsorted(costs, end)


def trials_figure(
    costs: np.ndarray,
    curves: dict[str, tuple[np.ndarray, float]],
    unit: str,
    colors: dict[str, str],
    path: Path,
    reference: float | None = None,
) -> Path:
    """Done trials against cumulative cost per group: mean over seeds, shaded between the extreme seeds.

    `curves` maps a group to its (seeds, bins) counts and the cost where its longest run ended."""
    fig = Figure(figsize=(7.5, 4.5))
    ax = fig.add_subplot()
    for label, (counts, end) in curves.items():
        upto = _until(costs, end)
        ax.plot(costs[upto], counts.mean(axis=0)[upto], color=colors[label], label=label)
        if len(counts) > 1:
            low, high = counts.min(axis=0)[upto], counts.max(axis=0)[upto]
            ax.fill_between(costs[upto], low, high, color=colors[label], alpha=0.15, linewidth=0)
    if reference is not None:
        _mark_standard_cost(ax, reference, unit)
    ax.set_xlim(0.0, costs[-1])
    ax.set_ylim(bottom=0.0)
    ax.set_xlabel(f"cumulative cost ({unit} of staging)")
    ax.set_ylabel("trials run")
    ax.set_title("Trials run vs cost (mean over seeds, band: fewest to most)")
    return save(fig, path)
