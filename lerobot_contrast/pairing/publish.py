"""Publishing an interleaved run: each policy's run directory as its own Hub dataset repo, USER/NAME-<its folder>
(a normal published run, so `--stop.compare=hub:...` and `report hub:...` read it as any other)."""

from __future__ import annotations

from pathlib import Path

from lerobot_contrast.pairing.pair_dir import policy_run_dirs


def publish_pair(path: Path, repo_id: str, private: bool = False, commit_message: str | None = None) -> list[str]:
    from lerobot_contrast.record.hub import check_repo_id, publish_run

    targets = [(run_dir, f"{repo_id}-{run_dir.name}") for run_dir in policy_run_dirs(Path(path))]
    for _, target in targets:  # every name is checked before anything is uploaded
        check_repo_id(target)
    return [publish_run(run_dir, target, private=private, commit_message=commit_message) for run_dir, target in targets]
