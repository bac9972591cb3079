"""The wire format: observation messages, version checks, and the host's exactly-once step gate."""

from __future__ import annotations

import numpy as np
import pytest
from lerobot_robot_locobot.protocol import (
    VERSION,
    ProtocolError,
    StepGate,
    decode,
    decode_depth,
    decode_observation,
    decode_rgb,
    encode,
    encode_frames,
    observation_message,
)


def test_an_observation_message_carries_its_header_a_jpeg_and_millimetre_depth():
    rng = np.random.default_rng(0)
    rgb = np.repeat(np.repeat(rng.integers(0, 255, (6, 8, 3), dtype=np.uint8), 8, 0), 8, 1)
    depth = rng.uniform(0.3, 9.0, (48, 64)).astype(np.float32)
    message = observation_message({"seq": 3, "state": {"odom.x": 1.5}}, encode_frames(rgb, depth))
    header, frames = decode_observation(message)
    assert header["v"] == VERSION and header["seq"] == 3 and header["state"] == {"odom.x": 1.5}
    assert np.abs(decode_rgb(frames["rgb"]).astype(int) - rgb).mean() < 12  # JPEG; swapped channels give ~60
    assert np.abs(decode_depth(frames["depth"]) - depth).max() <= 0.0005 + 1e-6  # rounded to millimetres


def test_messages_of_another_version_or_malformed_are_refused_with_a_reason():
    with pytest.raises(ProtocolError, match="same lerobot_robot_locobot version"):
        decode(b'{"v": 99, "op": "hello"}')
    with pytest.raises(ProtocolError, match="malformed"):
        decode(b"\xff not json")
    whole = observation_message({"seq": 1}, encode_frames(np.zeros((16, 16, 3), np.uint8), None))
    with pytest.raises(ProtocolError):
        decode_observation(whole[:-5])
    assert decode(encode({"op": "hello"})) == {"v": VERSION, "op": "hello"}


@pytest.mark.parametrize("seed", range(5))
def test_the_gate_starts_each_step_once_and_in_order_whatever_the_channel_does(seed):
    """A client resends step n until acknowledged; the channel loses, repeats and reorders commands and acks."""
    rng = np.random.default_rng(seed)
    gate, started, in_flight = StepGate(), [], []
    acked, next_step = 0, 1
    while next_step <= 20:
        in_flight.append(next_step)  # (re)send the current step
        rng.shuffle(in_flight)
        delivered = [s for s in in_flight if rng.random() < 0.5]
        in_flight = [s for s in in_flight if rng.random() < 0.5]  # some stay in the network, some vanish
        for step in delivered + delivered[: int(rng.integers(0, 2))]:
            if gate.offer(step):
                started.append(step)
        if gate.running is not None and rng.random() < 0.7:
            gate.finish("done")
        if rng.random() < 0.6:  # an observation (with the ack) gets through
            acked = max(acked, gate.ack("s")["step"])
        if acked >= next_step:
            next_step += 1
    assert started == list(range(1, len(started) + 1)) and len(started) >= 20
