"""Malformed checkpoints and unusable output paths: the converter answers each with one line and exit code 2, raises
no traceback, and leaves nothing behind."""

from __future__ import annotations

import errno
import subprocess
import sys
from pathlib import Path

import msgpack
import numpy as np
import pytest
from flax import serialization, traverse_util
from lerobot_policy_language_table.convert import main
from lerobot_policy_language_table.modeling_language_table import LanguageTablePolicy

from .synthetic_checkpoint import train_state

KERNEL = "params/action_projection/kernel"
BIAS = "params/action_projection/bias"
MEAN, STD = "norm_info/action_statistics/mean", "norm_info/action_statistics/std"
EMBEDDING = "params/encoder/TextEncoder_0/token_embedding/embedding"
FUSION_QUERY = "params/encoder/PrenormPixelLangEncoder_1/MultiHeadDotProductAttention_0/query/kernel"
BN_VAR = "batch_stats/encoder/ResNetVisualEncoder_0/MultiscaleResNet_0/init_bn/var"


def _ext(shape, dtype, buffer) -> msgpack.ExtType:
    """A Flax array extension (code 1) with arbitrary, possibly malformed, fields."""
    return msgpack.ExtType(1, msgpack.packb((shape, dtype, buffer)))


def _node(state: dict, path: str) -> tuple[dict, str]:
    *parents, key = path.split("/")
    for name in parents:
        state = state[name]
    return state, key


def _set(path: str, value):
    def prepare(state: dict) -> None:
        node, key = _node(state, path)
        node[key] = value

    return prepare


def _change(path: str, change):
    def prepare(state: dict) -> None:
        node, key = _node(state, path)
        node[key] = change(node[key])

    return prepare


def _one_nan(a: np.ndarray) -> np.ndarray:
    a = a.copy()
    a.flat[1] = np.nan
    return a


# (case, edit of the released-format state dict, what the one line must say)
EDITS = [
    ("params is a list", _set("params", [1, 2]), "params is a list, not a tree of named weights"),
    ("batch_stats is a number", _set("batch_stats", 3.5), "batch_stats is a float, not a tree"),
    ("integer leaf", _set(BIAS, 3), f"{BIAS} is the int 3, not an array of weights"),
    ("integer array", _set(BIAS, np.zeros(2, np.int32)), f"{BIAS} holds int32 values, not floating-point weights"),
    ("text leaf", _set(BIAS, "zero"), f"{BIAS} is the str 'zero', not an array"),
    ("numpy scalar leaf", _set(BIAS, np.float32(1.0)), f"{BIAS} is the float32"),
    ("dtype not text", _set(BIAS, _ext([2], 7, b"\0" * 8)), "(dtype 7 is not a dtype name)"),
    ("dtype of strings", _set(BIAS, _ext([2], b"<U1", b"\0" * 8)), "unsupported dtype '<U1'"),
    ("dtype unknown", _set(BIAS, _ext([2], b"bfloat16", b"\0" * 4)), "unsupported dtype 'bfloat16'"),
    ("shape not sizes", _set(BIAS, _ext("ab", b"<f4", b"\0" * 8)), "shape b'ab' is not a list of sizes"),
    ("truncated array", _set(BIAS, _ext([2], b"<f4", b"\0" * 4)), "shape (2,) of float32 but 4 bytes"),
    ("array not a triple", _set(BIAS, msgpack.ExtType(1, msgpack.packb(5))), "not a (shape, dtype, bytes) triple"),
    ("NaN weight", _change(KERNEL, _one_nan), f"{KERNEL} holds 1 NaN or infinite values"),
    ("inf statistic", _change(BN_VAR, lambda a: a + np.inf), f"{BN_VAR} holds 64 NaN or infinite values"),
    ("norm field text", _set(MEAN, "zero"), f"{MEAN} is the str 'zero', not 2 numbers"),
    ("norm field a dict", _set(STD, {"x": 1}), f"{STD} is the dict {{'x': 1}}, not 2 numbers"),
    ("norm field NaN", _set(MEAN, np.array([0.0, np.nan], np.float32)), f"{MEAN} must hold 2 finite numbers"),
    ("norm_info a list", _set("norm_info", [1]), "has no 'norm_info/action_statistics'"),
    ("step text", _set("step", "955k"), "step is the str '955k', not an integer"),
    ("embedding 1-D", _set(EMBEDDING, np.zeros(3, np.float32)), f"{EMBEDDING} has shape (3,), not 2-D"),
    ("3-D actions", _set(KERNEL, np.zeros((1024, 3), np.float32)), "gives 3-D actions; Language-Table's are 2-D"),
    ("heads differ", _change(FUSION_QUERY, lambda a: a.reshape(128, 4, 32)), "differ in attention heads [2, 4]"),
]


def _checkpoint(tmp_path: Path, variables: dict, edit=None) -> Path:
    state = traverse_util.unflatten_dict(traverse_util.flatten_dict(train_state(variables)))  # fresh dicts
    if edit is not None:
        edit(state)
    path = tmp_path / "ckpt"
    path.write_bytes(serialization.msgpack_serialize(state))
    return path


def _file(tmp_path: Path, data: bytes) -> Path:
    (tmp_path / "ckpt").write_bytes(data)
    return tmp_path / "ckpt"


def _int_key(tmp_path: Path, variables: dict) -> Path:
    """The state dict with one more entry, keyed 7 (Flax's writer sorts keys, so it cannot write mixed ones)."""
    data = _checkpoint(tmp_path, variables).read_bytes()
    assert data[0] == 0x85  # a msgpack map of 5 entries: step, params, opt_state, batch_stats, norm_info
    return _file(tmp_path, b"\x86" + data[1:] + msgpack.packb(7) + msgpack.packb(1))


def _full_disk(self, folder, *args, **kwargs):
    Path(folder, "model.safetensors").write_bytes(b"half")
    raise OSError(errno.ENOSPC, "No space left on device")


# (case, checkpoint, OUT_DIR, what the one line must say); the checkpoint is written to tmp_path / "ckpt"
FILES_AND_PATHS = [
    (
        "nested 990 deep",
        lambda t, v: _file(t, b"\x81\xa6params" + b"\x81\xa1a" * 990 + b"\x01"),
        "out",
        "nests deeper than 32 levels",
    ),
    ("integer top-level key", _int_key, "out", "unexpected top-level checkpoint entries ['7']"),
    ("cut short", lambda t, v: _file(t, _checkpoint(t, v).read_bytes()[:-100]), "out", "is the file complete?"),
    ("nested 1200 deep", lambda t, v: _file(t, b"\x81\xa1a" * 1200 + b"\x01"), "out", "checkpoint (StackError)"),
    ("out is a file", _checkpoint, "a_file", "a_file is a file, not a directory; choose a new OUT_DIR"),
    ("out under a file", _checkpoint, "a_file/out", "a_file is a file, not a directory"),
    ("out unwritable", _checkpoint, "/proc/language_table_out", "cannot write /proc/language_table_out"),
    ("disk full", _checkpoint, "full/out", "cannot write"),
]


def _run(tmp_path: Path, argv: list[str], capsys) -> str:
    before = sorted(tmp_path.rglob("*"))
    assert main(argv) == 2
    out, err = capsys.readouterr()
    assert not out and err.startswith("error: ") and err.count("\n") == 1 and "Traceback" not in err
    assert sorted(tmp_path.rglob("*")) == before, "the conversion left files behind"
    return err


@pytest.mark.parametrize(("edit", "message"), [pytest.param(e, m, id=i) for i, e, m in EDITS])
def test_malformed_checkpoints_get_one_line_and_leave_nothing(tmp_path, small_variables, edit, message, capsys):
    checkpoint = _checkpoint(tmp_path, small_variables, edit)
    assert message in _run(tmp_path, [str(checkpoint), str(tmp_path / "out")], capsys)


@pytest.mark.parametrize(
    ("checkpoint", "out", "message"), [pytest.param(c, o, m, id=i) for i, c, o, m in FILES_AND_PATHS]
)
def test_bad_files_and_output_paths_get_one_line_and_leave_nothing(
    tmp_path, small_variables, checkpoint, out, message, capsys, monkeypatch
):
    (tmp_path / "a_file").write_text("mine")
    if out == "full/out":
        monkeypatch.setattr(LanguageTablePolicy, "save_pretrained", _full_disk)
    path = checkpoint(tmp_path, small_variables)
    assert message in _run(tmp_path, [str(path), str(tmp_path / out)], capsys)
    assert (tmp_path / "a_file").read_text() == "mine"


def test_the_cli_exits_2_with_one_line_and_no_traceback(tmp_path, small_variables):
    checkpoint = _checkpoint(tmp_path, small_variables, _set("params", [1, 2]))
    result = subprocess.run(
        [sys.executable, "-m", "lerobot_policy_language_table.convert", str(checkpoint), str(tmp_path / "out")],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert result.returncode == 2 and result.stderr.count("\n") == 1 and "Traceback" not in result.stderr
    assert not (tmp_path / "out").exists()
