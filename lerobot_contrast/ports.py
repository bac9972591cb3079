"""A free TCP port on 127.0.0.1, for the twin's endpoints, the local Ray head and the tests' servers."""

from __future__ import annotations

import socket


def free_port() -> int:
    """A port nothing listens on now (the OS's pick); a caller binds it soon, as another process may take it."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]
