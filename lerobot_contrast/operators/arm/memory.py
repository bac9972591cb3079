"""What the arm spent staging the current trial (robot seconds, a person's seconds, calls), kept in
`arm_staging.json` in the run directory until the trial is journalled, so a run killed mid-staging resumes with
nothing lost and nothing counted twice: the trial is journalled once, with all the effort its staging took."""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path

from lerobot_contrast.contrast.errors import UserError

MEMORY = "arm_staging.json"


@dataclass(frozen=True)
class Spent:
    robot_s: float = 0.0
    person_s: float = 0.0
    calls: int = 0

    def add(self, robot_s: float, person_s: float, calls: int) -> Spent:
        return Spent(self.robot_s + robot_s, self.person_s + person_s, self.calls + calls)


class ArmMemory:
    """`run_dir`: a callable, as the run directory is chosen after the operator is built."""

    def __init__(self, run_dir: Callable[[], Path | None]) -> None:
        self.run_dir = run_dir

    def _path(self) -> Path | None:
        run_dir = self.run_dir()
        return None if run_dir is None else Path(run_dir) / MEMORY

    def recall(self, index: int) -> Spent:
        """What staging trial `index` spent before this session (nothing, for another trial: it was journalled)."""
        path = self._path()
        if path is None or not path.is_file():
            return Spent()
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
            return Spent(**data["spent"]) if data["trial"] == index else Spent()
        except (OSError, UnicodeDecodeError, json.JSONDecodeError, KeyError, TypeError):
            raise UserError(f"{path}: cannot read what the arm spent staging; delete it to count afresh") from None

    def keep(self, index: int, spent: Spent) -> None:
        path = self._path()
        if path is None:
            return
        temporary = path.with_suffix(".tmp")
        temporary.write_text(json.dumps({"trial": index, "spent": asdict(spent)}) + "\n", encoding="utf-8")
        temporary.replace(path)
