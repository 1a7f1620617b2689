"""Test helper: a recorder's streamer and a live chain run on threads against a console, stopped and closed after."""

from __future__ import annotations

import threading


def serve_and_run(streamer, samples, nav, server, run_chain):
    """Generator for a fixture: plays ``streamer`` and runs ``run_chain(stop)`` (its result in ``state["result"]``,
    any exception in ``state["error"]``, shown by the test, not lost in the thread); yields ``(server, state)``, then
    stops the chain, closes the sources, the streamer and the server."""
    stop, state = threading.Event(), {}

    def play():
        state["summary"] = streamer.serve(stop)

    def chain():
        try:
            state["result"] = run_chain(stop)
        except BaseException as exc:  # noqa: BLE001 - shown by the test
            state["error"] = exc

    threads = [threading.Thread(target=play, daemon=True), threading.Thread(target=chain, daemon=True)]
    for t in threads:
        t.start()
    yield server, state
    stop.set()
    for source in (samples, nav):
        source.close()
    for t in threads:
        t.join(30)
    streamer.close()
    server.stop()
