"""The console server without a browser: what it serves, what it refuses, what it pushes and what it accepts."""

from __future__ import annotations

import json
import socket
import sys
import threading
import time
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from wsclient import Client  # noqa: E402

from sonartrack.console.history import encode_update  # noqa: E402
from sonartrack.console.server import ConsoleServer, check_select  # noqa: E402
from sonartrack.core.errors import InputError  # noqa: E402


@pytest.fixture
def server():
    s = ConsoleServer(port=0, history_rows=5, max_clients=6)
    s.start()
    yield s
    s.stop()


def raw_request(server: ConsoleServer, target: str, *, method: str = "GET",
                host: str | None = None) -> tuple[int, bytes]:
    """(status, body) of one HTTP request written byte for byte (no client library tidies the path)."""
    with socket.create_connection(("127.0.0.1", server.port), timeout=10) as sock:
        sock.sendall(f"{method} {target} HTTP/1.1\r\nHost: {host or f'127.0.0.1:{server.port}'}\r\n"
                     f"Connection: close\r\n\r\n".encode("latin-1"))
        data = b""
        while chunk := sock.recv(65536):
            data += chunk
    head, _, body = data.partition(b"\r\n\r\n")
    return int(head.split()[1]), body


def asset_bytes(name: str) -> bytes:
    return (resources.files("sonartrack.console") / "assets" / name).read_bytes()


def test_serves_its_own_assets_byte_for_byte(server):
    for target, name in [("/", "index.html"), ("/index.html", "index.html"), ("/console.js", "console.js"),
                         ("/console.css", "console.css")]:
        status, body = raw_request(server, target)
        assert (status, body) == (200, asset_bytes(name)), target


def test_the_page_loads_nothing_from_elsewhere():
    html = asset_bytes("index.html").decode()
    js = asset_bytes("console.js").decode()
    for text in (html, js, asset_bytes("console.css").decode()):
        assert "http://" not in text and "https://" not in text and "//cdn" not in text
    assert 'src="/console.js"' in html and 'href="/console.css"' in html


@pytest.mark.parametrize("target", [
    "/../../../../etc/passwd", "/..%2F..%2F..%2Fetc%2Fpasswd", "/%2e%2e/%2e%2e/etc/passwd", "//etc/passwd",
    "/etc/passwd", "http://127.0.0.1/etc/passwd", "/console.js/../server.py", "/console.js%2F..%2Fserver.py",
    "/server.py", "/assets/console.js", "/console/assets/index.html", "/CONSOLE.JS", "/console.js/", "/%00",
    "/..\\..\\server.py", "/__init__.py", "/nothing-here.png"])
def test_no_path_reaches_the_file_system(server, target):
    status, body = raw_request(server, target)
    assert status in (400, 404), target
    assert b"root:" not in body and b"import" not in body and len(body) < 200


def test_only_get_and_head(server):
    assert raw_request(server, "/", method="HEAD")[0] == 200
    for method in ("POST", "PUT", "DELETE", "OPTIONS"):
        assert raw_request(server, "/", method=method)[0] == 405, method


def test_loopback_server_answers_only_loopback_names(server):
    assert raw_request(server, "/", host=f"localhost:{server.port}")[0] == 200
    assert raw_request(server, "/", host=f"[::1]:{server.port}")[0] == 200
    assert raw_request(server, "/", host=f"attacker.example:{server.port}")[0] == 403  # DNS rebinding


def test_websocket_from_another_origin_is_refused(server):
    import tornado.httpclient

    with pytest.raises((tornado.httpclient.HTTPClientError, ConnectionError)):
        Client(server.url, origin="http://attacker.example")
    ok = Client(server.url, origin=server.url.rstrip("/"))
    ok.wait(lambda m: len(m) >= 2)
    ok.close()


def test_binds_loopback_by_default_and_refuses_a_taken_port(server):
    assert server.url.startswith("http://127.0.0.1:")
    with pytest.raises(InputError, match="another --port"):
        ConsoleServer(port=server.port).start()


def test_push_history_and_late_join(server):
    early = Client(server.url)
    early.wait(lambda m: [x for x in m if x["type"] == "history"])
    for k in range(12):
        server.publish({"type": "btr", "t_s": float(k), "cone_deg": [0.0, 90.0], "level_db": [1.0, 2.0]})
    server.publish({"type": "targets", "t_s": 11.0, "rows": []})
    early.wait(lambda m: len(early.of_type("btr")) == 12)
    assert [u["t_s"] for u in early.of_type("btr")] == [float(k) for k in range(12)]  # every update, in order
    late = Client(server.url)
    hello, history = late.wait(lambda m: m[:2] if len(m) >= 2 else None)
    assert hello == {"type": "hello", "history_rows": 5}
    assert [u["t_s"] for u in history["updates"] if u["type"] == "btr"] == [7.0, 8.0, 9.0, 10.0, 11.0]  # ring of 5
    assert [u["type"] for u in history["updates"]][-1] == "targets"
    early.close()
    late.close()


def test_four_clients_at_once_come_and_go(server):
    clients = [Client(server.url) for _ in range(4)]
    for c in clients:
        c.wait(lambda m: len(m) >= 2)
    assert server.clients == 4
    server.publish({"type": "health", "t_s": 1.0, "events": ["gap of 400 samples"]})
    for c in clients:
        c.wait(lambda m, c=c: c.of_type("health"))
    clients[0].close()
    clients[1].close()
    clients += [Client(server.url), Client(server.url)]
    server.publish({"type": "health", "t_s": 2.0, "events": []})
    for c in clients[2:]:
        c.wait(lambda m, c=c: [u for u in c.of_type("health") if u["t_s"] == 2.0])
    # the newcomers got the event log in their history, though the latest health carries no events
    assert any(u["events"] == ["gap of 400 samples"] for u in clients[-1].of_type("health"))
    deadline = time.monotonic() + 10
    while server.clients != 4 and time.monotonic() < deadline:
        time.sleep(0.02)
    assert server.clients == 4
    for c in clients[2:]:
        c.close()


def test_too_many_clients_are_turned_away():
    with ConsoleServer(port=0, max_clients=2) as s:
        a, b = Client(s.url), Client(s.url)
        a.wait(lambda m: len(m) >= 2)
        b.wait(lambda m: len(m) >= 2)
        c = Client(s.url)
        assert c.closed.wait(10) and c.close_code == 1013 and c.messages == []
        for x in (a, b, c):
            x.close()


@pytest.mark.parametrize("message, why", [
    ("not json", "not JSON"), ('{"select": "3"}', "integer"), ('{"select": 3.0}', "integer"),
    ('{"select": true}', "integer"), ('{"select": -1}', "integer"), ('{"select": 2147483648}', "integer"),
    ('{"select": 3, "path": "/etc"}', "only message"), ('{"load": "/etc/passwd"}', "only message"), ("[3]", "only"),
    ('{"select": 3' + " " * 300 + "}", "longer than"), (b"\x00\x01", "binary")])
def test_every_message_is_checked(server, message, why):
    chosen = []
    server.on_select(chosen.append)
    c = Client(server.url)
    c.wait(lambda m: len(m) >= 2)
    c.send(message)
    error = c.wait(lambda m: [x for x in m if x["type"] == "error"])
    assert why in error[0]["detail"]
    assert chosen == [] and server.selected is None and server.rejected == 1
    c.close()


def test_a_message_over_the_frame_limit_closes_the_connection(server):
    c = Client(server.url)
    c.wait(lambda m: len(m) >= 2)
    c.send(json.dumps({"select": 1, "pad": "x" * 5000}))
    assert c.closed.wait(10) and c.close_code == 1009
    c.close()


def test_select_reaches_the_callback_and_every_client(server):
    chosen, got = [], threading.Event()
    server.on_select(lambda track: (chosen.append(track), got.set()))
    a, b = Client(server.url), Client(server.url)
    for c in (a, b):
        c.wait(lambda m: len(m) >= 2)
    a.send(json.dumps({"select": 7}))
    assert got.wait(10) and chosen == [7] and server.selected == 7
    assert b.wait(lambda m: [x for x in m if x["type"] == "selected"])[0]["track"] == 7
    late = Client(server.url)  # the selection is part of the history
    assert late.wait(lambda m: late.of_type("selected"))[0]["track"] == 7
    for c in (a, b, late):
        c.close()


def test_publish_from_many_threads_keeps_each_threads_order(server):
    c = Client(server.url)
    c.wait(lambda m: len(m) >= 2)

    def publisher(k):
        for i in range(150):
            server.publish({"type": "tracks", "t_s": float(i), "source": k, "tracks": []})

    threads = [threading.Thread(target=publisher, args=(k,)) for k in range(4)]  # a burst: no one is dropped
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    c.wait(lambda m: len(c.of_type("tracks")) >= 600)
    live = [u for u in c.messages if u["type"] == "tracks"]
    for k in range(4):
        assert [u["t_s"] for u in live if u["source"] == k] == [float(i) for i in range(150)]
    c.close()


def test_a_client_that_stops_reading_is_dropped():
    """A stalled client cannot make the server's memory grow: past max_pending_bytes unsent it is dropped."""
    with ConsoleServer(port=0, max_pending_bytes=4 * 2**20) as s:
        sock = socket.create_connection(("127.0.0.1", s.port), timeout=10)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        sock.sendall(f"GET /ws HTTP/1.1\r\nHost: 127.0.0.1:{s.port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                     f"Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n".encode())
        deadline = time.monotonic() + 10
        while s.clients != 1 and time.monotonic() < deadline:
            time.sleep(0.01)
        assert s.clients == 1
        big = {"type": "btr", "t_s": 0.0, "level_db": [0.5] * 200_000}  # ~1 MB each, never read
        for _ in range(60):
            s.publish(big)
            if s.clients == 0:
                break
            time.sleep(0.01)
        deadline = time.monotonic() + 10
        while s.clients and time.monotonic() < deadline:
            time.sleep(0.01)
        assert s.clients == 0
        sock.close()


def test_updates_are_plain_json_without_nan():
    kind, text = encode_update({"type": "ownship", "t_s": np.float64(1.5), "heading_deg": float("nan"),
                                "array": np.array([[0.0, 1.0], [np.inf, 2.0]]), "n": np.int64(3)})
    assert kind == "ownship"
    assert json.loads(text) == {"type": "ownship", "t_s": 1.5, "heading_deg": None, "array": [[0.0, 1.0], [None, 2.0]],
                                "n": 3}
    for bad in [{"t_s": 1}, {"type": "BTR"}, {"type": "x" * 40}, ["btr"], {"type": "btr", "f": object()}]:
        with pytest.raises(ValueError):
            encode_update(bad)


def test_check_select_accepts_only_a_track_id():
    assert check_select('{"select": 12}') == 12
    assert check_select('{ "select" : 0 }') == 0
