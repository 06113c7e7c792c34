"""The studio's web server: the page, its files, and the WebSocket of the solve loop (Starlette).

    GET  /                      the page (static/index.html)
    GET  /static/...            its ES modules, styles and the vendored three.js
    WS   /ws                    the solve loop: targets and commands in (messages.py), states out (view.py)
    GET  /obstacle/{id}         an obstacle mesh, binary: vertex and triangle counts (uint32), then float32
                                vertices (mm) and uint32 triangles
    GET  /problem.toml          the problem as a problem file that solves to the shape shown (saving.py);
                                ?as=assembled: with the twist as set (the shape "Place again" gives)
    GET  /export/{format}       iges, step, stl, ply, gltf or adams of the shape shown
    POST /upload/{name}         a dropped file (uploads.py); ?store=1 keeps it for a sweep file dropped with it
    POST /sweep                 run the open sweep, answer the address of its report
    GET  /reports/{run}/{file}  the files of a sweep run

The solver runs in one worker thread, off the event loop, and every use of the session goes
through it, one at a time.  While it works on a step, targets arriving over the WebSocket
coalesce (inbox.py).  A drag's step (a target) is answered with the shape and the readouts that cost
little; the others (view.PENDING_READOUTS: the stability margin, each obstacle's smallest gap) are
sent pending and follow in a "readouts" message when nothing arrives for IDLE_SECONDS.  Then the problem is
placed afresh and the page told whether that shape is the one shown; a message arriving meanwhile
abandons that placement after its current continuation step (and it is made again at the next idle
moment), so a drag never waits for it.  Requests must come
from the page's own origin and name an allowed host (no other site can drive the studio);
the page's Content-Security-Policy lets it load and connect to its own origin only.  Every edit
(a gesture of the page, a file opened) keeps the session before it for undo (history.py).
"""

from __future__ import annotations

import asyncio
import base64
import contextlib
import functools
import hashlib
import json
import logging
import re
import struct
import tempfile
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from starlette.applications import Starlette
from starlette.middleware import Middleware
from starlette.middleware.trustedhost import TrustedHostMiddleware
from starlette.requests import Request
from starlette.responses import HTMLResponse, JSONResponse, Response
from starlette.routing import Mount, Route, WebSocketRoute
from starlette.staticfiles import StaticFiles
from starlette.websockets import WebSocket, WebSocketDisconnect

from hoseline.procedures.placement.continuation import PlacementError
from hoseline.studio.history import History
from hoseline.studio.inbox import Inbox
from hoseline.studio.messages import Command, MessageError, Target, parse_message
from hoseline.studio.session import Session, StudioError
from hoseline.studio.uploads import MAX_FILES, SIZE_LIMITS, UploadError, checked_name, mount_labels, open_upload
from hoseline.studio.view import readouts_message, session_message, state_message

STATIC = Path(__file__).parent / "static"
IDLE_SECONDS = 0.3
LOCAL_HOSTS = ("127.0.0.1", "localhost")
REFUSED = (StudioError, PlacementError, ValueError)  # a change the session refuses: told to the page, session kept


class ComparisonAbandoned(Exception):
    """The idle comparison was given up for a message that arrived (raised in its placements' progress callback)."""


class Studio:
    """The server's state: the session, its worker thread, the open WebSockets, the work folder."""

    def __init__(self, session: Session, work_dir: Path) -> None:
        self.session = session
        self.history = History()
        self.solver = ThreadPoolExecutor(max_workers=1, thread_name_prefix="hoseline-solver")
        self.sweeps = ThreadPoolExecutor(max_workers=1, thread_name_prefix="hoseline-sweep")
        self.sockets: set[WebSocket] = set()
        self.uploads = work_dir / "uploads"
        self.reports = work_dir / "reports"
        self.uploads.mkdir(parents=True, exist_ok=True)
        self.reports.mkdir(parents=True, exist_ok=True)
        self.coalesced = 0  # targets dropped for a later one, over all connections
        self.abandoned = 0  # idle comparisons given up for a message
        self.readouts_pending = False  # the last state sent left readouts pending (a drag's step)

    async def run(self, function, *args):
        """function(*args) in the solver thread."""
        return await asyncio.get_running_loop().run_in_executor(self.solver, functools.partial(function, *args))

    def state_text(self, seq: int | None, started: float | None = None, complete: bool = True) -> str:
        """The state message as JSON (called in the solver thread).

        started: time.perf_counter() when the solver took up the message answered; the state then
        says how long the solver thread spent on it (seconds, without the final JSON encoding).
        complete: False leaves the readouts that cost most pending (view.state_message).
        """
        message = state_message(self.session, complete)
        message["seq"] = seq
        message["server_seconds"] = None if started is None else time.perf_counter() - started
        return json.dumps(message, allow_nan=False)

    def session_text(self) -> str:
        return json.dumps(session_message(self.session), allow_nan=False)

    async def broadcast(self, text: str, skip: WebSocket | None = None) -> None:
        """Send to every open page but `skip`."""
        for socket in list(self.sockets):
            if socket is not skip:
                try:
                    await socket.send_text(text)
                except (RuntimeError, WebSocketDisconnect):
                    self.sockets.discard(socket)

    async def changed(self) -> None:
        """Tell every page that a file was opened: the session message, then the state."""
        await self.broadcast(await self.run(self.session_text))
        await self.broadcast(await self.run(self.state_text, None))

    # --- the solve loop ---

    async def socket(self, websocket: WebSocket) -> None:
        if not _same_origin(websocket.headers):
            await websocket.close(code=1008)
            return
        await websocket.accept()
        self.sockets.add(websocket)
        inbox = Inbox()
        receiver = asyncio.create_task(self._receive(websocket, inbox))
        try:
            await websocket.send_text(await self.run(self.session_text))
            await websocket.send_text(await self.run(self.state_text, None))
            while not receiver.done():
                idle_work = self.readouts_pending or self.session.comparison is None
                waiting = asyncio.create_task(inbox.get(IDLE_SECONDS if idle_work else None))
                await asyncio.wait({waiting, receiver}, return_when=asyncio.FIRST_COMPLETED)
                if not waiting.done():
                    waiting.cancel()
                    break
                message = waiting.result()
                if message is None:
                    await self._complete_readouts()
                    if self.session.comparison is None:
                        await self._compare_while_idle(inbox)
                else:
                    await self._handle(websocket, message)
                self.coalesced = max(self.coalesced, inbox.coalesced)
        except (WebSocketDisconnect, RuntimeError):
            pass
        finally:
            self.sockets.discard(websocket)
            receiver.cancel()

    async def _receive(self, websocket: WebSocket, inbox: Inbox) -> None:
        """Read the page's messages into the inbox until it goes away; tell it about bad ones."""
        while True:
            try:
                text = await websocket.receive_text()
            except (WebSocketDisconnect, RuntimeError, KeyError):
                return
            try:
                inbox.put(parse_message(text))
            except MessageError as exc:
                await websocket.send_text(json.dumps({"type": "error", "message": str(exc)}))

    async def _complete_readouts(self) -> None:
        """Send every page the readouts a drag's states left pending (in the solver thread; a few ms)."""
        if self.readouts_pending:
            text = await self.run(lambda: json.dumps(readouts_message(self.session), allow_nan=False))
            self.readouts_pending = False
            await self.broadcast(text)

    async def _compare_while_idle(self, inbox: Inbox) -> None:
        """Compare with a fresh placement (in the solver thread) and tell every page, unless a message arrives in
        `inbox` first: then the comparison is abandoned after its current continuation step (waited for here, so
        that the solver thread is free for the message)."""
        abandon = threading.Event()
        comparing = asyncio.ensure_future(self.run(self._compare, abandon))
        arrival = asyncio.create_task(inbox.arrival())
        await asyncio.wait({comparing, arrival}, return_when=asyncio.FIRST_COMPLETED)
        abandon.set()
        arrival.cancel()
        text = await comparing
        if text is not None:
            await self.broadcast(text)

    async def _handle(self, websocket: WebSocket, message) -> None:
        """Solve one message and send the outcome."""
        error, state, opened = await self.run(self._solve, message)
        if opened:  # undone or redone across a file opened: every page takes the other file's names and obstacles
            await self.broadcast(await self.run(self.session_text))
        if error is not None:
            await websocket.send_text(error)
        await websocket.send_text(state)
        if len(self.sockets) > 1:
            await self.broadcast(await self.run(self.state_text, None, None, not self.readouts_pending), skip=websocket)

    def _compare(self, abandon: threading.Event) -> str | None:
        """The comparison with a fresh placement (in the solver thread), as a JSON message; None when `abandon` was
        set before it was done (checked after every continuation step)."""

        def abandoned(phase: str, fraction: float) -> None:
            if abandon.is_set():
                raise ComparisonAbandoned(f"abandoned in {phase} at {fraction:g}")

        try:
            comparison = self.session.compare_with_placement(abandoned)
        except ComparisonAbandoned:
            self.abandoned += 1
            return None
        except Exception as exc:  # a bug: logged, and the page told that the comparison failed
            logging.getLogger(__name__).exception("studio: the comparison with a fresh placement failed")
            comparison = self.session.comparison = {"same": False, "failed": f"internal error ({exc})"}
        return json.dumps({"type": "comparison", "comparison": comparison}, allow_nan=False)

    def _solve(self, message) -> tuple[str | None, str, bool]:
        """Carry out one message in the solver thread: (the error message or None, the state message, as JSON; whether
        an undo or redo went to another file's session).  A target's state leaves readouts pending (readouts_pending)."""
        started = time.perf_counter()
        error, opened = None, False
        recorded = message.type not in ("undo", "redo") and self.history.before(self.session, message.edit)
        try:
            if message.type == "undo":
                opened = self.history.undo(self.session)
            elif message.type == "redo":
                opened = self.history.redo(self.session)
            elif isinstance(message, Command):
                if message.type == "segments":
                    self.session.set_segments(message.segments)
                elif message.type == "clearance":
                    self.session.set_required_clearance(message.obstacle, message.required)
                else:
                    self.session.place_again()
            else:
                self.session.apply(message)
        except REFUSED as exc:
            error = json.dumps({"type": "error", "message": str(exc), "seq": message.seq})
        except Exception as exc:  # a bug: said on the page and logged; the session goes on from its last state
            logging.getLogger(__name__).exception("studio: %s failed", message.type)
            error = json.dumps({"type": "error", "message": f"internal error ({type(exc).__name__}: {exc}); "
                                "the shape shown is the last good one", "seq": message.seq})
        if error is not None and recorded:
            self.history.forget()
        self.readouts_pending = isinstance(message, Target)
        return error, self.state_text(message.seq, started, not self.readouts_pending), opened

    # --- HTTP ---

    async def index(self, request: Request) -> Response:
        return HTMLResponse(PAGE, headers={"Content-Security-Policy": CSP, "Cache-Control": "no-store"})

    async def obstacle_mesh(self, request: Request) -> Response:
        number = request.path_params["id"]

        def mesh() -> bytes:
            if not 0 <= number < len(self.session.obstacles):
                raise StudioError(f"no obstacle {number}")
            obstacle = self.session.obstacles[number].obstacle
            vertices, faces = obstacle.vertices.astype("<f4"), obstacle.faces.astype("<u4")
            return struct.pack("<II", len(vertices), len(faces)) + vertices.tobytes() + faces.tobytes()

        try:
            return Response(await self.run(mesh), media_type="application/octet-stream")
        except StudioError as exc:
            return JSONResponse({"error": str(exc)}, status_code=404)

    async def problem_file(self, request: Request) -> Response:
        text = await self.run(self.session.problem_toml, request.query_params.get("as") == "assembled")
        return Response(text, media_type="application/toml", headers=_attachment("problem.toml"))

    async def export(self, request: Request) -> Response:
        from hoseline.io.export_names import FILE_NAMES, parse_formats
        from hoseline.io.exports import ExportError, export_bytes

        try:
            (name,) = parse_formats(request.path_params["format"])
        except ValueError as exc:
            return JSONResponse({"error": str(exc)}, status_code=404)

        def make() -> bytes:
            return export_bytes(name, self.session.result())

        try:
            data = await self.run(make)
        except ExportError as exc:
            return JSONResponse({"error": f"export failed: {exc}"}, status_code=422)
        return Response(data, media_type="application/octet-stream", headers=_attachment(FILE_NAMES[name]))

    async def upload(self, request: Request) -> Response:
        if not _same_origin(request.headers):
            return JSONResponse({"error": "uploads come from the studio's own page only"}, status_code=403)
        try:
            name, kind = checked_name(request.path_params["name"])
            labels = mount_labels(request.query_params.get("labels"))
            if len(list(self.uploads.iterdir())) >= MAX_FILES:
                raise UploadError(f"more than {MAX_FILES} files uploaded in this session: restart the studio", 413)
            data = await _body(request, SIZE_LIMITS[kind], name)
            path = self.uploads / name
            path.write_bytes(data)
            done = await self.run(self._open, path, kind, request.query_params.get("store") == "1", labels)
        except UploadError as exc:
            answer = {"error": str(exc)} | ({"labels": exc.labels} if exc.labels is not None else {})
            return JSONResponse(answer, status_code=exc.status)
        except PlacementError as exc:
            return JSONResponse({"error": f"{name}: read, but the hose cannot be placed: {exc}"}, status_code=422)
        await self.changed()
        return JSONResponse({"message": done})

    def _open(self, path: Path, kind: str, store_only: bool, labels) -> str:
        """Read an upload into the session (uploads.open_upload, in the solver thread) as an edit of its own (none when
        the file was only kept for a sweep file: the session's revision then stays)."""
        revision = self.session.revision
        self.history.before(self.session, None)
        try:
            done = open_upload(self.session, path, kind, store_only, labels)
        except Exception:
            self.history.forget()
            raise
        if self.session.revision == revision:
            self.history.forget()
        return done

    async def run_sweep(self, request: Request) -> Response:
        if not _same_origin(request.headers):
            return JSONResponse({"error": "sweeps are run from the studio's own page only"}, status_code=403)
        from hoseline.procedures.sweep.quasi_static import run_sweep
        from hoseline.report.sweep_report import write_sweep_report

        try:
            sweep = await self.run(self.session.sweep_to_run)
        except StudioError as exc:
            return JSONResponse({"error": str(exc)}, status_code=409)
        number = len(list(self.reports.iterdir()))
        folder = self.reports / str(number)

        def sweep_and_report() -> None:
            write_sweep_report(run_sweep(sweep), folder)

        try:
            await asyncio.get_running_loop().run_in_executor(self.sweeps, sweep_and_report)
        except PlacementError as exc:
            return JSONResponse({"error": f"the sweep failed: {exc}"}, status_code=422)
        return JSONResponse({"report": f"/reports/{number}/report.html"})

    async def report_file(self, request: Request) -> Response:
        from starlette.responses import FileResponse

        from hoseline.report.sweep_report import SWEEP_FILES

        run, name = request.path_params["run"], request.path_params["file"]
        path = self.reports / str(run) / name
        if name not in SWEEP_FILES or not path.is_file():
            return JSONResponse({"error": "no such report file"}, status_code=404)
        return FileResponse(path)

    async def close(self) -> None:
        self.solver.shutdown(wait=False, cancel_futures=True)
        self.sweeps.shutdown(wait=False, cancel_futures=True)


def create_app(session: Session, work_dir: Path | None = None, allowed_hosts: tuple[str, ...] = LOCAL_HOSTS) -> Starlette:
    """The studio's Starlette app around `session`.

    work_dir: folder for uploads and sweep reports (default: a new temporary folder).
    allowed_hosts: host names the requests may name (DNS rebinding protection).
    """
    work_dir = Path(tempfile.mkdtemp(prefix="hoseline-studio-")) if work_dir is None else Path(work_dir)
    studio = Studio(session, work_dir)
    routes = [
        Route("/", studio.index),
        Route("/obstacle/{id:int}", studio.obstacle_mesh),
        Route("/problem.toml", studio.problem_file),
        Route("/export/{format}", studio.export),
        Route("/upload/{name}", studio.upload, methods=["POST"]),
        Route("/sweep", studio.run_sweep, methods=["POST"]),
        Route("/reports/{run:int}/{file}", studio.report_file),
        WebSocketRoute("/ws", studio.socket),
        Mount("/static", StaticFiles(directory=STATIC)),
    ]

    @contextlib.asynccontextmanager
    async def lifespan(app):
        yield
        await studio.close()

    app = Starlette(routes=routes, middleware=[Middleware(TrustedHostMiddleware, allowed_hosts=list(allowed_hosts))],
                    lifespan=lifespan)
    app.state.studio = studio
    return app


async def _body(request: Request, limit: int, name: str) -> bytes:
    """The request body, refused (413) beyond `limit` bytes, before reading it if the length says so."""
    declared = request.headers.get("content-length")
    too_large = UploadError(f"{name} is larger than {limit // (1024 * 1024)} MiB, the limit for this kind of file", 413)
    if declared is not None and declared.isdigit() and int(declared) > limit:
        raise too_large
    chunks, size = [], 0
    async for chunk in request.stream():
        size += len(chunk)
        if size > limit:
            raise too_large
        chunks.append(chunk)
    return b"".join(chunks)


def _same_origin(headers) -> bool:
    """Whether a request comes from the studio's own page (or from no page at all: no Origin header)."""
    origin = headers.get("origin")
    return origin is None or origin == f"http://{headers.get('host')}"


def _attachment(file_name: str) -> dict:
    return {"Content-Disposition": f'attachment; filename="{file_name}"', "Cache-Control": "no-store"}


def _page() -> tuple[str, str]:
    """The page and its Content-Security-Policy (its one inline script, the import map, allowed by hash)."""
    page = (STATIC / "index.html").read_text(encoding="utf-8")
    inline = re.search(r'<script type="importmap">(.*?)</script>', page, re.S).group(1)
    digest = base64.b64encode(hashlib.sha256(inline.encode("utf-8")).digest()).decode("ascii")
    policy = (f"default-src 'self'; script-src 'self' 'sha256-{digest}'; style-src 'self'; img-src 'self' data: blob:; "
              "connect-src 'self'; object-src 'none'; base-uri 'none'; form-action 'none'; frame-ancestors 'none'")
    return page, policy


PAGE, CSP = _page()
