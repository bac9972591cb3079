"""The sweep file (YAML): `eval` settings every cell shares, a `grid` whose every combination is a cell, and a
list of `cells`, each overriding some settings; expanded into named cells, each a checked EvalConfig."""

from __future__ import annotations

import difflib
import hashlib
import itertools
import json
import re
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import draccus
import yaml

from lerobot_contrast.policies import PRETRAINED_BUILD, policy_entry
from lerobot_contrast.record.shared_episodes import EPISODE_SETTINGS, FOLDER
from lerobot_contrast.spine.build import TASK_ROBOTS, choose_robot, register_robots
from lerobot_contrast.spine.config import ConfigError, EvalConfig, config_json
from lerobot_contrast.spine.flags import flag_names, flag_types

FILE_KEYS = ("output_dir", "eval", "grid", "cells", "share_episodes")
# Settings the sweep decides for every cell: where it is written, whether it resumes, who stages its scenes.
SET_BY_SWEEP = ("output_dir", "resume", "dry_run", "operator", "push_to_hub", "repo_id", "private")
# Settings written as nested mappings (policy: {type: oracle}) or dotted keys (policy.type: oracle): the robot
# and every group of flags (policy, stop, ...).
NESTED = ("robot", *sorted({name.split(".")[0] for name in flag_names(EvalConfig) if "." in name}))
SIMULATORS = tuple(sorted(set(TASK_ROBOTS.values())))
MAX_NAME = 150


class SweepFileError(ConfigError):
    pass


@dataclass(frozen=True)
class Cell:
    """One evaluation of the sweep: its run directory's name, the settings that set it apart, and its config."""

    name: str
    settings: dict[str, Any]
    config: EvalConfig
    label: str | None = None  # the `name` of its entry in the sweep file's cells list
    shared: Path | None = None  # the folder of episodes its cells share (share_episodes: true), else None


def studies_dir() -> Path:
    """The sweep files shipped with the package (the paper's studies), named without their .yaml."""
    return Path(str(resources.files("lerobot_contrast.sweep") / "studies"))


def sweep_file_path(ref: Path) -> Path:
    """The sweep file `ref` names: a path, or a shipped study's name (`paper_sim`) where no such file is here."""
    shipped = studies_dir() / f"{ref.stem}.yaml"
    if not ref.exists() and ref.parent == Path() and ref.suffix in ("", ".yaml") and shipped.is_file():
        return shipped
    return ref


def read_sweep_file(path: Path) -> dict[str, Any]:
    try:
        spec = yaml.safe_load(path.read_text(encoding="utf-8"))
    except OSError as error:
        raise SweepFileError(f"{path}: cannot read the sweep file ({error.strerror})") from None
    except yaml.YAMLError as error:
        raise SweepFileError(f"{path}: not valid YAML ({' '.join(str(error).split())})") from None
    if not isinstance(spec, dict):
        raise SweepFileError(f"{path}: a sweep file is a mapping with keys {', '.join(FILE_KEYS)}")
    unknown = sorted(set(spec) - set(FILE_KEYS))
    if unknown:
        raise SweepFileError(f"{path}: unknown key {unknown[0]!r}; a sweep file has {', '.join(FILE_KEYS)}")
    return spec


def flatten(settings: dict[str, Any]) -> dict[str, Any]:
    """`{policy: {type: oracle}}` as `{"policy.type": "oracle"}`; other mappings (rename_map) stay values."""
    flat: dict[str, Any] = {}
    for key, value in settings.items():
        if key in NESTED and isinstance(value, dict):
            flat |= {f"{key}.{inner}": v for inner, v in value.items()}
        else:
            flat[key] = value
    return flat


def nest(flat: dict[str, Any]) -> dict[str, Any]:
    nested: dict[str, Any] = {}
    for key, value in flat.items():
        head, _, inner = key.partition(".")
        if head in NESTED and inner:
            nested.setdefault(head, {})[inner] = value
        else:
            nested[key] = value
    return nested


def check_keys(path: Path, where: str, settings: dict[str, Any]) -> None:
    known = set(flag_types(EvalConfig))
    for key in settings:
        if key in SET_BY_SWEEP:
            raise SweepFileError(f"{path}: {where}: {key} is set by the sweep for every cell; remove it")
        if key not in known and not key.startswith("robot."):  # robot fields depend on robot.type
            close = difflib.get_close_matches(key, sorted(known), n=1)
            hint = f"did you mean {close[0]}?" if close else "see python -m lerobot_contrast.eval --help"
            raise SweepFileError(f"{path}: {where}: unknown eval setting {key!r}; {hint}")


def _section(path: Path, spec: dict[str, Any], key: str, kind: type) -> Any:
    value = spec.get(key) or kind()
    if not isinstance(value, kind):
        raise SweepFileError(f"{path}: {key} must be a {'mapping' if kind is dict else 'list'}")
    return value


def expand(path: Path, spec: dict[str, Any]) -> list[tuple[str | None, dict[str, Any], dict[str, Any]]]:
    """Each cell as (its list entry's `name` or None, the entry's settings, the grid combination's settings):
    every grid combination for every list entry."""
    grid = flatten(_section(path, spec, "grid", dict))
    entries = _section(path, spec, "cells", list) or [{}]
    check_keys(path, "grid", grid)
    for key, values in grid.items():
        if not isinstance(values, list) or not values:
            raise SweepFileError(f"{path}: grid: {key} must be a non-empty list of values")
    combos = [dict(zip(grid, values, strict=True)) for values in itertools.product(*grid.values())]
    out = []
    for number, entry in enumerate(entries, start=1):
        if not isinstance(entry, dict):
            raise SweepFileError(f"{path}: cells: entry {number} must be a mapping of eval settings")
        entry = dict(entry)
        label = entry.pop("name", None)
        overrides = flatten(entry)
        check_keys(path, f"cells: entry {number}", overrides)
        both = sorted(set(overrides) & set(grid))
        if both:
            raise SweepFileError(f"{path}: cells: entry {number} sets {both[0]}, which the grid also sets")
        out += [(None if label is None else str(label), overrides, combo) for combo in combos]
    return out


def _value_text(value: Any) -> str:
    if isinstance(value, list | tuple):
        return "+".join(map(_value_text, value))
    if isinstance(value, bool) or value is None:
        return str(value).lower()
    return str(value)


def cell_name(label: str | None, entry: dict[str, Any], combo: dict[str, Any]) -> str:
    """`strategy=contrast,perturbations=LB1+LB2,seed=0`, or with a label standing for the entry's settings
    `contrast_lb,seed=0`; filesystem-safe, and shortened with a hash of the whole beyond MAX_NAME."""
    shown = combo if label is not None else entry | combo
    parts = ([] if label is None else [label]) + [f"{key}={_value_text(value)}" for key, value in shown.items()]
    name = re.sub(r"[^A-Za-z0-9._=+,-]", "_", ",".join(parts)) or "base"
    if len(name) > MAX_NAME:
        name = name[: MAX_NAME - 9] + "-" + hashlib.sha256(name.encode()).hexdigest()[:8]
    return name


def cell_config(path: Path, name: str, settings: dict[str, Any]) -> EvalConfig:
    try:
        cfg = draccus.decode(EvalConfig, nest(settings))
    except Exception as error:  # draccus reports a bad value in a multi-line message naming its field
        raise SweepFileError(f"{path}: cell {name}: {' '.join(str(error).split())}") from None
    choose_robot(cfg)
    if cfg.robot.type not in SIMULATORS:
        given = settings.get("robot.type", cfg.robot.type)  # LeRobot names some robots by their config's alias
        raise SweepFileError(
            f"{path}: cell {name}: robot.type={given} is a real robot, one physical place; a sweep runs "
            f"simulated cells only ({', '.join(SIMULATORS)}); evaluate it with python -m lerobot_contrast.eval"
        )
    return cfg


def sweep_cells(path: Path, spec: dict[str, Any], output_dir: Path) -> list[Cell]:
    """The sweep's cells, each with its run directory under `output_dir` (made absolute: workers on other
    machines write there too)."""
    register_robots()  # robot types by name, so a real robot is recognised and refused
    base = flatten(_section(path, spec, "eval", dict))
    check_keys(path, "eval", base)
    share = spec.get("share_episodes", False)
    if not isinstance(share, bool):
        raise SweepFileError(f"{path}: share_episodes must be true or false, got {share!r}")
    shared = output_dir.resolve() / FOLDER if share else None
    cells: list[Cell] = []
    for label, entry, combo in expand(path, spec):
        name, settings = cell_name(label, entry, combo), entry | combo
        if any(cell.name == name for cell in cells):
            raise SweepFileError(f"{path}: two cells are both named {name}; give their cells entries distinct names")
        cfg = cell_config(path, name, base | settings)
        cfg.output_dir = output_dir.resolve() / name
        cells.append(Cell(name, settings, cfg, label, shared))
    return cells


def policy_shares_episodes(cfg: EvalConfig) -> bool:
    """Whether the cell's policy makes episodes the instance decides: a learned one without action noise or language
    blinding (scripted policies and noisy copies draw from each trial's own randomness, which differs between
    cells). Its simulator must also restage its whole state for the cell to share (see the sweep worker)."""
    learned = policy_entry(cfg.policy, cfg.task).build == PRETRAINED_BUILD
    return learned and not cfg.policy.noise_std and not cfg.policy.language_blind


def sharing_predecessors(cells: list[Cell]) -> dict[str, str | None]:
    """For each cell, the cell it waits for: cells that share episodes and stage the same base instances (same
    episode settings, seed and number of instances) run one after another in the sweep's order, so a later one
    takes the episodes an earlier one ran instead of running them beside it; all others run as soon as a CPU is
    free."""
    last: dict[str, str] = {}
    before: dict[str, str | None] = {}
    for cell in cells:
        if cell.shared is None or not policy_shares_episodes(cell.config):
            before[cell.name] = None
            continue
        encoded = config_json(cell.config)
        key = json.dumps(
            [{k: encoded.get(k) for k in EPISODE_SETTINGS}, encoded.get("seed"), encoded.get("n_instances")],
            sort_keys=True,
            default=str,
        )
        before[cell.name] = last.get(key)
        last[key] = cell.name
    return before
