"""Faults on the twin's serial line: status packets sent with a wrong checksum, or never sent, at chosen rates (seeded)."""

from dataclasses import dataclass

import numpy as np


@dataclass
class FaultsConfig:
    """What goes wrong on the line (the `--faults.*` flags of the twin)."""

    corrupt: float = 0.0
    """Share of status packets sent with a wrong checksum (0 to 1); the driver sees "Incorrect status packet"."""
    drop: float = 0.0
    """Share of status packets never sent (0 to 1); the driver waits for its timeout, then sees "no status packet"."""
    seed: int = 0
    """Seed of the faults' random draws: the same seed gives the same faults for the same traffic."""
    while_moving: bool = False
    """Only while a servo moves (noise from the motors, as on a real bus), so connect and configure see a clean line."""

    def __post_init__(self):
        for name in ("corrupt", "drop"):
            rate = getattr(self, name)
            if not 0.0 <= rate <= 1.0:
                raise ValueError(f"--faults.{name}={rate} is not a rate: give a number from 0 to 1")


class FaultInjector:
    """Decides the fate of each status packet the twin sends, and counts what it did."""

    def __init__(self, config: FaultsConfig | None = None):
        self.config = config or FaultsConfig()
        self._rng = np.random.default_rng(self.config.seed)
        self.corrupted = 0
        self.dropped = 0

    def apply(self, packet: bytes, moving: bool) -> bytes:
        """The bytes that go out on the line for this status packet (empty when it is dropped)."""
        config = self.config
        if config.while_moving and not moving or not (config.corrupt or config.drop):
            return packet
        draw = self._rng.random()
        if draw < config.drop:
            self.dropped += 1
            return b""
        if draw < config.drop + config.corrupt:
            self.corrupted += 1
            return packet[:-1] + bytes([packet[-1] ^ 0xFF])
        return packet
