"""Read a `flax.training.checkpoints` file (msgpack) with plain `msgpack` and numpy: no jax or flax needed.

Flax stores arrays as msgpack extension 1 (`(shape, dtype name, C-order bytes)`), numpy scalars as extension 3 (the
same, 0-d) and Python complex numbers as extension 2.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import msgpack
import numpy as np

EXT_NDARRAY, EXT_COMPLEX, EXT_NPSCALAR = 1, 2, 3
NUMERIC_KINDS = "biufc"
# The released parameter tree is 8 levels deep; far deeper nesting is damage, and its paths would make unreadable errors.
MAX_DEPTH = 32


DAMAGED = "the checkpoint is damaged or not a Language-Table BC checkpoint; convert an intact one"


class CheckpointError(ValueError):
    """The checkpoint file cannot be read or does not hold the released network."""


@dataclass(frozen=True)
class Undecodable:
    """An extension value that does not decode; kept in the tree so the error can name its path."""

    reason: str

    def __repr__(self) -> str:
        return f"an undecodable value ({self.reason})"


def _array(data: bytes) -> np.ndarray | Undecodable:
    try:
        shape, dtype_name, buffer = msgpack.unpackb(data, raw=True)
    except (TypeError, ValueError):
        return Undecodable("not a (shape, dtype, bytes) triple")
    if not isinstance(dtype_name, bytes) or not isinstance(buffer, bytes):
        return Undecodable(f"dtype {dtype_name!r:.30} is not a dtype name")
    name = dtype_name.decode(errors="replace")
    try:
        dtype = np.dtype(name)
    except (TypeError, ValueError):
        return Undecodable(f"unsupported dtype {name!r:.30}")
    if dtype.kind not in NUMERIC_KINDS:
        return Undecodable(f"unsupported dtype {name!r:.30}")
    if not isinstance(shape, list | tuple) or not all(isinstance(n, int) and n >= 0 for n in shape):
        return Undecodable(f"shape {shape!r:.30} is not a list of sizes")
    if len(buffer) != dtype.itemsize * math.prod(shape):
        return Undecodable(f"shape {tuple(shape)} of {dtype} but {len(buffer)} bytes")
    return np.frombuffer(buffer, dtype=dtype).reshape(shape)


def _complex(data: bytes) -> complex | Undecodable:
    try:
        real, imag = msgpack.unpackb(data)
        return complex(real, imag)
    except (TypeError, ValueError):
        return Undecodable("not a complex number")


def _ext_hook(code: int, data: bytes) -> Any:
    if code == EXT_NDARRAY:
        return _array(data)
    if code == EXT_NPSCALAR:
        value = _array(data)
        return value if isinstance(value, Undecodable) else value[()]
    if code == EXT_COMPLEX:
        return _complex(data)
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
        reason = str(err) or type(err).__name__  # msgpack's StackError (nested too deep) has no message
        raise CheckpointError(f"{path} is not a Flax msgpack checkpoint ({reason}): is the file complete?") from err
    if not isinstance(state, dict):
        raise CheckpointError(f"{path} is not a Flax checkpoint: it holds a {type(state).__name__}, not a state dict")
    return state


def describe(value: Any) -> str:
    """A short description of a checkpoint value for an error line: 'the str 'abc'', 'an undecodable value (...)'."""
    return repr(value) if isinstance(value, Undecodable) else f"the {type(value).__name__} {value!r:.30}"


def _weights(path: str, value: Any) -> np.ndarray:
    if not isinstance(value, np.ndarray):
        raise CheckpointError(f"{path} is {describe(value)}, not an array of weights: {DAMAGED}")
    if value.dtype.kind != "f":
        raise CheckpointError(f"{path} holds {value.dtype} values, not floating-point weights: {DAMAGED}")
    bad = value.size - int(np.count_nonzero(np.isfinite(value)))
    if bad:
        raise CheckpointError(
            f"{path} holds {bad} NaN or infinite values (training diverged or the file is damaged); "
            "convert a checkpoint whose weights are all finite"
        )
    return value


def flat_weights(tree: Any, name: str) -> dict[str, np.ndarray]:
    """{"a": {"b": x}} -> {"name/a/b": x}, the path notation of Flax parameter trees; every leaf a finite float array."""
    if not isinstance(tree, dict):
        raise CheckpointError(f"{name} is a {type(tree).__name__}, not a tree of named weights: {DAMAGED}")
    flat: dict[str, np.ndarray] = {}
    todo = [(name, tree, 1)]
    while todo:  # a loop, not recursion: msgpack nests 1,000 deep, as deep as Python's recursion limit
        prefix, node, depth = todo.pop()
        if depth > MAX_DEPTH:
            raise CheckpointError(f"{prefix[:80]}... nests deeper than {MAX_DEPTH} levels: {DAMAGED}")
        for key, value in node.items():
            path = f"{prefix}/{key}"
            if isinstance(value, dict):
                todo.append((path, value, depth + 1))
            else:
                flat[path] = _weights(path, value)
    return dict(sorted(flat.items()))
