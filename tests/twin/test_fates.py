"""Where a policy left the recorded task's cube, read from the scripted operator's log and the run's journal."""

import json

from lerobot_contrast.domains.task_file import load_task_file
from lerobot_contrast.twin.fates import ENDED, fates, fates_markdown, held_line

SPEC = load_task_file("so101_red_left").spec
START = {"red_cube": [0.25, 0.05, 0.0], "green_cube": [0.30, -0.05, 0.0]}


def trial(index, perturbation, success, status="done"):
    instance = {"scene": {"objects": START, "robot": None}}
    return {"index": index, "perturbation": perturbation, "success": success, "status": status, "instance": instance}


def test_each_trial_is_counted_where_the_cube_ended_and_an_aborted_one_not_at_all(tmp_path):
    run = tmp_path / "act"
    run.mkdir()
    records = [trial(0, None, True), trial(1, "L", False), trial(2, "LB2", False), trial(3, "LB3", False),
               trial(4, "SB", False, status="aborted")]  # fmt: skip
    (run / "journal.jsonl").write_text("".join(json.dumps(r) + "\n" for r in records))
    ended = {0: (0.31, 0.17), 1: (0.25, 0.05), 2: (0.30, -0.20), 3: (0.35, 0.02), 4: (0.31, 0.17)}
    log = "".join(
        f"──── trial {i + 1}/5 · so101_red_left-0000 · whatever ────\n[operator] moved 0.1 m\n"
        f"[operator] {ENDED}red_cube ({x:.3f}, {y:.3f}), green_cube (0.300, -0.050)\n[operator] y\n"
        for i, (x, y) in ended.items()
    )
    (tmp_path / "act.log").write_text(log)
    table = fates(run, tmp_path / "act.log", SPEC, "red_cube")
    assert set(table) == {"original", "L", "LB2", "LB3"}  # the aborted trial is not counted
    assert table["original"] == {"in left_bin": 1, "success": 1, "trials": 1}
    assert table["L"]["not moved"] == 1 and table["LB2"]["in right_bin"] == 1
    assert table["LB3"]["moved elsewhere"] == 1 and table["LB3"]["success"] == 0
    markdown = fates_markdown(table, "red_cube", ["left_bin", "right_bin"])
    assert "| ΔLB2 | 1 | 0 | 0 | 1 | 0 | 0 | 0 |" in markdown.splitlines()


def test_a_cube_still_held_in_the_gripper_over_a_bin_is_never_counted_in_the_bin(tmp_path):
    run = tmp_path / "act"
    run.mkdir()
    (run / "journal.jsonl").write_text("".join(json.dumps(trial(i, None, False)) + "\n" for i in range(2)))
    over_the_bin = f"{ENDED}red_cube (0.310, 0.170), green_cube (0.300, -0.050)"
    log = (
        f"──── trial 1/2 · so101_red_left-0000 · original ────\n[operator] {over_the_bin}\n"
        f"[operator] {held_line('red_cube', 0.035)}\n[operator] n\n"
        f"──── trial 2/2 · so101_red_left-0001 · original ────\n[operator] {over_the_bin}\n"
        f"[operator] {held_line('green_cube', 0.03)}\n[operator] n\n"
    )
    (tmp_path / "act.log").write_text(log)
    counts = fates(run, tmp_path / "act.log", SPEC, "red_cube")["original"]
    # Trial 1 holds the red cube 3.5 cm up over the left bin; trial 2 rests it there (another cube is held).
    assert counts["held in the gripper"] == 1 and counts["in left_bin"] == 1
    markdown = fates_markdown({"original": counts}, "red_cube", ["left_bin", "right_bin"])
    assert "red_cube held in the gripper" in markdown and "| original | 2 | 0 | 1 | 0 | 1 | 0 | 0 |" in markdown
