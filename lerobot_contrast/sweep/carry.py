"""Run directories carried through Ray's object store, for nodes that do not see the sweep folder: such a node runs
a cell on its own disk (resuming from what the driver holds) and its run directory comes back, as a tar, when it ends."""

from __future__ import annotations

import io
import os
import shutil
import tarfile
import tempfile
import uuid
from dataclasses import dataclass
from pathlib import Path

# The sweep folder's mark: a node that reads the same id there shares the driver's storage.
MARK = ".sweep_id"
RECORDINGS = ("rerun", "dataset")
LEFT_BEHIND = (".lock",)  # a lock is its holder's, on its own disk


@dataclass(frozen=True)
class Carry:
    """What a cell needs to run on a node without the sweep folder: the sweep's id, the driver's copy of the cell's
    run directory (a tar, or None where it has not started) and whether recordings come back."""

    sweep_id: str
    folder: Path  # the sweep folder, as the driver sees it
    run_dir: bytes | None = None
    recordings: bool = True

    def shares_folder(self) -> bool:
        try:
            return (self.folder / MARK).read_text(encoding="utf-8").strip() == self.sweep_id
        except OSError:
            return False

    def local_root(self) -> Path:
        """This node's own folder for the sweep, the same path on every node (resume finds it again)."""
        return Path(tempfile.gettempdir()) / "lerobot_contrast_sweeps" / self.sweep_id


def mark_folder(folder: Path) -> str:
    """The sweep folder's id, written on its first run and kept after (a resumed sweep finds its nodes' copies)."""
    path = folder / MARK
    if not path.is_file():
        tmp = path.with_name(MARK + ".tmp")
        tmp.write_text(uuid.uuid4().hex, encoding="utf-8")
        os.replace(tmp, path)
    return path.read_text(encoding="utf-8").strip()


def pack(run_dir: Path, recordings: bool = True) -> bytes:
    """`run_dir` as a tar (without its Rerun recordings and dataset unless `recordings`)."""
    skip = set(LEFT_BEHIND) | (set() if recordings else set(RECORDINGS))
    buffer = io.BytesIO()
    with tarfile.open(fileobj=buffer, mode="w") as tar:
        for path in sorted(run_dir.iterdir()):
            if path.name not in skip:
                tar.add(path, arcname=path.name)
    return buffer.getvalue()


def unpack(archive: bytes, run_dir: Path) -> None:
    """Replace `run_dir`'s contents by the tar's whole: extracted beside it, then swapped in, so a killed driver
    leaves the old copy or the new one, never half of one."""
    run_dir.parent.mkdir(parents=True, exist_ok=True)
    incoming = Path(tempfile.mkdtemp(prefix=f".{run_dir.name}.", dir=run_dir.parent))
    with tarfile.open(fileobj=io.BytesIO(archive), mode="r") as tar:
        tar.extractall(incoming, filter="data")
    old = run_dir.with_name(f".{run_dir.name}.old")
    if run_dir.exists():
        os.replace(run_dir, old)
    os.replace(incoming, run_dir)
    shutil.rmtree(old, ignore_errors=True)


def journal_lines(run_dir: Path) -> int:
    try:
        return (run_dir / "journal.jsonl").read_bytes().count(b"\n")
    except FileNotFoundError:
        return 0


def _packed_journal_lines(archive: bytes) -> int:
    with tarfile.open(fileobj=io.BytesIO(archive), mode="r") as tar:
        try:
            journal = tar.extractfile("journal.jsonl")
        except KeyError:
            return 0
        return journal.read().count(b"\n") if journal else 0


def local_run_dir(carry: Carry, name: str) -> Path:
    """The cell's run directory on this node: the node's own copy from an earlier attempt where it holds more
    trials than the driver's (a driver killed before that attempt's cell came back), else the driver's copy."""
    local = carry.local_root() / name
    local.parent.mkdir(parents=True, exist_ok=True)
    if carry.run_dir is not None and _packed_journal_lines(carry.run_dir) >= journal_lines(local):
        unpack(carry.run_dir, local)
    return local
