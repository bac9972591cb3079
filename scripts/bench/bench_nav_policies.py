"""Closed-loop figures of the VLN policies on held-out arrangements (the evaluation split, a seed training never
used): the learned navigator (shipped weights, or --model), a uniform random navigator and the scripted route
follower, all in the same simulator and on the same arrangements as scripts/train/train_nav_policy.py's final check.

    nice -n 10 .venv/bin/python scripts/bench/bench_nav_policies.py --n 250 --policies learned random route_follower

The last line is `n=... <policy>_success=... <policy>_progress=... <policy>_spl=...` for each policy.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import torch
from navigation_protocol import COMMANDS, discrete_command

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.trial import TrialContext
from lerobot_contrast.domains.vln.sampler import sample_arrangements
from lerobot_contrast.domains.vln.task import SUCCESS_RADIUS_M
from lerobot_contrast.policies.route_follower import RouteFollower
from lerobot_contrast.training.nav_episodes import NavSimulator
from lerobot_contrast.training.nav_learner import NavLearner, closed_loop
from lerobot_contrast.training.nav_recipe import NavRecipe


class RandomNavigator:
    """Uniform over the four commands each step (so it stops after four steps on average): the floor."""

    def __init__(self, seed: int) -> None:
        self.rng = np.random.default_rng(seed)

    def reset(self, instance: Instance) -> None:
        pass

    def act(self, observation, label=None) -> str:
        return COMMANDS[int(self.rng.integers(len(COMMANDS)))]


class FollowerActor:
    """The route follower (privileged: it reads the goal from the instance) fed the simulator's odometry."""

    def __init__(self) -> None:
        self.policy = RouteFollower()

    def reset(self, instance: Instance) -> None:
        rng = np.random.default_rng(0)
        self.policy.reset(TrialContext(0, instance, instance, instance.scene, 0.0, "reset", rng, 1))

    def act(self, observation, label=None) -> str:
        x, y, theta, _, _, bumper = observation["state"].tolist()
        action = self.policy.act({"odom.x": x, "odom.y": y, "odom.theta": theta, "bumper": bumper})
        return discrete_command(action) or "stop"


def main() -> None:
    recipe = NavRecipe()
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--n", type=int, default=recipe.eval_instances)
    p.add_argument("--seed", type=int, default=recipe.eval_seed)
    p.add_argument("--model", default=None, help="a vln_navigator checkpoint (default: the shipped weights)")
    p.add_argument("--policies", nargs="+", default=["learned", "random", "route_follower"])
    args = p.parse_args()
    torch.set_num_threads(1)
    instances = sample_arrangements(args.n, "eval", args.seed, SUCCESS_RADIUS_M)
    figures = [f"n={args.n}"]
    for name in args.policies:
        if name == "learned":
            from lerobot_policy_vln_navigator import WEIGHTS

            actor, simulator = NavLearner(args.model or WEIGHTS), NavSimulator()
        else:
            actor = RandomNavigator(args.seed) if name == "random" else FollowerActor()
            simulator = NavSimulator(camera=False)
        start = time.process_time()
        result = closed_loop(actor, simulator, instances, recipe.max_steps)
        print(f"{name}: {result} in {time.process_time() - start:.0f} CPU s", flush=True)
        figures += [f"{name}_{key}={value:.3f}" for key, value in result.items()]
    print(" ".join(figures))


if __name__ == "__main__":
    main()
