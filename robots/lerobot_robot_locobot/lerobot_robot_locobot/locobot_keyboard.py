"""LocobotKeyboard: w forward, a/d turn left/right, s or space stop. In discrete mode each key press is one
step (holding a key does not repeat it); in velocity mode the held keys set x.vel and theta.vel."""

from __future__ import annotations

import queue
from typing import Any

from lerobot.teleoperators.teleoperator import Teleoperator
from lerobot.utils.errors import DeviceAlreadyConnectedError, DeviceNotConnectedError
from navigation_protocol import one_hot

from lerobot_robot_locobot.actions import action_features
from lerobot_robot_locobot.config_locobot_keyboard import LocobotKeyboardConfig

KEY_COMMANDS = {"w": "forward", "a": "turn_left", "d": "turn_right", "s": "stop", " ": "stop"}


def keys_to_action(config: LocobotKeyboardConfig, held: set[str], pressed: list[str]) -> dict[str, float]:
    """The action for the keys `held` now and those `pressed` since the last call (in order)."""
    if config.action_mode == "discrete":
        commands = [KEY_COMMANDS[key] for key in pressed if key in KEY_COMMANDS]
        return one_hot(commands[0] if commands else None)
    x = config.x_vel * (("w" in held) - ("s" in held))
    theta = config.theta_vel * (("a" in held) - ("d" in held))
    return {"x.vel": float(x), "theta.vel": float(theta)}


class LocobotKeyboard(Teleoperator):
    config_class = LocobotKeyboardConfig
    name = "locobot_keyboard"

    def __init__(self, config: LocobotKeyboardConfig) -> None:
        super().__init__(config)
        self.config = config
        self.events: queue.Queue[tuple[str, bool]] = queue.Queue()
        self._held: set[str] = set()
        self._listener: Any = None

    @property
    def action_features(self) -> dict[str, type]:
        return action_features(self.config.action_mode)

    @property
    def feedback_features(self) -> dict:
        return {}

    @property
    def is_connected(self) -> bool:
        return self._listener is not None

    @property
    def is_calibrated(self) -> bool:
        return True

    def connect(self, calibrate: bool = True) -> None:
        if self._listener is not None:
            raise DeviceAlreadyConnectedError(f"{self} is already connected")
        try:
            from pynput import keyboard
        except ImportError as error:
            raise DeviceNotConnectedError(
                f"the LoCoBot keyboard needs pynput with a desktop session ({error}); `pip install pynput`"
            ) from None
        self._listener = keyboard.Listener(on_press=self.on_press, on_release=self.on_release)
        self._listener.start()

    def calibrate(self) -> None:
        """Nothing to calibrate."""

    def configure(self) -> None:
        """Nothing to configure."""

    def on_press(self, key: Any) -> None:
        self.events.put((_char(key), True))

    def on_release(self, key: Any) -> None:
        self.events.put((_char(key), False))

    def get_action(self) -> dict[str, float]:
        if self._listener is None:
            raise DeviceNotConnectedError(f"{self} is not connected; call connect() first")
        return self.read_keys()

    def read_keys(self) -> dict[str, float]:
        """Apply the queued key events and return the resulting action."""
        pressed = []
        while not self.events.empty():
            key, down = self.events.get_nowait()
            if down and key not in self._held:
                pressed.append(key)
            (self._held.add if down else self._held.discard)(key)
        return keys_to_action(self.config, self._held, pressed)

    def send_feedback(self, feedback: dict[str, Any]) -> None:
        """The keyboard gives no feedback."""

    def disconnect(self) -> None:
        if self._listener is None:
            raise DeviceNotConnectedError(f"{self} is not connected")
        self._listener.stop()
        self._listener = None


def _char(key: Any) -> str:
    """pynput keys as characters: letters as typed (lower case), the space bar as " "."""
    char = getattr(key, "char", None)
    if char is not None:
        return char.lower()
    return " " if getattr(key, "name", "") == "space" else str(getattr(key, "name", key))
