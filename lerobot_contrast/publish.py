"""`python -m lerobot_contrast.publish RUN_DIR --repo_id=USER/NAME [--private=true]`: publish a run to the Hugging
Face Hub as a dataset repo (see PublishConfig), with the run viewer's page under view/."""

from __future__ import annotations

import sys
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.spine.flags import ConfigError, parse_config, usage_text, wants_help

USAGE = "python -m lerobot_contrast.publish RUN_DIR --repo_id=USER/NAME [--flag=value | --flag value] ..."


@dataclass
class PublishConfig:
    """Publish a run directory to the Hugging Face Hub as a dataset repo (results table, summary, report, Rerun
    episodes, LeRobotDataset, dataset card, and the run viewer's page in view/). The token comes from
    `hf auth login` or HF_TOKEN, never from the command line; HF_ENDPOINT selects another Hub."""

    # The run directory written by lerobot_contrast.eval; usually given as the first argument (required).
    run_dir: Path | None = None
    # The dataset repo to publish to, USER/NAME or ORG/NAME (required).
    repo_id: str | None = None
    # Create the repo private (an existing repo keeps its visibility).
    private: bool = False
    # Commit message (default: names the run directory).
    message: str | None = None


def parse_args(argv: Sequence[str]) -> PublishConfig:
    args = parse_config(PublishConfig, list(argv), positional="run_dir")
    if args.run_dir is None:
        raise ConfigError(f"give the run directory to publish: {USAGE}")
    if args.repo_id is None:
        raise ConfigError("--repo_id is required: the Hub dataset repo to publish to, USER/NAME")
    return args


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if wants_help(argv):
        print(usage_text(PublishConfig, USAGE))
        return 0
    try:
        args = parse_args(argv)
        from lerobot_contrast.pairing.pair_dir import is_pair_dir
        from lerobot_contrast.record.hub import publish_run, run_files  # after the flags: a typo is answered at once

        if is_pair_dir(args.run_dir):  # an interleaved run: one repo per policy (pairing/publish.py)
            from lerobot_contrast.pairing.publish import publish_pair

            urls = publish_pair(args.run_dir, args.repo_id, private=args.private, commit_message=args.message)
            print("\n".join(f"published {args.run_dir} ({url.split('/datasets/')[-1]})" for url in urls))
            return 0
        run_files(args.run_dir)  # a folder that holds no run is refused before the viewer reads it
        with tempfile.TemporaryDirectory(prefix="lerobot-contrast-view-") as tmp:
            view = viewer_files(args.run_dir, Path(tmp) / "view")
            url = publish_run(
                args.run_dir, args.repo_id, private=args.private, commit_message=args.message, extra_files=view
            )
    except UserError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("\ninterrupted: nothing was committed; run the same command again to publish", file=sys.stderr)
        return 130
    print(f"published {args.run_dir} to {args.repo_id}: {url}")
    return 0


def viewer_files(run_dir: Path, out: Path) -> dict[str, Path]:
    """The run viewer's page of the run (`view --bundle`), as files under view/ in the repo: it opens from a
    download of the repo with no Python, and plays the published dataset's own videos (../dataset/)."""
    from lerobot_contrast.view.bundle import write_bundle
    from lerobot_contrast.view.payload import load_inputs

    files = write_bundle(load_inputs([str(run_dir)]), out, video_base="../dataset/")
    return {f"view/{path.relative_to(out).as_posix()}": path for path in files}


if __name__ == "__main__":
    sys.exit(main())
