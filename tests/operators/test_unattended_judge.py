"""The unattended benchmark's judge judges what ran: a session whose policy still holds its cube when the episode ends
is labelled a failure by the camera and by the twin's truth at that moment, and the in-place perturbation staged from
where the policy left the cube is judged against that trial's own targets, as the channel says the evaluator ran it."""

import json
import math

import pytest

from tests.study_scripts import load_script

pytestmark = pytest.mark.slow


def test_a_cube_held_at_the_episodes_end_and_the_in_place_trial_after_it_are_judged_on_what_ran(tmp_path, capsys):
    bench = load_script("bench_unattended")
    # The demonstrator lets go 8.25 s into its episode: at 6 s the red cube hangs in the jaws beside its target.
    code = bench.main(["--bases=1", "--perturbations=LB3", "--episode_s=6", f"--work={tmp_path}"])
    assert code == 0, capsys.readouterr().err
    judged = [json.loads(line) for line in (tmp_path / "judge.jsonl").read_text().splitlines()]
    journal = [json.loads(line) for line in (tmp_path / "run" / "journal.jsonl").read_text().splitlines()]
    assert [r["status"] for r in journal] == ["done", "done"]
    first = next(r for r in judged if r["kind"] == "label" and r["trial"] == 0)
    assert (first["camera"], first["truth"], first["sure"]) == (False, False, True)  # held, not put down
    assert journal[0]["success"] is False
    after = journal[1]["instance"]["scene"]["objects"]  # the ΔLB3 trial, staged where the episode left things
    assert math.dist(after["red_cube"][:2], journal[0]["instance"]["scene"]["objects"]["red_cube"][:2]) > 0.02
    placed = {r["object"]: r for r in judged if r["kind"] == "placed" and r["trial"] == 1}
    assert set(placed) == {"red_cube", "green_cube", "blue_cube"}
    assert all(r["off_m"] < 0.02 for r in placed.values()), placed  # against its own targets, not the base's
    assert "labelled_by_camera=" in capsys.readouterr().out
