"""Convert the released Flax checkpoint (`bc_resnet_sim_checkpoint_955000`) to LeRobot's pretrained-policy format.

    python -m lerobot_policy_language_table.convert CHECKPOINT OUT_DIR [--push_to_hub REPO]

Every parameter and batch statistic is mapped with a shape check; anything missing or left over stops the conversion.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import shutil
import sys
from pathlib import Path
from typing import Any

import httpx
import numpy as np
import torch
from huggingface_hub import HfApi
from huggingface_hub.errors import HfHubHTTPError

from lerobot_policy_language_table.architecture import entry, network_sizes, resnet_stage_sizes
from lerobot_policy_language_table.configuration_language_table import ACTION_KEY, LanguageTableConfig
from lerobot_policy_language_table.flax_checkpoint import (
    DAMAGED,
    CheckpointError,
    describe,
    flat_weights,
    read_checkpoint,
)
from lerobot_policy_language_table.model_card import model_card
from lerobot_policy_language_table.modeling_language_table import LanguageTablePolicy
from lerobot_policy_language_table.param_map import UNUSED_PREFIX, to_torch_layout, torch_key, unused_resnet_shapes
from lerobot_policy_language_table.processor_language_table import make_language_table_pre_post_processors

MODEL_COLLECTIONS = ("params", "batch_stats")
# Training state the policy does not need: the optimiser's moments and the step counter.
IGNORED_ENTRIES = ("opt_state", "step")


def _require(tree: dict[str, Any], path: str) -> Any:
    node: Any = tree
    for key in path.split("/"):
        if not isinstance(node, dict) or key not in node:
            raise CheckpointError(f"the checkpoint has no {path!r}: is it the Language-Table BC checkpoint?")
        node = node[key]
    return node


def _check_unused(flat: dict[str, np.ndarray], width: int) -> None:
    expected = unused_resnet_shapes(width, resnet_stage_sizes(flat))
    for path, shape in expected.items():
        found = entry(flat, path)
        if found.shape != shape:
            raise CheckpointError(f"{path} has shape {found.shape}, expected {shape}")
    extra = [p for p in flat if p.split("/", 1)[1].startswith(UNUSED_PREFIX) and p not in expected]
    if extra:
        raise CheckpointError(f"left over: checkpoint entry {extra[0]} is not part of the ResNet's stages")


def load_state_dict(policy: LanguageTablePolicy, flat: dict[str, np.ndarray]) -> None:
    """Copy every checkpoint entry into `policy.model`; raise on a shape mismatch, an unmapped or a missing entry."""
    _check_unused(flat, policy.config.resnet_width)
    state = policy.model.state_dict()
    filled: set[str] = set()
    for path, value in flat.items():
        inner = path.split("/", 1)[1]
        if inner.startswith(UNUSED_PREFIX):
            continue
        key = torch_key(inner)
        if key is None or key not in state:
            raise CheckpointError(f"left over: checkpoint entry {path} {value.shape} has no place in the network")
        array = to_torch_layout(inner, np.asarray(value, dtype=np.float32))
        if tuple(array.shape) != tuple(state[key].shape):
            raise CheckpointError(f"{path} has shape {value.shape}, which does not fit {key} {tuple(state[key].shape)}")
        state[key] = torch.from_numpy(np.array(array, order="C"))  # a writable copy of the read-only buffer
        filled.add(key)
    missing = [k for k in state if k not in filled and not k.endswith("num_batches_tracked")]
    if missing:
        raise CheckpointError(
            f"missing from the checkpoint: {', '.join(missing[:5])}{' ...' if len(missing) > 5 else ''}"
        )
    policy.model.load_state_dict(state)


def _statistic(stats: dict[str, Any], name: str) -> np.ndarray:
    path, value = f"norm_info/action_statistics/{name}", _require(stats, name)
    try:
        array = np.array(value, dtype=np.float32)
    except (TypeError, ValueError) as err:
        raise CheckpointError(f"{path} is {describe(value)}, not 2 numbers: {DAMAGED}") from err
    if array.shape != (2,) or not np.isfinite(array).all():
        raise CheckpointError(f"{path} must hold 2 finite numbers (one per action axis), got {value!r:.60}")
    return array


def action_statistics(checkpoint: dict[str, Any]) -> dict[str, torch.Tensor]:
    """The action mean and std the network's outputs are de-normalised with (std floored at float32 eps, as released)."""
    stats = _require(checkpoint, "norm_info/action_statistics")
    std = np.maximum(_statistic(stats, "std"), np.finfo(np.float32).eps)
    return {"mean": torch.from_numpy(_statistic(stats, "mean")), "std": torch.from_numpy(std)}


def _step(checkpoint: dict[str, Any]) -> int | None:
    step = checkpoint.get("step")
    if step is not None and (isinstance(step, bool) or not isinstance(step, int | np.integer)):
        raise CheckpointError(f"the checkpoint's step is {describe(step)}, not an integer: {DAMAGED}")
    return None if step is None else int(step)


def _check_out_dir(out_dir: Path) -> None:
    """Refuse an OUT_DIR that cannot become the converted policy's folder, before the (slow) conversion."""
    try:
        if out_dir.is_dir() and any(out_dir.iterdir()):
            raise CheckpointError(f"{out_dir} already exists and is not empty; choose a new OUT_DIR")
    except OSError as err:
        raise CheckpointError(f"cannot read {out_dir} ({err.strerror}); choose a new OUT_DIR") from err
    existing = next((p for p in (out_dir, *out_dir.parents) if p.exists()), None)
    if existing is not None and not existing.is_dir():
        raise CheckpointError(f"{existing} is a file, not a directory; choose a new OUT_DIR")


def _write(out_dir: Path, policy: LanguageTablePolicy, stats: dict[str, Any], card: str) -> None:
    """Write the policy folder next to OUT_DIR and rename it at the end, so no OUT_DIR looks done but is not."""
    partial, created = None, [p for p in out_dir.parents if not p.exists()]
    try:
        out_dir.parent.mkdir(parents=True, exist_ok=True)
        folder = out_dir.with_name(f"{out_dir.name}.partial-{os.getpid()}")
        folder.mkdir()
        partial = folder  # set once made: a folder that was there before is never removed
        policy.save_pretrained(partial)
        for pipeline in make_language_table_pre_post_processors(policy.config, dataset_stats=stats):
            pipeline.save_pretrained(partial)
        (partial / "README.md").write_text(card)
        if out_dir.exists():
            out_dir.rmdir()
        partial.rename(out_dir)
    except OSError as err:
        raise CheckpointError(f"cannot write {out_dir} ({err.strerror or err}); choose a writable OUT_DIR") from err
    finally:
        if partial is not None:
            shutil.rmtree(partial, ignore_errors=True)
        for parent in created:  # the folders made for OUT_DIR, deepest first: removed unless OUT_DIR is in them
            with contextlib.suppress(OSError):
                parent.rmdir()


def convert(checkpoint_path: str | Path, out_dir: str | Path) -> Path:
    """Write config.json, model.safetensors, the processor files and README.md to `out_dir`; return it."""
    out_dir = Path(out_dir)
    _check_out_dir(out_dir)
    checkpoint = read_checkpoint(checkpoint_path)
    unknown = sorted(map(str, set(checkpoint) - {*MODEL_COLLECTIONS, *IGNORED_ENTRIES, "norm_info"}))
    if unknown:
        raise CheckpointError(f"left over: unexpected top-level checkpoint entries {unknown}")
    flat = {k: v for c in MODEL_COLLECTIONS for k, v in flat_weights(_require(checkpoint, c), c).items()}
    sizes = network_sizes(flat)
    policy = LanguageTablePolicy(LanguageTableConfig(device="cpu", **sizes))
    load_state_dict(policy, flat)
    stats = {ACTION_KEY: action_statistics(checkpoint)}
    released = LanguageTableConfig(device="cpu")
    other_sizes = {k: v for k, v in sizes.items() if v != getattr(released, k)}
    _write(out_dir, policy, stats, model_card(Path(checkpoint_path).name, _step(checkpoint), other_sizes))
    return out_dir


def push_to_hub(out_dir: Path, repo_id: str) -> str:
    """Upload the converted policy folder as a model repository; returns the repository URL."""
    api = HfApi()
    url = api.create_repo(repo_id, repo_type="model", exist_ok=True)
    api.upload_folder(
        repo_id=repo_id, folder_path=out_dir, repo_type="model", commit_message="Convert Language-Table BC"
    )
    return str(url)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("checkpoint", help="the Flax checkpoint file, e.g. bc_resnet_sim_checkpoint_955000")
    parser.add_argument("out_dir", help="new directory for the LeRobot policy (config.json, model.safetensors, ...)")
    parser.add_argument("--push_to_hub", metavar="REPO", help="also upload OUT_DIR to this Hub model repository")
    args = parser.parse_args(argv)
    try:
        out_dir = convert(args.checkpoint, args.out_dir)
    except CheckpointError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    print(f"wrote {out_dir}: load it with --policy.path={out_dir}")
    if args.push_to_hub:
        try:
            print(f"pushed to {push_to_hub(out_dir, args.push_to_hub)}")
        except (HfHubHTTPError, httpx.HTTPError, OSError) as err:  # refused, unauthorised, unreachable, ...
            reason = str(err).splitlines()[0]
            print(
                f"error: pushing to {args.push_to_hub} failed ({reason}); the converted policy is in {out_dir}",
                file=sys.stderr,
            )
            return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
