"""One Feetech servo's register memory, laid out by the control table LeRobot itself uses (imported, not copied), with
the sign-magnitude encodings LeRobot applies to some registers."""

from lerobot.motors.encoding_utils import decode_sign_magnitude, encode_sign_magnitude
from lerobot.motors.feetech.tables import MODEL_CONTROL_TABLE, MODEL_ENCODING_TABLE, MODEL_NUMBER_TABLE

MEMORY_BYTES = 256  # addresses are one byte on the wire

# What a factory-fresh STS3215 holds (Feetech's manual); registers not named here start at zero.
FACTORY = {
    "Firmware_Major_Version": 3,
    "Firmware_Minor_Version": 10,
    "Return_Delay_Time": 250,
    "Response_Status_Level": 1,
    "Max_Position_Limit": 4095,
    "Max_Temperature_Limit": 70,
    "Max_Voltage_Limit": 140,
    "Min_Voltage_Limit": 40,
    "Max_Torque_Limit": 1000,
    "Phase": 0x1C,  # bit 4 set: LeRobot clears it at configure (angle feedback mode 0)
    "P_Coefficient": 32,
    "D_Coefficient": 32,
    "Protection_Current": 500,
    "Angular_Resolution": 1,
    "Protective_Torque": 20,
    "Protection_Time": 200,
    "Overload_Torque": 80,
    "Torque_Limit": 1000,
    "Lock": 1,
    "Present_Voltage": 120,  # 12.0 V
    "Present_Temperature": 30,
    "Maximum_Acceleration": 254,
}

# Registers the servo's firmware owns: a WRITE from the bus leaves them as they are.
READ_ONLY = {
    "Firmware_Major_Version",
    "Firmware_Minor_Version",
    "Model_Number",
    "Present_Position",
    "Present_Velocity",
    "Present_Load",
    "Present_Voltage",
    "Present_Temperature",
    "Status",
    "Moving",
    "Present_Current",
    "Goal_Position_2",
}


class ControlTable:
    """The bytes of one servo (little-endian words), addressed by LeRobot's register names or by raw address."""

    def __init__(self, servo_id: int, model: str = "sts3215"):
        if model not in MODEL_CONTROL_TABLE or model not in MODEL_NUMBER_TABLE:
            raise ValueError(f"unknown Feetech model {model!r}: use one of {sorted(MODEL_NUMBER_TABLE)}")
        if not 0 <= servo_id <= 252:
            raise ValueError(f"servo id {servo_id} is outside 0-252")
        self.model = model
        self.registers = MODEL_CONTROL_TABLE[model]
        self.encodings = MODEL_ENCODING_TABLE.get(model, {})
        self._bytes = bytearray(MEMORY_BYTES)
        self._read_only = {addr + i for name in READ_ONLY for addr, size in [self.registers[name]] for i in range(size)}
        for name, value in FACTORY.items():
            self.set(name, value)
        self.set("Model_Number", MODEL_NUMBER_TABLE[model])
        self.set("ID", servo_id)

    def get(self, name: str) -> int:
        """A register's value, decoded as LeRobot decodes it (sign-magnitude where its table says so)."""
        addr, size = self.registers[name]
        value = int.from_bytes(self._bytes[addr : addr + size], "little")
        if name in self.encodings:
            return decode_sign_magnitude(value, self.encodings[name])
        return value

    def encode(self, name: str, value: int) -> tuple[int, bytes]:
        """A register's address and the bytes LeRobot would send to write `value` there."""
        addr, size = self.registers[name]
        if name in self.encodings:
            value = encode_sign_magnitude(int(value), self.encodings[name])
        return addr, int(value).to_bytes(size, "little")

    def set(self, name: str, value: int) -> None:
        """Store a register's value (the firmware's own write: read-only registers included)."""
        addr, data = self.encode(name, value)
        self._bytes[addr : addr + len(data)] = data

    def read_bytes(self, addr: int, length: int) -> bytes:
        """What a READ instruction returns; past the end of memory reads zeros, as unused addresses do."""
        return bytes(self._bytes[addr : addr + length]).ljust(length, b"\0")

    def write_bytes(self, addr: int, data: bytes) -> list[str]:
        """A WRITE instruction from the bus; returns the names of the registers it touched."""
        end = min(addr + len(data), MEMORY_BYTES)
        for i in range(addr, end):
            if i not in self._read_only:
                self._bytes[i] = data[i - addr]
        return [name for name, (a, size) in self.registers.items() if a < end and addr < a + size]
