"""``sonartrack simulate``: a passive towed-array scene (recording, navigation, truth) and a sample input for
every other command, written into ``--out`` (the simulate system; systems/simulate/files.py lists the files);
with ``--kind active``, an active towed-array scene instead: pings, ping table, navigation and truth
(systems/simulate/active_files.py; the input of ``sonartrack active``). With ``--stream``, nothing is written: the
passive scene is played as a recorder plays it, its samples over TCP and its navigation as NMEA over UDP, at real
time x ``--speed`` (systems/simulate/stream.py), for ``sonartrack live``.

The scene's settings are the system's tree, :class:`sonartrack.sim.scene.PassiveSceneSettings` (or, with
``--kind active``, :class:`sonartrack.sim.active_scene.ActiveSceneSettings`): defaults, then the ``--scene`` TOML
file (or a shipped scene's name), then the options; ``--print-config`` prints them.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from sonartrack.cli._settings import PRINT_CONFIG_HELP, output_folder, print_config_and_exit, resolve, settings_help
from sonartrack.systems.simulate.settings import PassiveSceneSettings

_help = settings_help(PassiveSceneSettings)


#: the passive-only options and their defaults: given with --kind active, they are refused
PASSIVE_ONLY = {"only": "all", "format": "wav", "split_s": None, "gap_s": None, "nmea": False, "start_utc": None,
                "manifest": False}

#: the options of --stream (systems/simulate/stream.py); given without --stream, they are refused
StreamOpt = Annotated[bool, typer.Option("--stream", help="Play the passive scene as a recorder would instead of "
                                                          "writing it: samples over TCP on 127.0.0.1 (--port), the "
                                                          "ship's NMEA over UDP (--nav-udp), at real time x --speed; "
                                                          "the clock starts when the live side connects.")]
PortOpt = Annotated[int | None, typer.Option(help="With --stream: TCP port of the samples on 127.0.0.1 (0, the "
                                                  "default: a free port, printed).")]
NavUdpOpt = Annotated[int | None, typer.Option(help="With --stream: UDP port on 127.0.0.1 the ship's NMEA 0183 "
                                                    "(GGA, RMC, HDT, every second) is sent to.")]
SpeedOpt = Annotated[float | None, typer.Option(help="With --stream: play at real time x this factor (default 1).")]


def simulate_cmd(
    kind: Annotated[str, typer.Option(help="passive: a towed-array recording and sample inputs; active: pings of a "
                                           "towed source on a towed line array (the input of sonartrack active).")]
    = "passive",
    scene: Annotated[Path | None, typer.Option(help="Scene TOML file (see --print-config), or a shipped scene's "
                                                    "name (passive, active, zigzag).")] = None,
    duration_s: Annotated[float | None, typer.Option(help=_help("duration_s"))] = None,
    seed: Annotated[int | None, typer.Option(help=_help("seed"))] = None,
    propagation: Annotated[str | None, typer.Option(help=_help("propagation"))] = None,
    only: Annotated[str, typer.Option(help="all; passive (recording, nav, truth); samples (the other commands' "
                                           "inputs).")] = "all",
    print_config: Annotated[bool, typer.Option("--print-config", help=PRINT_CONFIG_HELP)] = False,
    out: Annotated[str, typer.Option(help="Output folder.")] = "scene",
    format: Annotated[str, typer.Option("--format", help="Recording format: wav (32-bit float), rf64, wav24 (24-bit "
                                                         "PCM) or flac (24-bit, <= 8 channels); the integer ones come "
                                                         "with calibration.toml.")] = "wav",
    split_s: Annotated[float | None, typer.Option(help="Write the recording as consecutive files of this many "
                                                       "seconds in recording/, named rec_YYYYmmdd_HHMMSS.")] = None,
    gap_s: Annotated[float | None, typer.Option(help="Leave out this many seconds at the start of the second file "
                                                     "(a gap between the first two files).")] = None,
    nmea: Annotated[bool, typer.Option("--nmea", help="Also write the ship's navigation as an NMEA 0183 log "
                                                      "nav.nmea (RMC + HDT, UTC); the recording goes in recording/ "
                                                      "named by its start.")] = False,
    start_utc: Annotated[str | None, typer.Option(help="UTC time of the first sample (ISO 8601), for the file names "
                                                       "and nav.nmea; default 2024-05-17T12:00:00Z.")] = None,
    manifest: Annotated[bool, typer.Option("--manifest", help="Also write manifest.csv: this recording's line of a "
                                                              "survey manifest (sonartrack survey).")] = False,
    stream: StreamOpt = False, port: PortOpt = None, nav_udp: NavUdpOpt = None, speed: SpeedOpt = None,
) -> None:
    """Simulate a passive sonar scene: N-channel WAV, navigation, truth, and sample inputs for every command
    (--kind active: an active scene's pings, ping table, navigation and truth)."""
    from sonartrack.core.errors import require

    require(kind in ("passive", "active"), f"--kind {kind}: choose passive or active")
    given = dict(only=only, format=format, split_s=split_s, gap_s=gap_s, nmea=nmea, start_utc=start_utc,
                 manifest=manifest)
    if stream:
        return _simulate_stream(kind, scene, dict(duration_s=duration_s, seed=seed, propagation=propagation),
                                print_config, given, (port, nav_udp, speed))
    bad = [k for k, v in dict(port=port, nav_udp=nav_udp, speed=speed).items() if v is not None]
    require(not bad, f"--{bad[0].replace('_', '-') if bad else ''} is an option of --stream: add --stream, or leave "
                     "it out")
    if kind == "active":
        return _simulate_active(scene, duration_s, seed, propagation, print_config, out,
                                [k for k, v in given.items() if v != PASSIVE_ONLY[k]])
    _simulate_passive(scene, dict(duration_s=duration_s, seed=seed, propagation=propagation), print_config, out,
                      given)


def _simulate_passive(scene: Path | None, overrides: dict, print_config: bool, out: str, given: dict) -> None:
    """The passive scene's settings, then its files (systems/simulate/files.py)."""
    from sonartrack.io.run_outputs import check_out_path, discard_on_failure
    from sonartrack.systems.simulate.files import check_only, check_recording_fits, shipped_scene_path, write_scene
    from sonartrack.systems.simulate.recording_layout import describe_layout, make_layout

    only = given["only"]
    path = shipped_scene_path(scene) if scene is not None else None
    settings = resolve(PassiveSceneSettings, path, **overrides)
    if print_config:
        print_config_and_exit(settings)
    check_only(only)
    layout = make_layout(given["format"], given["split_s"], given["gap_s"], given["nmea"], given["start_utc"],
                         given["manifest"])
    folder = check_out_path(out)
    check_recording_fits(settings, only, folder, layout)
    from sonartrack.cli._progress import TrialProgress, make_progress

    try:  # the folder before the progress bar: a bad --out is one line; a failed run leaves none of its files
        with output_folder(folder), discard_on_failure(folder), make_progress() as bar:
            files = write_scene(settings, folder, only=only, progress=TrialProgress(bar), layout=layout)
    except BaseException as exc:
        raise _as_interrupt(exc, folder)  # noqa: B904 (an interrupt gets simulate's line; anything else goes on)
    typer.echo(f"simulate: {files.summary}; wrote {len(files.paths)} files in {folder}")
    if layout != make_layout() and only != "samples":
        typer.echo(describe_layout(layout, settings.duration_s, settings.sample_rate_hz))


def _simulate_active(scene: Path | None, duration_s: float | None, seed: int | None, propagation: str | None,
                     print_config: bool, out: str, passive_options: list[str]) -> None:
    """``--kind active``: the active scene's settings, then its files (systems/simulate/active_files.py)."""
    from sonartrack.core.errors import require
    from sonartrack.sim.active_scene import ActiveSceneSettings
    from sonartrack.systems.simulate.files import shipped_scene_path

    require(not passive_options, f"--{passive_options[0].replace('_', '-') if passive_options else ''} is an option "
                                 "of the passive scene: leave it out with --kind active")
    path = shipped_scene_path(scene) if scene is not None else None
    settings = resolve(ActiveSceneSettings, path, duration_s=duration_s, seed=seed, propagation=propagation)
    if print_config:
        print_config_and_exit(settings)
    from sonartrack.cli._progress import TrialProgress, make_progress
    from sonartrack.io.run_outputs import check_out_path
    from sonartrack.systems.simulate.active_files import write_active

    folder = check_out_path(out)
    try:
        with output_folder(folder), make_progress() as bar:
            paths, summary = write_active(settings, folder, progress=TrialProgress(bar))
    except BaseException as exc:
        raise _as_interrupt(exc, folder)  # noqa: B904 (an interrupt gets simulate's line; anything else goes on)
    typer.echo(f"simulate: {summary}; wrote {len(paths)} files in {folder} (sonartrack active --pings {folder} "
               f"--nav {folder / 'nav.csv'} --spacing {settings.spacing_m:g})")


def _simulate_stream(kind: str, scene: Path | None, overrides: dict, print_config: bool, given: dict,
                     wire: tuple) -> None:
    """``--stream``: the scene's settings (passive, or active with ``--kind active``), then the scene played over TCP
    and UDP until its end or Ctrl-C (systems/simulate/stream.py); nothing is written."""
    from sonartrack.core.errors import require
    from sonartrack.systems.simulate.files import shipped_scene_path
    from sonartrack.systems.simulate.recording_layout import make_layout

    extra = [k for k, v in given.items() if k != "start_utc" and v != PASSIVE_ONLY[k]]
    require(not extra, f"--{extra[0].replace('_', '-') if extra else ''} shapes the files simulate writes; --stream "
                       "writes none: leave it out")
    port, nav_udp, speed = wire
    streamer, summary = _streamer(kind, shipped_scene_path(scene) if scene is not None else None, overrides,
                                  print_config, dict(port=port or 0, nav_udp=nav_udp,
                                                     speed=1.0 if speed is None else speed,
                                                     start_utc=make_layout(start_utc=given["start_utc"]).start_utc))
    nav = f", NMEA to udp://127.0.0.1:{nav_udp}" if nav_udp is not None else ""
    try:  # from the line that gives the port on: an interrupt gets the stream's own line
        typer.echo(f"simulate: streaming {summary} on tcp://127.0.0.1:{streamer.port}{nav} at "
                   f"{streamer.speed:g}x real time; waiting for the live side to connect (Ctrl-C stops)")
        done = streamer.serve()
    except BaseException as exc:
        streamer.close()
        raise _stream_interrupt(exc)  # noqa: B904 (an interrupt gets the stream's line; anything else goes on)
    what = "pings" if kind == "active" else "blocks"
    typer.echo(f"simulate: streamed {done.seconds:g} s of the scene ({done.blocks} {what}, {done.sentences} NMEA "
               f"sentences) to {done.connections} connection(s)")


def _streamer(kind: str, path, overrides: dict, print_config: bool, wire: dict):
    """(the streamer of the passive or active scene, its one-line summary): systems/simulate/stream.py."""
    from sonartrack.systems.simulate.stream import ActiveSceneStreamer, SceneStreamer

    if kind == "active":
        from sonartrack.sim.active_scene import ActiveSceneSettings
        from sonartrack.systems.simulate.active_files import active_scene_summary

        settings = resolve(ActiveSceneSettings, path, **overrides)
        if print_config:
            print_config_and_exit(settings)
        return ActiveSceneStreamer(settings, **wire), active_scene_summary(settings)
    from sonartrack.systems.simulate.run import scene_summary

    settings = resolve(PassiveSceneSettings, path, **overrides)
    if print_config:
        print_config_and_exit(settings)
    return SceneStreamer(settings, **wire), scene_summary(settings)


def _stream_interrupt(exc: BaseException) -> BaseException:
    """An interrupt of ``--stream`` as its own line (nothing was written, so nothing to remove); else ``exc``."""
    from sonartrack.cli import Interrupted, interrupt_of

    intr = interrupt_of(exc)
    if intr is None:
        return exc
    out = Interrupted(getattr(intr, "signum", 2), "interrupted: simulate --stream stopped (it writes no files); run "
                                                  "the same command again to play the scene from the start")
    out.__suppress_context__ = True
    return out


def _as_interrupt(exc: BaseException, folder: Path) -> BaseException:
    """An interrupt, whatever it became on the way (cli ``interrupt_of``: a SystemError out of a compiled call), as
    simulate's own :func:`_interrupted`; any other exception itself."""
    from sonartrack.cli import interrupt_of

    intr = interrupt_of(exc)
    if intr is None:
        return exc
    out = _interrupted(intr, folder)
    out.__suppress_context__ = True
    return out


def _interrupted(exc: KeyboardInterrupt, folder: Path) -> KeyboardInterrupt:
    """The interrupt with simulate's own line: an unfinished scene is not kept (nothing resumes)."""
    import signal

    from sonartrack.cli import Interrupted

    return Interrupted(getattr(exc, "signum", signal.SIGINT),
                       f"interrupted: simulate keeps no part of an unfinished scene (the files it had written in "
                       f"{folder} were removed); run the same command again to make it from the start")
