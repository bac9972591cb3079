"""The README.md (Hub model card) written next to a converted Language-Table policy."""

from __future__ import annotations

from huggingface_hub import ModelCard, ModelCardData

BODY = """
# Language-Table BC (ResNet + CLIP, simulation)

The behaviour-cloning policy released with *Interactive Language: Talking to Robots in Real Time* (Lynch et al.,
2022), converted from its Flax checkpoint `{source}`{step} to a LeRobot policy of type `language_table`
(plugin distribution `lerobot_policy_language_table`).

- Network: LAVA (`SequenceLAVMSE`): a ResNet stem and conv pyramid turn each 180x320 camera frame into 1029 visual
  tokens; the frozen CLIP ViT-B/16 text embedding of the instruction attends to them (cross-attention, 4 layers); a
  temporal transformer reads the last 4 frames; a dense ResNet head outputs a 2-D end-effector delta.
- Inputs: `observation.images.top` (RGB, 180x320, values in [0, 1]) and the instruction as `task`.
- Output: `action` = (delta_x, delta_y) in metres per 10 Hz step, de-normalised with the checkpoint's action
  statistics and clipped to ±0.1.
- The checkpoint's ResNet stages 1-2 are not converted: the released network computes them but reads neither output.

With the plugin installed, load it in any LeRobot tool with `--policy.path=<this repository or folder>`, or in
Python with `LanguageTablePolicy.from_pretrained(...)` and `make_pre_post_processors(config, pretrained_path=...)`.

Licence: the checkpoint was released without a licence of its own (the Language-Table code is Apache-2.0).
"""


def model_card(source: str, step: int | None, other_sizes: dict[str, object]) -> str:
    """The card; `other_sizes` are the config sizes in which this checkpoint's network differs from the released one."""
    data = ModelCardData(
        library_name="lerobot",
        pipeline_tag="robotics",
        license="other",
        tags=["lerobot", "robotics", "language_table", "behavior-cloning"],
    )
    body = BODY.format(source=source, step="" if step is None else f" (training step {step:,})")
    if other_sizes:
        sizes = ", ".join(f"`{k}={v}`" for k, v in other_sizes.items())
        body += f"\nThis checkpoint's network is the released architecture at other sizes: {sizes}.\n"
    return str(ModelCard(f"---\n{data.to_yaml()}\n---\n{body}"))
