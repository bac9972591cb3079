"""Small, random-weight LeRobot policies for the simulated tabletop, saved as `--policy.path` loads them."""

import json
from pathlib import Path

from lerobot_contrast.domains.language_table.config_language_table_sim import LanguageTableSimConfig
from lerobot_contrast.domains.language_table.language_table_sim import LanguageTableSim
from lerobot_contrast.policies.pretrained import save_fresh_policy

# A small ACT: short chunks so the model runs every few steps, and quick on a CPU.
SMALL_ACT = {
    "dim_model": 64,
    "n_heads": 2,
    "dim_feedforward": 128,
    "n_encoder_layers": 1,
    "n_decoder_layers": 1,
    "chunk_size": 5,
    "n_action_steps": 5,
    "use_vae": False,
}


def save_act(directory: Path, camera_key: str = "observation.images.top") -> Path:
    """An ACT policy for the simulated tabletop that expects its camera under `camera_key`."""
    save_fresh_policy(LanguageTableSim(LanguageTableSimConfig()), "act", directory, device="cpu", **SMALL_ACT)
    config_path = directory / "config.json"
    config = json.loads(config_path.read_text())
    config["input_features"][camera_key] = config["input_features"].pop("observation.images.top")
    config_path.write_text(json.dumps(config, indent=2))
    return directory
