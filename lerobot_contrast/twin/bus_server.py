"""The Feetech serial bus of the twin, served on a pseudo-terminal: LeRobot's `FeetechMotorsBus` opens `/dev/pts/N` as it
would the arm's USB adapter. Protocol 0: PING (broadcast too), READ, WRITE, SYNC_READ, SYNC_WRITE."""

import multiprocessing
import os
import select
import threading
import time
import tty

from lerobot_contrast.twin.bus_process import SharedLink, SharedTable, publish, take_updates
from lerobot_contrast.twin.faults import FaultInjector, FaultsConfig
from lerobot_contrast.twin.servos import ServoBank

BROADCAST_ID = 0xFE
PING, READ, WRITE, SYNC_READ, SYNC_WRITE = 0x01, 0x02, 0x03, 0x82, 0x83
MAX_LENGTH = 250  # the SDK's longest packet
TICK_S = 0.005  # how often the bus process steps its servos and trades state with the twin
START_TIMEOUT_S = 60
SILENT_S = 60  # how long the port stays open, answering nothing, after the twin dies
DRAIN_POLL_S = 0.0002


def checksum(body: bytes) -> int:
    """Feetech's checksum: the inverted low byte of the sum of id, length, instruction/error and parameters."""
    return ~sum(body) & 0xFF


def status_packet(servo_id: int, params: bytes = b"", error: int = 0) -> bytes:
    body = bytes([servo_id, len(params) + 2, error]) + params
    return b"\xff\xff" + body + bytes([checksum(body)])


def take_packets(buffer: bytearray) -> list[tuple[int, int, bytes]]:
    """Remove the complete instruction packets at the front of `buffer`: (id, instruction, params) each. Noise and
    packets with a wrong checksum are dropped, as a servo ignores them; an incomplete tail stays for the next read."""
    packets = []
    while True:
        start = buffer.find(b"\xff\xff")
        if start < 0:
            del buffer[: max(len(buffer) - 1, 0)]  # keep a lone trailing 0xFF: it may start a header
            return packets
        del buffer[:start]
        if len(buffer) < 4:
            return packets
        servo_id, length = buffer[2], buffer[3]
        if servo_id == 0xFF or length < 2 or length > MAX_LENGTH:
            del buffer[:1]  # a third 0xFF or a length no packet has: resynchronise one byte on
            continue
        if len(buffer) < length + 4:
            return packets
        packet = bytes(buffer[: length + 4])
        del buffer[: length + 4]
        if packet[-1] == checksum(packet[2:-1]):
            packets.append((servo_id, packet[4], packet[5:-1]))


class BusServer:
    """Answers instruction packets for the servos of `bank`. With `clocked`, the bank is advanced by the wall-clock time
    before each packet (no physics running); otherwise whatever steps the physics steps the bank.

    With `process` (the default when not `clocked`), the bus is served from a process of its own, holding a copy of
    the servos that steps in real time: its replies then meet LeRobot's 50 ms deadline however busy the physics and
    camera threads keep this interpreter (in one process, 9 connects in 10 failed on a loaded 2-core machine). The
    bank here then mirrors those servos at each `step` and passes its measurements and register writes on."""

    def __init__(self, bank: ServoBank, faults: FaultsConfig | None = None, clocked: bool = False,
                 process: bool | None = None):  # fmt: skip
        self.bank = bank
        self.faults = FaultInjector(faults)
        self.clocked = clocked
        self.process = not clocked if process is None else process
        self.port: str | None = None
        self._thread: threading.Thread | None = None
        self._fds: list[int] = []
        self._last_step = time.monotonic()
        self._child = None
        self._serving = threading.Lock()  # held while bytes read from the port are answered
        self.silent = False  # the servos have no power: instruction packets get no reply

    def start(self) -> str:
        """Open the pseudo-terminal and serve it (on a daemon thread, or in a process); returns the port to give
        LeRobot."""
        if self.process:
            return self._start_process()
        master, slave = os.openpty()
        tty.setraw(slave)  # no echo, no line editing: bytes pass as on a serial line
        wake_read, wake_write = os.pipe()
        self._fds = [master, slave, wake_read, wake_write]
        self.port = os.ttyname(slave)
        self._last_step = time.monotonic()
        self._thread = threading.Thread(target=self._serve, name=f"twin-bus {self.port}", daemon=True)
        self._thread.start()
        return self.port

    def stop(self) -> None:
        if self._child is not None:
            child, table, stopping = self._child
            stopping.set()
            child.join(timeout=5)
            self.bank.link, self._child = None, None
            table.close()
        if self._thread is None:
            return
        os.write(self._fds[3], b"x")
        self._thread.join(timeout=5)
        for fd in self._fds:
            os.close(fd)
        self._thread, self._fds = None, []

    def __enter__(self) -> str:
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()

    def _start_process(self) -> str:
        spawn = multiprocessing.get_context("spawn")  # not fork: the twin's other threads hold locks and sockets
        table, writes, ports, stopping = SharedTable(self.bank.ids), spawn.Queue(), spawn.Queue(), spawn.Event()
        publish(self.bank, table)
        child = spawn.Process(
            target=_serve_process,
            args=(self.bank, self.faults.config, table.memory.name, writes, ports, stopping),
            name="twin-bus",
            daemon=True,
        )
        child.start()
        self._child = (child, table, stopping)
        try:
            self.port = ports.get(timeout=START_TIMEOUT_S)
        except Exception:
            self.stop()
            raise RuntimeError("the twin's bus process did not start") from None
        self.bank.link = SharedLink(table, writes)
        return self.port

    def advance(self) -> None:
        """Step the servos by the wall-clock time since the last step (clocked)."""
        with self.bank.lock:
            now = time.monotonic()
            self.bank.step(now - self._last_step)
            self._last_step = now

    def _serve(self) -> None:
        master, _, wake, _ = self._fds
        buffer = bytearray()
        while True:
            ready, _, _ = select.select([master, wake], [], [])
            if wake in ready:
                return
            with self._serving:
                buffer += os.read(master, 4096)
                packets = take_packets(buffer)
                for k, (servo_id, instruction, params) in enumerate(packets):
                    # The driver sends its next packet only once it has the reply or has given up waiting, so a
                    # packet with another behind it was given up on: its late reply would be read as the next one's.
                    reply = self.answer(servo_id, instruction, params, reply=k == len(packets) - 1 and not buffer)
                    if reply:
                        os.write(master, reply)

    def drain(self) -> None:
        """Return once every byte written to the port so far has been acted on (served on a thread here): on the
        simulated clock, the driver's last goals reach the servos before time moves on."""
        master = self._fds[0]
        while True:
            with self._serving:
                if not select.select([master], [], [], 0)[0]:
                    return
            time.sleep(DRAIN_POLL_S)

    def answer(self, servo_id: int, instruction: int, params: bytes, reply: bool = True) -> bytes:
        """The bytes the bus sends back for one instruction packet (status packets, after faults); with `reply`
        False the servos act on it but stay silent."""
        if self.clocked:
            self.advance()
        packets = self._status_packets(servo_id, instruction, params)
        if not packets or not reply or self.silent:
            return b""
        moving = any(self.bank.memory(i).read("Moving") for i in self.bank.ids)
        return b"".join(self.faults.apply(packet, moving) for packet in packets)

    def _status_packets(self, servo_id: int, instruction: int, params: bytes) -> list[bytes]:
        bank, present = self.bank, servo_id in self.bank.ids
        if instruction == PING and servo_id == BROADCAST_ID:
            return [status_packet(i) for i in bank.ids]
        if instruction == PING and present:
            return [status_packet(servo_id)]
        if instruction == READ and present and len(params) == 2:
            return [status_packet(servo_id, bank.bus_read(servo_id, params[0], params[1]))]
        if instruction == WRITE and params and (present or servo_id == BROADCAST_ID):
            targets = bank.ids if servo_id == BROADCAST_ID else [servo_id]
            for i in targets:
                bank.bus_write(i, params[0], params[1:])
            replies = servo_id != BROADCAST_ID and bank.memory(servo_id).read("Response_Status_Level")
            return [status_packet(servo_id)] if replies else []
        if instruction == SYNC_READ and len(params) >= 2:
            addr, length = params[0], params[1]
            return [status_packet(i, bank.bus_read(i, addr, length)) for i in params[2:] if i in bank.ids]
        if instruction == SYNC_WRITE and len(params) >= 2:
            addr, length = params[0], params[1]
            for offset in range(2, len(params) - length, length + 1):
                if params[offset] in bank.ids:
                    bank.bus_write(params[offset], addr, params[offset + 1 : offset + 1 + length])
        return []


def _serve_process(bank: ServoBank, faults: FaultsConfig, table_name: str, writes, ports, stopping) -> None:
    """The bus process: serve the bank's copy, clocked, trading state with the twin every TICK_S."""
    table = SharedTable(bank.ids, table_name)
    server = BusServer(bank, faults, clocked=True, process=False)
    ports.put(server.start())
    twin = os.getppid()
    try:
        while not stopping.wait(TICK_S):
            if os.getppid() != twin:  # the twin was killed: its arm lost power, the USB adapter is still plugged in
                server.silent = True
                stopping.wait(SILENT_S)
                return
            with bank.lock:
                take_updates(bank, table, writes)
                server.advance()
                publish(bank, table)
    finally:
        server.stop()
        table.close()
