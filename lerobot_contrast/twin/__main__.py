"""`python -m lerobot_contrast.twin --task=so101_blocks [--robot_id=twin] [--fps=30] [--width=640 --height=480]
[--lens_k1=-0.3] [--camera_port=5555] [--control_port=5556] [--clock=wall|sim] [--clock_port=5557] [--seed=0]
[--faults.*]`: start the virtual SO-101,
print its endpoints and the flags to give eval, and run until Ctrl-C or SIGTERM."""

from __future__ import annotations

import signal
import sys
import threading
from collections.abc import Sequence

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.extras import require_extra
from lerobot_contrast.spine.flags import parse_config, usage_text, wants_help
from lerobot_contrast.twin.launch import stop_with_parent
from lerobot_contrast.twin.process import TwinConfig

USAGE = "python -m lerobot_contrast.twin [--flag=value | --flag value] ..."


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if wants_help(argv):
        print(usage_text(TwinConfig, USAGE))
        return 0
    stop_with_parent()
    stopping = threading.Event()
    for signum in (signal.SIGINT, signal.SIGTERM):  # set first: a Ctrl-C while starting still stops cleanly
        signal.signal(signum, lambda *_: stopping.set())
    try:
        require_extra("twin", "python -m lerobot_contrast.twin")
        config = parse_config(TwinConfig, argv)
        config.check()
        from lerobot_contrast.twin.process import Twin  # after the flags: a typo is answered before MuJoCo loads

        twin = Twin(config)
        endpoints = twin.start()
    except (UserError, ValueError, ImportError, RuntimeError, OSError) as error:
        print(f"error: {' '.join(str(error).split())}", file=sys.stderr)
        return 2
    try:
        print(f"bus: {endpoints['bus']} (so101_follower, id {config.robot_id})")
        print(f"camera: {endpoints['camera']} ({config.width}x{config.height} at {config.fps} fps, lens k1 "
              f"{config.lens_k1:g})")  # fmt: skip
        print(f"placement: {endpoints['placement']} (python -m lerobot_contrast.twin.place OBJECT X Y [YAW])")
        print(f"calibration: {endpoints['calibration']}")
        clock = endpoints.get("clock")
        print(f"clock: {clock} (simulated: it moves when eval advances it)" if clock else "clock: wall (real time)")
        print(f"eval flags: {twin.eval_flags()}", flush=True)
        while not stopping.wait(0.5) and twin.failure is None:
            pass
        failed = twin.failure  # a part's thread printed why; the twin cannot go on without it
    finally:
        twin.stop()
    print("twin stopped", file=sys.stderr)
    return 0 if failed is None else 1


if __name__ == "__main__":
    sys.exit(main())
