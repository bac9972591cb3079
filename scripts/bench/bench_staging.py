"""How well the staging bench measures on the tabletop simulator's camera: the fitted homography against the
simulator's own, and where the colour check places randomly laid cubes against where they are. Then through a lens:
the synthetic webcam (640 x 480, oblique poses at elevation 25-85 degrees, any azimuth, radial k1 of 0, -0.12 and
-0.3) photographs the board laid near the workspace's centre; the farthest a cube's centre anywhere on the so101_blocks
workspace is placed from where it is, and the farthest the colour check places four 3 cm cubes standing at the
workspace's corners, with the lens measured and with the homography alone, and how many poses calibrate refuses.

    .venv/bin/python scripts/bench/bench_staging.py [--layouts=200] [--poses=12]

Figures last, on one line: name=value pairs (pixels at 320 x 180 and 640 x 360; centimetres).
"""

from __future__ import annotations

import sys

import cv2
import numpy as np

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.domains.language_table import board as tabletop
from lerobot_contrast.domains.language_table.render import TabletopRenderer
from lerobot_contrast.staging import board, homography, locate
from lerobot_contrast.staging.synthetic import ObliqueCamera, board_photo

WHERE = board.BoardArgs(x=0.35, y=0.0, yaw_deg=10.0)
WORKSPACE = ((0.15, -0.25), (0.45, 0.25))  # so101_blocks
GRID = np.array([[x, y] for x in np.linspace(0.15, 0.45, 7) for y in np.linspace(-0.25, 0.25, 7)])
CUBES = ("red_cube", "green_cube", "blue_cube", "yellow_cube")
LENSES = (0.0, -0.12, -0.3)
CORNER_CUBES = {"red": (0.175, 0.225), "green": (0.175, -0.225), "blue": (0.425, 0.225), "yellow": (0.425, -0.225)}
CUBE_CENTRE = 0.015  # a 3 cm cube is placed where the ray through its centre meets the plane at half its height


def sim_pixels(renderer: TabletopRenderer, xy: np.ndarray) -> np.ndarray:
    return renderer.project(np.column_stack([xy, np.zeros(len(xy))])) - 0.5


def board_frame(renderer: TabletopRenderer) -> np.ndarray:
    page, per_m = board.page_image(dpi=150)
    margin = round(board.MARGIN_M * per_m)
    corners = np.array([[0, 0], [page.shape[1], 0], [page.shape[1], page.shape[0]], [0, page.shape[0]]], float) - 0.5
    on_table = board.board_to_table((corners + 0.5 - margin) / per_m, WHERE)
    warp = cv2.getPerspectiveTransform(corners.astype(np.float32), sim_pixels(renderer, on_table).astype(np.float32))
    size = (renderer.camera.width, renderer.camera.height)
    image = renderer.render({})
    covered = cv2.warpPerspective(np.full(page.shape, 255, np.uint8), warp, size) > 127
    image[covered] = cv2.warpPerspective(cv2.cvtColor(page, cv2.COLOR_GRAY2RGB), warp, size)[covered]
    return image


def layouts(n: int, rng: np.random.Generator) -> list[dict[str, tuple[float, float, float]]]:
    """Cube layouts as so101_blocks places them: in its play area, at least 6 cm apart."""
    out = []
    while len(out) < n:
        xy = np.column_stack([rng.uniform(0.19, 0.41, 4), rng.uniform(-0.2, 0.2, 4)])
        gaps = np.linalg.norm(xy[:, None] - xy[None], axis=2) + np.eye(4)
        if gaps.min() > 0.06:
            out.append({name: (*p, rng.uniform(-np.pi, np.pi)) for name, p in zip(CUBES, xy, strict=True)})
    return out


def located_off_cm(calibration: homography.CameraCalibration, camera: ObliqueCamera) -> float:
    """The farthest a cube's centre seen on the workspace's grid is placed from where it is."""
    seen = camera.project(np.column_stack([GRID, np.full(len(GRID), CUBE_CENTRE)]))
    return float(np.max(np.linalg.norm(calibration.to_table(seen, CUBE_CENTRE) - GRID, axis=1)) * 100)


def cubes_off_cm(calibration: homography.CameraCalibration, camera: ObliqueCamera) -> float:
    """The farthest the colour check places four cubes standing at the workspace's corners from where they are."""
    found = locate.find_objects(
        board_photo(camera, None, cubes=CORNER_CUBES), calibration, {c: c for c in CORNER_CUBES}, WORKSPACE, 0.03
    )
    if len(found) < len(CORNER_CUBES):
        return float("inf")
    return max(float(np.hypot(x - CORNER_CUBES[c][0], y - CORNER_CUBES[c][1])) * 100 for c, (x, y) in found.items())


def lens_figures(poses: int) -> dict[str, float]:
    """Per lens: the worst placement over the accepted poses (lens measured; homography alone), the poses the
    homography alone puts past the 2 cm staging tolerance, and the refusals."""
    figures = {}
    for k1 in LENSES:
        rng = np.random.default_rng(1)
        worst, worst_plain, refused, plain_past_2cm, cubes, cubes_plain = 0.0, 0.0, 0, 0, 0.0, 0.0
        for pose in range(poses):
            camera = ObliqueCamera(rng.uniform(25, 85), rng.uniform(0, 360), k1)
            where = board.BoardArgs(0.30 + rng.uniform(-0.03, 0.03), rng.uniform(-0.05, 0.05), rng.uniform(-20, 20))
            photo = board_photo(camera, where, seed=pose)
            plain = homography.fit("front", photo, where, 2.0, WORKSPACE, lens=False)
            worst_plain = max(worst_plain, located_off_cm(plain, camera))
            plain_past_2cm += located_off_cm(plain, camera) > 2.0
            cubes_plain = max(cubes_plain, cubes_off_cm(plain, camera))
            try:
                calibration = homography.fit("front", photo, where, 2.0, WORKSPACE)
            except UserError:
                refused += 1
                continue
            worst, cubes = (
                max(worst, located_off_cm(calibration, camera)),
                max(cubes, cubes_off_cm(calibration, camera)),
            )
        name = f"lens_k1_{abs(k1):g}"
        figures |= {f"{name}_max_cm": round(worst, 2), f"{name}_plain_max_cm": round(worst_plain, 2)}
        figures |= {f"{name}_cubes_max_cm": round(cubes, 2), f"{name}_cubes_plain_max_cm": round(cubes_plain, 2)}
        figures |= {f"{name}_plain_past_2cm": plain_past_2cm, f"{name}_refused": refused}
    return figures | {"lens_poses": poses}


def main() -> int:
    n = int(next((a.split("=")[1] for a in sys.argv[1:] if a.startswith("--layouts=")), 200))
    poses = int(next((a.split("=")[1] for a in sys.argv[1:] if a.startswith("--poses=")), 12))
    figures = {}
    for height, width in ((180, 320), (360, 640)):
        renderer = TabletopRenderer(height, width)
        calibration = homography.fit("top", board_frame(renderer), WHERE, 2.0, WORKSPACE)
        error = np.abs(calibration.to_pixels(GRID) - sim_pixels(renderer, GRID)).max()
        figures[f"homography_max_px_{width}"] = round(float(error), 3)
        figures[f"board_rms_px_{width}"] = round(calibration.error_px, 3)
    renderer = TabletopRenderer()
    calibration = homography.fit("top", board_frame(renderer), WHERE, 2.0, WORKSPACE)
    misses, errors = 0, []
    colours = {name: name.split("_")[0] for name in CUBES}
    for blocks in layouts(n, np.random.default_rng(0)):
        seen = locate.find_objects(
            renderer.render(blocks, (0.2, 0.0)), calibration, colours, WORKSPACE, tabletop.SHAPE_FOOTPRINT["cube"][0]
        )
        misses += len(CUBES) - len(seen)
        errors += [np.hypot(x - blocks[name][0], y - blocks[name][1]) for name, (x, y) in seen.items()]
    errors = np.array(errors) * 100
    figures |= {
        "locate_median_cm": round(float(np.median(errors)), 2),
        "locate_p95_cm": round(float(np.percentile(errors, 95)), 2),
        "locate_max_cm": round(float(errors.max()), 2),
        "cubes_missed": misses,
        "cubes": n * len(CUBES),
    }
    figures |= lens_figures(poses)
    print(" ".join(f"{k}={v}" for k, v in figures.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
