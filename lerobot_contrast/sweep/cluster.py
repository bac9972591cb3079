"""Joining the Ray cluster `--ray.address` names: its head checked reachable first (so a wrong address is one line in
seconds, not minutes of Ray's retries), with the authentication token where Ray looks for one."""

from __future__ import annotations

import logging
import os
import socket
import time
from pathlib import Path

import ray

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.sweep.settings import RayArgs
from lerobot_contrast.sweep.shipping import runtime_env

PROBE_S = 3.0
# Ray Client's server on the head starts a server process of its own for each driver; on a loaded head that start
# sometimes fails ("Starting Ray client server failed"), and the next try gets a fresh one.
CLIENT_START_TRIES = 3
CLIENT_RETRY_S = 2.0
CLIENT_PORT = 10001
START_HEAD = "start one there with `ray start --head` (its client port is 10001, its cluster port 6379)"
TOKEN_PLACES = (
    "Ray reads it from RAY_AUTH_TOKEN, else the file RAY_AUTH_TOKEN_PATH names, else ~/.ray/auth_token: "
    "copy the head's token there (`ray get-auth-token` on the head prints it)"
)
# Ray before 2.52 has no token authentication, so nothing to catch.
AUTH_ERROR = getattr(ray.exceptions, "AuthenticationError", ())
# Ray's notes on every start that token authentication is on (or off): noise to a sweep, whose own lines say
# what went wrong with a token.
NOISY = ("ray._private.authentication.authentication_token_setup",)


class ClusterError(UserError):
    pass


def join(args: RayArgs) -> None:
    """Join the cluster `args` names, with this project's code for its nodes (the job's runtime environment, which
    Ray Client's server on the head also takes), or start a local Ray; a Ray this process already joined is used as
    is."""
    if ray.is_initialized():
        return
    quiet_notes()
    quiet = {"log_to_driver": False, "logging_level": logging.WARNING}
    if args.address is None:
        start_local(args, quiet)
        return
    address = reach(args.address)
    try:
        target = args.address if args.address.startswith("ray://") else address
        init_with_retries(address=target, runtime_env=runtime_env(), **quiet)
    except AUTH_ERROR:
        raise ClusterError(
            f"--ray.address={args.address}: the cluster refused this machine's token; {TOKEN_PLACES}"
        ) from None
    except ConnectionError as error:
        raise ClusterError(f"--ray.address={args.address}: cannot join ({' '.join(str(error).split())})") from None


def start_local(args: RayArgs, quiet: dict) -> None:
    """A Ray of this sweep's own on this machine: "local" starts one even where a head runs here or a killed one left
    its address behind (a plain `ray.init()` would join either, and then refuses the CPU and GPU counts)."""
    local = {"num_cpus": args.num_cpus or os.cpu_count(), "num_gpus": args.num_gpus, "include_dashboard": False}
    try:
        ray.init(address="local", **quiet, **local)
    except (ConnectionError, RuntimeError, ValueError) as error:
        raise ClusterError(f"cannot start Ray on this machine ({' '.join(str(error).split())[:300]})") from None


def init_with_retries(**init) -> None:
    """`ray.init(**init)`, tried again when the head could not start this driver's Ray Client server."""
    for attempt in range(1, CLIENT_START_TRIES + 1):
        try:
            ray.init(**init)
            return
        except ConnectionAbortedError as error:  # Ray Client's "Initialization failure from server"
            if attempt == CLIENT_START_TRIES:
                raise
            logging.getLogger(__name__).warning(
                "the Ray head could not start a client server (%s); trying again", str(error).splitlines()[-1]
            )
            ray.shutdown()
            time.sleep(CLIENT_RETRY_S)


def reach(given: str) -> str:
    """The head's HOST:PORT (its client port for ray://), checked to answer and to take this machine's token (sent
    wherever one is found): each failure one line, in seconds."""
    quiet_notes()
    address = head_address(given)
    use_token_if_any()
    check_token(given, address)
    return address


def quiet_notes() -> None:
    for name in NOISY:
        logging.getLogger(name).setLevel(logging.ERROR)


def head_address(given: str) -> str:
    """`given` as HOST:PORT, checked to answer: auto read from this machine's running Ray, ray:// with its client
    port (10001 unless given)."""
    if given == "auto":
        from ray._private.services import find_bootstrap_address

        found = find_bootstrap_address(None)
        if not found:
            raise ClusterError(f"--ray.address=auto: no Ray runs on this machine; {START_HEAD}")
        given = found
    host, _, port = given.removeprefix("ray://").rpartition(":")
    if not host or not port.isdigit():
        host, port = given.removeprefix("ray://"), str(CLIENT_PORT if given.startswith("ray://") else 6379)
    try:
        socket.create_connection((host, int(port)), timeout=PROBE_S).close()
    except OSError as error:
        why = error.strerror or type(error).__name__
        raise ClusterError(
            f"--ray.address={given}: no Ray cluster answers at {host}:{port} ({why}); {START_HEAD}"
        ) from None
    return f"{host}:{port}"


def use_token_if_any() -> None:
    """Send the token where one is found (the Ray Client sends none unless RAY_AUTH_MODE=token is set)."""
    if os.environ.get("RAY_AUTH_MODE") or not AUTH_ERROR:
        return
    from ray._private.authentication.authentication_token_setup import maybe_enable_token_auth_if_token_available

    maybe_enable_token_auth_if_token_available(warn_if_disabled=False)


def check_token(given: str, address: str) -> None:
    """Ask the head once for its cluster's id (through its client server for ray://): a missing or wrong token is
    refused at once here, where Ray itself retries for 30 s, printing a warning each second, then names a timeout."""
    import grpc
    from ray._private.grpc_utils import init_grpc_channel
    from ray.core.generated import gcs_service_pb2, gcs_service_pb2_grpc, ray_client_pb2, ray_client_pb2_grpc

    channel = init_grpc_channel(address)
    try:
        if given.startswith("ray://"):
            request = ray_client_pb2.ClusterInfoRequest(type=ray_client_pb2.ClusterInfoType.PING)
            ray_client_pb2_grpc.RayletDriverStub(channel).ClusterInfo(request, timeout=10 * PROBE_S)
        else:
            stub = gcs_service_pb2_grpc.NodeInfoGcsServiceStub(channel)
            stub.GetClusterId(gcs_service_pb2.GetClusterIdRequest(), timeout=10 * PROBE_S)
    except grpc.RpcError as error:
        if error.code() != grpc.StatusCode.UNAUTHENTICATED:
            return  # anything else is Ray's to report as it connects
        has = _token_source()
        what = f"refused the token from {has}" if has else "needs a token and this machine has none"
        raise ClusterError(f"--ray.address={given}: the Ray cluster {what}; {TOKEN_PLACES}") from None
    finally:
        channel.close()


def _token_source() -> str | None:
    if os.environ.get("RAY_AUTH_TOKEN"):
        return "RAY_AUTH_TOKEN"
    if os.environ.get("RAY_AUTH_TOKEN_PATH"):
        return os.environ["RAY_AUTH_TOKEN_PATH"]
    default = Path.home() / ".ray" / "auth_token"
    return str(default) if default.is_file() else None
