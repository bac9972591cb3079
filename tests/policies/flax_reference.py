"""A Flax (linen) reference of the released Language-Table network, written from the spec, for the tests.

Its module names follow the released parameter tree (Flax auto-names), so `init` yields checkpoints in the released
layout; `apply` gives the reference outputs the PyTorch port must reproduce. Test-only: needs jax and flax.
"""

from __future__ import annotations

import flax.linen as nn
import jax
import jax.numpy as jnp
import numpy as np

RESNET_MEAN, RESNET_STD = np.array([0.485, 0.456, 0.406]), np.array([0.229, 0.224, 0.225])


def pos_encoding_2d(d_model: int, height: int, width: int) -> np.ndarray:
    """Channels-first (d, H, W) sin/cos table reshaped without transposing, written loop by loop from the spec."""
    half = d_model // 2
    pe = np.zeros((d_model, height, width))
    for c in range(half // 2):
        div = np.exp(2 * c * -(np.log(10000.0) / half))
        for h in range(height):
            for w in range(width):
                pe[2 * c, h, w], pe[2 * c + 1, h, w] = np.sin(w * div), np.cos(w * div)
                pe[half + 2 * c, h, w], pe[half + 2 * c + 1, h, w] = np.sin(h * div), np.cos(h * div)
    return pe.reshape(height * width, d_model)


def pos_encoding_1d(length: int, d_model: int) -> np.ndarray:
    pe = np.zeros((length, d_model))
    for t in range(length):
        for c in range(0, d_model, 2):
            angle = t * np.exp(c * -(np.log(1.0e4) / d_model))
            pe[t, c], pe[t, c + 1] = np.sin(angle), np.cos(angle)
    return pe


class Bottleneck(nn.Module):
    filters: int
    strides: int

    @nn.compact
    def __call__(self, x):
        bn = lambda name: nn.BatchNorm(use_running_average=True, momentum=0.9, name=name)  # noqa: E731
        residual = x
        y = nn.relu(bn("bn1")(nn.Conv(self.filters, (1, 1), use_bias=False, name="conv1")(x)))
        y = nn.Conv(self.filters, (3, 3), (self.strides, self.strides), use_bias=False, name="conv2")(y)
        y = bn("bn3")(nn.Conv(4 * self.filters, (1, 1), use_bias=False, name="conv3")(nn.relu(bn("bn2")(y))))
        if residual.shape != y.shape:
            strides = (self.strides, self.strides)
            residual = nn.Conv(4 * self.filters, (1, 1), strides, use_bias=False, name="proj_conv")(residual)
            residual = bn("proj_bn")(residual)
        return nn.relu(residual + y)


class ResNetStage(nn.Module):
    blocks: int
    filters: int
    strides: int

    @nn.compact
    def __call__(self, x):
        for k in range(self.blocks):
            x = Bottleneck(self.filters, self.strides if k == 0 else 1, name=f"block{k + 1}")(x)
        return x


class MultiscaleResNet(nn.Module):
    """Computes stages 1 and 2 like the released network, whose pyramid then reads only the max-pool output."""

    @nn.compact
    def __call__(self, x):
        x = nn.Conv(64, (7, 7), (2, 2), use_bias=False, name="init_conv")(x)
        x = nn.relu(nn.BatchNorm(use_running_average=True, momentum=0.9, name="init_bn")(x))
        outputs = [nn.max_pool(x, (3, 3), strides=(2, 2), padding="SAME")]
        for stage, (blocks, filters) in enumerate(((3, 64), (4, 128)), start=1):
            outputs.append(ResNetStage(blocks, filters, 1 if stage == 1 else 2, name=f"stage{stage}")(outputs[-1]))
        return outputs


class ResNetVisualEncoder(nn.Module):
    @nn.compact
    def __call__(self, rgb):
        x = (rgb - RESNET_MEAN) / RESNET_STD
        x = jax.image.resize(x, (x.shape[0], 224, 224, 3), method="bilinear", antialias=False)
        x = MultiscaleResNet()(x)[0]
        pyramid = []
        for channels in (128, 256):
            x = nn.max_pool(nn.relu(nn.Conv(channels, (3, 3))(x)), (2, 2), strides=(2, 2), padding="VALID")
            pyramid.append(x)
        pyramid.append(nn.max_pool(x, (2, 2), strides=(2, 2), padding="VALID"))
        return pyramid


class VisualDescriptorsNet(nn.Module):
    d_model: int

    @nn.compact
    def __call__(self, pyramid):
        tokens = []
        for x in pyramid:
            b, h, w, _ = x.shape
            x = nn.Dense(self.d_model)(x).reshape(b, h * w, self.d_model) * jnp.sqrt(float(self.d_model))
            tokens.append(x + pos_encoding_2d(self.d_model, h, w)[None])
        return jnp.concatenate(tokens, axis=1)


class Mlp(nn.Module):
    @nn.compact
    def __call__(self, x):
        h = nn.Dense(4 * x.shape[-1], name="c_fc")(x)
        return nn.Dense(x.shape[-1], name="c_proj")(h * jax.nn.sigmoid(1.702 * h))


class ResidualAttentionBlock(nn.Module):
    heads: int

    @nn.compact
    def __call__(self, x, mask):
        xn = nn.LayerNorm(epsilon=1e-5, name="ln_1")(x)
        x = x + nn.MultiHeadDotProductAttention(self.heads, name="attn")(xn, xn, mask=mask)
        return x + Mlp(name="mlp")(nn.LayerNorm(epsilon=1e-5, name="ln_2")(x))


class Transformer(nn.Module):
    heads: int
    layers: int

    @nn.compact
    def __call__(self, x, mask):
        for i in range(self.layers):
            x = ResidualAttentionBlock(self.heads, name=f"resblocks.{i}")(x, mask)
        return x


class TextEncoder(nn.Module):
    width: int
    heads: int
    layers: int
    embed_dim: int

    @nn.compact
    def __call__(self, text):
        pos = self.param("positional_embedding", nn.initializers.normal(0.01), (text.shape[1], self.width))
        mask = nn.combine_masks(nn.make_attention_mask(text > 0, text > 0), nn.make_causal_mask(text))
        x = nn.Embed(49408, self.width, name="token_embedding")(text) + pos[None]
        x = Transformer(self.heads, self.layers, name="transformer")(x, mask)
        x = nn.LayerNorm(epsilon=1e-5, name="ln_final")(x)
        x = x[jnp.arange(x.shape[0]), text.argmax(-1)]
        return nn.Dense(self.embed_dim, use_bias=False, name="text_projection")(x)


def feed_forward(x):
    """LayerNorm -> Dense -> ReLU -> Dense, residual; modules created in the released order."""
    h = nn.relu(nn.Dense(x.shape[-1])(nn.LayerNorm()(x)))
    return x + nn.Dense(x.shape[-1])(h)


class PrenormPixelLangEncoder(nn.Module):
    heads: int

    @nn.compact
    def __call__(self, pixels, lang):
        pixels_n = nn.LayerNorm()(pixels)
        lang_n = nn.LayerNorm()(lang)
        return feed_forward(lang + nn.MultiHeadDotProductAttention(self.heads)(lang_n, pixels_n))


class PrenormEncoderLayer(nn.Module):
    heads: int

    @nn.compact
    def __call__(self, x):
        xn = nn.LayerNorm()(x)
        return feed_forward(x + nn.MultiHeadDotProductAttention(self.heads)(xn, xn))


class TemporalTransformer(nn.Module):
    d_model: int
    heads: int

    @nn.compact
    def __call__(self, x):
        x = nn.Dense(self.d_model)(x) * jnp.sqrt(self.d_model) + pos_encoding_1d(x.shape[1], self.d_model)[None]
        for _ in range(2):
            x = PrenormEncoderLayer(self.heads)(x)
        return nn.LayerNorm()(jnp.mean(x, axis=1))


class Encoder(nn.Module):
    clip: tuple[int, int, int, int]  # width, heads, layers, embed_dim

    @nn.compact
    def __call__(self, rgb, tokens):
        b, t = rgb.shape[:2]
        pixels = VisualDescriptorsNet(128)(ResNetVisualEncoder()(rgb.reshape(b * t, *rgb.shape[2:])))
        lang = TextEncoder(*self.clip)(tokens)
        lang = jnp.repeat(lang / jnp.linalg.norm(lang, axis=-1, keepdims=True), t, axis=0)
        x = (nn.Dense(128)(lang) * jnp.sqrt(128))[:, None]
        for _ in range(4):
            x = PrenormPixelLangEncoder(2)(pixels, x)
        x = nn.LayerNorm()(x[:, 0]).reshape(b, t, -1)
        return TemporalTransformer(128, 2)(x)


class ResnetDenseBlock(nn.Module):
    @nn.compact
    def __call__(self, x):
        y = nn.Dense(256)(nn.relu(x))
        y = nn.Dense(256)(nn.relu(y))
        return x + nn.Dense(1024)(nn.relu(y))


class DenseResnet(nn.Module):
    @nn.compact
    def __call__(self, x):
        x = nn.Dense(1024)(x)
        for _ in range(2):
            x = ResnetDenseBlock()(x)
        return x


class SequenceLAVMSE(nn.Module):
    clip: tuple[int, int, int, int] = (512, 8, 12, 512)

    def setup(self):
        self.encoder = Encoder(self.clip)
        self.dense_resnet = DenseResnet()
        self.action_projection = nn.Dense(2)

    def __call__(self, rgb, tokens):
        """rgb (B, T, 180, 320, 3) preprocessed, tokens (B, 77) -> normalised actions (B, 2)."""
        return self.action_projection(self.dense_resnet(self.encoder(rgb, tokens)))
