"""The live operator console: a local web page fed by the live chain's display updates (issue 31).

* server.py -- :class:`ConsoleServer`: HTTP for its own assets only, a WebSocket that pushes every update to
  every client, bounded history for a client that joins late, ``{"select": id}`` back from the page;
* history.py -- the ring buffers of that history and the one JSON encoding of an update;
* assets.py -- the page's files (assets/index.html, console.js, console.css), read once into a name -> bytes map;
* fake.py -- a small generator of display updates in the LIVE.md shapes (tests, benchmarks, the demo page).

Nothing heavy is imported here (tornado loads when a server is made).
"""
