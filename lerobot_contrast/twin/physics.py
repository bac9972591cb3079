"""MuJoCo stepping the twin's world: each tick the servo bank advances, the arm's position actuators follow its
setpoints, and the measured joint angles go back as Present_Position. Real time on a thread, or stepped in tests."""

from __future__ import annotations

import math
import sys
import threading
import time
from collections.abc import Callable, Iterable, Mapping
from typing import TypeVar

import mujoco

from lerobot_contrast.so101 import arm
from lerobot_contrast.twin.servos import ServoBank

CONTROL_DT = 0.01  # s per tick: the bank and the actuators' targets update at 100 Hz
# A tick late by more than this is dropped rather than caught up, so a busy machine slows the world instead of
# running it in bursts.
MAX_LAG = 0.1
PLACE_CLEARANCE = 0.0005  # m above the table a placed object starts, so it settles without a jump
JAW_PADS = ("fixed_jaw_pad", "moving_jaw_pad")  # the gripper's pad geoms, as the arm's model names them
T = TypeVar("T")


class Physics:
    """The world of `spec` with its arm driven by `bank`; `objects` are the bodies whose true poses are reported."""

    def __init__(
        self, spec: mujoco.MjSpec, bank: ServoBank, objects: Iterable[str], offsets: Mapping[str, float] | None = None
    ):
        self.spec, self.bank, self.objects = spec, bank, tuple(objects)
        # Each joint's true angle is its calibrated reading plus its offset: a calibration off the model's zero.
        self.offsets = {name: (offsets or {}).get(name, 0.0) for name in arm.MOTOR_NAMES}
        self.lock = threading.RLock()
        self.model = spec.compile()
        self.data = mujoco.MjData(self.model)
        self._index()
        self.version = 0  # counts recompilations (edit), so a renderer knows to rebuild
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self.error: str | None = None  # why the real-time thread stopped, if it failed
        for name in arm.MOTOR_NAMES:
            angle = arm.to_angle(name, bank.present(name)) + self.offsets[name]
            self.data.qpos[self.model.joint(name).qposadr[0]] = angle
            self.data.ctrl[self.model.actuator(name).id] = angle
        mujoco.mj_forward(self.model, self.data)

    def _index(self) -> None:
        """Each motor's actuator and joint position in the compiled model (looked up by name once, not each tick)."""
        self._actuator = {name: self.model.actuator(name).id for name in arm.MOTOR_NAMES}
        self._qpos = {name: self.model.joint(name).qposadr[0] for name in arm.MOTOR_NAMES}
        self.substeps = max(1, round(CONTROL_DT / self.model.opt.timestep))

    def tick(self) -> None:
        """One control period: the servos' profiles, then the physics under their setpoints, then the measurement."""
        self.bank.step(CONTROL_DT)
        # A servo without torque holds its last target here (a real one goes limp): the twin's arm never collapses.
        targets = {
            n: arm.to_angle(n, self.bank.setpoint(n)) + self.offsets[n]
            for n in arm.MOTOR_NAMES
            if self.bank.torque_enabled(n)
        }
        with self.lock:
            for name, angle in targets.items():
                self.data.ctrl[self._actuator[name]] = angle
            mujoco.mj_step(self.model, self.data, nstep=self.substeps)
            measured = {n: float(self.data.qpos[self._qpos[n]]) for n in arm.MOTOR_NAMES}
        for name, angle in measured.items():
            self.bank.set_present(name, arm.to_raw(name, angle - self.offsets[name]))

    def run(self, seconds: float) -> None:
        """Advance `seconds` of simulated time at once, without sleeping (tests, scripted demonstrations)."""
        for _ in range(max(1, round(seconds / CONTROL_DT))):
            self.tick()

    def start(self) -> None:
        """Step in real time on a daemon thread until `stop()`."""
        self._stop.clear()
        self._thread = threading.Thread(target=self._loop, name="twin-physics", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5)
            self._thread = None

    def _loop(self) -> None:
        due = time.monotonic()
        try:
            while not self._stop.is_set():
                self.tick()
                due += CONTROL_DT
                lag = time.monotonic() - due
                if lag > MAX_LAG:
                    due = time.monotonic()
                elif lag < 0:
                    self._stop.wait(-lag)
        except Exception as error:  # a frozen arm must say why
            self.error = f"twin physics stopped: {' '.join(str(error).split())[:200]}"
            print(self.error, file=sys.stderr)

    def read(self, view: Callable[[mujoco.MjModel, mujoco.MjData], T]) -> T:
        """`view(model, data)` while no step runs: a consistent state (a renderer's update_scene, say)."""
        with self.lock:
            return view(self.model, self.data)

    def poses(self) -> dict[str, tuple[float, float, float, float]]:
        """Each object's true pose: x, y, z (its centre, metres, task frame) and yaw (radians, in (-pi, pi])."""
        with self.lock:
            return {name: _pose(self.data.body(name)) for name in self.objects}

    def gripped(self) -> set[str]:
        """The objects touching the gripper's jaws (the bodies that carry its pads)."""
        with self.lock:
            jaws = {int(self.model.geom(pad).bodyid[0]) for pad in JAW_PADS}
            touching = set()
            for contact in self.data.contact[: self.data.ncon]:
                bodies = {int(self.model.geom_bodyid[contact.geom1]), int(self.model.geom_bodyid[contact.geom2])}
                if bodies & jaws:
                    touching |= bodies - jaws
            return {name for name in self.objects if self.model.body(name).id in touching}

    def place(self, name: str, x: float, y: float, yaw: float) -> None:
        """Put object `name` upright on the table at (x, y) turned by yaw, at rest."""
        with self.lock:
            joint = self.model.joint(name)
            z = _rest_height(self.model.geom(name)) + PLACE_CLEARANCE
            q = joint.qposadr[0]
            self.data.qpos[q : q + 7] = [x, y, z, math.cos(yaw / 2), 0, 0, math.sin(yaw / 2)]
            self.data.qvel[joint.dofadr[0] : joint.dofadr[0] + 6] = 0.0
            mujoco.mj_forward(self.model, self.data)

    def reset_arm(self) -> None:
        """Put the arm at rest at once; servos under torque hold the rest pose from now on."""
        with self.lock:
            for name in arm.MOTOR_NAMES:
                self.data.qpos[self.model.joint(name).qposadr[0]] = arm.REST[name] + self.offsets[name]
                self.data.qvel[self.model.joint(name).dofadr[0]] = 0.0
                self.data.ctrl[self.model.actuator(name).id] = arm.REST[name] + self.offsets[name]
            mujoco.mj_forward(self.model, self.data)
            for name, (servo_id, _) in arm.MOTORS.items():
                self.bank.set_present(name, arm.to_raw(name, arm.REST[name]))
                if self.bank.torque_enabled(name):  # re-enabling torque makes the servo hold where it now is
                    memory = self.bank.memory(servo_id)
                    memory.write("Torque_Enable", 0)
                    memory.write("Torque_Enable", 1)
                    # and the goal, for a bank mirroring a bus process that may see the writes before the measurement
                    memory.write("Goal_Position", round(arm.to_raw(name, arm.REST[name])))

    def edit(self, change: Callable[[mujoco.MjSpec], None]) -> None:
        """Change the world (add or remove a body) and recompile, keeping every joint's state."""
        with self.lock:
            change(self.spec)
            self.model, self.data = self.spec.recompile(self.model, self.data)
            self._index()
            mujoco.mj_forward(self.model, self.data)
            self.version += 1


def _rest_height(geom) -> float:
    """How high above the table an upright object's centre rests: a half side, a radius or a half height."""
    axis = {mujoco.mjtGeom.mjGEOM_SPHERE: 0, mujoco.mjtGeom.mjGEOM_CYLINDER: 1}.get(int(geom.type[0]), 2)
    return float(geom.size[axis])


def _pose(body) -> tuple[float, float, float, float]:
    w, x, y, z = body.xquat
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return float(body.xpos[0]), float(body.xpos[1]), float(body.xpos[2]), float(yaw)
