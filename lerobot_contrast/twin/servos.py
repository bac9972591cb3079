"""A bank of simulated STS3215 servos: register memory per servo, and a profiled setpoint that moves toward
Goal_Position at finite speed and acceleration inside the position limits while torque is on. Thread-safe.

Positions here ("raw") are in the register frame LeRobot reads: Present_Position = encoder - Homing_Offset."""

import math
import threading
from dataclasses import dataclass
from typing import Protocol

from lerobot_contrast.twin.control_table import ControlTable

# STS3215 at 12 V: 0.222 s per 60 degrees without load, i.e. 270 degrees/s, in steps of 4096 per turn.
MAX_SPEED = 270 * 4096 / 360
ACCELERATION_UNIT = 100  # steps/s^2 per unit of the Acceleration register (Feetech's manual)
NO_RAMP = 1e6  # Acceleration 0 means no ramp: effectively instant
SUBSTEP = 0.002  # s; the profile is integrated in steps no longer than this
STEPS_PER_TURN = 4096
PHASE_NO_WRAP = 0x10  # Phase bit 4 set: positions are not wrapped into one turn


@dataclass
class _Servo:
    table: ControlTable
    setpoint: float  # encoder frame (before Homing_Offset)
    present: float  # encoder frame
    velocity: float = 0.0  # steps/s, of the setpoint
    measured: bool = False  # True once physics reports present positions


class Link(Protocol):
    """Where a bank whose servos run in another process (the bus process) sends what happens here."""

    def pull(self, bank: "ServoBank") -> None: ...  # copy the servos' setpoints, torque and presents here
    def present(self, servo_id: int, raw: float) -> None: ...  # a measurement for the servo
    def write(self, servo_id: int, addr: int, data: bytes) -> None: ...  # a register write for the servo


class Memory:
    """One servo's registers by name, under the bank's lock, with the side effects a write has on a real servo."""

    def __init__(self, bank: "ServoBank", servo_id: int):
        self._bank, self._id = bank, servo_id

    def read(self, name: str) -> int:
        with self._bank.lock:
            return self._bank._servo(self._id).table.get(name)

    def write(self, name: str, value: int) -> None:
        """Write as the bus does (read-only registers stay as they are)."""
        addr, data = self._bank._servo(self._id).table.encode(name, value)
        self._bank.bus_write(self._id, addr, data)


class ServoBank:
    """The servos of one arm: `motors` maps name -> (id, model); `initial_raw` gives each one's starting position."""

    def __init__(
        self,
        motors: dict[str, tuple[int, str]],
        initial_raw: dict[str, int],
        *,
        homing_offsets: dict[str, int] | None = None,
        limits: dict[str, tuple[int, int]] | None = None,
    ):
        if set(initial_raw) != set(motors):
            raise ValueError(f"initial_raw names {sorted(initial_raw)} differ from the motors {sorted(motors)}")
        self.lock = threading.RLock()
        self.link: Link | None = None  # set while the servos run in the bus process (bus_process.py)
        self.names = {servo_id: name for name, (servo_id, _) in motors.items()}
        if len(self.names) != len(motors):
            raise ValueError(f"two motors share an id: {motors}")
        self._servos: dict[int, _Servo] = {}
        for name, (servo_id, model) in motors.items():
            table = ControlTable(servo_id, model)
            table.set("Homing_Offset", (homing_offsets or {}).get(name, 0))
            low, high = (limits or {}).get(name, (0, STEPS_PER_TURN - 1))
            table.set("Min_Position_Limit", low)
            table.set("Max_Position_Limit", high)
            encoder = initial_raw[name] + table.get("Homing_Offset")
            self._servos[servo_id] = _Servo(table, setpoint=encoder, present=encoder)
            table.set("Goal_Position", initial_raw[name])
            self._publish(self._servos[servo_id])

    @property
    def ids(self) -> list[int]:
        return sorted(self._servos)

    def memory(self, servo_id: int) -> Memory:
        self._servo(servo_id)
        return Memory(self, servo_id)

    def setpoint(self, name: str) -> float:
        """Where the servo's controller is taking the joint now (raw), for physics to drive the actuator to."""
        with self.lock:
            servo = self._named(name)
            return servo.setpoint - servo.table.get("Homing_Offset")

    def set_present(self, name: str, raw: float) -> None:
        """What the physics measured (raw): Present_Position reports it from now on, instead of the setpoint."""
        with self.lock:
            servo = self._named(name)
            servo.present = raw + servo.table.get("Homing_Offset")
            servo.measured = True
            self._publish(servo)
            if self.link is not None:
                self.link.present(servo.table.get("ID"), raw)

    def present(self, name: str) -> float:
        with self.lock:
            servo = self._named(name)
            return servo.present - servo.table.get("Homing_Offset")

    def torque_enabled(self, name: str) -> bool:
        with self.lock:
            return bool(self._named(name).table.get("Torque_Enable"))

    def step(self, dt: float) -> None:
        """Advance every servo's controller by dt seconds (linked to a bus process, where they step in real time:
        take their state from there)."""
        if self.link is not None:
            self.link.pull(self)
            return
        with self.lock:
            for servo in self._servos.values():
                if servo.table.get("Torque_Enable"):
                    _follow_profile(servo, dt)
                else:  # limp: the controller tracks wherever the joint is
                    servo.setpoint, servo.velocity = servo.present, 0.0
                if not servo.measured:
                    servo.present = servo.setpoint
                self._publish(servo)

    def bus_read(self, servo_id: int, addr: int, length: int) -> bytes:
        with self.lock:
            return self._servo(servo_id).table.read_bytes(addr, length)

    def bus_write(self, servo_id: int, addr: int, data: bytes) -> None:
        """A WRITE from the bus, with its side effects: enabling torque holds the joint where it is."""
        with self.lock:
            if self.link is not None:
                self.link.write(servo_id, addr, data)
            servo = self._servo(servo_id)
            torque_was = servo.table.get("Torque_Enable")
            touched = servo.table.write_bytes(addr, data)
            if "Torque_Enable" in touched and servo.table.get("Torque_Enable") and not torque_was:
                servo.setpoint, servo.velocity = servo.present, 0.0
                servo.table.set("Goal_Position", round(servo.present - servo.table.get("Homing_Offset")))
            self._publish(servo)

    def mirror(self, servo_id: int, setpoint: float, present: float, torque: bool) -> None:
        """Take a linked servo's state (raw) as the bus process reports it."""
        with self.lock:
            servo = self._servo(servo_id)
            offset = servo.table.get("Homing_Offset")
            servo.setpoint, servo.present = setpoint + offset, present + offset
            servo.table.set("Torque_Enable", int(torque))
            self._publish(servo)

    def __getstate__(self) -> dict:
        state = {**self.__dict__, "link": None}
        del state["lock"]
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self.lock = threading.RLock()

    def _servo(self, servo_id: int) -> _Servo:
        if servo_id not in self._servos:
            raise KeyError(f"no servo with id {servo_id} on this bank (ids {self.ids})")
        return self._servos[servo_id]

    def _named(self, name: str) -> _Servo:
        servo_id = next((i for i, n in self.names.items() if n == name), None)
        if servo_id is None:
            raise KeyError(f"no motor named {name!r} on this bank ({sorted(self.names.values())})")
        return self._servos[servo_id]

    @staticmethod
    def _publish(servo: _Servo) -> None:
        """Refresh the read-only registers a status packet reports from the servo's state."""
        table = servo.table
        position = round(servo.present) - table.get("Homing_Offset")
        if not table.get("Phase") & PHASE_NO_WRAP:
            position %= STEPS_PER_TURN
        table.set("Present_Position", position)
        table.set("Present_Velocity", round(servo.velocity))
        target = _target(servo)
        moving = abs(servo.velocity) > 0.5 or (table.get("Torque_Enable") and abs(target - servo.setpoint) > 1)
        table.set("Moving", int(bool(moving)))


def _target(servo: _Servo) -> float:
    """Goal_Position clipped to the position limits, in the encoder frame."""
    table = servo.table
    low, high = table.get("Min_Position_Limit"), table.get("Max_Position_Limit")
    goal = min(max(table.get("Goal_Position"), low), high) if low < high else table.get("Goal_Position")
    return goal + table.get("Homing_Offset")


def _follow_profile(servo: _Servo, dt: float) -> None:
    """Trapezoidal velocity profile toward the target (speed from Goal_Velocity, ramp from Acceleration)."""
    target = _target(servo)
    speed = abs(servo.table.get("Goal_Velocity")) or MAX_SPEED
    speed = min(speed, MAX_SPEED)
    accel = servo.table.get("Acceleration") * ACCELERATION_UNIT or NO_RAMP
    remaining = dt
    while remaining > 1e-12:
        h = min(SUBSTEP, remaining)
        remaining -= h
        gap = target - servo.setpoint
        if abs(gap) < 0.5 and abs(servo.velocity) <= accel * h:
            servo.setpoint, servo.velocity = target, 0.0
            return
        wanted = math.copysign(min(speed, math.sqrt(2 * accel * abs(gap))), gap)
        servo.velocity += min(max(wanted - servo.velocity, -accel * h), accel * h)
        move = servo.velocity * h
        if gap * move > 0 and abs(move) >= abs(gap):
            servo.setpoint, servo.velocity = target, 0.0
            return
        servo.setpoint += move
