"""Live input: the TCP framing of sample blocks, and the sources a live run reads (issue 31).

* types.py -- what every source yields: :class:`StreamHeader`, :class:`SampleBlock`, :class:`NavFix`,
  :class:`StreamEvent` (the contract of /work/team/LIVE.md);
* frames.py -- the wire format (byte layout in its docstring), :func:`encode_header`, :func:`encode_block`,
  :func:`encode_end` and the incremental :class:`FrameDecoder` that checks every frame;
* reorder.py -- blocks put back in order within a small window, duplicates dropped, gaps and late blocks named;
* tcp.py -- :class:`TcpSampleSource` (connects to a recorder, reconnects with backoff);
* folder.py -- :class:`FolderSampleSource` (a folder a recorder writes, the newest file read as it grows);
* nav.py -- :class:`UdpNmeaSource` (NMEA 0183 over UDP) and :class:`FileNavSource` (a growing NMEA or CSV log);
* sources.py -- the sources under one name each (``from sonartrack.io.stream.sources import ...``).

Nothing is imported here.
"""
