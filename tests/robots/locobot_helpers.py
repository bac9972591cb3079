"""Loopback helpers for LoCoBot tests: a client config for a host thread, a backend that counts steps, and a
proxy that loses, repeats and reorders messages between client and host."""

from __future__ import annotations

import threading
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import zmq
from lerobot_robot_locobot import LocobotConfig
from lerobot_robot_locobot.config_host import HostConfig

FREE_PORTS = HostConfig(port_command=0, port_observation=0, port_rpc=0)


def client_config(ports: dict[str, int], calibration_dir: Path, **changes: Any) -> LocobotConfig:
    config = LocobotConfig(
        port_command=ports["command"],
        port_observation=ports["observation"],
        port_rpc=ports["rpc"],
        calibration_dir=calibration_dir,
        camera_width=160,
        camera_height=120,
        connect_timeout_s=2.0,
    )
    return replace(config, **changes)


class CountingBackend:
    """Wraps a backend and records every step it is asked to start."""

    def __init__(self, backend: Any) -> None:
        self.backend = backend
        self.started: list[tuple[str, float]] = []

    def start_step(self, command: str, amount: float) -> None:
        self.started.append((command, amount))
        self.backend.start_step(command, amount)

    def __getattr__(self, name: str) -> Any:
        return getattr(self.backend, name)


class DyingBackend(CountingBackend):
    """Stops its host (sets `host_stop`, the HostThread's stop event) as it starts step number `dies_at`: the host
    goes silent mid-step, as when its process dies."""

    def __init__(self, backend: Any, dies_at: int) -> None:
        super().__init__(backend)
        self.dies_at = dies_at
        self.host_stop: threading.Event | None = None

    def start_step(self, command: str, amount: float) -> None:
        if len(self.started) + 1 == self.dies_at and self.host_stop is not None:
            self.started.append((command, amount))
            self.host_stop.set()  # the step never finishes
            return
        super().start_step(command, amount)


class ChaosProxy:
    """Sits between client and host on the command and observation channels; each message is dropped,
    sent twice, or held back and delivered after later ones, at random."""

    def __init__(
        self, host_ports: dict[str, int], seed: int, drop: float = 0.3, repeat: float = 0.2, hold: float = 0.3
    ):
        self.rng = np.random.default_rng(seed)
        self.drop, self.repeat, self.hold = drop, repeat, hold
        self.context = zmq.Context()
        self.command_in = self._socket(zmq.PULL)
        self.command_out = self._socket(zmq.PUSH)
        self.command_out.connect(f"tcp://127.0.0.1:{host_ports['command']}")
        self.observation_in = self._socket(zmq.SUB)
        self.observation_in.setsockopt(zmq.SUBSCRIBE, b"")
        self.observation_in.connect(f"tcp://127.0.0.1:{host_ports['observation']}")
        self.observation_out = self._socket(zmq.PUB)
        self.ports = {
            "command": self.command_in.bind_to_random_port("tcp://127.0.0.1"),
            "observation": self.observation_out.bind_to_random_port("tcp://127.0.0.1"),
            "rpc": host_ports["rpc"],
        }
        self.stats = {"dropped": 0, "repeated": 0, "held": 0}
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _socket(self, kind: int) -> zmq.Socket:
        s = self.context.socket(kind)
        s.linger = 0
        return s

    def _run(self) -> None:
        poller = zmq.Poller()
        poller.register(self.command_in, zmq.POLLIN)
        poller.register(self.observation_in, zmq.POLLIN)
        held: dict[zmq.Socket, list[bytes]] = {self.command_out: [], self.observation_out: []}
        while not self._stop.is_set():
            for source in dict(poller.poll(20)):
                out = self.command_out if source is self.command_in else self.observation_out
                self._forward(source.recv(), out, held[out])

    def _forward(self, message: bytes, out: zmq.Socket, held: list[bytes]) -> None:
        draw = self.rng.random()
        if draw < self.drop:
            self.stats["dropped"] += 1
        elif draw < self.drop + self.hold:
            self.stats["held"] += 1
            held.append(message)
            return
        else:
            out.send(message)
            if self.rng.random() < self.repeat:
                self.stats["repeated"] += 1
                out.send(message)
        while held and self.rng.random() < 0.5:  # late arrivals, after newer messages
            out.send(held.pop(0))

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2.0)
        self.context.destroy(linger=0)
