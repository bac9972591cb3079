"""`python -m lerobot_contrast.review RUN_DIR`: pick a run's episodes by perturbation, outcome or base instance,
merge their Rerun recordings so each base instance and its perturbations sit side by side, and open the result
in the Rerun viewer, or serve the web viewer on localhost (`--web`, works offline)."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING
from urllib.parse import quote

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.perturbation import perturbation_label
from lerobot_contrast.contrast.trial import TrialRecord
from lerobot_contrast.record.journal import read_journal
from lerobot_contrast.spine.flags import parse_config, usage_text, wants_help

if TYPE_CHECKING:
    import rerun.blueprint as rrb

ORIGINAL = "original"
OUTCOMES = ("success", "failure")
DEFAULT_OUTPUT = Path("review") / "review.rrd"


class ReviewError(UserError):
    pass


def load_records(run_dir: Path) -> list[TrialRecord]:
    """The journal's records, read without touching the file: the run may still be writing it."""
    from lerobot_contrast.pairing.pair_dir import is_pair_dir, pair_records

    if is_pair_dir(run_dir):  # an interleaved run: every policy's episodes, side by side per base
        return pair_records(run_dir)
    if not (run_dir / "journal.jsonl").is_file():
        raise ReviewError(f"{run_dir}: no journal.jsonl; pass a run directory written by lerobot_contrast.eval")
    return read_journal(run_dir / "journal.jsonl")


def _names(values: str | None) -> list[str] | None:
    if values is None:
        return None
    return [v.strip().removeprefix("Δ") for v in values.split(",") if v.strip()]


def _check_known(flag: str, names: list[str] | None, recorded: set[str]) -> None:
    """A filter value with no recorded episode is a typo or a perturbation that never applied: say so."""
    unknown = [name for name in names or [] if name not in recorded]
    if unknown:
        shown = ", ".join(sorted(recorded)) if len(recorded) <= 12 else f"{len(recorded)} values"
        raise ReviewError(f"{flag}: no recorded episode has {', '.join(unknown)}; this run has {shown}")


def select(
    records: Sequence[TrialRecord],
    perturbation: str | None = None,
    outcome: str | None = None,
    base: str | None = None,
) -> list[TrialRecord]:
    """The recorded episodes matching every given filter, grouped by base instance (originals first)."""
    if outcome is not None and outcome not in OUTCOMES:
        raise ReviewError(f"--outcome must be one of {', '.join(OUTCOMES)}, got {outcome!r}")
    recorded = [r for r in records if r.status == "done" and r.rerun_path]
    perturbations, bases = _names(perturbation), _names(base)
    chosen = [
        r
        for r in recorded
        if (perturbations is None or (r.perturbation or ORIGINAL) in perturbations)
        and (outcome is None or bool(r.success) == (outcome == "success"))
        and (bases is None or r.base_id in bases)
    ]
    if not recorded:
        raise ReviewError("the run recorded no Rerun episodes (its journal names no .rrd files)")
    _check_known("--perturbation", perturbations, {r.perturbation or ORIGINAL for r in recorded})
    _check_known("--base", bases, {r.base_id for r in recorded})
    if not chosen:
        seen = sorted({r.perturbation or ORIGINAL for r in recorded})
        raise ReviewError(
            f"no recorded episode matches the filters; this run has perturbations {', '.join(seen)} "
            f"and {len({r.base_id for r in recorded})} base instances"
        )
    order = {base_id: k for k, base_id in enumerate(dict.fromkeys(r.base_id for r in chosen))}
    return sorted(chosen, key=lambda r: (order[r.base_id], r.perturbation is not None, r.index))


def episode_title(record: TrialRecord) -> str:
    verdict = "✓" if record.success else "✗"
    policy = record.extra.get("pairing", {}).get("policy")  # set in an interleaved run (--policies)
    return f"{perturbation_label(record.perturbation)} · trial {record.index + 1} {verdict}" + (
        f" · {policy}" if policy else ""
    )


def entity_prefix(record: TrialRecord) -> str:
    name = re.sub(r"[^A-Za-z0-9_-]+", "_", record.perturbation or ORIGINAL)
    policy = record.extra.get("pairing", {}).get("policy")
    suffix = "" if policy is None else "_" + re.sub(r"[^A-Za-z0-9_-]+", "_", policy)
    return f"/episodes/trial_{record.index:06d}_{name}{suffix}"


def _remap(path: str, prefix: str) -> str | None:
    """An episode's entity path inside the merged recording; its properties become ordinary static data."""
    if path == "/__properties":  # the recording's name and start time: the merged recording has its own
        return None
    if path.startswith("/__properties/"):
        return f"{prefix}/properties/{path.removeprefix('/__properties/')}"
    return prefix + path


def _cell(record: TrialRecord, cameras: list[str]) -> rrb.Container:
    import rerun.blueprint as rrb

    prefix = entity_prefix(record)
    views = [rrb.Spatial2DView(origin=f"{prefix}/camera/{cam}", name=cam) for cam in cameras]
    views += [
        rrb.Spatial2DView(origin=f"{prefix}/map", name="map"),
        rrb.TextDocumentView(origin=f"{prefix}/instruction", name="instruction"),
        rrb.TextDocumentView(origin=f"{prefix}/outcome", name="outcome"),
    ]
    return rrb.Vertical(*views, name=episode_title(record))


def merge_episodes(run_dir: Path, records: Sequence[TrialRecord], output: Path) -> tuple[Path, list[str]]:
    """One recording holding each episode under `/episodes/trial_N_<perturbation>`, in one tab per base
    instance with its episodes side by side; all share the `frame` and `time` timelines, so they play in step.

    Returns the merged file and the episode files that were missing."""
    import rerun as rr  # here, not at the top: the flags are checked before Rerun loads
    import rerun.blueprint as rrb

    from lerobot_contrast.record.rerun_log import APPLICATION_ID

    try:  # rerun-sdk 0.38+ moved the chunk API out of `experimental`
        from rerun.chunk import RrdReader, send_chunks
    except ImportError:
        from rerun.experimental import RrdReader, send_chunks
    chunks, missing, tabs = [], [], {}
    for record in records:
        path = run_dir / str(record.rerun_path)
        if not path.is_file():
            missing.append(str(record.rerun_path))
            continue
        prefix, cameras = entity_prefix(record), set()
        for chunk in RrdReader(path).stream().to_chunks():
            target = _remap(chunk.entity_path, prefix)
            if target is not None:
                chunks.append(chunk.with_entity_path(target))
            if chunk.entity_path.startswith("/camera/"):
                cameras.add(chunk.entity_path.removeprefix("/camera/"))
        tabs.setdefault(record.base_id, []).append(_cell(record, sorted(cameras)))
    if not tabs:
        raise ReviewError(f"none of the selected episode files exist under {run_dir}")
    blueprint = rrb.Blueprint(rrb.Tabs(*(rrb.Horizontal(*cells, name=base) for base, cells in tabs.items())))
    output.parent.mkdir(parents=True, exist_ok=True)
    partial = output.with_name(output.name + ".partial")
    recording = rr.RecordingStream(APPLICATION_ID, recording_id=f"review-{run_dir.resolve().name}")
    recording.save(partial, default_blueprint=blueprint)
    recording.send_recording_name(f"review of {run_dir.resolve().name}")
    recording.send_property("review", rr.AnyValues(trials=[r.index for r in records if r.rerun_path not in missing]))
    send_chunks(chunks, recording=recording)
    recording.flush(timeout_sec=60.0)
    recording.disconnect()
    os.replace(partial, output)
    return output, missing


def rerun_binary() -> str:
    """The `rerun` executable shipped in the rerun-sdk wheel (its `rerun_cli` wrapper would leave it running
    when stopped), or RERUN_CLI_PATH as that wrapper honours it."""
    import rerun_cli

    name = "rerun.exe" if sys.platform.startswith("win") else "rerun"
    return os.environ.get("RERUN_CLI_PATH") or str(Path(rerun_cli.__file__).with_name(name))


def viewer_command(path: Path, web: bool, web_port: int, grpc_port: int) -> list[str]:
    """The native viewer on `path`, or the web viewer and the recording served on localhost only."""
    command = [rerun_binary()]
    if web:
        command += ["--serve-web", "--bind", "127.0.0.1", "--web-viewer-port", str(web_port), "--port", str(grpc_port)]
    return [*command, str(path)]


def _has_display() -> bool:
    return not sys.platform.startswith("linux") or bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def open_viewer(path: Path, web: bool, web_port: int, grpc_port: int) -> int:
    command = viewer_command(path, web, web_port, grpc_port)
    if not web:
        return subprocess.run(command, check=False).returncode
    url = f"http://127.0.0.1:{web_port}/?url=" + quote(f"rerun+http://127.0.0.1:{grpc_port}/proxy", safe="")
    print(f"open {url} in a browser (works offline); Ctrl-C stops", flush=True)
    server = subprocess.Popen(command)
    # SIGTERM (a service manager, `kill`) must stop the server too, or it keeps holding both ports.
    previous = signal.signal(signal.SIGTERM, _interrupt)
    try:
        return server.wait()
    except KeyboardInterrupt:
        server.terminate()
        server.wait(timeout=10)
        return 0
    finally:
        signal.signal(signal.SIGTERM, previous)


def _interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt


USAGE = "python -m lerobot_contrast.review RUN_DIR [--flag=value | --flag value] ..."


@dataclass
class ReviewConfig:
    """Pick a run's episodes by perturbation, outcome or base instance, merge their Rerun recordings so each base
    instance and its perturbations sit side by side, and open the result in the Rerun viewer, or serve the web
    viewer on localhost (--web=true, works offline)."""

    # The run directory written by lerobot_contrast.eval; usually given as the first argument (required).
    run_dir: Path | None = None
    # Perturbations to show, e.g. LB1 or original,LB1,SB2 (default: all).
    perturbation: str | None = None
    # Only episodes that ended in success or failure (default: both).
    outcome: str | None = None
    # Base instance ids to show, e.g. lt-0003 (default: all).
    base: str | None = None
    # Serve the web viewer on localhost instead of opening the native viewer.
    web: bool = False
    # HTTP port of the web viewer.
    web_port: int = 9090
    # Port the viewer reads the recording from.
    grpc_port: int = 9876
    # The merged recording (default: RUN_DIR/review/review.rrd).
    output: Path | None = None
    # Write the merged recording and open nothing.
    save_only: bool = False


def plural(n: int, noun: str) -> str:
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"


def review(argv: Sequence[str] | None = None) -> int:
    args = parse_config(ReviewConfig, list(sys.argv[1:] if argv is None else argv), positional="run_dir")
    if args.run_dir is None:
        raise ReviewError(f"give the run directory to review: {USAGE}")
    records = select(load_records(args.run_dir), args.perturbation, args.outcome, args.base)
    if not (args.save_only or args.web or _has_display()):
        raise ReviewError("no display to open the Rerun viewer on; pass --web to serve the web viewer on localhost")
    output = args.output or args.run_dir / DEFAULT_OUTPUT
    merged, missing = merge_episodes(args.run_dir, records, output)
    if missing:
        print(f"warning: {len(missing)} episode file(s) missing, left out: {', '.join(missing)}", file=sys.stderr)
    episodes, bases = len(records) - len(missing), len({r.base_id for r in records})
    print(f"{plural(episodes, 'episode')} of {plural(bases, 'base instance')}: {merged}")
    if args.save_only:
        return 0
    return open_viewer(merged, args.web, args.web_port, args.grpc_port)


def main(argv: Sequence[str] | None = None) -> int:
    if wants_help(list(sys.argv[1:] if argv is None else argv)):
        print(usage_text(ReviewConfig, USAGE))
        return 0
    try:
        return review(argv)
    except UserError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
