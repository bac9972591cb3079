"""The arm's own costs beside metres: robot seconds of staging (planned from the planner's motions, then measured)
and a person's calls, in the journal's extra, the summary and its table."""

import pytest

from lerobot_contrast.contrast.cost import InterventionCost, RobotTimeCost
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.contrast.trial import TrialRecord
from lerobot_contrast.domains import load_task
from lerobot_contrast.operators.arm.args import ArmArgs
from lerobot_contrast.record.summary import format_summary, summarize
from lerobot_contrast.so101 import PICK_AND_PLACE_S

BEFORE = Scene({"red_cube": Pose(0.2, 0.0), "green_cube": Pose(0.3, 0.1), "blue_cube": Pose(0.4, 0.0)})
AFTER = Scene({"red_cube": Pose(0.25, 0.0), "green_cube": Pose(0.3, -0.1), "blue_cube": Pose(0.4, 0.0)})


def test_robot_time_is_planned_per_object_the_arm_moves():
    assert RobotTimeCost(per_object_s=10.0)(BEFORE, AFTER) == 20.0
    from lerobot_contrast.spine.config import EvalConfig
    from lerobot_contrast.spine.flags import parse_config
    from lerobot_contrast.spine.run_setup import run_cost_model

    cfg = parse_config(EvalConfig, ["--task=so101_blocks", "--cost=robot_time", "--arm.pace=2"])
    planned = run_cost_model(load_task("so101_blocks"), cfg)  # at the pace the arm stages with
    assert planned.unit == "s" and planned.per_object_s == pytest.approx(PICK_AND_PLACE_S * 2)
    assert ArmArgs().pace != 2
    assert InterventionCost()(BEFORE, AFTER) == 0.0
    assert load_task("so101_blocks").cost_model("interventions").unit == "calls"


def record(index: int, extra: dict) -> TrialRecord:
    return TrialRecord(index, "b0", None, None, "f", "reset", 0, "done", None, 1.0, float(index + 1),
                       success=True, spl=1.0, progress=1.0, extra=extra)  # fmt: skip


def test_the_summary_counts_robot_seconds_calls_and_unlabelled_trials():
    records = [
        record(0, {"robot_s": 30.5, "interventions": 1}),
        record(1, {"robot_s": 12.0, "interventions": 0, "label_asked": True, "unlabelled": False}),
        record(2, {"robot_s": 8.0, "interventions": 0, "unlabelled": True}),
    ]
    summary = summarize(records, settings={}, complete=True)
    assert summary["robot_staging"] == {"trials": 3, "robot_s": 50.5, "interventions": 2, "unlabelled": 1}
    assert "staged by the arm: 3 trials, 50 robot seconds, a person called 2 times, 1 left unlabelled" in (
        format_summary(summary, "s")
    )
    assert "robot_staging" not in summarize([record(0, {})], settings={}, complete=True)


def test_the_report_has_a_table_of_what_the_arm_staged():
    from types import SimpleNamespace

    from lerobot_contrast.reporting.markdown import robot_staging_section

    summary = summarize([record(0, {"robot_s": 30.0, "interventions": 1})], settings={}, complete=True)
    lines = robot_staging_section([SimpleNamespace(name="run", summary=summary)])
    assert lines[0] == "## Staged by the arm" and any("| run | 1 | 30 | 30.0 | 1 | 0 |" in line for line in lines)
    assert robot_staging_section([SimpleNamespace(name="run", summary={})]) == []
