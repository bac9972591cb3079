"""--lanes: simulated chains of trials side by side give the journal, the observers' episodes and the stopping point
of one lane, trial for trial; a run killed with lanes resumes to the same journal; hardware runs one lane."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest

from lerobot_contrast.domains.language_table.language_table_sim import LanguageTableSim
from lerobot_contrast.eval import planned_evaluation
from lerobot_contrast.lanes import runner as lane_runner
from lerobot_contrast.lanes.choice import AUTO_LANES, LanesError, choose_lanes, parse_lanes
from lerobot_contrast.lanes.runner import LaneRunner, chains
from lerobot_contrast.lanes.seats import batches_lanes
from lerobot_contrast.policies import PolicyArgs, make_policy
from lerobot_contrast.record.observer import EpisodeFiles, QuietObserver
from lerobot_contrast.spine.build import make_robot, register_robots
from lerobot_contrast.spine.config import EvalConfig, StopArgs
from lerobot_contrast.spine.evaluation import run
from lerobot_contrast.spine.runner import RobotLostError

WALL_CLOCK = ("started_at", "duration_s")
register_robots()


class Watch(QuietObserver):
    """What the observers see of each episode, without its wall-clock times."""

    def __init__(self, stop_after: int | None = None) -> None:
        self.episodes: list[tuple] = []
        self.stop_after = stop_after

    def start(self, context, features, pose_keys):
        self.episodes.append((context.index, context.instance.id, round(context.planned_cost, 12), []))

    def step(self, timestamp_s, observation, action):
        state = {k: v for k, v in observation.items() if isinstance(v, float)}
        self.episodes[-1][3].append((state, dict(action)))

    def end(self, record):
        if self.stop_after is not None and len(self.episodes) > self.stop_after:
            raise KeyboardInterrupt  # as a kill between an episode and its journal line
        return EpisodeFiles()


class Sizes(QuietObserver):
    """The bytes of each step's observation, as a lane holds it."""

    def __init__(self) -> None:
        self.bytes: list[int] = []

    def step(self, timestamp_s, observation, action):
        self.bytes.append(sum(getattr(v, "nbytes", 8) for v in observation.values()))


class LostTabletop(LanguageTableSim):
    """The tabletop behind a link that drops for good at its fifth action (each copy its own link)."""

    def __init__(self, config):
        super().__init__(config)
        self.actions = 0

    def connect(self, calibrate=True):
        if self.actions:
            raise ConnectionError("no route to host")
        super().connect(calibrate)

    def send_action(self, action):
        self.actions += 1
        if self.actions == 5:
            raise ConnectionError("link lost")
        return super().send_action(action)


def evaluate(run_dir: Path, lanes: int, *, policy="oracle", task="language_table", n=3, steps=30, resume=False,
             observers=(), robot_class=None, lane_threads=1, **settings):  # fmt: skip
    cfg = EvalConfig(task=task, n_instances=n, seed=5, max_episode_steps=steps, rerun=False, **settings)
    cfg.policy = PolicyArgs(type=policy)
    planned = planned_evaluation(cfg)
    robot = make_robot(cfg)
    robot = robot if robot_class is None else robot_class(robot.config)
    robot.connect()
    try:
        evaluation = dataclasses.replace(
            planned, robot=robot, policy=make_policy(cfg.policy, robot, planned.task), max_steps=steps, lanes=lanes,
            lane_threads=lane_threads,
            policy_for=lambda lane_robot: make_policy(cfg.policy, lane_robot, planned.task),
            observers=observers, output_dir=run_dir, resume=resume, config={"seed": 5, "task": task},
        )  # fmt: skip
        return run(evaluation)
    finally:
        if robot.is_connected:
            robot.disconnect()


def journal(run_dir: Path) -> list[dict]:
    lines = (run_dir / "journal.jsonl").read_text().splitlines()
    return [{k: v for k, v in json.loads(line).items() if k not in WALL_CLOCK} for line in lines]


@pytest.mark.slow
@pytest.mark.parametrize(
    ("task", "policy", "lanes", "steps", "driven"),
    [("language_table", "tabletop_pointer", 4, 25, 50), ("vln", "vln_navigator", 3, 40, 100)],
)
def test_each_learned_default_gives_one_lanes_journal_and_episodes_with_lanes_answered_by_two_threads(
    tmp_path, task, policy, lanes, steps, driven
):
    watched = {}
    for n in (1, lanes):
        watched[n] = Watch()
        evaluate(
            tmp_path / f"l{n}", n, task=task, policy=policy, n=lanes, steps=steps, observers=[watched[n]],
            lane_threads=2,
        )  # fmt: skip
    assert journal(tmp_path / "l1") == journal(tmp_path / f"l{lanes}")
    assert watched[1].episodes == watched[lanes].episodes
    assert sum(len(e[3]) for e in watched[1].episodes) > driven  # the policy really drove the robot


def test_the_apartment_gives_the_same_journal_with_three_lanes(tmp_path):
    for lanes in (1, 3):
        evaluate(tmp_path / f"l{lanes}", lanes, task="vln", policy="route_follower", n=3, steps=60)
    assert journal(tmp_path / "l1") == journal(tmp_path / "l3")


def test_lanes_hold_at_most_their_memory_bound_and_one_episode_and_give_one_lanes_journal(tmp_path, monkeypatch):
    """Episodes waiting for their turn to be recorded are held in memory: past the bound only the trial earliest in
    plan order steps, so a heavy observation (the apartment's images) cannot fill the machine."""
    steps, held, sizes = 30, [], Sizes()
    evaluate(tmp_path / "one", 1, n=4, steps=steps, observers=[sizes])
    step_bytes = max(sizes.bytes)
    monkeypatch.setattr(lane_runner, "HELD_BYTES", 4 * steps * step_bytes)
    advance = LaneRunner._advance

    def watched(runner):
        held.append(runner._held())
        advance(runner)

    monkeypatch.setattr(LaneRunner, "_advance", watched)
    evaluate(tmp_path / "lanes", 4, n=4, steps=steps, observers=[Watch()])
    assert journal(tmp_path / "lanes") == journal(tmp_path / "one")
    assert lane_runner.HELD_BYTES <= max(held) <= lane_runner.HELD_BYTES + 2 * steps * step_bytes


def test_a_run_killed_with_lanes_resumes_to_the_journal_of_one_lane(tmp_path):
    evaluate(tmp_path / "one", 1)
    with pytest.raises(KeyboardInterrupt):
        evaluate(tmp_path / "killed", 3, observers=[Watch(stop_after=4)])
    killed, whole = journal(tmp_path / "killed"), journal(tmp_path / "one")
    assert 4 <= len(killed) < len(whole) and killed == whole[: len(killed)]  # up to the killed trial, no further
    evaluate(tmp_path / "killed", 2, resume=True)
    assert journal(tmp_path / "killed") == journal(tmp_path / "one")


def test_the_budget_stops_lanes_where_it_stops_one_lane(tmp_path):
    ran = {}
    for lanes in (1, 3):
        ran[lanes] = Watch()
        evaluate(tmp_path / f"l{lanes}", lanes, n=6, budget=8.0, observers=[ran[lanes]])
    kept = journal(tmp_path / "l1")
    assert kept == journal(tmp_path / "l3")
    assert kept[-1]["cumulative_cost"] > 8.0 and len(kept) < 6 * 7
    assert [e[0] for e in ran[3].episodes] == [e[0] for e in ran[1].episodes]  # nothing recorded past the stop


def test_a_stopping_rule_stops_lanes_where_it_stops_one_lane(tmp_path):
    for lanes in (1, 4):
        results = evaluate(tmp_path / f"l{lanes}", lanes, n=8, stop=StopArgs(width=0.9), strategy="standard")
        assert results.summary["stopping"]["reason"] == "width"
    assert journal(tmp_path / "l1") == journal(tmp_path / "l4")


def test_a_robot_lost_in_one_lane_stops_the_run_where_one_lane_stops_it(tmp_path):
    watched = {}
    for lanes in (1, 4):
        watched[lanes] = Watch()
        with pytest.raises(RobotLostError, match="could not reconnect"):
            evaluate(tmp_path / f"l{lanes}", lanes, robot_class=LostTabletop, observers=[watched[lanes]])
    assert [r["status"] for r in journal(tmp_path / "l4")] == ["aborted"]
    assert journal(tmp_path / "l1") == journal(tmp_path / "l4")
    assert watched[1].episodes == watched[4].episodes and len(watched[4].episodes) == 1


def test_chains_start_where_a_trial_is_staged_in_full():
    plan = planned_evaluation(EvalConfig(n_instances=3, seed=5, repeats=2)).plan
    cut = chains(plan)
    assert len(cut) == 3 and sum(map(len, cut)) == len(plan)
    assert all(chain[0].staging == "reset" and chain[0].repeat == 0 for chain in cut)
    assert chains(plan[3:])[0][0].index == 3  # a resumed run goes on mid-chain


class Hardware:
    name = "so101_follower"
    simulated = False


def test_hardware_runs_one_lane_and_says_so_for_more():
    assert choose_lanes("auto", Hardware(), None, operator=True, fps=10.0) == 1
    with pytest.raises(LanesError, match="runs one trial at a time"):
        choose_lanes("4", Hardware(), None, operator=True, fps=10.0)
    with pytest.raises(LanesError, match="--lanes must be auto or a whole number"):
        parse_lanes("0")
    simulator = dataclasses.make_dataclass("Sim", [("name", str, "sim"), ("simulated", bool, True)])()
    with pytest.raises(LanesError, match="--max_episode_s limits episodes in wall time"):
        choose_lanes("3", simulator, None, operator=False, fps=None, max_episode_s=5.0)
    assert choose_lanes("3", simulator, None, operator=False, fps=None) == 3


def test_the_learned_default_answers_every_lane_in_one_call_and_auto_runs_lanes_on_our_simulators(tmp_path):
    cfg = EvalConfig(n_instances=1)
    robot = make_robot(cfg)
    robot.connect()
    try:
        task = planned_evaluation(cfg).task
        learned = make_policy(PolicyArgs(), robot, task)
        noisy = make_policy(PolicyArgs(noise_std=0.01), robot, task)
        oracle = make_policy(PolicyArgs(type="oracle"), robot, task)
        assert batches_lanes(learned) and batches_lanes(noisy) and not batches_lanes(oracle)
        assert choose_lanes("auto", robot, learned, operator=False, fps=None) == AUTO_LANES > 1
        plugin = LostTabletop(robot.config)  # another package's subclass: its copies may share a link
        assert choose_lanes("auto", plugin, learned, operator=False, fps=None) == 1
        assert choose_lanes("3", plugin, learned, operator=False, fps=None) == 3
        assert choose_lanes("auto", robot, oracle, operator=False, fps=None) == 1  # a copy per lane gains nothing
    finally:
        robot.disconnect()
