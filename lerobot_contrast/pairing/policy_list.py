"""`--policies=A,B[,C]`: each entry a registered policy type, a LeRobot policy type, a checkpoint directory or a Hub
repo id, with its own `--policy.*` options after colons, e.g. `tabletop_pointer:noise_std=0.02`."""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass
from pathlib import Path

from lerobot_contrast.policies import POLICIES
from lerobot_contrast.policies.base import PolicyArgs
from lerobot_contrast.spine.flags import ConfigError

# The --policy.* options an entry may set for itself, with how their values are read.
OPTIONS = {"noise_std": float, "language_blind": float, "device": str, "use_amp": bool}
TRUE_WORDS, FALSE_WORDS = ("true", "1", "yes"), ("false", "0", "no")


@dataclass(frozen=True)
class PolicySpec:
    """One compared policy: its label (the entry as given), its settings, and its run directory's name."""

    label: str
    args: PolicyArgs
    dirname: str


def parse_policies(text: str, defaults: PolicyArgs) -> list[PolicySpec]:
    """The entries of --policies, each over `defaults` (the --policy.* flags given for all of them)."""
    entries = [e.strip() for e in text.strip().removeprefix("[").removesuffix("]").split(",") if e.strip()]
    if len(entries) < 2:
        raise ConfigError(f"--policies needs at least two policies separated by commas, got {text!r}")
    repeated = sorted({e for e in entries if entries.count(e) > 1})
    if repeated:
        raise ConfigError(f"--policies: {', '.join(repeated)} given more than once; give each policy once")
    return [_spec(entry, number, defaults) for number, entry in enumerate(entries, start=1)]


def _spec(entry: str, number: int, defaults: PolicyArgs) -> PolicySpec:
    name, *options = entry.split(":")
    if not name:
        raise ConfigError(f"--policies: entry {entry!r} names no policy; start it with a policy type or path")
    args = dataclasses.replace(defaults, path=None, type=None)
    args = dataclasses.replace(args, **({"type": name} if _is_type(name) else {"path": name}))
    for option in options:
        key, _, value = option.partition("=")
        if key not in OPTIONS or not value:
            raise ConfigError(
                f"--policies: {option!r} in {entry!r} is not an option; write NAME:KEY=VALUE with KEY one of "
                f"{', '.join(OPTIONS)}"
            )
        args = dataclasses.replace(args, **{key: _value(key, value, entry)})
    return PolicySpec(entry, args, f"{number}_{re.sub(r'[^A-Za-z0-9._-]+', '-', entry).strip('-')}")


def _is_type(name: str) -> bool:
    """A registered policy or a bare LeRobot type name (act, diffusion); anything with a slash is a path or repo."""
    if name in POLICIES:
        return True
    return "/" not in name and not name.startswith((".", "~")) and not Path(name).is_dir()


def _value(key: str, value: str, entry: str) -> float | str | bool:
    kind = OPTIONS[key]
    if kind is bool:
        if value.lower() not in TRUE_WORDS + FALSE_WORDS:
            raise ConfigError(f"--policies: {key}={value} in {entry!r} is not true or false")
        return value.lower() in TRUE_WORDS
    try:
        return kind(value)
    except ValueError:
        raise ConfigError(f"--policies: {key}={value} in {entry!r} is not a number") from None
