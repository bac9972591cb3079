"""`--order=adaptive`: after each trial, run the planned trial with the most expected information per unit of
staging cost, given the outcomes so far.

Candidates are the trials still to run on the current base (its perturbations, staged in place) and the original of
the next base in planned order; moving on leaves the current base's remaining trials unrun. The information of a
trial is the reduction of the variance of its perturbation's mean (the original's counts twice: it is also the
headline), with each mean's variance from a Beta(1/2, 1/2)-smoothed estimate. Base instances are still visited in
their planned, i.i.d. order, so the originals' mean stays an unbiased estimate; which perturbations run on a base
depends on earlier outcomes, so the per-perturbation means become adaptive (see the README).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace

from lerobot_contrast.contrast.strategy import PlannedTrial
from lerobot_contrast.contrast.trial import TrialRecord

ORIGINAL = "original"
FREE = 1e-3  # staging cost added to every candidate, so that free (language) trials rank by information too


def _key(trial: PlannedTrial | TrialRecord) -> tuple[str, str | None, int]:
    return (trial.base.id if isinstance(trial, PlannedTrial) else trial.base_id, trial.perturbation, trial.repeat)


def information(history: Sequence[TrialRecord], perturbation: str | None, metric: str) -> float:
    """The expected reduction of the variance of `perturbation`'s mean from one more trial of it."""
    name = perturbation or ORIGINAL
    values = [
        float(getattr(r, metric)) for r in history
        if r.status == "done" and (r.perturbation or ORIGINAL) == name and getattr(r, metric) is not None
    ]  # fmt: skip
    n, total = len(values), sum(values)
    variance = (total + 0.5) * (n - total + 0.5) / (n + 1) ** 2
    gain = variance / ((n + 1) * (n + 2))
    return 2 * gain if perturbation is None else gain


def next_trial(
    plan: Sequence[PlannedTrial],
    history: Sequence[TrialRecord],
    staging_cost: Callable[[PlannedTrial], float | None],
    metric: str = "progress",
) -> PlannedTrial | None:
    """The next trial to run (indexed by its position in the run), or None when no base is left.

    `staging_cost(trial)`: what staging `trial` next would cost, None where it does not apply now.
    """
    ran = {_key(r) for r in history}
    bases = list(dict.fromkeys(t.base.id for t in plan))
    current = history[-1].base_id if history else None
    following = bases.index(current) + 1 if current is not None else 0
    candidates = [t for t in plan if t.base.id == current and _key(t) not in ran]
    candidates += [t for t in plan if following < len(bases) and t.base.id == bases[following]][:1]
    best, best_score = None, -1.0
    for trial in candidates:
        trial = replace(trial, index=len(history))
        cost = staging_cost(trial)
        if cost is None:
            continue
        score = information(history, trial.perturbation, metric) / (cost + FREE)
        if score > best_score:
            best, best_score = trial, score
    return best
