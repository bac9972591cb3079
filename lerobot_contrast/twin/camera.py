"""The twin's webcam: a MuJoCo perspective camera in front of and beside the table looking down at the workspace,
rendered offscreen, then through the lens; its true intrinsics and pose, so tests know where a point shows.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import cv2
import numpy as np

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.twin.lens import Lens, LensArgs

VIEW_HULL_VERTICES = 128  # the arm's links stay recognisable; their CAD meshes hold 320k triangles


@dataclass(frozen=True)
class CameraArgs:
    """Where the twin's webcam stands and what it sees."""

    width: int = 640
    height: int = 480
    # The camera's height above the workspace centre, degrees above the table (40-60 for a bench webcam on a stand).
    elevation_deg: float = 50.0
    # Around the table: 0 stands straight in front of the robot facing it, +90 at the robot's left.
    azimuth_deg: float = 35.0
    # Metres from the workspace centre to the camera.
    distance: float = 0.85
    # Focal length as a fraction of the image width (1.0: 640 px at 640x480; smaller sees more).
    focal: float = 1.0
    # Draw meshes in full detail; by default a mesh that has a convex hull is drawn as its hull (see `view_hulls`):
    # the SO-101's CAD meshes cost a CPU renderer 20 ms a frame, their hulls 6.
    full_meshes: bool = False

    def check(self) -> None:
        if self.width < 16 or self.height < 16:
            raise UserError(f"camera size {self.width}x{self.height}: give --width and --height of 16 pixels or more")
        if not 10 <= self.elevation_deg <= 85:
            raise UserError(f"camera elevation {self.elevation_deg:g} degrees: give 10 to 85 (a bench webcam: 40-60)")
        if self.distance <= 0 or self.focal <= 0:
            raise UserError(f"camera distance {self.distance:g} m, focal {self.focal:g}: both must be positive")


def view_hulls(spec, vertices: int = VIEW_HULL_VERTICES) -> None:
    """A spec edit (`scene.build_spec(extras=[view_hulls])`): each mesh geom that never collides, on a body whose
    inertia is given (so the geom weighs nothing), gets a copy of its mesh with a convex hull of at most `vertices`
    vertices for the camera to draw. Contacts, masses and the full meshes stay as they are."""
    import mujoco

    copies: dict[str, str] = {}
    for geom in spec.geoms:
        visual = geom.type == mujoco.mjtGeom.mjGEOM_MESH and not (geom.contype or geom.conaffinity)
        if not visual or not geom.parent.explicitinertial and geom.parent != spec.worldbody:
            continue
        if geom.meshname not in copies:
            mesh = spec.mesh(geom.meshname)
            copies[geom.meshname] = f"{geom.meshname}_view"
            # A convex inertia makes MuJoCo compute the hull of a mesh no contact needs.
            spec.add_mesh(name=copies[geom.meshname], file=mesh.file, uservert=mesh.uservert, userface=mesh.userface,
                          scale=mesh.scale, maxhullvert=vertices, inertia=mujoco.mjtMeshInertia.mjMESH_INERTIA_CONVEX)  # fmt: skip
        geom.meshname = copies[geom.meshname]


class TwinCamera:
    """Renders the twin's world as the webcam sees it. Render from one thread: the GL context belongs to the thread
    that made it, and `close()` must be called from that thread too."""

    def __init__(self, target: tuple[float, float, float], args: CameraArgs, lens: LensArgs) -> None:
        args.check()
        self.args = args
        self.lens = Lens(lens, args.focal * args.width, (args.width, args.height))
        self.target = np.asarray(target, np.float64)
        elevation, azimuth = math.radians(args.elevation_deg), math.radians(args.azimuth_deg)
        outward = np.array([math.cos(elevation) * math.cos(azimuth), math.cos(elevation) * math.sin(azimuth),
                            math.sin(elevation)])  # fmt: skip
        self.position = self.target + args.distance * outward
        forward = -outward
        right = np.cross(forward, (0.0, 0.0, 1.0))
        right /= np.linalg.norm(right)
        self.rotation = np.stack([right, np.cross(forward, right), forward])  # world -> camera (OpenCV axes)
        self.translation = -self.rotation @ self.position
        self._renderer = None
        self._model = None
        self._hulls: set[int] = set()

    @property
    def intrinsics(self) -> np.ndarray:
        """The frame's camera matrix (pixel centres at integers, OpenCV's convention)."""
        return self.lens.intrinsics

    @property
    def distortion(self) -> np.ndarray:
        """The lens's OpenCV distortion vector (k1, k2, p1, p2)."""
        return self.lens.args.coefficients()

    def project(self, points: np.ndarray) -> np.ndarray:
        """World points (N, 3), metres -> their pixels (N, 2) in the frame, as OpenCV's model with the true
        intrinsics, pose and lens gives them; NaN where a point is behind the camera or outside the rendered view."""
        points = np.asarray(points, np.float64).reshape(-1, 3)
        camera = points @ self.rotation.T + self.translation
        rvec, _ = cv2.Rodrigues(self.rotation)
        pixels, _ = cv2.projectPoints(points, rvec, self.translation, self.intrinsics, self.distortion)
        pixels = pixels.reshape(-1, 2)
        with np.errstate(divide="ignore", invalid="ignore"):
            normalised = camera[:, :2] / camera[:, 2:]
        half = (np.array(self.lens.canvas_size) - 1) / 2 / self.intrinsics[0, 0]
        seen = (camera[:, 2] > 0) & np.all(np.abs(normalised) <= half, axis=1)
        pixels[~seen] = np.nan
        return pixels

    def frame(self, model, data) -> np.ndarray:
        """The webcam's RGB frame of `data` (`capture` then `develop`)."""
        self.capture(model, data)
        return self.develop()

    def capture(self, model, data) -> None:
        """Take the scene from `data`: call it while the physics holds still (`Physics.read(camera.capture)`); it
        costs a copy, the drawing happens in `develop`."""
        if model is not self._model:
            self._open(model)
        # The free camera's field of view is the model's: set it each time, another camera may share the model.
        model.vis.global_.fovy = self.lens.canvas_fovy_deg()
        self._renderer.update_scene(data, self._camera)
        if not self.args.full_meshes:
            self._draw_hulls()

    def develop(self) -> np.ndarray:
        """Draw the captured scene and pass it through the lens: RGB, uint8, the frame's size."""
        return self.lens.apply(self._renderer.render())

    def _draw_hulls(self) -> None:
        import mujoco

        scene = self._renderer.scene
        for index in range(scene.ngeom):
            geom = scene.geoms[index]
            if geom.type == mujoco.mjtGeom.mjGEOM_MESH and geom.dataid // 2 in self._hulls:
                geom.dataid = geom.dataid // 2 * 2 + 1  # a scene's mesh id is 2 * mesh, or 2 * mesh + 1: its hull

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
        self._renderer, self._model = None, None

    def _open(self, model) -> None:
        import mujoco

        self.close()
        width, height = self.lens.canvas_size
        # Shadows, reflections and multisampling cost 10x the render time on a CPU renderer, and a webcam's frame
        # softens edges anyway.
        model.vis.global_.orthographic = 0
        model.vis.global_.offwidth = max(model.vis.global_.offwidth, width)
        model.vis.global_.offheight = max(model.vis.global_.offheight, height)
        model.vis.quality.offsamples = 0
        try:
            self._renderer = mujoco.Renderer(model, height, width)
        except Exception as error:
            raise UserError(
                f"no offscreen renderer (MUJOCO_GL={os.environ.get('MUJOCO_GL', '')}: {' '.join(str(error).split())[:120]}); "
                "import lerobot_contrast.twin before mujoco or set MUJOCO_GL=egl, and install Mesa's EGL (libegl1)"
            ) from None
        self._renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = 0
        self._renderer.scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = 0
        self._camera = mujoco.MjvCamera()
        self._camera.type = mujoco.mjtCamera.mjCAMERA_FREE
        self._camera.lookat[:] = self.target
        self._camera.distance = self.args.distance
        self._camera.azimuth = self.args.azimuth_deg + 180  # MuJoCo's azimuth is where the camera looks, not stands
        self._camera.elevation = -self.args.elevation_deg
        self._hulls = {mesh for mesh in range(model.nmesh) if model.mesh_graphadr[mesh] >= 0}
        self._model = model
