"""Interleaved comparisons in the simulator (--policies): one staged scene per trial for every policy, restaging
counted, the chain continuing from the last policy's scene, resume after a kill between two policies' runs of a
trial, agreement with separate runs, the operator's prompts and blind labels, and report/review on the pair dir."""

from __future__ import annotations

import io
import json
import sys
from pathlib import Path

import pytest

from lerobot_contrast.contrast.scene import Scene
from lerobot_contrast.domains import load_task
from lerobot_contrast.eval import main
from lerobot_contrast.pairing import session as command
from lerobot_contrast.publish import main as publish
from lerobot_contrast.report import main as report
from lerobot_contrast.review import main as review
from lerobot_contrast.spine.runner import RobotRunner

SMALL = ["--n_instances=2", "--seed=5", "--perturbations=SB1", "--max_episode_steps=40", "--rerun=false"]
TWO_ORACLES = "oracle,oracle:noise_std=0.02"
# What differs between two runs of the same trials: when they ran and how long they took.
TIMING = ("started_at", "duration_s")


def journal(run: Path) -> list[dict]:
    return [json.loads(line) for line in (run / "journal.jsonl").read_text().splitlines()]


def policy_dirs(pair: Path) -> dict[str, Path]:
    return {e["label"]: pair / e["name"] for e in json.loads((pair / "pairs.json").read_text())["policies"]}


def untimed(lines: list[dict]) -> list[dict]:
    return [{k: v for k, v in line.items() if k not in TIMING} for line in lines]


@pytest.mark.slow
def test_oracle_and_learned_default_share_each_start_scene_and_pay_restaging(tmp_path, capsys):
    pair = tmp_path / "pair"
    assert main([*SMALL, "--policies=oracle,tabletop_pointer", f"--output_dir={pair}"]) == 0
    dirs = policy_dirs(pair)
    oracle, learned = journal(dirs["oracle"]), journal(dirs["tabletop_pointer"])
    assert len(oracle) == len(learned) == 4
    cost = load_task("language_table").cost_model("distance")
    chain = load_task("language_table").storage_scene()
    for a, b in zip(oracle, learned, strict=True):
        assert a["instance"] == b["instance"]  # the same start scene, trial for trial
        order = a["extra"]["pairing"]["order"]
        first, second = (a, b) if order[0] == "oracle" else (b, a)
        scene = Scene.from_json(a["instance"]["scene"])
        assert first["extra"]["pairing"]["restage"] is False and second["extra"]["pairing"]["restage"] is True
        assert first["cost"] == pytest.approx(cost(chain, scene))  # staged from the scene the last policy left
        assert second["cost"] == pytest.approx(cost(Scene.from_json(first["scene_after"]), scene))
        chain = Scene.from_json(second["scene_after"])
    firsts = [r["extra"]["pairing"]["order"][0] for r in oracle]
    assert firsts == ["oracle", "oracle", "tabletop_pointer", "tabletop_pointer"]  # the order turns with each base
    summary = json.loads((pair / "summary.json").read_text())
    restaged = sum(r["cost"] for r in oracle + learned if r["extra"]["pairing"]["restage"])
    assert summary["cost"]["restaging"] == pytest.approx(restaged) and restaged > 0
    out = capsys.readouterr().out
    assert "restaging" in out and "oracle vs tabletop_pointer" in out
    comparison = (pair / "comparison.md").read_text()
    assert "oracle minus tabletop_pointer" in comparison and "ΔSB1" in comparison and "Each policy" in comparison
    assert report([str(pair)]) == 0
    text = (pair / "report" / "report.md").read_text()
    assert "## Policies on the same plan" in text and "## Interleaved comparison: pair" in text


def test_a_run_killed_between_two_policies_of_a_trial_resumes_without_losing_or_repeating(tmp_path, monkeypatch, hub):
    whole, cut = tmp_path / "whole", tmp_path / "cut"
    assert main([*SMALL, f"--policies={TWO_ORACLES}", f"--output_dir={whole}"]) == 0
    calls = []

    class Killed(RobotRunner):
        def __call__(self, context):
            calls.append(context.index)
            if len(calls) == 4:  # the second policy's run of trial 2: the first's is journalled already
                raise KeyboardInterrupt
            return super().__call__(context)

    monkeypatch.setattr(command, "RobotRunner", Killed)
    assert main([*SMALL, f"--policies={TWO_ORACLES}", f"--output_dir={cut}"]) == 130
    lengths = sorted(len(journal(d)) for d in policy_dirs(cut).values())
    assert lengths == [1, 2]
    monkeypatch.setattr(command, "RobotRunner", RobotRunner)
    assert main([f"--output_dir={cut}", "--resume=true"]) == 0
    for label, path in policy_dirs(whole).items():
        assert untimed(journal(policy_dirs(cut)[label])) == untimed(journal(path))
    assert (
        json.loads((cut / "summary.json").read_text())["cost"]
        == json.loads((whole / "summary.json").read_text())["cost"]
    )
    assert publish([str(cut), "--repo_id=user/ab"]) == 0  # each policy's run as a normal published run
    assert {name for _, name in hub.repos} == {"user/ab-1_oracle", "user/ab-2_oracle-noise_std-0.02"}


def test_each_policy_agrees_trial_for_trial_with_its_own_separate_run(tmp_path):
    # Standard order stages every trial in full, so a separate run starts every trial from the same scene too.
    flags = ["--n_instances=3", "--seed=5", "--max_episode_steps=40", "--rerun=false", "--strategy=standard"]
    assert main([*flags, f"--policies={TWO_ORACLES}", f"--output_dir={tmp_path / 'pair'}"]) == 0
    assert main([*flags, "--policy.type=oracle", f"--output_dir={tmp_path / 'a'}"]) == 0
    assert main([*flags, "--policy.type=oracle", "--policy.noise_std=0.02", f"--output_dir={tmp_path / 'b'}"]) == 0
    dirs = policy_dirs(tmp_path / "pair")
    for label, alone in (("oracle", "a"), ("oracle:noise_std=0.02", "b")):
        paired, single = journal(dirs[label]), journal(tmp_path / alone)
        keys = ("instance", "success", "spl", "steps", "path_length", "scene_after")
        assert [{k: r[k] for k in keys} for r in paired] == [{k: r[k] for k in keys} for r in single]


def test_the_operator_is_told_to_restage_and_blind_labels_name_the_policy_only_after(tmp_path, monkeypatch, capsys):
    # Per policy and trial: Enter once staged, then Enter to accept what the scene shows.
    monkeypatch.setattr(sys, "stdin", io.StringIO("\n" * 8))
    flags = ["--n_instances=1", "--seed=5", "--perturbations=SB1", "--max_episode_steps=40", "--operator=console"]
    pair = tmp_path / "pair"
    assert main([*flags, f"--policies={TWO_ORACLES}", "--blind=true", f"--output_dir={pair}"]) == 0
    out = " ".join(capsys.readouterr().out.split())
    assert out.count("restage trial") == 2 and "put back what the last policy moved" in out
    session = out[out.index("trial 1, policy") : out.index("sequential:")]  # the header lists them all
    first_label = session.index("labelled; that run was")
    assert "policy 1 of 2 (blind" in session and "oracle:noise_std" not in session[:first_label]
    assert "labelled; that run was oracle" in session
    records = [r for d in policy_dirs(pair).values() for r in journal(d)]
    assert all(r["status"] == "done" and r["extra"]["reset_s"] >= 0 for r in records)
    assert review([str(pair), "--save_only=true"]) == 0
    assert "4 episodes of 1 base instance" in capsys.readouterr().out
