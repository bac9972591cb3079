"""What links a servo bank to its copy in the bus process: a shared-memory table (the servos' setpoints, presents and
torque one way, the physics' measurements the other) and a queue of register writes made outside the bus."""

from __future__ import annotations

import queue
from multiprocessing import shared_memory

import numpy as np

from lerobot_contrast.twin.servos import ServoBank

# Columns of the shared table, one row per servo: written by the bus process, then by the twin.
SETPOINT, PRESENT, TORQUE, MEASURED, HAS_MEASURED = range(5)


class SharedTable:
    """The rows of `ids` in shared memory (created here, or attached by `name`)."""

    def __init__(self, ids: list[int], name: str | None = None):
        size = len(ids) * 5 * 8
        self.memory = shared_memory.SharedMemory(name=name, create=name is None, size=size)
        self.array = np.ndarray((len(ids), 5), dtype=np.float64, buffer=self.memory.buf)
        self.rows = {servo_id: row for row, servo_id in enumerate(ids)}
        self.owner = name is None
        if self.owner:
            self.array[:] = 0.0

    def close(self) -> None:
        del self.array  # the buffer must have no views left before it closes
        self.memory.close()
        if self.owner:
            self.memory.unlink()


class SharedLink:
    """The twin's side (servos.Link): mirror the bus process's servos, send it measurements and register writes."""

    def __init__(self, table: SharedTable, writes):
        self.table, self.writes = table, writes

    def pull(self, bank: ServoBank) -> None:
        for servo_id, row in self.table.rows.items():
            values = self.table.array[row]
            bank.mirror(servo_id, float(values[SETPOINT]), float(values[PRESENT]), bool(values[TORQUE]))

    def present(self, servo_id: int, raw: float) -> None:
        row = self.table.array[self.table.rows[servo_id]]
        row[MEASURED], row[HAS_MEASURED] = raw, 1.0

    def write(self, servo_id: int, addr: int, data: bytes) -> None:
        self.writes.put((servo_id, addr, bytes(data)))


def publish(bank: ServoBank, table: SharedTable) -> None:
    """The bus process's side: its servos' state into the table."""
    for servo_id, row in table.rows.items():
        name = bank.names[servo_id]
        table.array[row, [SETPOINT, PRESENT, TORQUE]] = (
            bank.setpoint(name),
            bank.present(name),
            bank.torque_enabled(name),
        )


def take_updates(bank: ServoBank, table: SharedTable, writes) -> None:
    """The bus process's side: the twin's latest measurements, then its register writes, into the servos."""
    while True:
        _measurements(bank, table)  # before each write: a write that re-enables torque holds the newest pose
        try:
            servo_id, addr, data = writes.get_nowait()
        except queue.Empty:
            return
        bank.bus_write(servo_id, addr, data)


def _measurements(bank: ServoBank, table: SharedTable) -> None:
    for servo_id, row in table.rows.items():
        if table.array[row, HAS_MEASURED]:
            bank.set_present(bank.names[servo_id], float(table.array[row, MEASURED]))
