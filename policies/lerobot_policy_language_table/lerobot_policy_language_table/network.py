"""The released `SequenceLAVMSE` network in PyTorch: ResNet stem and conv pyramid, visual tokens, CLIP language query,
cross-attention fusion per frame, a temporal transformer over the frame history, and a dense ResNet head.

Frames are encoded one at a time (`encode_frames`) and the history is decoded (`decode`), so a caller can keep the
encodings of past frames instead of recomputing them: nothing mixes frames before the temporal transformer.
"""

from __future__ import annotations

import math

import torch
import torch.nn.functional as F
from torch import nn

from lerobot_policy_language_table.clip_text import ClipTextEncoder
from lerobot_policy_language_table.configuration_language_table import LanguageTableConfig
from lerobot_policy_language_table.layers import (
    Attention,
    SameConv2d,
    max_pool_same,
    normalize_imagenet,
    positional_encoding_1d,
    positional_encoding_2d,
    resize_bilinear,
)

LAYER_NORM_EPS = 1e-6  # flax.linen.LayerNorm's default, used everywhere outside CLIP
BATCH_NORM_EPS = 1e-5


class ResNetStem(nn.Module):
    """`MultiscaleResNet` up to its max-pool output, the only output the released network reads.

    The checkpoint also holds ResNet stages 1 and 2; their outputs feed nothing, so they are not built here
    (the converter checks and reports them).
    """

    def __init__(self, width: int) -> None:
        super().__init__()
        self.init_conv = SameConv2d(3, width, 7, stride=2, bias=False)
        self.init_bn = nn.BatchNorm2d(width, eps=BATCH_NORM_EPS)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return max_pool_same(F.relu(self.init_bn(self.init_conv(x))), 3, 2)


class VisualEncoder(nn.Module):
    """Frames (N, 3, H, W) in [0, 1] -> pyramid levels 2, 3, 4, as released (N, 128, 28, 28), (N, 256, 14, 14),
    (N, 256, 7, 7)."""

    def __init__(self, input_size: int, stem_width: int, pyramid_channels: tuple[int, int]) -> None:
        super().__init__()
        self.input_size = input_size
        self.resnet = ResNetStem(stem_width)
        channels = (stem_width, *pyramid_channels)
        self.pyramid_convs = nn.ModuleList(SameConv2d(i, o, 3) for i, o in zip(channels, channels[1:], strict=False))

    def forward(self, frames: torch.Tensor) -> list[torch.Tensor]:
        x = resize_bilinear(normalize_imagenet(frames), self.input_size, self.input_size)
        # Channels-last makes the CPU convolutions and max-pools about twice as fast; the values are the same.
        x = self.resnet(x.contiguous(memory_format=torch.channels_last))
        levels = []
        for conv in self.pyramid_convs:
            x = F.max_pool2d(F.relu(conv(x)), 2, 2)
            levels.append(x)
        levels.append(F.max_pool2d(x, 2, 2))
        return levels


class VisualTokens(nn.Module):
    """Pyramid levels -> (N, 784 + 196 + 49, d_model) tokens: projected, scaled by sqrt(d_model), 2-D encoded."""

    def __init__(self, d_model: int, input_size: int, pyramid_channels: tuple[int, int]) -> None:
        super().__init__()
        self.d_model = d_model
        sizes = [input_size // 4 // 2**k for k in (1, 2, 3)]
        self.dense = nn.ModuleList(nn.Linear(c, d_model) for c in (*pyramid_channels, pyramid_channels[-1]))
        for k, size in enumerate(sizes):
            self.register_buffer(f"pos_{k}", positional_encoding_2d(d_model, size, size), persistent=False)

    def forward(self, levels: list[torch.Tensor]) -> torch.Tensor:
        tokens = []
        for k, (dense, x) in enumerate(zip(self.dense, levels, strict=True)):
            x = dense(x.flatten(2).transpose(1, 2)) * math.sqrt(self.d_model)
            tokens.append(x + getattr(self, f"pos_{k}"))
        return torch.cat(tokens, dim=1)


class FeedForward(nn.Module):
    def __init__(self, d_model: int) -> None:
        super().__init__()
        self.norm = nn.LayerNorm(d_model, eps=LAYER_NORM_EPS)
        self.dense_in = nn.Linear(d_model, d_model)
        self.dense_out = nn.Linear(d_model, d_model)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return x + self.dense_out(F.relu(self.dense_in(self.norm(x))))


class FusionLayer(nn.Module):
    """`PrenormPixelLangEncoder`: the language query attends to the visual tokens; residual on the language path."""

    def __init__(self, d_model: int, num_heads: int) -> None:
        super().__init__()
        self.pixel_norm = nn.LayerNorm(d_model, eps=LAYER_NORM_EPS)
        self.lang_norm = nn.LayerNorm(d_model, eps=LAYER_NORM_EPS)
        self.attn = Attention(d_model, num_heads)
        self.ffn = FeedForward(d_model)

    def forward(self, pixels: torch.Tensor, lang: torch.Tensor) -> torch.Tensor:
        return self.ffn(lang + self.attn(self.lang_norm(lang), self.pixel_norm(pixels)))


class EncoderLayer(nn.Module):
    """`PrenormEncoderLayer`: pre-norm self-attention over time (no causal mask) and feed-forward."""

    def __init__(self, d_model: int, num_heads: int) -> None:
        super().__init__()
        self.norm = nn.LayerNorm(d_model, eps=LAYER_NORM_EPS)
        self.attn = Attention(d_model, num_heads)
        self.ffn = FeedForward(d_model)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        xn = self.norm(x)
        return self.ffn(x + self.attn(xn, xn))


class TemporalTransformer(nn.Module):
    def __init__(self, d_model: int, num_heads: int, layers: int, sequence_length: int) -> None:
        super().__init__()
        self.d_model = d_model
        self.dense = nn.Linear(d_model, d_model)
        self.register_buffer("pos", positional_encoding_1d(sequence_length, d_model), persistent=False)
        self.layers = nn.ModuleList(EncoderLayer(d_model, num_heads) for _ in range(layers))
        self.norm = nn.LayerNorm(d_model, eps=LAYER_NORM_EPS)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        x = self.dense(x) * math.sqrt(self.d_model) + self.pos[: x.shape[1]]
        for layer in self.layers:
            x = layer(x)
        return self.norm(x.mean(dim=1))


class DenseResnetBlock(nn.Module):
    def __init__(self, width: int) -> None:
        super().__init__()
        self.dense = nn.ModuleList([nn.Linear(width, width // 4), nn.Linear(width // 4, width // 4)])
        self.dense.append(nn.Linear(width // 4, width))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        y = x
        for dense in self.dense:
            y = dense(F.relu(y))
        return x + y


class DenseResnet(nn.Module):
    def __init__(self, d_in: int, width: int, blocks: int) -> None:
        super().__init__()
        self.dense = nn.Linear(d_in, width)
        self.blocks = nn.ModuleList(DenseResnetBlock(width) for _ in range(blocks))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        x = self.dense(x)
        for block in self.blocks:
            x = block(x)
        return x


class LanguageTableNet(nn.Module):
    """Frames and an instruction -> the normalised 2-D action (the released model's output before de-normalising)."""

    def __init__(self, config: LanguageTableConfig) -> None:
        super().__init__()
        c, d = config, config.d_model
        self.d_model = d
        pyramid = tuple(c.pyramid_channels)
        self.vision = VisualEncoder(c.resnet_input_size, c.resnet_width, pyramid)
        self.tokens = VisualTokens(d, c.resnet_input_size, pyramid)
        self.text = ClipTextEncoder(
            c.clip_vocab_size, c.clip_context_length, c.clip_width, c.clip_heads, c.clip_layers, c.clip_embed_dim
        )
        self.lang_proj = nn.Linear(c.clip_embed_dim, d)
        self.fusion = nn.ModuleList(FusionLayer(d, c.fusion_heads) for _ in range(c.fusion_layers))
        self.fusion_norm = nn.LayerNorm(d, eps=LAYER_NORM_EPS)
        self.temporal = TemporalTransformer(d, c.num_heads, c.temporal_layers, c.sequence_length)
        self.head = DenseResnet(d, c.dense_resnet_width, c.dense_resnet_blocks)
        self.action_projection = nn.Linear(c.dense_resnet_width, 2)

    def embed_text(self, tokens: torch.Tensor) -> torch.Tensor:
        """CLIP token ids (B, 77) -> the L2-normalised CLIP text embedding (B, clip_embed_dim)."""
        x = self.text(tokens)
        return x / torch.linalg.vector_norm(x, dim=-1, keepdim=True)

    def encode_frames(self, frames: torch.Tensor, text_embedding: torch.Tensor) -> torch.Tensor:
        """Preprocessed frames (N, 3, H, W) and their instructions' embeddings (N, E) -> (N, d_model)."""
        pixels = self.tokens(self.vision(frames))
        lang = (self.lang_proj(text_embedding) * math.sqrt(self.d_model))[:, None]
        for layer in self.fusion:
            lang = layer(pixels, lang)
        return self.fusion_norm(lang[:, 0])

    def decode(self, history: torch.Tensor) -> torch.Tensor:
        """Frame encodings (B, T, d_model), oldest first -> normalised actions (B, 2)."""
        return self.action_projection(self.head(self.temporal(history)))

    def forward(self, frames: torch.Tensor, text_embedding: torch.Tensor) -> torch.Tensor:
        """Preprocessed frame histories (B, T, 3, H, W) and text embeddings (B, E) -> normalised actions (B, 2)."""
        b, t = frames.shape[:2]
        encodings = self.encode_frames(frames.flatten(0, 1), text_embedding.repeat_interleave(t, dim=0))
        return self.decode(encodings.view(b, t, -1))
