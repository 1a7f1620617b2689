"""UdpNmeaSource and FileNavSource: sentences written here from the NMEA 0183 layout (own checksum), bad sentences
as events, a fix that jumps, a dropout (in the log's time and in wall time) and the return of the fixes."""

from __future__ import annotations

import math
import socket
import time
from datetime import UTC, datetime

import pytest

from sonartrack.io.stream.nav import FileNavSource, UdpNmeaSource
from sonartrack.io.stream.nav_fixes import NmeaFixer
from sonartrack.io.stream.types import NavFix, StreamEvent


def _nmea(body: str) -> str:
    c = 0
    for ch in body.encode():
        c ^= ch
    return f"${body}*{c:02X}"


def _cycle(second: int, lat_min: float = 0.0, heading: float = 45.0) -> list[str]:
    """RMC, GGA, HDT of 12:00:second on 2024-05-17 at 50 deg lat_min' N, 4 deg W."""
    hms = f"1200{second:02d}.00"
    return [_nmea(f"GPRMC,{hms},A,50{lat_min:09.6f},N,00400.000000,W,10.00,45.00,170524,,,A"),
            _nmea(f"GPGGA,{hms},50{lat_min:09.6f},N,00400.000000,W,1,08,1.0,0.0,M,0.0,M,,"),
            _nmea(f"HEHDT,{heading:.2f},T")]


def _fixer_run(lines):
    f = NmeaFixer("test", dropout_s=5.0)
    out = []
    for line in lines:
        out += f.line(line)
    return out + f.flush()


def test_one_fix_per_cycle_with_heading_and_speed():
    out = _fixer_run(_cycle(0) + _cycle(1, 0.0015))
    assert [type(o).__name__ for o in out] == ["NavFix", "NavFix"]
    a, b = out
    assert a.utc == datetime(2024, 5, 17, 12, 0, 0, tzinfo=UTC) and a.heading_deg == 45.0
    assert a.lat_deg == pytest.approx(50.0) and a.lon_deg == pytest.approx(-4.0)
    assert a.speed_mps == pytest.approx(10 * 1852 / 3600)
    assert b.lat_deg == pytest.approx(50.0 + 0.0015 / 60)


def test_bad_sentences_are_events_and_fixes_go_on():
    bad_checksum = _cycle(1)[0][:-2] + "00"
    bad_minutes = _nmea("GPRMC,120002.00,A,5061.000000,N,00400.000000,W,10.00,45.00,170524,,,A")
    out = _fixer_run(_cycle(0) + [bad_checksum, "garbage $$$", bad_minutes, "$GPXXX,1,2*00"] + _cycle(3))
    kinds = [o.kind if isinstance(o, StreamEvent) else "fix" for o in out]
    assert kinds.count("fix") == 2 and kinds.count("bad_sentence") == 4
    assert any("minutes" in o.detail for o in out if isinstance(o, StreamEvent))


def test_a_jump_is_dropped_and_a_gap_in_the_log_is_a_dropout():
    far = _cycle(1, lat_min=30.0)  # 30' = 55 km in a second
    out = _fixer_run(_cycle(0) + far + _cycle(20))
    kinds = [o.kind if isinstance(o, StreamEvent) else "fix" for o in out]
    assert kinds == ["fix", "nav_jump", "nav_dropout", "fix"]


def test_gga_alone_takes_the_last_rmc_date_and_a_fix_without_hdt_has_no_heading():
    lines = [_cycle(0)[0], _nmea("GPGGA,120001.00,5000.000000,N,00400.000000,W,1,08,1.0,0.0,M,0.0,M,,")]
    out = _fixer_run(lines)
    assert [o.utc.second for o in out] == [0, 1] and all(math.isnan(o.heading_deg) for o in out)


def _send(port: int, lines):
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        for line in lines:
            s.sendto((line + "\r\n").encode(), ("127.0.0.1", port))


def _take_until(source, kinds: set[str], limit_s: float = 5.0) -> list:
    out, t0 = [], time.monotonic()
    for item in source:
        out.append(item)
        if (item.kind if isinstance(item, StreamEvent) else "fix") in kinds or time.monotonic() - t0 > limit_s:
            break
    return out


def test_udp_source_bad_sentence_dropout_and_resume():
    with UdpNmeaSource(0, dropout_s=0.3) as source:
        assert source.address.startswith("udp://127.0.0.1:")
        _send(source.port, _cycle(0) + ["$GPRMC,broken*77"])
        first = _take_until(source, {"bad_sentence"})
        assert [type(i).__name__ for i in first] == ["NavFix", "StreamEvent"]
        silent = _take_until(source, {"nav_dropout"})  # nothing sent for 0.3 s of wall time
        assert silent[-1].kind == "nav_dropout"
        _send(source.port, _cycle(1))
        back = _take_until(source, {"fix"})
        assert [i.kind if isinstance(i, StreamEvent) else "fix" for i in back] == ["nav_resumed", "fix"]
    assert not source.alive


def test_file_source_nmea_growing(tmp_path):
    path = tmp_path / "nav.nmea"
    with FileNavSource(path, poll_s=0.01, idle_end_s=0.3) as source:
        it = iter(source)
        path.write_text("\r\n".join(_cycle(0)) + "\r\n" + _cycle(1)[0][:20])  # the last line not yet complete
        assert isinstance(next(it), NavFix)
        with open(path, "a") as fh:
            fh.write(_cycle(1)[0][20:] + "\r\n" + "\r\n".join(_cycle(1)[1:]) + "\r\n")
        rest = list(it)
    assert [i.utc.second for i in rest if isinstance(i, NavFix)] == [1]


def test_file_source_csv_and_a_bad_row(tmp_path):
    path = tmp_path / "nav.csv"
    path.write_text("utc,lat_deg,lon_deg,heading_deg\n2024-05-17T12:00:00Z,50.0,-4.0,90\nnot,a,row,x\n"
                    "2024-05-17T12:00:01Z,50.0,-3.99995,90\n")
    with FileNavSource(path, poll_s=0.01, idle_end_s=0.1) as source:
        items = list(source)
    kinds = [i.kind if isinstance(i, StreamEvent) else "fix" for i in items]
    assert kinds == ["fix", "bad_line", "fix"]
    assert items[2].lon_deg == pytest.approx(-3.99995) and items[2].heading_deg == 90
