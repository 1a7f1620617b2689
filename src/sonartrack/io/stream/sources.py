"""The live sources under one roof: samples from a recorder's TCP stream or folder, or a finished recording replayed;
navigation over UDP or from a growing log (each in its own module; all yield the types of io/stream/types.py and stop
with ``close()``)."""

from __future__ import annotations

from sonartrack.io.stream.folder import FolderSampleSource
from sonartrack.io.stream.nav import FileNavSource, UdpNmeaSource
from sonartrack.io.stream.replay import ReplaySampleSource
from sonartrack.io.stream.tcp import TcpSampleSource

__all__ = ["FileNavSource", "FolderSampleSource", "ReplaySampleSource", "TcpSampleSource", "UdpNmeaSource"]
