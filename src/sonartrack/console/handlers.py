"""The console server's two tornado handlers: a fixed asset map over HTTP, and the update WebSocket.

Kept apart from server.py so that ``import sonartrack.console.server`` does not load tornado until a server
starts. Every handler first checks the request's Host header (:meth:`ConsoleServer.allowed_host`).
"""

from __future__ import annotations

import json

import tornado.web
import tornado.websocket

from sonartrack.console.assets import asset_map

#: the page may load its own files and open its own WebSocket, nothing else
_CSP = ("default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' data:; connect-src 'self'; "
        "base-uri 'none'; form-action 'none'; frame-ancestors 'none'")


class AssetHandler(tornado.web.RequestHandler):
    """GET/HEAD of a name in the asset map (exact path, no decoding, no file system); 404 for any other."""

    def initialize(self, server) -> None:
        """Tornado's per-request set-up: the :class:`ConsoleServer` this handler answers for."""
        self.server = server

    def prepare(self) -> None:
        """403 for a request addressed to a name the server does not answer to."""
        if not self.server.allowed_host(self.request.host):
            raise tornado.web.HTTPError(403)

    def get(self, *args) -> None:
        """The asset named by the exact request path, or 404."""
        entry = asset_map().get(self.request.path)
        if entry is None:
            raise tornado.web.HTTPError(404)
        body, content_type = entry
        self.set_header("Content-Type", content_type)
        self.set_header("Cache-Control", "no-store")
        self.set_header("X-Content-Type-Options", "nosniff")
        self.set_header("Content-Security-Policy", _CSP)
        self.write(body)

    def head(self, *args) -> None:
        """As GET (tornado leaves the body out)."""
        self.get()

    def write_error(self, status_code: int, **kwargs) -> None:
        """A one-line plain-text error page (no traceback, nothing echoed from the request)."""
        self.set_header("Content-Type", "text/plain; charset=utf-8")
        self.finish(f"{status_code} {self._reason}\n")


class UpdateSocket(tornado.websocket.WebSocketHandler):
    """One client: on open a hello and the history, then every published update; its messages go to the server."""

    def initialize(self, server) -> None:
        """Tornado's per-connection set-up: the server, the characters not yet sent and the bad messages."""
        self.server = server
        self.pending = 0
        self.bad_messages = 0
        self.accepted = False

    def prepare(self) -> None:
        """403 for an upgrade addressed to a name the server does not answer to (the origin is tornado's check)."""
        if not self.server.allowed_host(self.request.host):
            raise tornado.web.HTTPError(403)

    def open(self, *args) -> None:
        """Join (or be refused when the server is full), then the hello and the history."""
        if not self.server.joined(self):
            self.close(1013, "too many clients; try again later")
            return
        self.accepted = True
        self.set_nodelay(True)
        self.push(json.dumps({"type": "hello", "history_rows": self.server.history.rows}))
        self.push(self.server.history.snapshot())

    def on_message(self, message) -> None:
        """Every message goes to the server's checks (:meth:`ConsoleServer.receive`)."""
        if self.accepted:
            self.server.receive(self, message)

    def on_close(self) -> None:
        """Leave the server's list of clients."""
        self.server.left(self)

    def push(self, text: str) -> None:
        """Send ``text``; a client with more than :attr:`ConsoleServer.max_pending_bytes` unsent is dropped."""
        if self.pending + len(text) > self.server.max_pending_bytes and self.pending:
            self.server.left(self)
            self.close(1013, "too slow to follow the updates; reconnect for the history")
            return
        try:
            future = self.write_message(text)
        except tornado.websocket.WebSocketClosedError:
            self.server.left(self)
            return
        size = len(text)
        self.pending += size
        future.add_done_callback(lambda f: self._sent(f, size))

    def _sent(self, future, n: int) -> None:
        self.pending -= n
        future.exception()  # (a closed stream: retrieved, so that asyncio does not log it)


def make_application(server) -> tornado.web.Application:
    """The tornado application of ``server``: /ws the WebSocket, every other path the asset map."""
    return tornado.web.Application(
        [(r"/ws", UpdateSocket, {"server": server}), (r".*", AssetHandler, {"server": server})],
        websocket_max_message_size=1024, websocket_ping_interval=10.0, websocket_ping_timeout=10.0,
        log_function=lambda handler: None, compress_response=False)
