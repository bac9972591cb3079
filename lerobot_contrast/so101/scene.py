"""The bench as a `mujoco.MjSpec` built from a task file (the twin simulates it; the arm plans its reach in it): a
table, the SO-101 at the task frame's origin, each object a free body of its colour, shape and size, and each bin
region a low-walled bin."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping

import mujoco

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.domains.task_file.schema import ObjectSpec, Region, TaskSpec
from lerobot_contrast.domains.task_file.world import storage_scene
from lerobot_contrast.so101 import arm, marker

TABLE_MARGIN = 0.15  # m of table around the workspace, the base and the storage row
TABLE_THICKNESS = 0.04
TABLE_RGBA = (0.74, 0.71, 0.65, 1.0)  # unsaturated, so no colour check mistakes the table for an object
BIN_RGBA = (0.32, 0.32, 0.34, 1.0)
BIN_WALL_HEIGHT = 0.02
BIN_WALL_THICKNESS = 0.006
BIN_SIDES = 12
# Object sizes (edge or diameter, m) by the task file's `size:` word; a 3 cm cube is what SO-101 benches stack.
SIZES = {"tiny": 0.02, "small": 0.03, "medium": 0.04, "large": 0.05}
DEFAULT_SIZE = SIZES["small"]
DENSITY = 600  # kg/m^3, wood or dense plastic: a 3 cm cube weighs 16 g
# Hues inside the staging colour check's bands (lerobot_contrast/staging/locate.py), saturated and lit.
COLOURS = {
    "red": (0.85, 0.08, 0.08),
    "orange": (1.0, 0.5, 0.0),
    "yellow": (0.95, 0.85, 0.1),
    "green": (0.1, 0.7, 0.2),
    "blue": (0.1, 0.2, 0.85),
    "purple": (0.55, 0.1, 0.75),
    "pink": (1.0, 0.55, 0.7),
    "brown": (0.45, 0.28, 0.12),
    "white": (0.95, 0.95, 0.95),
    "black": (0.08, 0.08, 0.08),
    "grey": (0.5, 0.5, 0.5),
}
SHAPES = {"cube": mujoco.mjtGeom.mjGEOM_BOX, "block": mujoco.mjtGeom.mjGEOM_BOX}
SHAPES |= {"cylinder": mujoco.mjtGeom.mjGEOM_CYLINDER, "can": mujoco.mjtGeom.mjGEOM_CYLINDER}
SHAPES |= {"ball": mujoco.mjtGeom.mjGEOM_SPHERE, "sphere": mujoco.mjtGeom.mjGEOM_SPHERE}
# Grip: elliptic cones with a high impulse ratio and torsional friction (condim 4) keep a pinched cube from slipping
# or spinning in the jaws; the no-slip pass removes the creep a soft contact leaves.
IMPRATIO = 10.0
NOSLIP_ITERATIONS = 5
OBJECT_FRICTION = (1.0, 0.01, 0.0001)
PAD_FRICTION = (1.5, 0.01, 0.0001)
JAW_PADS = ("fixed_jaw_pad", "moving_jaw_pad")
# The base's underside lies this far below its body origin: raised by it, the arm stands on the table top.
BASE_LIFT = 0.0024
# The model's servo gain (kp 17.8) leaves the shoulder a degree short under gravity; an STS3215 holds it closer.
SERVO_KP = 100.0
# LeRobot's so101_follower configures the gripper at half torque (Max_Torque_Limit 500 of 1000): squeezing harder than
# that, a closed-to-the-stop command flicks a small cube out of the jaws.
GRIPPER_TORQUE_SHARE = 0.5
SPARE_GAP = 0.08  # m between the spare objects waiting past the storage row's end

SpecEdit = Callable[[mujoco.MjSpec], None]


def object_size(obj: ObjectSpec) -> float:
    return SIZES.get(obj.attributes.get("size", ""), DEFAULT_SIZE)


def is_bin(region: Region) -> bool:
    return "bin" in region.name or any("bin" in word for word in region.words)


def table_extent(task: TaskSpec) -> tuple[tuple[float, float], tuple[float, float]]:
    """The table top's ((x_min, x_max), (y_min, y_max)) in the task frame: the workspace, the arm and the storage row."""
    (x0, x1), (y0, y1) = task.workspace.area.box
    poses = start_poses(task, None).values()
    xs, ys = [0.0, x0, x1, *(p.x for p in poses)], [0.0, y0, y1, *(p.y for p in poses)]
    return (min(xs) - TABLE_MARGIN, max(xs) + TABLE_MARGIN), (min(ys) - TABLE_MARGIN, max(ys) + TABLE_MARGIN)


def start_poses(task: TaskSpec, scene: Scene | None) -> dict[str, Pose]:
    """Where each object starts: its pose in `scene`, else where it waits (the storage row of the cost model, the
    spare objects in the task's tray, or past the row's end without one), fixed objects where the task file puts
    them."""
    parked = dict(storage_scene(task).objects) | tray_slots(task)
    row = [parked[name] for name in task.placed]
    step = (row[-1].x - row[-2].x, row[-1].y - row[-2].y) if len(row) > 1 else (SPARE_GAP, 0.0)
    spares = [name for name, obj in task.objects.items() if obj.spare]
    end = row[-1] if row else Pose(*task.workspace.area.middle)
    scale = SPARE_GAP / max(math.hypot(*step), 1e-9)
    for k, name in enumerate(spares, start=1):
        parked.setdefault(name, Pose(end.x + k * step[0] * scale, end.y + k * step[1] * scale))
    given = {} if scene is None else scene.objects
    return {name: given.get(name, parked[name]) if obj.movable else obj.at for name, obj in task.objects.items()}


def tray_slots(task: TaskSpec) -> dict[str, Pose]:
    """Where each spare object waits in the task's tray (none without one): spread along its longer side."""
    tray, spares = task.workspace.tray, [name for name, obj in task.objects.items() if obj.spare]
    if tray is None or not spares:
        return {}
    (x0, x1), (y0, y1) = tray.box
    along = [(k + 0.5) / len(spares) for k in range(len(spares))]
    if x1 - x0 >= y1 - y0:
        return {name: Pose(x0 + f * (x1 - x0), (y0 + y1) / 2) for name, f in zip(spares, along, strict=True)}
    return {name: Pose((x0 + x1) / 2, y0 + f * (y1 - y0)) for name, f in zip(spares, along, strict=True)}


def build_spec(task: TaskSpec, scene: Scene | None = None, extras: Iterable[SpecEdit] = ()) -> mujoco.MjSpec:
    """The SO-101 on its table with the task's objects posed as in `scene` (others parked beside the workspace).
    `extras` edit the spec before it is returned: the camera and the calibration board add themselves this way."""
    spec = mujoco.MjSpec.from_file(str(arm.model_path()))
    spec.modelname = f"twin_{task.name}"
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    spec.option.impratio = IMPRATIO
    spec.option.noslip_iterations = NOSLIP_ITERATIONS
    spec.body("base").pos[2] += BASE_LIFT
    for name in arm.MOTOR_NAMES:
        spec.actuator(name).set_to_position(kp=SERVO_KP, dampratio=1.0)
    spec.actuator(arm.GRIPPER).forcerange *= GRIPPER_TORQUE_SHARE
    for name in JAW_PADS:  # the model ships the fingertip pads inert; they are what holds a cube
        pad = spec.geom(name)
        pad.contype, pad.conaffinity, pad.friction, pad.condim = 1, 1, PAD_FRICTION, 4
    marker.add_ball(spec, (*COLOURS[marker.COLOUR], 1.0))
    _add_room(spec, task)
    for region in task.workspace.regions.values():
        if is_bin(region):
            _add_bin(spec, region)
    for name, pose in start_poses(task, scene).items():
        _add_object(spec, name, task.objects[name], pose)
    for edit in extras:
        edit(spec)
    return spec


def _add_room(spec: mujoco.MjSpec, task: TaskSpec) -> None:
    (x0, x1), (y0, y1) = table_extent(task)
    world = spec.worldbody
    world.add_geom(
        name="table",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        pos=[(x0 + x1) / 2, (y0 + y1) / 2, -TABLE_THICKNESS / 2],
        size=[(x1 - x0) / 2, (y1 - y0) / 2, TABLE_THICKNESS / 2],
        rgba=TABLE_RGBA,
    )
    world.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, pos=[0, 0, -0.75], size=[3, 3, 0.1])
    world.add_light(name="ceiling", pos=[(x0 + x1) / 2, 0, 1.5], dir=[0, 0, -1], diffuse=[0.6, 0.6, 0.6])


def _add_bin(spec: mujoco.MjSpec, region: Region) -> None:
    """A ring of wall segments just outside the region's disc (or box), so whatever rests inside lies in the region."""
    (x0, x1), (y0, y1) = region.box
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    radius = min(x1 - x0, y1 - y0) / 2 + BIN_WALL_THICKNESS / 2
    half_length = radius * math.tan(math.pi / BIN_SIDES) + BIN_WALL_THICKNESS / 2
    body = spec.worldbody.add_body(name=region.name, pos=[cx, cy, 0])
    for k in range(BIN_SIDES):
        angle = 2 * math.pi * k / BIN_SIDES
        body.add_geom(
            type=mujoco.mjtGeom.mjGEOM_BOX,
            pos=[radius * math.cos(angle), radius * math.sin(angle), BIN_WALL_HEIGHT / 2],
            quat=[math.cos(angle / 2), 0, 0, math.sin(angle / 2)],
            size=[BIN_WALL_THICKNESS / 2, half_length, BIN_WALL_HEIGHT / 2],
            rgba=BIN_RGBA,
        )


def rgba(name: str, obj: ObjectSpec) -> tuple[float, float, float, float]:
    colour = obj.attributes.get("colour", "grey")
    if colour not in COLOURS:
        raise UserError(f"object {name!r}: the twin cannot show colour {colour!r}; use one of {', '.join(COLOURS)}")
    return (*COLOURS[colour], 1.0)


def _add_object(spec: mujoco.MjSpec, name: str, obj: ObjectSpec, pose: Pose) -> None:
    size = object_size(obj)
    shape = SHAPES.get(obj.attributes.get("shape", "cube"), mujoco.mjtGeom.mjGEOM_BOX)
    body = spec.worldbody.add_body(name=name, pos=[pose.x, pose.y, size / 2], quat=yaw_quat(pose.yaw))
    if obj.movable:
        body.add_freejoint(name=name)
    body.add_geom(
        name=name,
        type=shape,
        size=[size / 2] * 3,  # a box's half sides, a sphere's radius, a cylinder's radius and half height
        rgba=rgba(name, obj),
        density=DENSITY,
        friction=OBJECT_FRICTION,
        condim=4,
    )


def yaw_quat(yaw: float) -> list[float]:
    return [math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)]


def object_sizes(task: TaskSpec) -> Mapping[str, float]:
    """Each object's size (m): its centre rests half of it above the table."""
    return {name: object_size(obj) for name, obj in task.objects.items()}
