"""`python -m lerobot_contrast.view RUN_DIR [RUN_DIR ...]`: the runs as a web page on 127.0.0.1, or with
`--bundle=DIR` the same page as a static site."""

from __future__ import annotations

import contextlib
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.spine.flags import ConfigError, parse_config, usage_text, wants_help

USAGE = "python -m lerobot_contrast.view RUN_DIR [RUN_DIR ...] [--flag=value | --flag value] ..."
DEFAULT_PORT = 7576


@dataclass
class ViewConfig:
    """Look at runs in a browser: the report's tables and curves, every perturbed trial beside its base's original
    (changed words, moved objects, flips), a pair's videos side by side with its actions and states, and A/B
    sessions policy beside policy. A run in progress refreshes as trials come in."""

    # Run directories written by lerobot_contrast.eval, A/B (--policies) or sweep folders, or hub:USER/NAME; usually
    # given as arguments (required).
    runs: list[str] = field(default_factory=list)
    # The port on 127.0.0.1 to serve the page on (0: any free port).
    port: int = DEFAULT_PORT
    # Write the page as a static site into this folder instead of serving it (open its index.html in a browser).
    bundle: Path | None = None


def parse_args(argv: list[str]) -> ViewConfig:
    args = parse_config(ViewConfig, argv, positional="runs")
    if not args.runs:
        raise ConfigError(f"give the run directories to view: {USAGE}")
    if not 0 <= args.port <= 65535:
        raise ConfigError(f"--port must be from 0 to 65535, got {args.port}")
    return args


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if wants_help(argv):
        print(usage_text(ViewConfig, USAGE))
        return 0
    try:
        args = parse_args(argv)
        return view(args)
    except UserError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2


def view(args: ViewConfig) -> int:
    from lerobot_contrast.view.payload import Pages, load_inputs

    if args.bundle is not None:
        from lerobot_contrast.view.bundle import write_bundle

        files = write_bundle(load_inputs(args.runs), args.bundle)
        megabytes = sum(p.stat().st_size for p in files) / 1e6
        print(f"bundle: {args.bundle} ({len(files)} files, {megabytes:.1f} MB); open {args.bundle / 'index.html'}")
        return 0
    from lerobot_contrast.view.server import serve, url

    server = serve(args.port)  # a port in use is said before the runs are read
    try:
        server.RequestHandlerClass.pages = Pages(args.runs)
        print(f"viewing {len(args.runs)} run(s) at {url(server)} (Ctrl-C to stop)", flush=True)
        with contextlib.suppress(KeyboardInterrupt):
            server.serve_forever()
    finally:
        server.server_close()
    return 0
