"""The `--person.*` flags of `python -m lerobot_contrast.eval`: where the person who stages and labels is reached
(light: read before anything heavy loads)."""

from __future__ import annotations

from dataclasses import dataclass

NOTIFY_FORMATS = ("text", "json")


@dataclass
class PersonArgs:
    """The person at the bench, on their phone (docs/phone.md)."""

    # Serve a page for a phone: each trial (what to move where), why a person is called, and the console's answers
    # as buttons. The terminal and the page are two views of one console: whichever answers first counts.
    page: bool = False
    # The page's port (pass the --person.* flags again with --resume=true: an open page then reconnects by itself).
    port: int = 7577
    # Serve the page to the local network too, with a token in its link (printed with a QR code); without it, the
    # page answers this machine only (127.0.0.1).
    lan: bool = False
    # POST a short message to this URL when a person is needed, when a label is asked for, and when the session ends
    # or stops (an ntfy topic, a Slack incoming webhook, ...).
    notify: str | None = None
    # The message's body: text (plain text, as ntfy takes it) or json ({"text": ...}, as Slack's webhooks take it).
    notify_format: str = "text"
