"""Audited labels: a random share of the trials a camera labels is labelled by a person too, and prediction-powered
estimates (PPI++: Angelopoulos, Duchi and Zrnic, 2023) combine both into a success rate or a paired change whose 95%
interval covers whatever the camera's mistakes, clustered by base instance as the run's other intervals are.

Per trial j: f_j the run's label (the camera's, or a person's where the camera asked), a_j whether the audit drew it,
y_j the person's audit label. With p the share audited, u_j = a_j y_j / p and v_j = f_j (1 - a_j / p); the estimate
for a weight lambda is mean(u) + lambda mean(v): lambda = 0 is the audit alone, lambda = 1 the camera corrected by
its audited mistakes. Lambda is chosen to make the clustered variance least (PPI++'s power tuning), clipped to [0, 1],
and the interval uses Student's t with one degree of freedom fewer than the clusters. A small audit's variance is
floored (LAPLACE, below), in choosing lambda too. ppi_py's intervals are not clustered, so these are computed here
(docs/statistics.md)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lerobot_contrast.contrast.intervals import t_quantile

LAPLACE = 1.0  # pseudo audited trials in each cell of the audit's person-by-camera table, in the variance (below)
AUDIT_STREAM = 0xA0D17  # the audit's own random stream, apart from the plan's and the trials'


def audited(seed: int, index: int, fraction: float) -> bool:
    """Whether trial `index` of a run seeded `seed` is audited: a draw of its own, reproducible, made before the
    trial runs and blind to every label and to the camera's confidence."""
    return fraction > 0 and float(np.random.default_rng([seed, AUDIT_STREAM, index]).random()) < fraction


@dataclass(frozen=True)
class AuditedEstimate:
    mean: float
    low: float
    high: float
    weight: float  # the power-tuned lambda: 0 leans on the audit alone, 1 on the camera corrected by the audit
    n_trials: int
    n_audited: int
    n_clusters: int


def rate(labels, audit, person, clusters, confidence: float = 0.95) -> AuditedEstimate:
    """The success rate from every trial's `labels` (0/1), the `audit` mask and the `person`'s labels where
    audited, clustered by `clusters` (base ids)."""
    f, a, y = _arrays(labels, audit, person)
    return _estimate(f, a, y, np.ones(len(f)), np.asarray(clusters), confidence, bounds=(0.0, 1.0))


def paired_change(labels, audit, person, bases, perturbed, confidence: float = 0.95) -> AuditedEstimate:
    """The mean over bases of (a perturbation's label - its base's original's): each base gives one original
    trial and one perturbed trial (`perturbed` True), and is the cluster of both."""
    f, a, y = _arrays(labels, audit, person)
    signs = np.where(np.asarray(perturbed, dtype=bool), 1.0, -1.0)
    return _estimate(f, a, y, signs, np.asarray(bases), confidence, bounds=(-1.0, 1.0), per_cluster=True)


def _arrays(labels, audit, person) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    f = np.asarray(labels, dtype=np.float64)
    a = np.asarray(audit, dtype=bool)
    y = np.where(a, np.nan_to_num(np.asarray(person, dtype=np.float64)), 0.0)
    return f, a, y


def _estimate(f, a, y, signs, clusters, confidence: float, bounds, per_cluster: bool = False) -> AuditedEstimate:
    """`bounds`: the values the estimate can take, which the interval is kept within."""
    n_audited = int(a.sum())
    names, which = np.unique(clusters, return_inverse=True)
    if n_audited == 0 or len(names) < 2:
        return AuditedEstimate(float("nan"), float("nan"), float("nan"), float("nan"), len(f), n_audited, len(names))
    share = n_audited / len(f)
    u, v = signs * a * y / share, signs * f * (1 - a / share)
    cluster_u, cluster_v = np.bincount(which, u), np.bincount(which, v)
    sizes = np.ones(len(names)) if per_cluster else np.bincount(which).astype(np.float64)
    total = sizes.sum()
    mean_u, mean_v = cluster_u.sum() / total, cluster_v.sum() / total
    r, s = cluster_u - mean_u * sizes, cluster_v - mean_v * sizes  # each cluster's residual, linear in lambda
    g = len(names)
    spread = g / (g - 1) / total**2  # the clustered variance of the mean is spread * |r + lambda s|^2
    # A small audit may see no disagreement, or every audited label alike, and its variance then says the camera (or
    # the audit alone) cannot be wrong: lambda leans on it and the interval shrinks to a point. Laplace's rule:
    # LAPLACE more audited trials in each of the four cells (person 0/1 by camera 0/1), whose y - lambda f vary by
    # (1 + lambda^2) / 4, weigh in the variance as their share of the audited part, and lambda is tuned with them.
    cells = 4 * LAPLACE
    floor = cells / (n_audited + cells) / n_audited * (len(f) / total) ** 2 / 4
    weight = float(np.clip(-spread * (r @ s) / (spread * (s @ s) + floor), 0.0, 1.0))
    mean = mean_u + weight * mean_v
    residual = r + weight * s
    variance = spread * (residual @ residual) + floor * (1 + weight**2)
    half = t_quantile(g - 1, confidence) * np.sqrt(variance)
    low, high = max(bounds[0], mean - half), min(bounds[1], mean + half)
    return AuditedEstimate(float(mean), float(low), float(high), weight, len(f), n_audited, g)
