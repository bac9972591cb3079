"""Messages to a person who is not at the bench (`--person.notify=URL`): a short POST when a person is needed, when a
label is asked for, and when the session ends or stops, with the phone page's link where there is one. Sent from a
thread of their own, so a slow or unreachable service never holds the session up; one that fails is said once."""

from __future__ import annotations

import queue
import threading
from collections.abc import Callable
from typing import Any

import httpx

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.operators.person_args import NOTIFY_FORMATS

TIMEOUT_S = 5.0
FLUSH_S = 6.0  # at the session's end, the last message's time to go out before the process exits


class Notifier:
    """A console channel (operators/channel.py's messages) that turns a call, a label asked and the session's end
    into a message to `url`; `say`: where a failure is said (once); `link`: the phone page's, added to each."""

    def __init__(self, url: str, form: str, say: Callable[[str], None], link: str | None = None) -> None:
        if form not in NOTIFY_FORMATS:
            raise UserError(f"--person.notify_format: unknown {form!r}; choose from: {', '.join(NOTIFY_FORMATS)}")
        try:
            parsed = httpx.URL(url)
        except httpx.InvalidURL as error:
            raise UserError(f"--person.notify={url}: not a URL ({error}); give the http:// or https:// one to POST the "
                            "messages to") from None  # fmt: skip
        if parsed.scheme not in ("http", "https") or not parsed.host:
            raise UserError(f"--person.notify={url}: give an http:// or https:// URL to POST the messages to")
        self.url, self.form, self.say, self.link = url, form, say, link
        self._queue: queue.Queue[str | None] = queue.Queue()
        self._failed = False
        self._thread = threading.Thread(target=self._post_all, daemon=True, name="notify")
        self._thread.start()

    def send(self, **message: Any) -> None:
        text = _text(message)
        if text is not None:
            self._queue.put(text if self.link is None else f"{text} {self.link}")

    def close(self) -> None:
        """Send what is queued (the session's end) and stop, waiting at most FLUSH_S."""
        self._queue.put(None)
        self._thread.join(FLUSH_S)

    def _post_all(self) -> None:
        with httpx.Client(timeout=TIMEOUT_S) as client:
            while (text := self._queue.get()) is not None:
                try:
                    if self.form == "json":
                        answer = client.post(self.url, json={"text": text})
                    else:
                        answer = client.post(self.url, content=text.encode(), headers={"Content-Type": "text/plain"})
                    answer.raise_for_status()
                except Exception as error:  # whatever the service or the network does, the session goes on
                    if not self._failed:
                        self._failed = True
                        self.say(f"[yellow]a notification to {self.url} failed ({' '.join(str(error).split())[:160]}); "
                                 "the session goes on, and further failures are not said[/]")  # fmt: skip


def _text(message: dict[str, Any]) -> str | None:
    """The message for a channel line, or None for those that need nobody."""
    trial = f"trial {message['trial'] + 1}" if "trial" in message else "a trial"
    if message.get("prompt") == "call":
        return f"lerobot-contrast: a person is needed at the bench ({trial}): {message['trouble']}"
    if message.get("prompt") == "label":
        return f"lerobot-contrast: a label is asked for {trial}: {message.get('instruction', '')}"
    if message.get("prompt") == "aborted":
        return f"lerobot-contrast: a trial was aborted ({message['reason']}); the session waits for a person"
    if message.get("event") == "session":
        return f"lerobot-contrast: {message['text']}"
    return None
