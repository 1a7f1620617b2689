"""The console's web server: its own assets over HTTP, every display update pushed over one WebSocket.

Built on tornado (already installed with dask.distributed; measured against Starlette + uvicorn + websockets on
the same push test: both sub-millisecond median and 5-6 ms 99th percentile at 20 updates/s to 1 and 4 clients,
1.2-1.8 % of a core; tornado needs no new dependency and carries HTTP and WebSocket in one library).

Safety (issue 31 item 4): it binds 127.0.0.1 unless told otherwise; a request is answered only from the fixed
name -> bytes map of :mod:`sonartrack.console.assets`, looked up by its exact path (no part of a request
reaches the file system: ``..``, encoded slashes and absolute paths are simply names not in the map: 404); a
server bound to loopback answers only requests addressed to a loopback name (a DNS-rebinding page gets 403)
and WebSockets from its own origin; every message a client sends is checked (text, at most
:data:`MAX_MESSAGE_BYTES`, JSON, exactly ``{"select": int}``) and a bad one answered with an error message,
never acted on. A client too slow to take its updates is dropped (it reconnects and gets the history back),
so no client can make the server's memory grow.
"""

from __future__ import annotations

import asyncio
import json
import threading
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor

from sonartrack.console.history import UpdateHistory, encode_update
from sonartrack.core.errors import InputError

#: largest message a client may send (a selection is ~20 bytes); larger ones close the connection (1009)
MAX_MESSAGE_BYTES = 256
#: bad messages one client may send before it is disconnected
MAX_BAD_MESSAGES = 20
_LOOPBACK = ("127.0.0.1", "localhost", "::1")


def check_select(message) -> int:
    """The track id of a client's ``{"select": id}`` message; ValueError saying what is wrong with anything else."""
    if not isinstance(message, str):
        raise ValueError("binary messages are not accepted")
    if len(message.encode("utf-8")) > MAX_MESSAGE_BYTES:
        raise ValueError(f"message longer than {MAX_MESSAGE_BYTES} bytes")
    try:
        data = json.loads(message)
    except ValueError:
        raise ValueError("message is not JSON") from None
    if not isinstance(data, dict) or set(data) != {"select"}:
        raise ValueError('the only message accepted is {"select": <track id>}')
    track = data["select"]
    if type(track) is not int or not 0 <= track < 2**31:
        raise ValueError("select takes a track id: an integer from 0 to 2^31-1")
    return track


class ConsoleServer:
    """The live console's server (LIVE.md): start it, publish display updates from any thread, stop it.

    Parameters
    ----------
    host : str
        Address to bind; 127.0.0.1 (this machine only) unless the operator asks for another.
    port : int
        TCP port; 0 picks a free one (read :attr:`url` after :meth:`start`).
    history_rows : int
        Rows of each series kept for a client that joins late (bearing-time rows, track scans, LOFAR rows).
    max_clients : int
        Clients served at once; one more is refused (close code 1013) until another leaves.
    max_pending_bytes : int
        Bytes of updates queued for one client (written but not yet taken by its connection) before it counts as
        stalled and is dropped (a count of bytes, not of updates, so that a burst of small updates drops no one).
    """

    def __init__(self, host: str = "127.0.0.1", port: int = 0, *, history_rows: int = 3600, max_clients: int = 16,
                 max_pending_bytes: int = 32 * 2**20):
        self.host, self.port = host, int(port)
        self.history = UpdateHistory(history_rows)
        self.max_clients, self.max_pending_bytes = int(max_clients), int(max_pending_bytes)
        self.url = ""
        self.selected: int | None = None
        self.received = 0  # messages received from clients
        self.rejected = 0  # of which bad
        self._callbacks: list[Callable[[int], None]] = []
        self._clients: set = set()
        self._loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None
        self._stopping: asyncio.Event | None = None
        self._executor = ThreadPoolExecutor(max_workers=1, thread_name_prefix="console-select")

    @property
    def clients(self) -> int:
        """Clients connected now."""
        return len(self._clients)

    def on_select(self, callback: Callable[[int], None]) -> None:
        """Call ``callback(track_id)`` when a client selects a track; the calls run one at a time, in order, on a
        worker thread of their own (never on the server's, so a slow callback delays no update)."""
        self._callbacks.append(callback)

    def publish(self, update: dict) -> None:
        """Keep ``update`` in the history and push it to every client; safe to call from any thread. ValueError
        for an update that is not a JSON-able dict with a ``"type"`` (NaN and inf are sent as null)."""
        kind, text = encode_update(update)
        events = kind == "health" and bool(update.get("events"))
        loop = self._loop
        if loop is not None:
            # kept and pushed together on the server's loop, so that a client joining meanwhile gets the update once
            # (in its history or pushed), never both
            try:
                loop.call_soon_threadsafe(self._keep_and_broadcast, kind, text, events)
                return
            except RuntimeError:  # the loop closed under us: stop() is running
                pass
        self.history.add(kind, text, has_events=events)

    def start(self) -> None:
        """Bind the port and serve from a background thread; InputError naming the address if it cannot bind."""
        from tornado.netutil import bind_sockets

        if self._thread is not None:
            raise RuntimeError("this ConsoleServer was started already")
        try:
            sockets = bind_sockets(self.port, address=self.host)
        except OSError as exc:
            raise InputError(f"cannot serve the console on {self.host} port {self.port} ({exc.strerror or exc}); "
                             f"give another --port, or --port 0 to pick a free one") from None
        self.port = sockets[0].getsockname()[1]
        name = f"[{self.host}]" if ":" in self.host else self.host
        self.url = f"http://{name}:{self.port}/"
        ready = threading.Event()
        self._thread = threading.Thread(target=self._run, args=(sockets, ready), name="console-server", daemon=True)
        self._thread.start()
        ready.wait()

    def stop(self) -> None:
        """Close every client, stop serving and join the server's thread (idempotent)."""
        loop, thread = self._loop, self._thread
        if loop is not None and thread is not None and thread.is_alive():
            loop.call_soon_threadsafe(self._stopping.set)
            thread.join(10.0)
        self._executor.shutdown(wait=False, cancel_futures=True)

    def __enter__(self) -> ConsoleServer:
        self.start()
        return self

    def __exit__(self, *exc) -> None:
        self.stop()

    # ----- the server's thread ---------------------------------------------------------------------------------

    def _run(self, sockets, ready: threading.Event) -> None:
        asyncio.run(self._serve(sockets, ready))

    async def _serve(self, sockets, ready: threading.Event) -> None:
        from tornado.httpserver import HTTPServer

        from sonartrack.console.handlers import make_application

        self._loop = asyncio.get_running_loop()
        self._stopping = asyncio.Event()
        http = HTTPServer(make_application(self), xheaders=False)
        http.add_sockets(sockets)
        ready.set()
        try:
            await self._stopping.wait()
        finally:
            self._loop = None
            http.stop()
            for client in list(self._clients):
                client.close(1001, "server stopping")
            self._clients.clear()
            await http.close_all_connections()

    def allowed_host(self, host_header: str) -> bool:
        """Whether a request's Host header may be answered: any, unless bound to loopback, where only loopback
        names are (a page on another site that rebinds its name to 127.0.0.1 is refused)."""
        if self.host not in _LOOPBACK:
            return True
        name = host_header.rsplit(":", 1)[0] if not host_header.endswith("]") else host_header
        return name.strip("[]").lower() in _LOOPBACK

    def _keep_and_broadcast(self, kind: str, text: str, has_events: bool) -> None:
        self.history.add(kind, text, has_events=has_events)
        for client in list(self._clients):
            client.push(text)

    def joined(self, client) -> bool:
        """A client connected: False (and it is refused) when :attr:`max_clients` are connected already."""
        if len(self._clients) >= self.max_clients:
            return False
        self._clients.add(client)
        return True

    def left(self, client) -> None:
        """A client disconnected (or was dropped): it gets no more updates."""
        self._clients.discard(client)

    def receive(self, client, message) -> None:
        """A client's message: a selection is broadcast and handed to the callbacks; anything else is answered
        with an error and counted (too many and the client is disconnected)."""
        self.received += 1
        try:
            track = check_select(message)
        except ValueError as exc:
            self.rejected += 1
            client.bad_messages += 1
            client.push(json.dumps({"type": "error", "detail": str(exc)}))
            if client.bad_messages >= MAX_BAD_MESSAGES:
                client.close(1008, "too many bad messages")
            return
        self.selected = track
        self.publish({"type": "selected", "track": track})
        for callback in self._callbacks:
            self._executor.submit(callback, track)
