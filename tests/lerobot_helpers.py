"""Build small, random-weight LeRobot policies for the simulated tabletop, saved as `--policy.path` loads them."""

from pathlib import Path

from lerobot.policies import get_policy_class, make_policy_config, make_pre_post_processors
from lerobot.utils.feature_utils import dataset_to_policy_features

from lerobot_contrast.pretrained_policy import robot_dataset_features
from lerobot_contrast.sims.language_table.config_language_table_sim import LanguageTableSimConfig
from lerobot_contrast.sims.language_table.language_table_sim import LanguageTableSim

# A small ACT: no pretrained backbone (nothing is downloaded), short chunks so the model runs every few steps.
SMALL_ACT = {
    "pretrained_backbone_weights": None,
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
    """An ACT policy with the simulated tabletop's features (its camera under `camera_key`), written by
    LeRobot's own save_pretrained."""
    features = dataset_to_policy_features(robot_dataset_features(LanguageTableSim(LanguageTableSimConfig())))
    features[camera_key] = features.pop("observation.images.top")
    config = make_policy_config("act", device="cpu", **SMALL_ACT)
    config.input_features = {k: v for k, v in features.items() if k != "action"}
    config.output_features = {"action": features["action"]}
    policy = get_policy_class("act")(config)
    preprocessor, postprocessor = make_pre_post_processors(config, dataset_stats=None)
    for part in (policy, preprocessor, postprocessor):
        part.save_pretrained(directory)
    return directory
