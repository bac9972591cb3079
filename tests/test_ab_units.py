"""Interleaved comparisons without the simulator: --policies parsing and its one-line errors, the order turning by
base, the family-wise paired decisions, stopping once decided, and single-policy config.json left as it was."""

from __future__ import annotations

import dataclasses
import json

import pytest

from lerobot_contrast.contrast.trial import Outcome, TrialContext
from lerobot_contrast.eval import main, planned_evaluation
from lerobot_contrast.pairing.decide import PairMonitor
from lerobot_contrast.pairing.interleave import Interleaver, Seat, policy_order
from lerobot_contrast.pairing.policy_list import parse_policies
from lerobot_contrast.policies.base import PolicyArgs
from lerobot_contrast.spine.config import EvalConfig, config_json


def test_each_entry_names_a_policy_with_its_own_options():
    specs = parse_policies("tabletop_pointer,tabletop_pointer:noise_std=0.02,user/model", PolicyArgs(device="cpu"))
    assert [s.args.type for s in specs] == ["tabletop_pointer", "tabletop_pointer", None]
    assert specs[1].args.noise_std == 0.02 and specs[0].args.noise_std == 0.0
    assert specs[2].args.path == "user/model" and all(s.args.device == "cpu" for s in specs)
    assert len({s.dirname for s in specs}) == 3


@pytest.mark.parametrize(
    ("flags", "said"),
    [
        (["--policies=oracle"], "at least two policies"),
        (["--policies=oracle,oracle"], "given more than once"),
        (["--policies=oracle,oracle:speed=2"], "is not an option"),
        (["--policies=oracle,oracle:noise_std=lots"], "is not a number"),
        (["--policies=oracle,random", "--policy.type=oracle"], "drop --policy.path/--policy.type"),
        (["--policies=oracle,random", "--stop.width=0.1"], "drop --stop.width"),
    ],
)
def test_bad_policies_are_refused_in_one_line(flags, said, capsys, tmp_path):
    assert main([*flags, f"--output_dir={tmp_path / 'run'}"]) == 2
    err = capsys.readouterr().err
    assert said in err and err.count("\n") == 1 and not (tmp_path / "run").exists()


def test_the_order_turns_with_each_base():
    assert [policy_order(["A", "B"], k) for k in range(3)] == [["A", "B"], ["B", "A"], ["A", "B"]]
    assert policy_order(["A", "B", "C"], 1) == ["B", "C", "A"]


def test_a_single_policy_config_json_has_no_interleaving_settings():
    stored = config_json(EvalConfig())
    assert "policies" not in stored and "blind" not in stored and "decided" not in stored["stop"]
    assert config_json(EvalConfig(policies="a,b", blind=True))["policies"] == "a,b"


def session(success: dict[str, float], n_instances: int = 40):
    """Every policy on a standard plan, each trial's success drawn with the policy's rate (seeded per trial)."""
    import numpy as np

    planned = planned_evaluation(EvalConfig(n_instances=n_instances, strategy="standard", seed=1))
    seats = []
    for label, rate in success.items():

        def execute(context: TrialContext, rate=rate) -> Outcome:
            won = np.random.default_rng([context.index, int(rate * 100)]).random() < rate
            return Outcome(won, 1, 0.0, context.instance.scene, 0.0, progress=float(won))

        records: list = []
        seats.append(Seat(label, dataclasses.replace(planned), records, execute, records.append))
    return planned, Interleaver(seats, planned.plan, planned.cost_model, None, planned.task.storage_scene())


def test_the_session_stops_once_every_pair_is_decided_at_the_family_alpha():
    planned, interleaver = session({"A": 1.0, "B": 0.0, "C": 0.5}, n_instances=80)
    monitor = PairMonitor(planned.plan, ["A", "B", "C"], 0.05)
    for trial in interleaver.run(lambda: monitor.all_decided):
        monitor.observe(trial)
    report = monitor.report()
    assert all(p["alpha"] == pytest.approx(0.05 / 3) for p in report["pairs"]) and "Bonferroni" in report["correction"]
    decided = {(p["first"], p["second"]): p["verdict"] for p in report["pairs"]}
    assert decided == {("A", "B"): "first better", ("A", "C"): "first better", ("B", "C"): "second better"}
    assert monitor.bases < 80 and len(interleaver.seats[0].records) == monitor.bases  # stopped early, and said so
    assert json.dumps(report)  # the summary's form
