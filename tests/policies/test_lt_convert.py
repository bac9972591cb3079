"""The converter turns a checkpoint in the released format into a LeRobot policy that computes what Flax computes,
and refuses, in one line, checkpoints with anything missing, left over or misshapen."""

from __future__ import annotations

import json
from pathlib import Path

import jax
import numpy as np
import pytest
import torch
from flax import traverse_util
from lerobot_policy_language_table.convert import main
from lerobot_policy_language_table.layers import center_crop_resize
from lerobot_policy_language_table.modeling_language_table import LanguageTablePolicy
from lerobot_policy_language_table.tokenizer import ClipTokenizer
from safetensors.numpy import load_file

from .flax_reference import SequenceLAVMSE
from .synthetic_checkpoint import FULL_CLIP, SMALL_CLIP, random_variables, train_state, write_checkpoint

INSTRUCTION = "slide the blue cube towards the yellow star"


def _frames(seed: int) -> np.ndarray:
    """Four camera frames (1, 4, 3, 180, 320) in [0, 1]."""
    return np.random.default_rng(seed).uniform(size=(1, 4, 3, 180, 320)).astype(np.float32)


def _flax_action(model: SequenceLAVMSE, variables: dict, frames: np.ndarray, instruction: str) -> np.ndarray:
    # The benchmark's crop done with jax: rows 4..175, columns 8..312, resized back to 180x320.
    rgb = frames.transpose(0, 1, 3, 4, 2)[:, :, 4:175, 8:312]
    rgb = jax.image.resize(rgb, (1, 4, 180, 320, 3), method="bilinear", antialias=False)
    tokens = ClipTokenizer()(instruction)[None].astype(np.int32)
    return np.asarray(jax.jit(model.apply)(variables, rgb, tokens))


def _torch_action(policy: LanguageTablePolicy, frames: np.ndarray, instruction: str) -> np.ndarray:
    x = center_crop_resize(torch.from_numpy(frames).flatten(0, 1), 0.95).view(frames.shape)
    with torch.no_grad():
        return policy.model(x, policy.text_embedding([instruction])).numpy()


def test_converted_policy_computes_what_the_flax_network_computes(small_variables, converted):
    policy = LanguageTablePolicy.from_pretrained(converted)
    frames = _frames(1)
    np.testing.assert_allclose(
        _torch_action(policy, frames, INSTRUCTION), _flax_action(SequenceLAVMSE(SMALL_CLIP), small_variables, frames, INSTRUCTION),
        atol=1e-4, rtol=1e-4,
    )  # fmt: skip


def test_output_is_lerobots_pretrained_format_with_the_checkpoints_action_statistics(converted):
    names = {p.name for p in converted.iterdir()}
    assert {"config.json", "model.safetensors", "README.md"} <= names
    assert {"policy_preprocessor.json", "policy_postprocessor.json"} <= names
    config = json.loads((converted / "config.json").read_text())
    assert (config["type"], config["clip_width"], config["clip_layers"], config["device"]) == (
        "language_table",
        64,
        2,
        "cpu",
    )
    assert "training step 955,000" in (converted / "README.md").read_text()
    stats = load_file(converted / "policy_postprocessor_step_0_unnormalizer_processor.safetensors")
    np.testing.assert_allclose(stats["action.mean"], [0.0012, -0.0031])
    np.testing.assert_allclose(stats["action.std"], [0.012, 0.018])
    assert not converted.with_name(converted.name + ".partial").exists()


def _flat_state(variables: dict) -> dict:
    return traverse_util.flatten_dict(train_state(variables), sep="/")


def _convert_modified(tmp_path: Path, variables: dict, edit, capsys) -> tuple[int, str]:
    flat = _flat_state(variables)
    edit(flat)
    checkpoint = write_checkpoint(tmp_path / "ckpt", traverse_util.unflatten_dict(flat, sep="/"))
    code = main([str(checkpoint), str(tmp_path / "out")])
    return code, capsys.readouterr().err


TEXT_LN = "params/encoder/TextEncoder_0/ln_final/scale"
FUSION_DENSE = "params/encoder/PrenormPixelLangEncoder_2/Dense_1/kernel"
STAGE_BN = "batch_stats/encoder/ResNetVisualEncoder_0/MultiscaleResNet_0/stage2/block3/bn2/var"


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda f: f.pop(FUSION_DENSE), "missing from the checkpoint: fusion.2.ffn.dense_out.weight"),
        (lambda f: f.pop(STAGE_BN), f"the checkpoint has no {STAGE_BN!r}"),
        (lambda f: f.update({"params/encoder/Dense_7/kernel": np.zeros((3, 3))}), "left over: checkpoint entry"),
        (lambda f: f.update({"extra/x": np.zeros(1)}), "left over: unexpected top-level checkpoint entries ['extra']"),
        (lambda f: f.update({TEXT_LN: np.ones(65, np.float32)}), f"{TEXT_LN} has shape (65,)"),
        (lambda f: f.update({STAGE_BN: np.ones(7, np.float32)}), f"{STAGE_BN} has shape (7,), expected (128,)"),
        (lambda f: f.pop("norm_info/action_statistics/std"), "the checkpoint has no 'std'"),
    ],
)
def test_bad_checkpoints_fail_with_one_line_and_no_output(tmp_path, small_variables, edit, message, capsys):
    code, err = _convert_modified(tmp_path, small_variables, edit, capsys)
    assert code == 2
    assert err.startswith("error: ") and message in err and err.count("\n") == 1
    assert not (tmp_path / "out").exists() and not (tmp_path / "out.partial").exists()


def test_unreadable_inputs_and_a_used_out_dir_fail_with_one_line(tmp_path, small_checkpoint, capsys):
    (tmp_path / "not_msgpack").write_bytes(b"\xc1 this is not a flax checkpoint")
    (tmp_path / "used").mkdir()
    (tmp_path / "used" / "keep.txt").write_text("mine")
    cases = [
        ([str(tmp_path / "not_msgpack"), str(tmp_path / "a")], "is not a Flax msgpack checkpoint"),
        ([str(tmp_path), str(tmp_path / "b")], "is a directory; give the checkpoint file itself"),
        ([str(tmp_path / "nowhere"), str(tmp_path / "c")], "cannot read checkpoint"),
        ([str(small_checkpoint), str(tmp_path / "used")], "already exists and is not empty"),
    ]
    for argv, message in cases:
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert err.startswith("error: ") and message in err and err.count("\n") == 1
    assert (tmp_path / "used" / "keep.txt").read_text() == "mine"


@pytest.mark.slow
def test_full_size_checkpoint_converts_and_matches_flax(tmp_path):
    variables = random_variables(FULL_CLIP, seed=3)
    flat = traverse_util.flatten_dict(variables["params"])
    # The spec's count for the released network: CLIP text tower 63,428,096 + the rest 3,894,338.
    assert sum(v.size for v in flat.values()) == 67_322_434
    checkpoint = write_checkpoint(tmp_path / "bc_resnet_sim_checkpoint_955000", train_state(variables))
    assert main([str(checkpoint), str(tmp_path / "out")]) == 0
    policy = LanguageTablePolicy.from_pretrained(tmp_path / "out")
    # Everything but the ResNet stages 1-2 (1,435,392 parameters whose outputs the network never reads).
    assert sum(p.numel() for p in policy.parameters()) == 67_322_434 - 1_435_392
    frames = _frames(2)
    np.testing.assert_allclose(
        _torch_action(policy, frames, INSTRUCTION), _flax_action(SequenceLAVMSE(FULL_CLIP), variables, frames, INSTRUCTION),
        atol=1e-4, rtol=1e-4,
    )  # fmt: skip
