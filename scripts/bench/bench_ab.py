"""Interleaved A/B session on the simulated tabletop (issue 30): the learned default against its noisier copy
(--policy.noise_std=0.02), every trial run by both from the same staged scene. Figures last:
pairs=... restage_cost_share=... bases_to_decide=... fixed_n_bases=...

- pairs: trials both policies ran to a label (the paired differences rest on them);
- restage_cost_share: the share of the session's experimenter cost spent restaging for the second policy;
- bases_to_decide: complete bases after which the session's sequential paired test (per base, at --alpha) was
  decided, the point where --stop.decided=true ends it ("undecided>N" when the plan's N bases did not decide);
- fixed_n_bases: the fewest bases a fixed-n paired t-test at --alpha needs for the power the sequential test has
  on these bases (resampled with replacement, as scripts/study/savings_sequential.py does).

    .venv/bin/python scripts/bench/bench_ab.py [--n_instances=40] [--perturbations=LB1,SB1] [--max_episode_steps=200]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parents[1] / "study"))
from savings_sequential import compare_stop, fixed_bases_at_power, tables  # noqa: E402

COPY = "tabletop_pointer:noise_std=0.02"


def session(args: argparse.Namespace, pair: Path) -> dict:
    from lerobot_contrast.eval import main

    flags = [
        f"--policies=tabletop_pointer,{COPY}", f"--n_instances={args.n_instances}", f"--seed={args.seed}",
        f"--max_episode_steps={args.max_episode_steps}", f"--stop.alpha={args.alpha}", "--rerun=false",
        f"--output_dir={pair}",
    ]  # fmt: skip
    if args.perturbations:
        flags.append(f"--perturbations={args.perturbations}")
    if main(flags) != 0:
        sys.exit("bench_ab: the interleaved session failed")
    return json.loads((pair / "summary.json").read_text())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n_instances", type=int, default=40)
    parser.add_argument("--perturbations", default=None, help="default: all of the task's")
    parser.add_argument("--max_episode_steps", type=int, default=200)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--alpha", type=float, default=0.05)
    parser.add_argument("--studies", type=int, default=400, help="resampled sessions for the fixed-n power")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        pair = Path(tmp) / "pair"
        start = time.perf_counter()
        summary = session(args, pair)
        wall = time.perf_counter() - start
        index = json.loads((pair / "pairs.json").read_text())["policies"]
        _, _, own, paired, _ = tables(pair / index[0]["name"], pair / index[1]["name"])
    test = summary["stopping"]["pairs"][0]
    draws = np.random.default_rng(args.seed).integers(0, len(own), size=(args.studies, 4 * len(own)))
    power = float(np.mean(~np.isnan(compare_stop(own, paired, draws, args.alpha))))
    fixed = fixed_bases_at_power(own, paired, draws, power, args.alpha)
    decided = test["decided_at_bases"] or f"undecided>{summary['stopping']['complete_bases']}"
    print(f"session: {summary['trials']} planned trials in {wall:.0f} s; difference {test['difference_interval']}")
    print(f"sequential power on these bases (resampled, {4 * len(own)} bases at most): {power:.2f}")
    print(
        f"pairs={int(np.sum(~np.isnan(own) & ~np.isnan(paired)))} "
        f"restage_cost_share={summary['cost']['restage_share']:.3f} bases_to_decide={decided} "
        f"fixed_n_bases={'nan' if np.isnan(fixed) else int(fixed)}"
    )


if __name__ == "__main__":
    main()
