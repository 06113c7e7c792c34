"""Run the studio: the app on uvicorn, bound to one address, and the browser opened on it."""

from __future__ import annotations

import contextlib
import socket
import tempfile
import threading
import webbrowser
from collections.abc import Iterator
from pathlib import Path

import uvicorn

from hoseline.studio.messages import MAX_MESSAGE_BYTES
from hoseline.studio.server import LOCAL_HOSTS, create_app
from hoseline.studio.session import Session


def bind(host: str, port: int) -> socket.socket:
    """A listening TCP socket on host:port (port 0: any free one); OSError if it cannot be had."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    listener = socket.socket(family, socket.SOCK_STREAM)
    listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        listener.bind((host, port))
        listener.listen(64)
    except OSError:
        listener.close()
        raise
    return listener


def serve(session: Session, listener: socket.socket, open_browser: bool, announce) -> None:
    """Serve the studio on `listener` until interrupted (Ctrl+C); uploads and reports go to a temporary folder.

    open_browser: open the page in the default browser once the server listens.
    announce: callable(url) telling the user where the page is.
    """
    with tempfile.TemporaryDirectory(prefix="hoseline-studio-") as work_dir:
        server, url = _server(session, listener, Path(work_dir))
        announce(url)
        if open_browser:
            threading.Thread(target=_open_when_started, args=(server, url), daemon=True).start()
        server.run(sockets=[listener])


@contextlib.contextmanager
def in_background(session: Session, work_dir: Path) -> Iterator[str]:
    """Serve the studio on a free port of 127.0.0.1 in a background thread (for scripts, tests and the
    benchmark); yields the page's address and stops the server on leaving."""
    listener = bind("127.0.0.1", 0)
    server, url = _server(session, listener, work_dir)
    thread = threading.Thread(target=server.run, kwargs={"sockets": [listener]}, daemon=True)
    thread.start()
    try:
        for _ in range(300):
            if server.started:
                break
            threading.Event().wait(0.1)
        yield url
    finally:
        server.should_exit = True
        thread.join(timeout=10)
        listener.close()


def _server(session: Session, listener: socket.socket, work_dir: Path) -> tuple[uvicorn.Server, str]:
    """The uvicorn server of the studio app for `listener`, and the page's address."""
    host, port = listener.getsockname()[:2]
    url = f"http://{'[' + host + ']' if ':' in host else host}:{port}/"
    app = create_app(session, work_dir, allowed_hosts=tuple(dict.fromkeys((*LOCAL_HOSTS, host))))
    config = uvicorn.Config(app, log_level="warning", ws_max_size=MAX_MESSAGE_BYTES, ws="auto", lifespan="on",
                            timeout_graceful_shutdown=1)
    return uvicorn.Server(config), url


def _open_when_started(server: uvicorn.Server, url: str) -> None:
    """Open the page once uvicorn has started (within 30 s)."""
    for _ in range(300):
        if server.started:
            webbrowser.open(url)
            return
        threading.Event().wait(0.1)
