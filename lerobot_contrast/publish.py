"""`python -m lerobot_contrast.publish RUN_DIR --repo_id USER/NAME [--private]`: publish a run to the Hugging Face
Hub as a dataset repo (results table, summary, report, Rerun episodes, LeRobotDataset, dataset card).

The token comes from `hf auth login` or HF_TOKEN, never from the command line; HF_ENDPOINT selects another Hub."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from lerobot_contrast.contrast.errors import UserError


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # type: ignore[override]
        raise UserError(f"{message} (see --help)")


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="python -m lerobot_contrast.publish", description=__doc__)
    parser.add_argument("run_dir", type=Path, help="run directory written by lerobot_contrast.eval")
    parser.add_argument("--repo_id", required=True, help="dataset repo to publish to, USER/NAME or ORG/NAME")
    parser.add_argument(
        "--private", action="store_true", help="create the repo private (an existing repo keeps its visibility)"
    )
    parser.add_argument("--message", help="commit message (default: names the run directory)")
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    from lerobot_contrast.record.hub import publish_run

    try:
        args = _parser().parse_args(argv)
        url = publish_run(args.run_dir, args.repo_id, private=args.private, commit_message=args.message)
    except UserError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("\ninterrupted: nothing was committed; run the same command again to publish", file=sys.stderr)
        return 130
    print(f"published {args.run_dir} to {args.repo_id}: {url}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
