"""Joint goals that pick an object up and put it down elsewhere, from inverse kinematics on the twin's model.

The IK is damped least squares on MuJoCo's Jacobians with priorities: the point between the jaws goes where asked,
and the motion left closes the jaws across the object's faces and points them as nearly down as five joints allow
(the SO-101 grasps straight down only to about 30 cm out). That is a few dozen lines; an IK library (mink) would add
a QP solver to the twin's dependencies for the same five-joint problem."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from lerobot_contrast.so101 import PICK_AND_PLACE_STEPS as STEPS
from lerobot_contrast.so101 import arm

ARM_JOINTS = arm.MOTOR_NAMES[:5]
SITE = "gripperframe"  # on the fixed jaw's tip; its x axis points out of the fingertips, its z axis across the jaws
FIXED_PAD = "fixed_jaw_pad"
MOVING_PAD = "moving_jaw_pad"
# A pad coming down this far (m) from a neighbour's centre clears it (half a cube, the pad, a margin); nearer, the
# heading whose pads keep furthest away is taken, else the pad lands on the neighbour or pushes the object into it.
PAD_CLEARANCE = 0.03
ITERATIONS = 1500  # converged poses stop early; at the edge of reach 300 left the jaws 1.2 mm off (a cube not lifted)
# Steps bounded at MAX_STEP can swing between two poses at a joint limit for good (measured: 1500 iterations, a few of
# each pick's twelve solves, then going back to where they were to within 1e-7 rad): two steps back within this, stop.
SWING = 1e-6
DAMPING = 1e-3
ORIENTATION_DAMPING = 0.05  # larger: some turns (the roll, for pointing down) barely move the axis they steer
DOWN = np.array([0.0, 0.0, -1.0])
# Once the position holds: the jaws closing across the object's faces matter more than their pointing down.
ACROSS_WEIGHT, DOWN_WEIGHT = 1.0, 0.4
POSITION_TOLERANCE = 0.001  # m
MAX_STEP = 0.1  # rad per iteration and task, so a far target is approached along the way and not overshot
MAX_TILT_DEG = 60.0  # jaws tilted further from vertical than this would sweep the table
MAX_ACROSS_DEG = 20.0  # pads turned further than this from the faces push the object round instead of holding it
# The gripper's body between the jaws ends 14 mm above the pads' middle: gripping a bit above a small object's
# centre keeps it off the object's top.
GRASP_ABOVE_CENTRE = 0.004
HOVER = 0.06  # m above the grasp height on the way in and out
CARRY_HEIGHT = 0.10  # m, the grasp point's height while carrying
RELEASE_DROP = 0.004  # m between the carried object's underside and the table when it is let go
OPEN = 0.8  # rad, the gripper open around a small object (pads 64 mm apart)
SQUEEZE = 0.25  # rad past first contact the gripper is told to close: a firm grip, short of the joint's limit
# The fixed pad comes down this far from the object's face, not touching it: a few degrees of tilt or turn, or a few
# millimetres of where the camera saw the object, put a pad that skims the face on the object's top edge, pressing it
# into the table. Closing pushes the object the gap across to the fixed pad.
PAD_GAP = 0.006


@dataclass(frozen=True)
class Waypoint:
    """Joint goals (radians, every motor) and how long to give the arm to get there."""

    label: str
    goals: Mapping[str, float]
    seconds: float


class Unreachable(ValueError):
    """No joint angles put the jaws at the requested pose."""


def grasp_point(model: mujoco.MjModel, size: float) -> np.ndarray:
    """The point (site frame) midway between the jaws when they hold an object `size` wide: the fixed pad's inner
    face plus half the object."""
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    site = data.site(SITE)
    pad = model.geom(FIXED_PAD)
    centre = site.xmat.reshape(3, 3).T @ (data.geom(FIXED_PAD).xpos - site.xpos)
    return centre + np.array([0.0, 0.0, pad.size[0] + size / 2])


def jaw_angle(model: mujoco.MjModel, size: float) -> float:
    """The gripper angle at which the pads are `size` apart (bisection on the model's kinematics)."""
    data = mujoco.MjData(model)
    low, high = model.joint(arm.GRIPPER).range
    pads = (model.geom(FIXED_PAD), model.geom("moving_jaw_pad"))
    for _ in range(40):
        data.qpos[model.joint(arm.GRIPPER).qposadr[0]] = mid = (low + high) / 2
        mujoco.mj_kinematics(model, data)
        gap = (
            np.linalg.norm(data.geom(pads[1].id).xpos - data.geom(pads[0].id).xpos) - pads[0].size[0] - pads[1].size[0]
        )
        low, high = (mid, high) if gap < size else (low, mid)
    return float((low + high) / 2)


def solve(
    model: mujoco.MjModel,
    point: np.ndarray,
    target: np.ndarray,
    across: float | None,
    seed: Mapping[str, float],
) -> dict[str, float]:
    """Arm joint angles putting `point` (site frame) at `target` (world) with the jaws closing along heading `across`
    (None: any) and pointing as nearly down as the arm allows. Five joints cannot point the jaws straight down
    everywhere (the SO-101 reaches that pose at table height only to about 30 cm), so the position comes first and
    the two orientations share what motion is left, weighed against each other."""
    data = mujoco.MjData(model)
    addresses = [model.joint(name).qposadr[0] for name in ARM_JOINTS]
    dofs = [model.joint(name).dofadr[0] for name in ARM_JOINTS]
    ranges = np.array([model.joint(name).range for name in ARM_JOINTS])
    closing = None if across is None else np.array([math.cos(across), math.sin(across), 0.0])
    q = np.array([seed[name] for name in ARM_JOINTS], dtype=float)
    site_id = model.site(SITE).id
    jacp, jacr = np.zeros((3, model.nv)), np.zeros((3, model.nv))
    back = np.full_like(q, np.inf)  # the joints a step back
    for _ in range(ITERATIONS):
        data.qpos[addresses] = q
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        rotation = data.site_xmat[site_id].reshape(3, 3)
        where = data.site_xpos[site_id] + rotation @ point
        mujoco.mj_jac(model, data, jacp, jacr, where, model.site_bodyid[site_id])
        position_error = target - where
        rows, errors = [], []
        # The turn that takes axis `a` onto `b` is a x b; turns about `a` itself do not count.
        for axis, wanted, weight in ((0, DOWN, DOWN_WEIGHT), (2, closing, ACROSS_WEIGHT)):
            if wanted is not None:
                a = rotation[:, axis]
                errors.append(weight * np.cross(a, wanted))
                rows.append(weight * (np.eye(3) - np.outer(a, a)) @ jacr[:, dofs])
        step = _within_limits(q, ranges, jacp[:, dofs], position_error, np.vstack(rows), np.concatenate(errors))
        moved = np.clip(q + step, ranges[:, 0], ranges[:, 1])
        # Swinging between two poses for good: keep this one, whose error is the one checked.
        if np.abs(moved - back).max() < SWING:
            break
        back, q = q, moved
        if np.linalg.norm(step) < 1e-7:
            break
    return _checked(q, position_error, rotation, closing, target)


def _solve_near(
    model: mujoco.MjModel, point: np.ndarray, target: np.ndarray, across: float | None, seed: Mapping[str, float]
) -> dict[str, float]:
    """`solve` from `seed` (the pose before, so the arm moves least), else from rest turned towards the target: from a
    pose folded near the base a far target's search can stick against a joint limit a millimetre or two short."""
    try:
        return solve(model, point, target, across, seed)
    except Unreachable:
        return solve(model, point, target, across, {**arm.REST, "shoulder_pan": math.atan2(target[1], target[0])})


def _pinv(jacobian: np.ndarray, damping: float) -> np.ndarray:
    """Damped pseudo-inverse: bounded steps near singular poses."""
    return jacobian.T @ np.linalg.inv(jacobian @ jacobian.T + damping**2 * np.eye(len(jacobian)))


def _prioritised(jac_p: np.ndarray, error_p: np.ndarray, jac_o: np.ndarray, error_o: np.ndarray) -> np.ndarray:
    """A joint step that reduces the position error first and the orientation error only with what motion is left
    (the position task's null space), each part bounded so neither stalls the other."""
    inverse = _pinv(jac_p, DAMPING)
    first = _bounded(inverse @ error_p)
    null = np.eye(jac_p.shape[1]) - inverse @ jac_p
    return first + _bounded(null @ _pinv(jac_o @ null, ORIENTATION_DAMPING) @ (error_o - jac_o @ first))


def _bounded(step: np.ndarray) -> np.ndarray:
    norm = np.linalg.norm(step)
    return step if norm <= MAX_STEP else step * (MAX_STEP / norm)


def _within_limits(q, ranges, jac_p, error_p, jac_o, error_o) -> np.ndarray:
    """The prioritised step with the joints that sit at a limit and would push past it held still: clipping them
    instead would leave the position short while the other joints think it reached."""
    free = np.ones(len(q), bool)
    for _ in range(len(q)):
        step = _prioritised(jac_p * free, error_p, jac_o * free, error_o)
        blocked = ((q <= ranges[:, 0] + 1e-9) & (step < 0)) | ((q >= ranges[:, 1] - 1e-9) & (step > 0))
        if not (blocked & free).any():
            return step * free
        free &= ~blocked
    return np.zeros(len(q))


def _checked(q, position_error, rotation, closing, target) -> dict[str, float]:
    tilt = math.degrees(math.acos(np.clip(rotation[:, 0] @ DOWN, -1.0, 1.0)))
    off = 0.0 if closing is None else math.degrees(math.acos(abs(np.clip(rotation[:, 2] @ closing, -1.0, 1.0))))
    if np.linalg.norm(position_error) > POSITION_TOLERANCE or tilt > MAX_TILT_DEG or off > MAX_ACROSS_DEG:
        raise Unreachable(
            f"the jaws cannot reach ({target[0]:.3f}, {target[1]:.3f}, {target[2]:.3f}) m pointing down "
            f"(off by {1000 * np.linalg.norm(position_error):.1f} mm, tilted {tilt:.0f} deg, turned {off:.0f} deg)"
        )
    return {name: float(angle) for name, angle in zip(ARM_JOINTS, q, strict=True)}


def headings(yaw: float) -> list[float]:
    """The four directions across an object's faces, turned by its yaw."""
    return [yaw + k * math.pi / 2 for k in range(4)]


def _best(model, point, grip, above, yaw, seed, avoid) -> tuple[dict[str, float], dict[str, float], float]:
    """Grasp and hover poses for the heading across the faces, reachable at both heights, whose open pads come down
    clear of the objects at `avoid` ((x, y) each), turning the wrist least from `seed`; where no heading is clear,
    the one whose pads come down furthest from them."""
    found = []
    for across in headings(yaw):
        try:
            at_grasp = solve(model, point, grip, across, seed)
            found.append((at_grasp, solve(model, point, above, across, at_grasp), across))
        except Unreachable:
            continue
    if not found:
        raise Unreachable(f"no top-down grasp of the object at ({grip[0]:.3f}, {grip[1]:.3f}) m is reachable")

    def rank(option) -> tuple[float, float]:
        clearance = min(_pad_clearance(model, option[0], avoid), PAD_CLEARANCE)
        return -clearance, abs(option[0]["wrist_roll"] - seed["wrist_roll"])

    return min(found, key=rank)


def _pad_clearance(model: mujoco.MjModel, joints: Mapping[str, float], avoid: Sequence[tuple[float, float]]) -> float:
    """How near (m, on the table's plane) the open jaws' pads at `joints` come to the nearest centre of `avoid`."""
    if not avoid:
        return math.inf
    data = mujoco.MjData(model)
    for name in ARM_JOINTS:
        data.qpos[model.joint(name).qposadr[0]] = joints[name]
    data.qpos[model.joint(arm.GRIPPER).qposadr[0]] = OPEN
    mujoco.mj_kinematics(model, data)
    pads = [data.geom(pad).xpos[:2] for pad in (FIXED_PAD, MOVING_PAD)]
    return min(math.dist(pad, other) for pad in pads for other in avoid)


def pick_and_place(
    model: mujoco.MjModel,
    start: Mapping[str, float],
    obj: tuple[float, float, float, float],
    size: float,
    target: tuple[float, float],
    avoid: Sequence[tuple[float, float]] = (),
) -> list[Waypoint]:
    """Waypoints that take the object at `obj` (x, y, z of its centre, yaw; world frame) of width `size` and put it
    down at `target` (x, y), starting from joint angles `start`; each waypoint's joint goals come from the IK. The
    jaws come down across the faces whose pads keep clear of the objects at `avoid` ((x, y) each)."""
    x, y, z, yaw = obj
    point = grasp_point(model, size)  # where the held object's centre is
    clear = point + np.array([0.0, 0.0, PAD_GAP])  # ... and where it is while the fixed pad keeps its gap
    opened, closed = OPEN, jaw_angle(model, size) - SQUEEZE
    grip = np.array([x, y, z + GRASP_ABOVE_CENTRE])
    above = grip + [0.0, 0.0, HOVER]
    at_grasp, hover, across = _best(model, clear, grip, above, yaw, start, avoid)
    carry_at = np.array([target[0], target[1], CARRY_HEIGHT])
    release = np.array([target[0], target[1], size / 2 + RELEASE_DROP])
    lift = _solve_near(model, point, np.array([x, y, CARRY_HEIGHT]), None, hover)
    # Once held, the object turns with the jaws: where they point across no longer matters.
    carried = _solve_near(model, point, carry_at, None, lift)
    lowered = _solve_near(model, point, release, None, carried)
    cleared = _solve_near(model, clear, release, None, lowered)  # the fixed pad off the object's face before rising
    withdrawn = _solve_near(model, clear, carry_at, None, cleared)
    return [
        Waypoint("open", {**hover, arm.GRIPPER: opened}, STEPS["open"]),
        Waypoint("descend", {**at_grasp, arm.GRIPPER: opened}, STEPS["descend"]),
        Waypoint("close", {**at_grasp, arm.GRIPPER: closed}, STEPS["close"]),
        Waypoint("lift", {**lift, arm.GRIPPER: closed}, STEPS["lift"]),
        Waypoint("carry", {**carried, arm.GRIPPER: closed}, STEPS["carry"]),
        Waypoint("lower", {**lowered, arm.GRIPPER: closed}, STEPS["lower"]),
        Waypoint("release", {**lowered, arm.GRIPPER: opened}, STEPS["release"]),
        Waypoint("clear", {**cleared, arm.GRIPPER: opened}, STEPS["clear"]),
        Waypoint("retreat", {**withdrawn, arm.GRIPPER: opened}, STEPS["retreat"]),
        Waypoint("rest", dict(arm.REST), STEPS["rest"]),
    ]


def follow(physics, waypoints: list[Waypoint]) -> None:
    """Send each waypoint's goals to the servos (Goal_Position registers) and step the physics for its time."""
    for waypoint in waypoints:
        for name, angle in waypoint.goals.items():
            physics.bank.memory(arm.MOTORS[name][0]).write("Goal_Position", round(arm.to_raw(name, angle)))
        physics.run(waypoint.seconds)


def carry(physics, name: str, target: tuple[float, float]) -> tuple[float, float, float, float]:
    """Pick object `name` up and put it down at `target` (x, y) through joint goals alone; returns its pose after."""
    start = {n: arm.to_angle(n, physics.bank.present(n)) for n in arm.MOTOR_NAMES}
    size = 2 * float(physics.model.geom(name).size[0])
    follow(physics, pick_and_place(physics.model, start, physics.poses()[name], size, target))
    return physics.poses()[name]
