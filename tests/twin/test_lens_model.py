"""The twin's lens: points land where OpenCV's camera model says, a lens that folds the frame is refused in one line,
and the light and noise a webcam adds are there, uneven in the stated direction and reproducible from the seed."""

import cv2
import numpy as np
import pytest

from lerobot_contrast.twin.lens import Lens, LensArgs, LensError

SIZE = (320, 240)  # the model does not depend on the size; a small frame keeps the tests fast
FOCAL = 320.0
CLEAN = {"vignetting": 0.0, "gradient": 0.0, "noise": 0.0}


def blobs(lens: Lens, rays: np.ndarray) -> np.ndarray:
    """An ideal canvas with a small Gaussian spot where each normalised ray (N, 2) meets it."""
    width, height = lens.canvas_size
    cols, rows = np.meshgrid(np.arange(width), np.arange(height))
    canvas = np.zeros((height, width), np.float64)
    centres = rays * FOCAL + (np.array(lens.canvas_size) - 1) / 2
    for col, row in centres:
        canvas += 250 * np.exp(-((cols - col) ** 2 + (rows - row) ** 2) / (2 * 1.5**2))
    return np.repeat(np.clip(np.round(canvas), 0, 255).astype(np.uint8)[..., None], 3, axis=2)


def spot_centres(frame: np.ndarray) -> np.ndarray:
    grey = frame[..., 0].astype(np.float64)
    count, labels = cv2.connectedComponents((grey > 10).astype(np.uint8))
    centres = []
    for label in range(1, count):
        rows, cols = np.nonzero(labels == label)
        weights = grey[rows, cols]
        centres.append([cols @ weights / weights.sum(), rows @ weights / weights.sum()])
    return np.array(centres)


@pytest.mark.parametrize("args", [LensArgs(**CLEAN), LensArgs(k1=-0.2, k2=0.05, p1=0.004, p2=-0.003, **CLEAN)])
def test_points_land_where_opencv_projects_them(args):
    lens = Lens(args, FOCAL, SIZE)
    # Near the centre, half way out and near each corner, where a -0.3 lens moves points by tens of pixels.
    rays = np.array([[0.0, 0.0], [0.2, -0.1], [-0.45, 0.3], [0.5, 0.35], [-0.5, -0.35], [0.45, -0.35]])
    expected, _ = cv2.projectPoints(np.column_stack([rays, np.ones(len(rays))]), np.zeros(3), np.zeros(3),
                                    lens.intrinsics, args.coefficients())  # fmt: skip
    expected = expected.reshape(-1, 2)
    found = spot_centres(lens.apply(blobs(lens, rays)))
    assert len(found) == len(rays)
    pinhole = rays * FOCAL + (np.array(SIZE) - 1) / 2
    assert np.abs(expected - pinhole).max() > 10  # the lens really moves the outer points
    nearest = np.array([found[np.argmin(np.linalg.norm(found - point, axis=1))] for point in expected])
    assert np.abs(nearest - expected).max() < 0.1


def test_undistorting_the_frame_gives_back_the_pinhole_view():
    """What the staging code does with an estimated k1: cv2.undistortPoints with the true one inverts the lens."""
    lens = Lens(LensArgs(**CLEAN), FOCAL, SIZE)
    rays = np.array([[0.5, 0.35], [-0.52, 0.3], [0.1, -0.3]])
    found = spot_centres(lens.apply(blobs(lens, rays)))
    undone = cv2.undistortPointsIter(found.reshape(-1, 1, 2), lens.intrinsics, lens.args.coefficients(), None, None,
                                     (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12)).reshape(-1, 2)  # fmt: skip
    for ray in rays:
        assert np.linalg.norm(undone - ray, axis=1).min() * FOCAL < 0.15


@pytest.mark.parametrize("args", [LensArgs(k1=-0.6), LensArgs(k1=-0.3, p1=0.5)])
def test_a_lens_that_folds_the_frame_is_refused(args):
    with pytest.raises(LensError) as error:
        Lens(args, FOCAL, SIZE)
    message = str(error.value)
    assert "\n" not in message and "folds the image" in message and "weaker lens" in message


def test_the_render_must_be_the_canvas_size():
    lens = Lens(LensArgs(), FOCAL, SIZE)
    with pytest.raises(ValueError, match=r"the render is 320x240, the lens needs \d+x\d+"):
        lens.apply(np.zeros((240, 320, 3), np.uint8))


def flat_frame(args: LensArgs, level: int = 160) -> np.ndarray:
    lens = Lens(args, FOCAL, SIZE)
    width, height = lens.canvas_size
    return lens.apply(np.full((height, width, 3), level, np.uint8)).astype(float)


def test_vignetting_darkens_the_corners_by_the_stated_fraction():
    frame = flat_frame(LensArgs(k1=0.0, vignetting=0.3, gradient=0.0, noise=0.0))
    assert abs(frame[116:124, 156:164].mean() - 160) < 1.5
    assert abs(frame[:3, :3].mean() / 160 - 0.7) < 0.02 and abs(frame[-3:, -3:].mean() / 160 - 0.7) < 0.02


@pytest.mark.parametrize(("angle", "lit", "far"), [(0.0, (slice(115, 125), slice(0, 5)), (slice(115, 125), slice(-5, None))),
                                                  (90.0, (slice(0, 5), slice(155, 165)), (slice(-5, None), slice(155, 165)))])  # fmt: skip
def test_the_light_gradient_comes_from_the_stated_side(angle, lit, far):
    frame = flat_frame(LensArgs(k1=0.0, vignetting=0.0, gradient=0.4, gradient_deg=angle, noise=0.0))
    assert abs(frame[lit].mean() / frame[far].mean() - 1.2 / 0.8) < 0.04


def test_noise_has_the_stated_spread_and_follows_the_seed():
    def frames(seed: int) -> list[np.ndarray]:
        lens = Lens(LensArgs(k1=0.0, vignetting=0.0, gradient=0.0, noise=3.0, seed=seed), FOCAL, SIZE)
        width, height = lens.canvas_size
        return [lens.apply(np.full((height, width, 3), 128, np.uint8)) for _ in range(3)]

    first, again, other = frames(0), frames(0), frames(1)
    assert all(np.array_equal(a, b) for a, b in zip(first, again, strict=True))
    assert not np.array_equal(first[0], other[0])
    assert not np.array_equal(first[0], first[1])  # each frame its own noise
    spread = (first[0].astype(float) - 128).std()
    assert 2.7 < spread < 3.3
