"""Instruction words -> ids: the vocabulary is the training dataset's words; 0 pads, 1 is any unseen word."""

from __future__ import annotations

import re
from collections.abc import Iterable

import torch

PAD, UNKNOWN = 0, 1
_WORD = re.compile(r"[a-z]+")


def words(text: str) -> list[str]:
    return _WORD.findall(text.lower())


def build_vocabulary(instructions: Iterable[str]) -> list[str]:
    """Sorted distinct words of `instructions`."""
    return sorted({w for text in instructions for w in words(text)})


class Tokenizer:
    def __init__(self, vocabulary: list[str], max_words: int) -> None:
        self.ids = {w: i + 2 for i, w in enumerate(vocabulary)}
        self.max_words = max_words
        self.size = len(vocabulary) + 2

    def __call__(self, texts: list[str], device: torch.device | str = "cpu") -> torch.Tensor:
        """(B, max_words) int64 ids; longer instructions keep their first max_words words."""
        out = torch.zeros(len(texts), self.max_words, dtype=torch.long)
        for row, text in enumerate(texts):
            ids = [self.ids.get(w, UNKNOWN) for w in words(text)][: self.max_words] or [UNKNOWN]
            out[row, : len(ids)] = torch.tensor(ids)
        return out.to(device)
