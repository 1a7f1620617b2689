"""``sonartrack live``: the passive chain on a live stream, shown in the operator console in the browser.

Parses the options, opens the sample and navigation sources (:mod:`sonartrack.io.stream.sources`: a recorder's
TCP stream, a folder a recorder writes, or a finished recording replayed at ``--speed`` times real time), starts
the console's server (:class:`sonartrack.console.server.ConsoleServer`, bound to 127.0.0.1 unless ``--host``
says otherwise) and runs :func:`sonartrack.systems.live.run_live`, which publishes every display update to it;
the operator's selection of a trace goes back to the chain. At the end of the stream the targets are printed
as ``passive`` prints them; Ctrl-C stops the run (status 130), its state kept in ``--checkpoint`` if given.
A stream of active pings (``simulate --kind active --stream``) runs through the active chain ping by ping
(systems/live/active.py; ``--active-config``), tracked on the navigation's fixes with the source and the array
``--source-tow`` and ``--array-tow`` metres behind the ship; its targets are printed as ``active`` prints them.

Settings: :class:`sonartrack.systems.passive.settings.PassiveSettings`, as for ``passive`` (defaults, then
``--config``, then the options; ``--print-config``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from sonartrack.cli._settings import PRINT_CONFIG_HELP, print_config_and_exit, resolve, settings_help
from sonartrack.systems.passive.settings import FrontEndSettings, PassiveSettings

_help = settings_help(PassiveSettings)


#: the options of a stream's active pings (systems/live/active.py)
ActiveConfigOpt = Annotated[Path | None, typer.Option(help="TOML file of active settings for a stream's pings (as "
                                                           "`active --config`; --spacing applies to both).")]
SourceTowOpt = Annotated[float | None, typer.Option("--source-tow", min=0.0, help="Active pings: the source's "
                                                    "distance behind the ship along its track (m); with --array-tow "
                                                    "the pings are tracked on the navigation's fixes.")]
ArrayTowOpt = Annotated[float | None, typer.Option("--array-tow", min=0.0, help="Active pings: the array centre's "
                                                   "distance behind the ship along its track (m).")]


def live_cmd(
    tcp: Annotated[str | None, typer.Option(help="A recorder's sample stream to connect to, HOST:PORT (the framing "
                                                 "of sonartrack.io.stream.frames; reconnects when it drops).")] = None,
    folder: Annotated[Path | None, typer.Option(help="A folder a recorder writes WAV/RF64/W64/FLAC files into: new "
                                                     "files are read as they appear, the newest as it grows.")] = None,
    wav: Annotated[Path | None, typer.Option(help="A finished recording, replayed as if live (see --speed).")] = None,
    speed: Annotated[float, typer.Option(help="Replay --wav at this many times real time.", min=0.01)] = 1.0,
    nav_udp: Annotated[int | None, typer.Option("--nav-udp", help="UDP port on which NMEA 0183 navigation arrives "
                                                                  "(as ship systems broadcast it).",
                                                min=1, max=65535)] = None,
    nav: Annotated[Path | None, typer.Option(help="Navigation file, read as it grows: NMEA 0183 or CSV.")] = None,
    host: Annotated[str, typer.Option(help="Address the console listens on (127.0.0.1: this machine only; 0.0.0.0 "
                                           "opens it to the network).")] = "127.0.0.1",
    port: Annotated[int, typer.Option(help="Port of the console (0 picks a free one).", min=0, max=65535)] = 8765,
    checkpoint: Annotated[Path | None, typer.Option(help="Keep the chain's state in this file (a stream's pings: in "
                                                         "FILE.active), so that a restart resumes (and the display "
                                                         "with it).")] = None,
    calibration: Annotated[Path | None, typer.Option(help="Hydrophone calibration TOML/CSV, as for passive: "
                                                          "sensitivity_db (dB re 1 V/uPa), gain_db[, full_scale_v]; "
                                                          "a stream's header may state the full scale itself. Not "
                                                          "given: the samples are pascals.")] = None,
    spacing: Annotated[float | None, typer.Option("--spacing", help=_help("spacing_m"))] = None,
    elements: Annotated[int | None, typer.Option(help=_help("elements"))] = None,
    method: Annotated[str | None, typer.Option(help=_help("method", FrontEndSettings))] = None,
    band_hz: Annotated[tuple[float, float] | None, typer.Option(help=_help("band_hz", FrontEndSettings)
                                                              + " Two numbers: LOW HIGH.")] = None,
    config: Annotated[Path | None, typer.Option(help="TOML file of passive settings (see --print-config).")] = None,
    active_config: ActiveConfigOpt = None, source_tow: SourceTowOpt = None, array_tow: ArrayTowOpt = None,
    keep_open: Annotated[bool, typer.Option("--keep-open", help="When the stream ends, keep the console open (the "
                                                                "last picture, for study) until Ctrl-C.")] = False,
    print_config: Annotated[bool, typer.Option("--print-config", help=PRINT_CONFIG_HELP)] = False,
) -> None:
    """Live passive or active chain on a stream (TCP, a recorder's folder, a replayed recording), browser console."""
    settings = resolve(PassiveSettings, config, spacing_m=spacing, elements=elements, front_end__method=method,
                       front_end__band_hz=list(band_hz) if band_hz else None)
    if print_config:
        print_config_and_exit(settings)
    plan = _plan(tcp, folder, wav, speed, nav_udp, nav)
    from sonartrack.console.server import ConsoleServer
    from sonartrack.io.calibration import read_calibration
    from sonartrack.systems.live.passive import check_live_settings

    check_live_settings(settings)
    plan["calibration"] = read_calibration(calibration) if calibration is not None else None  # checked before start
    plan["active"] = _active_plan(active_config, spacing, source_tow, array_tow)
    server = ConsoleServer(host=host, port=port)
    server.start()
    typer.echo(f"live: console at {server.url} (Ctrl-C to stop)", err=True)
    try:
        try:
            result = _run(plan, settings, server, checkpoint=checkpoint)
        except KeyboardInterrupt as exc:
            raise _interrupted(exc, checkpoint) from None
        _summary(result)
        if keep_open:
            _hold(server)
    finally:
        server.stop()


def _active_plan(config: Path | None, spacing: float | None, source_tow: float | None,
                 array_tow: float | None) -> dict:
    """The active chain's settings and tow lengths for a stream's pings (checked before anything starts)."""
    from sonartrack.core.errors import require
    from sonartrack.systems.active.settings import ActiveSettings

    require((source_tow is None) == (array_tow is None), "give both --source-tow and --array-tow (m), or neither")
    settings = resolve(ActiveSettings, config, spacing_m=spacing) if config is not None or spacing is not None \
        else None
    options = {} if source_tow is None else {"source_tow_m": source_tow, "array_tow_m": array_tow}
    return {"settings": settings, "options": options}


def _summary(result) -> None:
    """The targets printed as ``passive`` (or ``active``, for a stream of pings) prints them (or why there are
    none)."""
    from sonartrack.systems.active.run import ActiveResult
    from sonartrack.systems.passive.files import passive_summary

    if isinstance(result, ActiveResult):
        from sonartrack.systems.active.files import summary_lines

        for line in summary_lines(result):
            typer.echo(line)
        typer.echo("live: the stream ended", err=True)
        return
    if result is None:
        typer.echo("live: the stream ended before one whole window of samples: no passive result", err=True)
        return
    for warning in getattr(result, "warnings", []):
        typer.echo(warning, err=True)
    for line in passive_summary(result):
        typer.echo(line)
    typer.echo("live: the stream ended", err=True)


def _hold(server) -> None:
    """``--keep-open``: the console stays up, its last picture served to every client, until Ctrl-C (status 0)."""
    import time

    typer.echo(f"live: the console stays open at {server.url} (Ctrl-C to close it)", err=True)
    try:
        while True:
            time.sleep(0.5)
    except KeyboardInterrupt:
        typer.echo("live: console closed", err=True)


def parse_host_port(text: str) -> tuple[str, int]:
    """``HOST:PORT`` (``[v6]:PORT`` too) as (host, port); InputError naming the form otherwise."""
    from sonartrack.core.errors import InputError

    host, sep, port = text.rpartition(":")
    host = host.strip("[]")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise InputError(f"--tcp takes HOST:PORT (e.g. 127.0.0.1:5555), not {text!r}")
    return host, int(port)


def _plan(tcp, folder, wav, speed, nav_udp, nav) -> dict:
    """The sources asked for, checked before anything starts: one sample source, one navigation source."""
    from sonartrack.core.errors import require

    given = [name for name, v in (("--tcp", tcp), ("--folder", folder), ("--wav", wav)) if v is not None]
    require(len(given) == 1, "give one sample source: --tcp HOST:PORT, --folder DIR or --wav FILE"
            + (f" (not {' and '.join(given)})" if given else ""))
    require(wav is not None or speed == 1.0, "--speed replays a finished --wav; a live --tcp or --folder runs at the "
                                             "recorder's pace")
    require((nav_udp is None) != (nav is None), "give one navigation source: --nav-udp PORT or --nav FILE")
    require(folder is None or folder.is_dir(), f"--folder {folder} is not a folder")
    require(wav is None or wav.is_file(), f"--wav {wav} is not a file")
    return {"tcp": parse_host_port(tcp) if tcp else None, "folder": folder, "wav": wav, "speed": speed,
            "nav_udp": nav_udp, "nav": nav}


def _open_sources(plan: dict):
    """(sample source, navigation source) of the plan (io/stream/sources.py, LIVE.md)."""
    from sonartrack.io.stream import sources

    if plan["tcp"] is not None:
        samples = sources.TcpSampleSource(*plan["tcp"])
    elif plan["folder"] is not None:
        samples = sources.FolderSampleSource(plan["folder"])
    else:
        samples = sources.ReplaySampleSource(plan["wav"], speed=plan["speed"])
    if plan["nav_udp"] is not None:
        navigation = sources.UdpNmeaSource(plan["nav_udp"])
    elif plan["wav"] is not None:
        navigation = _replayed_navigation(plan["wav"], plan["nav"])
    else:
        navigation = sources.FileNavSource(plan["nav"])
    return samples, navigation


def _replayed_navigation(wav: Path, nav: Path):
    """A finished recording's navigation, read and placed on its time axis as ``passive`` reads it (the replay
    then gives the chain the same navigation the file run has)."""
    from sonartrack.io.recording_sequence import open_sequence
    from sonartrack.systems.passive.files import read_recording_navigation

    return read_recording_navigation(nav, open_sequence(wav)).nav


def _run(plan: dict, settings, server, *, checkpoint):
    """Run the live chain, publishing to ``server``, until the stream ends (or Ctrl-C); its PassiveResult (or the
    ActiveResult of a stream of pings)."""
    import threading

    from sonartrack.systems.live import run_live

    samples, navigation = _open_sources(plan)
    stop = threading.Event()
    try:
        return run_live(samples, navigation, settings, server.publish, checkpoint=checkpoint, stop=stop,
                        ready=lambda live: server.on_select(lambda i: [server.publish(u) for u in live.select(i)]),
                        calibration=plan.get("calibration"), active_settings=plan["active"]["settings"],
                        active_options=plan["active"]["options"])
    finally:
        stop.set()
        for source in (samples, navigation):
            if hasattr(source, "close"):
                source.close()


def _interrupted(exc: KeyboardInterrupt, checkpoint: Path | None) -> KeyboardInterrupt:
    """The interrupt with live's own line: what was kept, and how to resume."""
    import signal

    from sonartrack.cli import Interrupted

    kept = (f"the chain's state is in {checkpoint} (pings: {checkpoint}.active) as of its last checkpoint; run the "
            "same command to resume"
            if checkpoint is not None else "nothing was kept (give --checkpoint FILE to resume after a restart)")
    return Interrupted(getattr(exc, "signum", signal.SIGINT), f"interrupted: the live run stopped; {kept}")
