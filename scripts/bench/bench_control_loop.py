"""Control-loop timing of the evaluator on CPU: a LeRobot policy (a small random ACT) drives the simulated
tabletop at 10 and 30 Hz through the same RobotRunner used on hardware.

Reported per rate: the jitter of the step period (standard deviation of the intervals between steps, ms) and the
evaluator's own overhead per step as a fraction of the period: the loop's busy time minus the time spent in
the robot (get_observation, send_action) and the policy (act), measured in the same run.

Last line: overhead_frac_10hz=... overhead_frac_30hz=... jitter_ms=...
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from lerobot_contrast.contrast.trial import TrialContext
from lerobot_contrast.domains.language_table import LanguageTableTask
from lerobot_contrast.domains.language_table.config_language_table_sim import LanguageTableSimConfig
from lerobot_contrast.domains.language_table.language_table_sim import LanguageTableSim
from lerobot_contrast.policies.pretrained import PretrainedPolicy, save_fresh_policy
from lerobot_contrast.record.observer import QuietObserver
from lerobot_contrast.spine.runner import RobotRunner

SMALL_ACT = {
    "dim_model": 128,
    "n_heads": 4,
    "n_encoder_layers": 2,
    "n_decoder_layers": 1,
    "chunk_size": 10,
    "n_action_steps": 10,
}


class Clock:
    """Wraps a callable and adds its wall time to a running total."""

    def __init__(self) -> None:
        self.total = 0.0

    def wrap(self, fn):
        def timed(*args, **kwargs):
            start = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                self.total += time.perf_counter() - start

        return timed


class StepTimes(QuietObserver):
    """An episode observer that records when each step's action was sent."""

    def start(self, context, features, pose_keys):
        self.times = []

    def step(self, timestamp_s, observation, action):
        self.times.append(time.perf_counter())


def episode(robot, policy, instance, fps: float | None, steps: int) -> tuple[float, list[float], float]:
    """Run one episode; returns (wall seconds, step send times, seconds inside robot and policy)."""
    clock, times = Clock(), StepTimes()
    robot.get_observation = clock.wrap(type(robot).get_observation.__get__(robot))
    robot.send_action = clock.wrap(type(robot).send_action.__get__(robot))
    policy.act = clock.wrap(type(policy).act.__get__(policy))
    # A task that is never achieved keeps the episode running for exactly `steps` steps.
    runner = RobotRunner(robot, policy, NeverDone(), operator=None, fps=fps, max_steps=steps, observers=[times])
    context = TrialContext(0, instance, instance, instance.scene, 0.0, "reset", np.random.default_rng(0), 1)
    start = time.perf_counter()
    runner(context)
    return time.perf_counter() - start, times.times, clock.total


class NeverDone(LanguageTableTask):
    def is_achieved(self, instance, scene) -> bool:
        return False


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=4.0, help="episode length at each rate")
    args = parser.parse_args()
    robot = LanguageTableSim(LanguageTableSimConfig())
    robot.connect()
    with tempfile.TemporaryDirectory() as tmp:
        path = save_fresh_policy(robot, "act", Path(tmp) / "act", device="cpu", **SMALL_ACT)
        policy = PretrainedPolicy(robot, str(path))
    instance = LanguageTableTask().sample(1, np.random.default_rng(0))[0]
    episode(robot, policy, instance, None, 20)  # warm-up: first inference, renderer start
    figures = {}
    jitters = []
    for fps in (10, 30):
        steps = int(args.seconds * fps)
        busy_wall, _, inside = episode(robot, policy, instance, None, steps)
        overhead = (busy_wall - inside) / steps
        _, times, _ = episode(robot, policy, instance, fps, steps)
        intervals = np.diff(times)
        jitter_ms = float(np.std(intervals) * 1e3)
        jitters.append(jitter_ms)
        print(
            f"{fps} Hz: period {np.mean(intervals) * 1e3:.2f} ms (target {1e3 / fps:.2f}), jitter {jitter_ms:.3f} ms, "
            f"robot+policy {inside / steps * 1e3:.2f} ms/step, evaluator overhead {overhead * 1e3:.3f} ms/step"
        )
        figures[f"overhead_frac_{fps}hz"] = overhead * fps
    figures["jitter_ms"] = max(jitters)
    print(" ".join(f"{name}={value:.4f}" for name, value in figures.items()))


if __name__ == "__main__":
    main()
