"""LeRobot's own `SO101Follower`, unmodified, drives the twin's Feetech bus on a pseudo-terminal (no MuJoCo)."""

import time

import pytest
from lerobot.robots.so_follower import SO101Follower, SO101FollowerConfig

from lerobot_contrast.twin.bus_server import BusServer
from lerobot_contrast.twin.calibration_file import bank_calibration, write_calibration_file
from lerobot_contrast.twin.faults import FaultsConfig
from lerobot_contrast.twin.servos import ServoBank

NAMES = ["shoulder_pan", "shoulder_lift", "elbow_flex", "wrist_flex", "wrist_roll", "gripper"]
LIMITS = {name: (800, 3300) for name in NAMES} | {"wrist_roll": (0, 4095), "gripper": (2000, 3400)}
OFFSETS = {name: 150 * k - 300 for k, name in enumerate(NAMES)}  # negative ones exercise the sign-magnitude encoding
START = {"shoulder_pan": 2050, "shoulder_lift": 1200, "elbow_flex": 3000, "wrist_flex": 2048, "wrist_roll": 1500,
         "gripper": 2100}  # fmt: skip
pytestmark = pytest.mark.realtime  # LeRobot's reply deadlines against a bus whose servos step in real time
POSE = {"shoulder_pan.pos": 30.0, "shoulder_lift.pos": -40.0, "elbow_flex.pos": 45.0, "wrist_flex.pos": -10.0,
        "wrist_roll.pos": 90.0, "gripper.pos": 80.0}  # fmt: skip


def degrees(name: str, raw: float) -> float:
    """LeRobot's reading of a raw position (`use_degrees`; the gripper in 0-100), from the calibration's range."""
    low, high = LIMITS[name]
    if name == "gripper":
        return (raw - low) / (high - low) * 100
    return (raw - (low + high) / 2) * 360 / 4095


@pytest.fixture
def twin(tmp_path):
    """Start a bus for a fresh arm with the given faults; returns (bank, server, robot) with the calibration written."""
    started = []

    def start(faults: FaultsConfig | None = None, **robot_flags):
        bank = ServoBank({n: (k + 1, "sts3215") for k, n in enumerate(NAMES)}, START, homing_offsets=OFFSETS,
                         limits=LIMITS)  # fmt: skip
        server = BusServer(bank, faults=faults, clocked=True)
        port = server.start()
        started.append(server)
        write_calibration_file(bank, "twin", tmp_path)
        config = SO101FollowerConfig(port=port, id="twin", calibration_dir=tmp_path, **robot_flags)
        return bank, server, lambda: SO101Follower(config)

    yield start
    for server in started:
        server.stop()


def connected(make_robot) -> SO101Follower:
    """A connected robot. LeRobot waits 50 ms for each reply and does not retry at connect; on a loaded CI machine the
    twin's thread can miss that, so a connect that times out is tried again (as a user would), four times at most."""
    for attempt in range(5):
        robot = make_robot()
        try:
            robot.connect()
            return robot
        except (ConnectionError, RuntimeError):
            robot.bus.port_handler.closePort()
            if attempt == 4:
                raise


def reach(robot, goal: dict[str, float], timeout: float) -> tuple[float, dict[str, float]]:
    """Seconds until every joint reads within 2 degrees of `goal` (or the timeout), and the last reading."""
    start = time.perf_counter()
    while True:
        obs = robot.get_observation()
        if all(abs(obs[k] - v) < 2 for k, v in goal.items()) or time.perf_counter() - start > timeout:
            return time.perf_counter() - start, obs


def test_connect_reads_the_six_joints_without_asking_to_calibrate(twin):
    bank, _, make_robot = twin()
    robot = connected(make_robot)  # input() under pytest would raise: a mismatch would fail here
    obs = robot.get_observation()
    assert obs == pytest.approx({f"{n}.pos": degrees(n, START[n]) for n in NAMES})
    assert robot.bus.read_calibration() == bank_calibration(bank)
    assert all(bank.torque_enabled(n) for n in NAMES)
    memory = bank.memory(6)  # what configure() wrote landed in the registers
    written = [memory.read(name) for name in ("P_Coefficient", "Max_Torque_Limit", "Return_Delay_Time")]
    assert written == [16, 500, 0]
    assert memory.read("Phase") & 0x10 == 0
    robot.disconnect()
    assert not any(bank.torque_enabled(n) for n in NAMES)


def test_a_commanded_pose_is_reached_within_2_degrees_in_1_s(twin):
    robot = connected(twin()[2])
    sent = robot.send_action(POSE)
    assert sent == POSE
    seconds, obs = reach(robot, POSE, timeout=1.0)
    assert seconds < 1.0, obs
    robot.disconnect()


def test_max_relative_target_clips_and_limits_bound_the_joint(twin):
    robot = connected(twin(max_relative_target=5.0)[2])
    before = robot.get_observation()["shoulder_pan.pos"]
    sent = robot.send_action({"shoulder_pan.pos": before + 40})
    assert sent["shoulder_pan.pos"] == pytest.approx(before + 5)
    time.sleep(0.3)
    assert robot.get_observation()["shoulder_pan.pos"] == pytest.approx(before + 5, abs=0.2)
    robot.disconnect()
    robot = connected(twin()[2])
    robot.send_action({"elbow_flex.pos": 170.0})  # past Max_Position_Limit: the servo stops at the limit
    time.sleep(0.3)
    assert robot.get_observation()["elbow_flex.pos"] == pytest.approx(degrees("elbow_flex", LIMITS["elbow_flex"][1]))
    robot.disconnect()


def test_signed_registers_round_trip_through_lerobot(twin):
    bank, _, make_robot = twin()
    robot = connected(make_robot)
    robot.bus.write("Homing_Offset", "wrist_flex", -1234, num_retry=2)
    assert robot.bus.read("Homing_Offset", "wrist_flex", num_retry=2) == -1234 == bank.memory(4).read("Homing_Offset")
    robot.send_action({"shoulder_pan.pos": -80.0})  # moving toward lower raw values: a negative velocity
    time.sleep(0.1)
    assert robot.bus.read("Present_Velocity", "shoulder_pan", num_retry=2) < -1000
    assert robot.bus.broadcast_ping(num_retry=2) == {k + 1: 777 for k in range(6)}
    robot.disconnect()


def test_corrupted_replies_are_retried_through(twin):
    _, server, make_robot = twin(FaultsConfig(corrupt=0.05, seed=3, while_moving=True), num_read_retries=10)
    robot = connected(make_robot)
    robot.send_action(POSE)
    seconds, obs = reach(robot, POSE, timeout=2.0)
    assert seconds < 2.0, obs
    assert server.faults.corrupted > 0
    robot.disconnect()


def test_when_retries_run_out_lerobot_raises_its_error(twin):
    _, server, make_robot = twin(FaultsConfig(corrupt=1.0, while_moving=True))
    robot = connected(make_robot)  # nothing moves yet: a clean line
    robot.send_action(POSE)
    with pytest.raises(ConnectionError, match="sync read 'Present_Position'.*after 3 tries.*Incorrect status"):
        robot.get_observation()
    assert server.faults.corrupted >= 3


def test_a_silent_bus_fails_the_connect_with_lerobots_error(twin):
    _, server, make_robot = twin(FaultsConfig(drop=1.0))
    with pytest.raises(RuntimeError, match="motor check failed"):
        make_robot().connect()
    assert server.faults.dropped > 0


def test_bad_input_gets_one_line(tmp_path):
    with pytest.raises(ValueError, match=r"--faults.corrupt=1.5 is not a rate"):
        FaultsConfig(corrupt=1.5)
    bank = ServoBank({"a": (1, "sts3215")}, {"a": 2048})
    (tmp_path / "file").write_text("")
    with pytest.raises(OSError, match="cannot write the twin's calibration file") as error:
        write_calibration_file(bank, "twin", tmp_path / "file")
    assert "\n" not in str(error.value)
    with pytest.raises(ValueError, match="initial_raw names"):
        ServoBank({"a": (1, "sts3215")}, {"b": 2048})


def test_noise_is_ignored_and_a_packet_given_up_on_gets_no_late_reply(twin):
    import serial

    _, server, _ = twin()
    read_model = bytes([0xFF, 0xFF, 1, 4, 0x02, 3, 2])  # READ id 1, Model_Number (address 3, 2 bytes)
    read_model += bytes([~sum(read_model[2:]) & 0xFF])
    with serial.Serial(server.port, 1_000_000, timeout=0.5) as line:
        line.write(b"\x00\xff\x17" + read_model[:5])  # noise, then a packet split over two writes
        time.sleep(0.05)
        line.write(read_model[5:])
        reply = line.read(8)
        assert reply[:6] == bytes([0xFF, 0xFF, 1, 4, 0, 777 & 0xFF]) and reply[6] == 777 >> 8
        line.write(read_model[:-1] + bytes([read_model[-1] ^ 1]))  # a wrong checksum: the servo stays silent
        assert line.read(8) == b""
        line.write(read_model + read_model)  # the driver gave up on the first: only the second is answered
        assert len(line.read(32)) == 8


def test_the_bus_process_drives_the_bank_that_physics_steps(tmp_path):
    bank = ServoBank({n: (k + 1, "sts3215") for k, n in enumerate(NAMES)}, START, homing_offsets=OFFSETS, limits=LIMITS)
    write_calibration_file(bank, "twin", tmp_path)
    with BusServer(bank) as port:  # physics steps this bank: the servos run in the bus process
        config = SO101FollowerConfig(port=port, id="twin", calibration_dir=tmp_path)
        robot = connected(lambda: SO101Follower(config))
        robot.send_action(POSE)
        start = time.perf_counter()
        while time.perf_counter() - start < 1.0:  # a stand-in for the physics: joints go where the servos take them
            bank.step(0.01)
            for name in NAMES:
                bank.set_present(name, bank.setpoint(name))
            time.sleep(0.01)
        _, obs = reach(robot, POSE, timeout=1.0)
        assert obs == pytest.approx(POSE, abs=2.0)
        assert all(bank.torque_enabled(n) for n in NAMES)
        bank.memory(1).write("Torque_Enable", 0)  # a write made in the twin reaches the servo on the bus
        time.sleep(0.1)
        assert robot.bus.read("Torque_Enable", "shoulder_pan", num_retry=2) == 0
        robot.disconnect()
        bank.step(0.01)
        time.sleep(0.05)
        bank.step(0.01)
        assert not any(bank.torque_enabled(n) for n in NAMES)
