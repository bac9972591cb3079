"""The shipped `tabletop_pointer` weights: they load through LeRobot's own factory and still push blocks.

A regression check on a small fixed set, not the benchmark: the README's figures come from
`scripts/train/train_default_policy.py` on 250 fresh instances.
"""

import numpy as np
import pytest
import torch
from lerobot.configs import PreTrainedConfig
from lerobot.policies import get_policy_class, make_pre_post_processors
from lerobot_policy_tabletop_pointer import WEIGHTS, TabletopPointerPolicy

from lerobot_contrast.domains.language_table.task import LanguageTableTask
from lerobot_contrast.training.episodes import Simulator
from lerobot_contrast.training.learner import Learner, closed_loop

# The shipped weights scored 0.77 on these 30 instances (0.70 through select_action; the check acts through
# lane_step, as evaluations do); the floor leaves room for platform differences in float math.
SUCCESS_FLOOR = 0.5
# Metres of a step: a row batched may round its last bits otherwise (about 1e-8 m measured), never more than this.
BATCH_ATOL = 1e-6


def test_shipped_files_are_small_and_complete():
    names = {p.name for p in WEIGHTS.iterdir()}
    assert {"config.json", "model.safetensors", "policy_preprocessor.json", "policy_postprocessor.json"} <= names
    assert sum(p.stat().st_size for p in WEIGHTS.iterdir()) < 20e6


def test_shipped_policy_loads_through_lerobot_factories():
    config = PreTrainedConfig.from_pretrained(WEIGHTS)
    policy = get_policy_class(config.type).from_pretrained(WEIGHTS, config=config)
    assert isinstance(policy, TabletopPointerPolicy) and policy.config.vocabulary
    preprocessor, postprocessor = make_pre_post_processors(config, pretrained_path=str(WEIGHTS))
    batch = preprocessor(
        {
            "observation.images.top": torch.rand(3, 180, 320),
            "observation.state": torch.tensor([0.3, 0.0, 0.3, 0.0]),
            "task": "push the red moon to the blue cube",
        }
    )
    action = postprocessor(policy.select_action(batch))
    assert action.shape == (1, 2) and action.abs().max() <= 0.1


@pytest.mark.slow
def test_shipped_policy_clears_its_success_floor():
    torch.set_num_threads(1)
    instances = LanguageTableTask().sample(30, np.random.default_rng(20261125))
    figures = closed_loop(Learner(WEIGHTS), Simulator(LanguageTableTask()), instances, max_steps=200)
    assert figures["success"] >= SUCCESS_FLOOR, figures


def test_a_rows_action_does_not_depend_on_its_batch():
    """Lanes decide as one lane: each episode's action alone or batched with up to 11 others (two calls of the
    network past 8 rows) points into the same heading bin and agrees within BATCH_ATOL. Not to the last bit: a CPU's
    kernels may round a row otherwise in another batch size (AVX-512's do at 6 rows; docs/development.md)."""
    torch.set_num_threads(1)
    policy = TabletopPointerPolicy.from_pretrained(WEIGHTS).eval()
    generator = torch.Generator().manual_seed(0)
    images, states = torch.rand(12, 3, 180, 320, generator=generator), torch.rand(12, 4, generator=generator) * 0.4
    tasks = [f"push the {c} star to the {p} of the board" for c in ("red", "blue", "green") for p in ("top", "left")]
    tasks = (tasks * 2)[:12]

    def step(rows: slice, memories: list[dict]) -> torch.Tensor:
        batch = {"observation.images.top": images[rows], "observation.state": states[rows], "task": tasks[rows]}
        return policy.lane_step(batch, memories)

    alone = torch.cat([step(slice(i, i + 1), [{}]) for i in range(12)])
    assert alone.abs().max() > 100 * BATCH_ATOL  # the actions are large against the tolerance
    for size in range(2, 13):
        batched = step(slice(0, size), [{} for _ in range(size)])
        assert torch.allclose(batched, alone[:size], rtol=0, atol=BATCH_ATOL), f"a batch of {size} acts otherwise"
        assert torch.equal(policy.steering.heading_bin(batched), policy.steering.heading_bin(alone[:size]))
