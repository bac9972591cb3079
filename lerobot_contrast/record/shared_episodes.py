"""Episodes shared between a sweep's cells (`share_episodes: true`): a simulated episode is a function of the
staged instance, the policy, the robot and the episode limits, so a cell that stages an instance another cell
already ran takes that episode (its path, steps and the scene it left) instead of running it again. Everything
else in the trial's record (cost, label, index) is computed by the cell as usual, so its journal is the same."""

from __future__ import annotations

import hashlib
import json
import os
import pickle
from pathlib import Path
from typing import Any

from lerobot_contrast.contrast.scene import Scene
from lerobot_contrast.contrast.trial import TrialContext

# The settings an episode depends on besides its instance; the rest (strategy, seed, budget...) only decide which
# instances a cell stages, and the instance is in the key.
EPISODE_SETTINGS = (
    "task", "max_episode_steps", "max_episode_s", "policy", "robot", "fps", "operator", "rename_map", "weights",
)  # fmt: skip
FOLDER = "shared_episodes"


def weights_digest(module: Any) -> str:
    """A digest of a torch module's parameters and buffers: the weights themselves, not the path they came from."""
    digest = hashlib.sha256()
    for name, tensor in sorted(module.state_dict().items()):
        digest.update(name.encode())
        digest.update(tensor.detach().cpu().double().numpy().tobytes())  # any dtype, exactly
    return digest.hexdigest()


class SharedEpisodes:
    """A folder of finished episodes keyed by what they depend on; written atomically, so cells in other processes
    (or a killed one) only ever see whole episodes."""

    def __init__(self, folder: Path, settings: dict[str, Any]) -> None:
        self.folder = Path(folder)
        self.scope = json.dumps({k: settings.get(k) for k in EPISODE_SETTINGS}, sort_keys=True, default=str)
        self.hits = self.misses = 0

    def _path(self, context: TrialContext) -> Path:
        instance = json.dumps(context.instance.to_json(), sort_keys=True, default=str)
        digest = hashlib.sha256(f"{self.scope}\n{instance}".encode()).hexdigest()
        return self.folder / digest[:2] / f"{digest}.pkl"

    def get(self, context: TrialContext) -> tuple[Any, Scene] | None:
        """The episode of `context`'s instance another cell ran, with the scene it left, if one did."""
        try:
            with self._path(context).open("rb") as file:
                found = pickle.load(file)
        except (FileNotFoundError, EOFError, pickle.UnpicklingError):
            self.misses += 1
            return None
        self.hits += 1
        return found

    def put(self, context: TrialContext, episode: Any, scene_after: Scene) -> None:
        path = self._path(context)
        path.parent.mkdir(parents=True, exist_ok=True)
        part = path.with_name(f"{path.name}.{os.getpid()}.part")
        part.write_bytes(pickle.dumps((episode, scene_after), protocol=pickle.HIGHEST_PROTOCOL))
        os.replace(part, path)  # whole or absent: a reader never sees half an episode
