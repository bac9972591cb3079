"""CurveZMQ keys for the host-client link: create them, and secure sockets with them on either side.

`python -m lerobot_robot_locobot.keys DIR` writes a server and a client key pair into DIR and puts the client's
public key into DIR/authorized_clients. The robot needs server.key_secret and authorized_clients/; the
workstation needs client.key_secret and server.key. Without keys the link is plain TCP on a trusted network."""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

import zmq
import zmq.auth
from zmq.auth.thread import ThreadAuthenticator


class KeyFileError(ValueError):
    """A key file or directory that is missing or of the wrong kind; the message names it and what to do."""


HINT = "create keys with `python -m lerobot_robot_locobot.keys DIR`"


def create_keys(directory: Path) -> None:
    directory.mkdir(parents=True, exist_ok=True)
    zmq.auth.create_certificates(directory, "server")
    public, _ = zmq.auth.create_certificates(directory, "client")
    authorized = directory / "authorized_clients"
    authorized.mkdir(exist_ok=True)
    shutil.copy(public, authorized / "client.key")


def load_keys(path: Path, flag: str, secret: bool) -> tuple[bytes, bytes | None]:
    """(public, secret) from a key file; `flag` names the option that gave the path, for the error message."""
    if not path.is_file():
        raise KeyFileError(f"{flag}: no key file at {path}; {HINT}")
    try:
        public, secret_key = zmq.auth.load_certificate(path)
    except (ValueError, OSError) as error:
        raise KeyFileError(f"{flag}: {path} is not a CurveZMQ key file ({error}); {HINT}") from None
    if secret and secret_key is None:
        raise KeyFileError(f"{flag}: {path} holds only a public key; pass the matching .key_secret file")
    return public, secret_key


def secure_server(socket: zmq.Socket, secret_file: Path, flag: str) -> None:
    public, secret = load_keys(secret_file, flag, secret=True)
    socket.curve_secretkey, socket.curve_publickey, socket.curve_server = secret, public, True


def secure_client(socket: zmq.Socket, secret_file: Path, server_public_file: Path, flags: tuple[str, str]) -> None:
    public, secret = load_keys(secret_file, flags[0], secret=True)
    server_public, _ = load_keys(server_public_file, flags[1], secret=False)
    socket.curve_secretkey, socket.curve_publickey, socket.curve_serverkey = secret, public, server_public


def start_authenticator(context: zmq.Context, authorized: Path | None, flag: str) -> ThreadAuthenticator:
    """Accept only clients whose public key is in `authorized` (any client holding the server key if None)."""
    if authorized is not None and not authorized.is_dir():
        raise KeyFileError(f"{flag}: {authorized} is not a directory of client public keys; {HINT}")
    auth = ThreadAuthenticator(context)
    auth.start()
    auth.configure_curve(domain="*", location=str(authorized) if authorized else zmq.auth.CURVE_ALLOW_ANY)
    return auth


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if len(args) != 1 or args[0].startswith("-"):
        print("usage: python -m lerobot_robot_locobot.keys DIR", file=sys.stderr)
        return 2
    directory = Path(args[0])
    if (directory / "server.key_secret").exists():
        print(f"error: {directory} already holds keys; choose another directory", file=sys.stderr)
        return 2
    create_keys(directory)
    print(
        f"robot:       {directory / 'server.key_secret'} and {directory / 'authorized_clients'}/\n"
        f"workstation: {directory / 'client.key_secret'} and {directory / 'server.key'}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
