"""Read a `flax.training.checkpoints` file (msgpack) with plain `msgpack` and numpy: no jax or flax needed.

Flax stores arrays as msgpack extension 1 (`(shape, dtype name, C-order bytes)`), numpy scalars as extension 3 (the
same, 0-d) and Python complex numbers as extension 2.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import msgpack
import numpy as np

EXT_NDARRAY, EXT_COMPLEX, EXT_NPSCALAR = 1, 2, 3


class CheckpointError(ValueError):
    """The checkpoint file cannot be read or does not hold the released network."""


def _array(data: bytes) -> np.ndarray:
    shape, dtype_name, buffer = msgpack.unpackb(data, raw=True)
    try:
        dtype = np.dtype(dtype_name.decode())
    except TypeError as err:
        raise CheckpointError(f"array of unsupported dtype {dtype_name.decode()!r} in the checkpoint") from err
    return np.frombuffer(buffer, dtype=dtype).reshape(shape)


def _ext_hook(code: int, data: bytes) -> Any:
    if code == EXT_NDARRAY:
        return _array(data)
    if code == EXT_NPSCALAR:
        return _array(data)[()]
    if code == EXT_COMPLEX:
        real, imag = msgpack.unpackb(data)
        return complex(real, imag)
    raise CheckpointError(f"unknown msgpack extension type {code} in the checkpoint (not a Flax checkpoint?)")


def read_checkpoint(path: str | Path) -> dict[str, Any]:
    """The checkpoint's state dict: nested dicts of numpy arrays (e.g. `params`, `batch_stats`, `norm_info`)."""
    path = Path(path)
    if path.is_dir():
        raise CheckpointError(f"{path} is a directory; give the checkpoint file itself")
    try:
        data = path.read_bytes()
    except OSError as err:
        raise CheckpointError(f"cannot read checkpoint {path}: {err.strerror}") from err
    try:
        state = msgpack.unpackb(data, ext_hook=_ext_hook, raw=False, strict_map_key=False)
    except CheckpointError:
        raise
    except ValueError as err:  # msgpack's unpack errors (truncated data, bad format) are ValueErrors
        raise CheckpointError(f"{path} is not a Flax msgpack checkpoint ({err})") from err
    if not isinstance(state, dict):
        raise CheckpointError(f"{path} is not a Flax checkpoint: it holds a {type(state).__name__}, not a state dict")
    return state


def flatten(tree: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    """{"a": {"b": x}} -> {"a/b": x}, the path notation of Flax parameter trees."""
    flat: dict[str, Any] = {}
    for key, value in tree.items():
        path = f"{prefix}{key}"
        if isinstance(value, dict):
            flat.update(flatten(value, f"{path}/"))
        else:
            flat[path] = value
    return flat
