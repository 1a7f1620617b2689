"""Live navigation: NMEA 0183 over UDP as ship systems broadcast it, or a navigation log that grows as it is
written (NMEA or CSV); both checked fix by fix (io/stream/nav_fixes.py).

:class:`UdpNmeaSource` binds ``host:port`` (127.0.0.1 unless told otherwise; port 0 picks a free one,
:attr:`UdpNmeaSource.port`) and reads datagrams of one or more sentences. :class:`FileNavSource` follows a file
from its start, reading each line once it is complete (a file not yet there is waited for); its format is told
by its first line: NMEA sentences, or a CSV header with ``lat_deg, lon_deg`` and ``utc`` (ISO 8601) or
``time_unix_s`` (optional ``heading_deg``, ``speed_mps``), or simulate's nav.csv ``time_s, x_m, y_m,
heading_deg`` (metres east and north of ``origin_deg``, seconds after ``start_utc``: both must then be given).
A CSV row that does not parse is a "bad_line" event. Both yield NavFix | StreamEvent and stop with ``close()``.
"""

from __future__ import annotations

import math
import socket
from datetime import date, datetime
from pathlib import Path

from sonartrack.core.errors import InputError, require
from sonartrack.io.stream._threaded import POLL_S, ThreadedSource
from sonartrack.io.stream.nav_fixes import DROPOUT_S, NmeaFixer, utc_of
from sonartrack.io.stream.types import NavFix, StreamEvent

#: longest line taken (bytes): longer is no navigation sentence (NMEA 0183 allows 82 characters)
MAX_LINE_BYTES = 4096


class UdpNmeaSource(ThreadedSource):
    """NMEA 0183 over UDP (module doc). ``port`` 0 binds a free port (then :attr:`port`)."""

    _name = "udp-nmea"

    def __init__(self, port: int, host: str = "127.0.0.1", *, dropout_s: float = DROPOUT_S,
                 log_date: date | None = None):
        super().__init__()
        require(0 <= int(port) < 65536, f"UDP port {port}: give 0 (any free port) or 1..65535")
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            self._sock.bind((host, int(port)))
        except OSError as exc:
            self._sock.close()
            raise InputError(f"cannot listen for NMEA on udp://{host}:{port} ({exc.strerror}): choose another "
                             "--nav-udp port") from None
        self._sock.settimeout(POLL_S)
        self.port = self._sock.getsockname()[1]
        self.address = f"udp://{host}:{self.port}"
        self._fixer = NmeaFixer(self.address, dropout_s=dropout_s, log_date=log_date)

    def _run(self) -> None:
        try:
            while not self._stop.is_set():
                try:
                    data = self._sock.recv(65536)
                except TimeoutError:
                    data = b""
                for line in data.decode("ascii", "replace").splitlines():
                    if len(line) > MAX_LINE_BYTES:
                        self._put(StreamEvent("bad_sentence", f"{self.address}: a line of {len(line)} bytes: "
                                                              "skipped"))
                        continue
                    for item in self._fixer.line(line):
                        self._put(item)
                for item in self._fixer.tick():
                    self._put(item)
        finally:
            self._sock.close()

    def close(self, timeout_s: float = 5.0) -> None:
        """Stop the reader and close the socket.

        Parameters
        ----------
        timeout_s : float
            Longest wait (s) for the reader thread.
        """
        super().close(timeout_s)
        if self._thread is None:
            self._sock.close()


class FileNavSource(ThreadedSource):
    """A navigation log read as it grows (module doc).

    Parameters
    ----------
    path : str or Path
        The log (it may not exist yet).
    poll_s : float
        How often (s) the file is looked at.
    dropout_s : float
        A silence longer than this (s) is a "nav_dropout".
    idle_end_s : float, optional
        End when the file has not grown for this long (s); None: follow it for ever.
    origin_deg : (float, float), optional
        Latitude and longitude (deg) of x = y = 0 of a ``time_s, x_m, y_m`` CSV.
    start_utc : datetime, optional
        UTC time of time_s = 0 of such a CSV.
    """

    _name = "file-nav"

    def __init__(self, path, *, poll_s: float = 0.2, dropout_s: float = DROPOUT_S, idle_end_s: float | None = None,
                 origin_deg: tuple[float, float] | None = None, start_utc: datetime | None = None):
        super().__init__()
        self.path = Path(path)
        require(self.path.parent.is_dir(), f"navigation log folder not found: {self.path.parent}")
        self._poll_s, self._idle_end_s = float(poll_s), idle_end_s
        self._origin, self._start_utc = origin_deg, start_utc
        self._fixer = NmeaFixer(str(self.path), dropout_s=dropout_s)
        self._columns: list[str] | None = None
        self._projection = None

    def _run(self) -> None:
        import time

        pos, tail, last_growth = 0, b"", time.monotonic()
        while not self._stop.is_set():
            data = b""
            if self.path.is_file():
                with open(self.path, "rb") as fh:
                    fh.seek(pos)
                    data = fh.read(1 << 20)
            pos += len(data)
            *lines, tail = (tail + data).split(b"\n")
            if len(tail) > MAX_LINE_BYTES:
                self._put(StreamEvent("bad_line", f"{self.path}: a line of more than {MAX_LINE_BYTES} bytes: skipped"))
                tail = b""
            for raw in lines:
                for item in self._line(raw.decode("ascii", "replace").strip()):
                    self._put(item)
            for item in self._fixer.tick():
                self._put(item)
            if data:
                last_growth = time.monotonic()
            elif self._idle_end_s is not None and time.monotonic() - last_growth > self._idle_end_s:
                for item in self._fixer.flush():
                    self._put(item)
                return
            else:
                self._stop.wait(self._poll_s)

    def _line(self, line: str) -> list:
        if not line:
            return []
        if self._columns is None and "$" not in line:
            self._columns = _csv_columns(line, self.path, self._origin is not None and self._start_utc is not None)
            return []
        if self._columns is None or "$" in line:
            return self._fixer.line(line)
        try:
            fix = self._csv_fix(dict(zip(self._columns, line.split(","), strict=True)))
        except (ValueError, KeyError, InputError) as exc:
            return [StreamEvent("bad_line", f"{self.path}: line {line[:60]!r} does not parse ({exc}): skipped")]
        return self._fixer.take(fix)

    def _csv_fix(self, row: dict) -> NavFix:
        heading = float(row.get("heading_deg", "nan") or "nan")
        speed = float(row.get("speed_mps", "nan") or "nan")
        if "lat_deg" in row:
            when = (datetime.fromisoformat(row["utc"].replace("Z", "+00:00")) if "utc" in row
                    else utc_of(float(row["time_unix_s"])))
            require(when.tzinfo is not None, f"time {row['utc']} has no zone: give UTC (…Z)")
            lat, lon = float(row["lat_deg"]), float(row["lon_deg"])
        else:
            if self._projection is None:
                from sonartrack.io.nmea import LocalProjection

                self._projection = LocalProjection(*self._origin)
            lat, lon = (float(v) for v in self._projection.latlon(float(row["x_m"]), float(row["y_m"])))
            when = utc_of(self._start_utc.timestamp() + float(row["time_s"]))
        require(-90 <= lat <= 90 and -180 <= lon <= 180 and all(map(math.isfinite, (lat, lon))),
                f"position ({lat:g}, {lon:g}) deg is no latitude/longitude")
        require(math.isnan(heading) or 0 <= heading <= 360, f"heading {heading:g} deg is outside 0..360")
        return NavFix(when, lat, lon, heading, speed)


def _csv_columns(line: str, path: Path, projected_ok: bool) -> list[str]:
    """The columns of a CSV log's header line (module doc); InputError for a header that is none of them."""
    cols = [c.strip() for c in line.split(",")]
    geo = {"lat_deg", "lon_deg"} <= set(cols) and ({"utc", "time_unix_s"} & set(cols))
    local = {"time_s", "x_m", "y_m"} <= set(cols)
    require(geo or local, f"navigation log {path}: header {line[:80]!r} has neither lat_deg, lon_deg and utc (or "
                          "time_unix_s) nor time_s, x_m, y_m: give NMEA sentences or one of those CSV layouts")
    require(geo or projected_ok, f"navigation log {path} gives x_m, y_m: give its origin (lat, lon) and the UTC time "
                                 "of time_s = 0 (origin_deg, start_utc), or log latitude and longitude")
    return cols
