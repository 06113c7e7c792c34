"""An existing Dask scheduler, given by its address or its scheduler file: checked reachable at once.

Dask's own connection waits its whole timeout (30 s) even on a refused port; this opens the port
with a REACH_SECONDS timeout first, so a study with a wrong address is refused before anything is
solved.  Standard library only, so the command can check before it loads the solver.
"""

from __future__ import annotations

import json
import os
import re
import socket
from urllib.parse import urlsplit

REACH_SECONDS = 1.0  # opening a TCP connection to an existing scheduler's port
_ADDRESS = re.compile(r"[a-z][a-z0-9+.-]*://.*")  # tcp://HOST:PORT, tls://HOST:PORT, ...; anything else is a file
_TCP = ("tcp", "tls")  # the protocols whose port is checked (others, e.g. ucx, are left to Dask)


class ClusterError(RuntimeError):
    """The Dask cluster could not be started or reached; the message says which and why."""


def scheduler_address(scheduler: str) -> str:
    """The address of an existing scheduler given as an address (tcp://HOST:PORT) or a scheduler file (the JSON
    `dask scheduler --scheduler-file` writes), checked reachable: for TCP and TLS, the port opened within
    REACH_SECONDS.

    Raises ClusterError saying what is wrong: a scheduler file that does not exist or holds no address, an address
    that cannot be read, a port that refuses or does not answer.
    """
    address = scheduler if _ADDRESS.fullmatch(scheduler) else _address_in_file(scheduler)
    try:
        parts = urlsplit(address)
        host, port = parts.hostname, parts.port
    except ValueError as exc:
        raise ClusterError(f"--scheduler {scheduler}: cannot read the address {address!r} ({exc}): give "
                           "tcp://HOST:PORT or a scheduler file") from None
    if parts.scheme not in _TCP:
        return address
    if not host or port is None:
        raise ClusterError(f"--scheduler {scheduler}: the address {address!r} needs a host and a port: give "
                           "tcp://HOST:PORT or a scheduler file")
    try:
        socket.create_connection((host, port), timeout=REACH_SECONDS).close()
    except OSError as exc:
        reason = "no answer" if isinstance(exc, TimeoutError) else (exc.strerror or str(exc))
        raise ClusterError(f"cannot reach the Dask scheduler at {address}: {reason} (port {port} of {host} checked "
                           f"with a {REACH_SECONDS:g} s timeout, before any solving); is the scheduler running, and "
                           "is the address right?") from None
    return address


def _address_in_file(scheduler: str) -> str:
    """The address in a scheduler file; ClusterError when the file does not exist or holds none."""
    path = os.path.abspath(scheduler)
    if not os.path.isfile(path):
        raise ClusterError(f"--scheduler {scheduler}: the scheduler file {path} does not exist (give the file "
                           "`dask scheduler --scheduler-file` wrote, or an address tcp://HOST:PORT)")
    try:
        with open(path, encoding="utf-8") as file:
            address = json.load(file)["address"]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise ClusterError(f"--scheduler {scheduler}: the scheduler file {path} holds no scheduler address "
                           f"(\"address\": \"tcp://HOST:PORT\"): {exc!r}") from None
    if not isinstance(address, str):
        raise ClusterError(f"--scheduler {scheduler}: the scheduler file {path} gives address = {address!r}, not "
                           "tcp://HOST:PORT")
    return address
