"""A small WebSocket test client of the console server (tornado's client in a thread of its own)."""

from __future__ import annotations

import asyncio
import json
import threading


class Client:
    """One connection to ``url``/ws; :attr:`messages` collects what arrives (parsed JSON), in order."""

    def __init__(self, url: str, *, origin: str | None = None, host_header: str | None = None):
        import tornado.httpclient
        import tornado.websocket

        self.messages: list[dict] = []
        self.closed = threading.Event()
        self._arrived = threading.Condition()
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._loop.run_forever, daemon=True)
        self._thread.start()
        headers = {}
        if origin is not None:
            headers["Origin"] = origin
        if host_header is not None:
            headers["Host"] = host_header
        request = tornado.httpclient.HTTPRequest(url.replace("http://", "ws://") + "ws", headers=headers)

        async def connect():
            return await tornado.websocket.websocket_connect(request, on_message_callback=self._on_message)

        self.ws = asyncio.run_coroutine_threadsafe(connect(), self._loop).result(10)

    def _on_message(self, text) -> None:
        if text is None:
            self.closed.set()
        else:
            with self._arrived:
                self.messages.append(json.loads(text))
                self._arrived.notify_all()

    @property
    def close_code(self) -> int | None:
        return self.ws.close_code

    def send(self, message) -> None:
        async def write():
            await self.ws.write_message(message, binary=isinstance(message, bytes))

        asyncio.run_coroutine_threadsafe(write(), self._loop).result(10)

    def wait(self, predicate, timeout_s: float = 10.0):
        """Wait until ``predicate(messages)`` is truthy; its value (AssertionError on time-out)."""
        with self._arrived:
            ok = self._arrived.wait_for(lambda: predicate(self.messages) or self.closed.is_set(), timeout_s)
            value = predicate(self.messages)
        assert value, (f"never happened within {timeout_s} s; {len(self.messages)} messages, "
                       f"closed={self.closed.is_set()}")
        assert ok
        return value

    def of_type(self, kind: str) -> list[dict]:
        """Updates of ``kind`` received so far, those inside history messages included, in order."""
        out = []
        for m in list(self.messages):
            for u in m["updates"] if m["type"] == "history" else [m]:
                if u["type"] == kind:
                    out.append(u)
        return out

    def close(self) -> None:
        self._loop.call_soon_threadsafe(self.ws.close)
        self.closed.wait(5)
        self._loop.call_soon_threadsafe(self._loop.stop)
        self._thread.join(5)
