"""Where the arm's camera sees each object against the twin's truth, and the error of what each goal tests: the
distance between two cubes (`near`/`within`) and a cube's distance from a bin's centre (`in`). Starts its own twin
(640x480, wide-angle lens; `--joint_offset_deg` as the unattended benchmark takes it), calibrates the camera from the
printed board as a person would once, then lays the task's cubes at random, free of each other, on the table, in
the bins and in the tray, folds the arm aside and looks, `--layouts` times. Nothing here stages or labels: it
measures the band inside which the camera's verdict on a goal may be wrong (`--arm.uncertainty`).

    .venv/bin/python scripts/bench/bench_seeing.py [--layouts=40] [--joint_offset_deg=0] [--seed=0] [--clock=sim]

Figures last: seen=... unseen=... position_p50_cm=... position_p95_cm=... position_max_cm=... distance_p95_cm=...
bin_radius_p95_cm=... each_<colour>_p95_cm=... clock=... (position: one object's seen position against the truth;
distance: |seen - true| distance between two cubes; bin_radius: |seen - true| distance of a cube in a bin from the
bin's centre).
"""

from __future__ import annotations

import math
import sys
import tempfile
from pathlib import Path

import numpy as np

from lerobot_contrast.clock.robot_clock import robot_clock
from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.domains import load_task
from lerobot_contrast.spine.flags import ScriptParser
from lerobot_contrast.twin.arm_session import connected_arm
from lerobot_contrast.twin.launch import running_twin
from lerobot_contrast.twin.placement_client import PlacementClient
from lerobot_contrast.twin.table_calibration import calibrate_table

TASK = "so101_blocks"
SETTLE_S = 0.6  # a placed cube comes to rest and the camera's latest frame shows it
GAP_M = 0.05  # cubes laid at least this far apart (centre to centre)


def layout(task, rng: np.random.Generator) -> dict[str, tuple[float, float]]:
    """A random free place for every cube of the task: on the table's play area, in a bin or in the tray."""
    spec = task.spec
    places = [spec.workspace.regions[name] for name in spec.workspace.regions] + [spec.workspace.tray]
    chosen: dict[str, tuple[float, float]] = {}
    for name in spec.objects:
        for _ in range(200):
            region = places[rng.integers(len(places))]
            (x0, x1), (y0, y1) = region.box
            x, y = rng.uniform(x0 + 0.02, x1 - 0.02), rng.uniform(y0 + 0.02, y1 - 0.02)
            if region.contains(x, y) and all(math.dist((x, y), other) > GAP_M for other in chosen.values()):
                chosen[name] = (float(x), float(y))
                break
    return chosen


def measure(layouts: int, joint_offset_deg: float, seed: int, work: Path, clock: str) -> dict[str, list[float]]:
    task = load_task(TASK)
    bins = {name: region for name, region in task.spec.workspace.regions.items() if "bin" in name}
    errors: dict[str, list[float]] = {"position": [], "distance": [], "bin_radius": [], "unseen": []}
    rng = np.random.default_rng(seed)
    flags = f"--task={TASK}", f"--joint_offset_deg={joint_offset_deg}", f"--seed={seed}", f"--clock={clock}"
    with running_twin(*flags) as twin:
        table = calibrate_table(twin, TASK, work / "table.calibration.json")
        placement = PlacementClient(twin.placement)
        robot, arm = connected_arm(twin, table, TASK)
        try:
            arm.motion.open_and_withdraw()
            for _ in range(layouts):
                for name, (x, y) in layout(task, rng).items():
                    placement.place(name, x, y, float(rng.uniform(-math.pi, math.pi)))
                robot_clock().sleep(SETTLE_S)
                truth = placement.scene().objects
                view = arm._look()
                seen = {name: (at.x, at.y) for name, at in view.seen.items() if not at.held}
                errors["unseen"].extend(1.0 for name in truth if name not in seen)
                for name, (x, y) in seen.items():
                    errors["position"].append(math.dist((x, y), (truth[name].x, truth[name].y)))
                    errors.setdefault(name, []).append(errors["position"][-1])
                names = sorted(seen)
                for i, a in enumerate(names):
                    for b in names[i + 1 :]:
                        true = math.dist((truth[a].x, truth[a].y), (truth[b].x, truth[b].y))
                        errors["distance"].append(abs(math.dist(seen[a], seen[b]) - true))
                    for region in bins.values():
                        if region.contains(truth[a].x, truth[a].y):
                            true = math.dist((truth[a].x, truth[a].y), region.center)
                            errors["bin_radius"].append(abs(math.dist(seen[a], region.center) - true))
        finally:
            robot.disconnect()
    return errors


def main(argv: list[str] | None = None) -> int:
    parser = ScriptParser(description=__doc__.splitlines()[0])
    parser.add_argument("--layouts", type=int, default=40, help="random layouts of the cubes looked at")
    parser.add_argument("--joint_offset_deg", type=float, default=0.0, help="each joint's calibration off by up to D")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--clock", choices=("sim", "wall"), default="sim", help="the twin's clock")
    args = parser.parse_args(argv)
    if args.layouts < 1 or not 0 <= args.joint_offset_deg <= 10:
        parser.error("--layouts must be at least 1 and --joint_offset_deg within 0-10")
    try:
        with tempfile.TemporaryDirectory() as work:
            errors = measure(args.layouts, args.joint_offset_deg, args.seed, Path(work), args.clock)
    except UserError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2

    def cm(values: list[float], q: float) -> str:
        return f"{np.percentile(np.array(values) * 100, q):.2f}" if values else "nan"

    figures = {
        "seen": str(len(errors["position"])),
        "unseen": str(len(errors["unseen"])),
        "position_p50_cm": cm(errors["position"], 50),
        "position_p95_cm": cm(errors["position"], 95),
        "position_max_cm": cm(errors["position"], 100),
        "distance_p95_cm": cm(errors["distance"], 95),
        "bin_radius_p95_cm": cm(errors["bin_radius"], 95),
    }
    for name in sorted(key for key in errors if key.endswith("_cube")):
        figures[f"each_{name.removesuffix('_cube')}_p95_cm"] = cm(errors[name], 95)
    figures["clock"] = args.clock
    print(" ".join(f"{key}={value}" for key, value in figures.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
