"""The i.i.d. arrangement sampler behind --task=vln: valid arrangements, a train/eval split that never shares one,
and one-line errors at its limits."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.domains import load_task
from lerobot_contrast.domains.vln import routes, sampler
from lerobot_contrast.domains.vln.apartment.furniture import STUDIO
from lerobot_contrast.domains.vln.wording import name_of

RADIUS = 0.75


@pytest.fixture(scope="module")
def drawn() -> dict[str, list]:
    return {
        "train": sampler.sample_arrangements(6, "train", 0, RADIUS)
        + sampler.sample_arrangements(6, "train", 1, RADIUS),
        "eval": [
            *load_task("vln").sample(6, np.random.default_rng(0)),
            *sampler.sample_arrangements(6, "eval", 0, RADIUS),
        ],
    }


def test_arrangements_move_a_few_pieces_and_have_a_route_through_both_subgoals(drawn):
    task = load_task("vln")
    for instance in drawn["eval"]:
        moved = [n for n, p in instance.scene.objects.items() if (p.x, p.y, p.yaw) != STUDIO[n]]
        assert sampler.MOVED[0] <= len(moved) <= sampler.MOVED[1]
        first, final = instance.goal["subgoals"]
        assert instance.instruction.index(name_of(first)) < instance.instruction.index(name_of(final))
        assert task.rebase(instance, instance.scene) == instance and not task.is_achieved(instance, instance.scene)
        assert task.reference_length(instance) >= sampler.MIN_ROUTE_M
        assert routes.start_is_free(instance.scene, instance.scene.robot)


def test_training_and_evaluation_never_share_an_arrangement(drawn):
    keys = {split: {sampler.arrangement_key(i) for i in drawn[split]} for split in sampler.SPLITS}
    assert len(keys["train"]) == len(drawn["train"]) and len(keys["eval"]) == len(drawn["eval"])
    assert not keys["train"] & keys["eval"]
    assert all(sampler.split_of(i) == split for split in sampler.SPLITS for i in drawn[split])


def test_the_same_seed_draws_the_same_arrangements_another_seed_others(drawn):
    task = load_task("vln")
    again = task.sample(6, np.random.default_rng(0))
    assert again == drawn["eval"][:6]
    other = task.sample(3, np.random.default_rng(1))
    assert not {sampler.arrangement_key(i) for i in other} & {sampler.arrangement_key(i) for i in again}


def test_the_sampler_names_its_limits_in_one_line(monkeypatch):
    with pytest.raises(UserError, match=f"1 to {sampler.MAX_INSTANCES} instances"):
        load_task("vln").sample(sampler.MAX_INSTANCES + 1, np.random.default_rng(0))
    monkeypatch.setattr(sampler, "_candidate", lambda *args: None)
    with pytest.raises(UserError, match=f"could not place the furniture of arrangement 0 in {sampler.MAX_TRIES} tries"):
        sampler.sample_arrangements(1, "eval", 0, RADIUS)


def test_the_paper_arrangements_stay_available_by_name():
    task = load_task("vln_paper")
    assert task.default_instances == 5 and sorted(i.id for i in task.sample(5, np.random.default_rng(0)))[0] == "vln-1"


@pytest.mark.parametrize(
    ("flags", "message"),
    [
        (
            ["--task=vln_nowhere"],
            "choose from: language_table, libero_10, libero_goal, libero_object, libero_spatial, vln, vln_paper",
        ),
        (["--task=vln", f"--n_instances={sampler.MAX_INSTANCES + 1}"], f"1 to {sampler.MAX_INSTANCES} instances"),
    ],
)
def test_bad_task_flags_are_one_line(tmp_path, flags, message):
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "lerobot_contrast.eval",
            *flags,
            "--policy.type=route_follower",
            f"--output_dir={tmp_path}/r",
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode != 0 and message in done.stderr
    assert "Traceback" not in done.stderr and len(done.stderr.strip().splitlines()) == 1, done.stderr
