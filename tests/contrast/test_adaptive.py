"""--order=adaptive: the next trial is the most informative per unit of staging cost among the current base's
remaining trials and the next base's original; bases keep their planned order; a resumed run chooses the same."""

from __future__ import annotations

import dataclasses
import json

import pytest

from lerobot_contrast.contrast.adaptive import information, next_trial
from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Scene
from lerobot_contrast.contrast.strategy import PlannedTrial
from lerobot_contrast.contrast.trial import Outcome, TrialContext, TrialRecord
from lerobot_contrast.eval import planned_evaluation
from lerobot_contrast.spine.config import EvalConfig
from lerobot_contrast.spine.evaluation import run


def chain_plan(bases, perturbations=("A", "B")):
    plan = []
    for j in range(bases):
        base = Instance(id=f"b{j}", family="f", instruction="go", scene=Scene())
        for name in (None, *perturbations):
            plan.append(PlannedTrial(len(plan), base, name, "reset" if name is None else "in_place"))
    return plan


def done(trial, index, success):
    return TrialRecord(
        index, trial.base.id, trial.perturbation, None, "f", trial.staging, 0, "done", trial.base, 0.0, 0.0,
        success, None, float(success),
    )  # fmt: skip


def test_the_first_trial_is_the_first_bases_original():
    plan = chain_plan(3)
    assert next_trial(plan, [], lambda t: 1.0) == plan[0]


def test_a_free_untried_perturbation_beats_an_expensive_next_base():
    plan = chain_plan(3)
    history = [done(plan[0], 0, True)]
    costs = {"b1": 2.0}
    chosen = next_trial(plan, history, lambda t: costs.get(t.base.id, 0.0 if t.perturbation == "B" else 0.5))
    assert (chosen.base.id, chosen.perturbation, chosen.index) == ("b0", "B", 1)


def test_well_measured_costly_perturbations_give_way_to_the_next_base_in_planned_order():
    plan = chain_plan(4)
    history = []
    for j in range(2):  # two whole bases: A and B measured twice, the original twice
        history += [done(t, len(history) + k, True) for k, t in enumerate(plan[3 * j : 3 * j + 3])]
    history.append(done(plan[6], len(history), False))  # the third base's original
    chosen = next_trial(plan, history, lambda t: 1.0 if t.perturbation is None else 5.0)
    assert (chosen.base.id, chosen.perturbation) == ("b3", None)
    skipped = next_trial(plan, history, lambda t: None if t.base.id == "b3" else 5.0)
    assert skipped.base.id == "b2"  # never b0 or b1 again: only the current and the next base are candidates


def test_trials_that_do_not_apply_now_are_not_candidates_and_no_base_left_ends_the_run():
    plan = chain_plan(1)
    history = [done(plan[0], 0, True)]
    assert next_trial(plan, history, lambda t: None) is None
    assert next_trial(plan, [*history, done(plan[1], 1, True), done(plan[2], 2, True)], lambda t: 1.0) is None


def test_the_information_of_a_trial_falls_as_its_perturbation_is_measured():
    plan = chain_plan(5)
    few = [done(plan[1], 0, True)]
    many = [done(plan[3 * j + 1], j, j % 2 == 0) for j in range(5)]
    assert information(few, "A", "progress") > information(many, "A", "progress") > 0
    assert information([], None, "progress") == 2 * information([], "A", "progress")


INTERRUPT: dict[str, int] = {}


def succeeds(context: TrialContext) -> Outcome:
    if context.index == INTERRUPT.get("at"):
        raise KeyboardInterrupt
    return Outcome(
        success=context.index % 3 != 1, steps=1, path_length=0.0, scene_after=context.instance.scene, duration_s=0.0
    )


def evaluate(output_dir, resume=False):
    planned = planned_evaluation(EvalConfig(n_instances=8, seed=5, order="adaptive"))
    evaluation = dataclasses.replace(
        planned, execute=succeeds, output_dir=output_dir, resume=resume, config={"seed": 5, "order": "adaptive"}
    )
    return run(evaluation)


def test_an_adaptive_run_keeps_bases_in_planned_order_and_resumes_to_the_same_choices(tmp_path):
    whole = evaluate(tmp_path / "whole")
    plan = planned_evaluation(EvalConfig(n_instances=8, seed=5)).plan
    visited = list(dict.fromkeys(r.base_id for r in whole.records))
    assert visited == list(dict.fromkeys(t.base.id for t in plan))
    assert [r.index for r in whole.records] == list(range(len(whole.records)))
    INTERRUPT["at"] = len(whole.records) // 2
    try:
        with pytest.raises(KeyboardInterrupt):
            evaluate(tmp_path / "cut")
    finally:
        INTERRUPT.clear()
    evaluate(tmp_path / "cut", resume=True)

    def chosen(path):
        lines = (json.loads(line) for line in (path / "journal.jsonl").read_text().splitlines())
        return [(d["index"], d["base_id"], d["perturbation"], d["success"]) for d in lines]

    assert chosen(tmp_path / "cut") == chosen(tmp_path / "whole")


def test_the_report_says_which_estimates_of_an_adaptive_run_stay_unbiased(tmp_path):
    from lerobot_contrast.reporting import load_run
    from lerobot_contrast.reporting.build import build_report

    evaluate(tmp_path / "run")
    text = build_report([load_run(str(tmp_path / "run"))], tmp_path / "report").path.read_text()
    assert "original instances' mean is an unbiased i.i.d. estimate" in text and "per-perturbation rows" in text
