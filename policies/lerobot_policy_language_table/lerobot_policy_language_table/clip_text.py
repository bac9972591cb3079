"""The CLIP ViT-B/16 text tower as Scenic's `clip_layers.TextEncoder` computes it (frozen in the released policy)."""

from __future__ import annotations

import torch
from torch import nn

from lerobot_policy_language_table.layers import Attention

CLIP_LAYER_NORM_EPS = 1e-5


class QuickGELU(nn.Module):
    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return x * torch.sigmoid(1.702 * x)


class Mlp(nn.Module):
    def __init__(self, width: int) -> None:
        super().__init__()
        self.c_fc = nn.Linear(width, 4 * width)
        self.act = QuickGELU()
        self.c_proj = nn.Linear(4 * width, width)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.c_proj(self.act(self.c_fc(x)))


class ResidualAttentionBlock(nn.Module):
    def __init__(self, width: int, heads: int) -> None:
        super().__init__()
        self.ln_1 = nn.LayerNorm(width, eps=CLIP_LAYER_NORM_EPS)
        self.attn = Attention(width, heads)
        self.ln_2 = nn.LayerNorm(width, eps=CLIP_LAYER_NORM_EPS)
        self.mlp = Mlp(width)

    def forward(self, x: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
        xn = self.ln_1(x)
        x = x + self.attn(xn, xn, mask)
        return x + self.mlp(self.ln_2(x))


class ClipTextEncoder(nn.Module):
    """Token ids (B, 77), zero padded, -> (B, embed_dim): the final-LayerNorm state at the end-of-text token, projected.

    Attention is causal and ignores token id 0 (padding), as in Scenic; the end-of-text token has the largest id,
    so `argmax` finds it.
    """

    def __init__(self, vocab_size: int, context_length: int, width: int, heads: int, layers: int, embed_dim: int):
        super().__init__()
        self.token_embedding = nn.Embedding(vocab_size, width)
        self.positional_embedding = nn.Parameter(torch.zeros(context_length, width))
        self.resblocks = nn.ModuleList(ResidualAttentionBlock(width, heads) for _ in range(layers))
        self.ln_final = nn.LayerNorm(width, eps=CLIP_LAYER_NORM_EPS)
        self.text_projection = nn.Linear(width, embed_dim, bias=False)

    def forward(self, tokens: torch.Tensor) -> torch.Tensor:
        n = tokens.shape[1]
        valid = tokens > 0
        causal = torch.ones(n, n, dtype=torch.bool, device=tokens.device).tril()
        mask = (valid[:, :, None] & valid[:, None, :] & causal)[:, None]
        x = self.token_embedding(tokens) + self.positional_embedding[None]
        for block in self.resblocks:
            x = block(x, mask)
        x = self.ln_final(x)
        x = x[torch.arange(x.shape[0], device=x.device), tokens.argmax(dim=-1)]
        return self.text_projection(x)
