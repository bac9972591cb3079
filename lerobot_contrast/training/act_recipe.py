"""LeRobot's ACT sized for a 2-core CPU and 160x120 frames: what scripts/train/train_so101_act.py trains on the twin's
demonstrations and what scripts/bench/bench_twin.py times with random weights, so both measure the same network.

Why: no VAE (the scripted demonstrator is deterministic: one mode to fit, and the VAE encoder would cost more than the
backbone at this frame size); a smaller transformer; chunks of 50 steps (1.7 s at 30 Hz) run 25 at a time; ResNet-18
from scratch, as nothing may download ImageNet weights here, so the backbone learns at the transformer's rate."""

from __future__ import annotations

# The network: ACTConfig's fields.
ARCHITECTURE = {
    "dim_model": 256,
    "dim_feedforward": 1024,
    "n_encoder_layers": 4,
    "n_decoder_layers": 1,
    "chunk_size": 50,
    "n_action_steps": 25,
    "use_vae": False,
}
# How it is trained: ACTConfig's fields too, as lerobot-train takes them.
TRAINING = {"pretrained_backbone_weights": None, "optimizer_lr": 1e-4, "optimizer_lr_backbone": 1e-4}


def policy_flags() -> list[str]:
    """The recipe as lerobot-train's `--policy.*` flags."""

    def said(value: object) -> str:
        return "null" if value is None else str(value).lower() if isinstance(value, bool) else str(value)

    return [f"--policy.{name}={said(value)}" for name, value in {**ARCHITECTURE, **TRAINING}.items()]
