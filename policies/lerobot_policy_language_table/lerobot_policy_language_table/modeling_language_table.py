"""`LanguageTablePolicy`: the released Language-Table BC policy as a LeRobot `PreTrainedPolicy`.

At inference it keeps the benchmark's 4-frame history itself (the first frame repeated at reset) and the CLIP text
embedding of each instruction it has seen; `select_action` returns the normalised action, which the postprocessor
de-normalises and clips.
"""

from __future__ import annotations

from collections import deque
from typing import Any

import torch
import torch.nn.functional as F
from lerobot.policies.pretrained import PreTrainedPolicy
from torch import Tensor

from lerobot_policy_language_table.configuration_language_table import ACTION_KEY, LanguageTableConfig
from lerobot_policy_language_table.layers import center_crop_resize
from lerobot_policy_language_table.network import LanguageTableNet
from lerobot_policy_language_table.tokenizer import ClipTokenizer


def _tasks(batch: dict[str, Any], batch_size: int) -> list[str]:
    task = batch.get("task")
    if isinstance(task, str):
        return [task] * batch_size
    if not isinstance(task, list | tuple) or len(task) != batch_size:
        raise ValueError(
            f"language_table needs the instruction of each of the {batch_size} observations as batch['task'] "
            f"(a list of str), got {task!r}"
        )
    return list(task)


class LanguageTablePolicy(PreTrainedPolicy):
    config_class = LanguageTableConfig
    name = "language_table"

    def __init__(self, config: LanguageTableConfig, **kwargs: Any) -> None:
        super().__init__(config)
        config.validate_features()
        self.config: LanguageTableConfig = config
        self.model = LanguageTableNet(config)
        self.model.text.requires_grad_(False)  # frozen in the released training run
        self._tokenizer: ClipTokenizer | None = None
        self._text_cache: dict[str, Tensor] = {}
        self.reset()

    def reset(self) -> None:
        """Start a new episode: forget the frame history (the text embedding cache is kept)."""
        self._history: deque[Tensor] = deque(maxlen=self.config.sequence_length)
        self._history_tasks: list[str] | None = None

    def get_optim_params(self) -> list[Tensor]:
        return [p for p in self.parameters() if p.requires_grad]

    def text_embedding(self, tasks: list[str]) -> Tensor:
        """(B, E) L2-normalised CLIP embeddings of the instructions, computed once per distinct instruction."""
        device = self.model.lang_proj.weight.device
        missing = sorted({t for t in tasks if t not in self._text_cache})
        if missing:
            if self._tokenizer is None:
                self._tokenizer = ClipTokenizer(self.config.clip_context_length)
            tokens = torch.stack([torch.from_numpy(self._tokenizer(t)) for t in missing])
            with torch.no_grad():
                embeddings = self.model.embed_text(tokens.to(device))
            self._text_cache.update(zip(missing, embeddings, strict=True))
        return torch.stack([self._text_cache[t] for t in tasks]).to(device)

    def _frames(self, images: Tensor) -> Tensor:
        if images.dtype == torch.uint8:
            images = images.float() / 255.0
        return center_crop_resize(images, self.config.crop_factor)

    @torch.no_grad()
    def predict_action_chunk(self, batch: dict[str, Any], **kwargs: Any) -> Tensor:
        """(B, 1, 2) normalised action for the current frame and the history before it (one action per step)."""
        images = batch[self.config.image_key]
        tasks = _tasks(batch, images.shape[0])
        encoding = self.model.encode_frames(self._frames(images), self.text_embedding(tasks))
        if tasks != self._history_tasks or self._history[-1].shape != encoding.shape:
            # A new episode, instruction or batch: the benchmark's history starts as the first frame repeated.
            self.reset()
            self._history_tasks = tasks
            self._history.extend([encoding] * self.config.sequence_length)
        else:
            self._history.append(encoding)
        return self.model.decode(torch.stack(list(self._history), dim=1))[:, None]

    @torch.no_grad()
    def select_action(self, batch: dict[str, Any], **kwargs: Any) -> Tensor:
        """(B, 2) normalised action; call `reset()` at the start of every episode."""
        return self.predict_action_chunk(batch)[:, 0]

    def forward(self, batch: dict[str, Any]) -> tuple[Tensor, dict[str, float]]:
        """Behaviour-cloning loss: MSE between predicted and normalised actions, as in the released training.

        `batch[image_key]` holds frame histories (B, T, 3, H, W) (see `observation_delta_indices`); they get the
        evaluation-time centre crop, not the training-time random crop and colour jitter.
        """
        images = batch[self.config.image_key]
        if images.ndim != 5:
            raise ValueError(f"forward needs frame histories (B, T, 3, H, W), got shape {tuple(images.shape)}")
        b, t = images.shape[:2]
        frames = self._frames(images.flatten(0, 1)).view(b, t, *images.shape[2:])
        predicted = self.model(frames, self.text_embedding(_tasks(batch, b)))
        loss = F.mse_loss(predicted, batch[ACTION_KEY])
        return loss, {"loss": loss.item()}
