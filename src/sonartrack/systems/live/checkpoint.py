"""Checkpoints of the live chain: its state in one versioned file, written atomically (io/atomic.py).

The file is a pickle of a dict: ``format`` and ``version`` (:data:`CHECKPOINT_VERSION`; a file of another format or
version is refused with what to do), the settings (as their dict), the stream header, the options, and the state:
the window assembler (with the part-filled window's samples), the tracker (its live tracks), the LOFAR accumulator's
open period, the history deques (bearing-time rows, tracker rows, LOFAR periods), the waiting scans, the navigation
fixes (with their projected positions and unwrapped headings), the per-track tonal accumulators
(systems/live/tonals.py: ~0.26 MB per track and hour), the selected track and the health counters. Not kept: the
tonal band's spectra ring (0.4 GB an hour, on disk); the tonal lines after a restore rest on the accumulators, which
hold the windows before the checkpoint and those since (the final pass too reads them then, not the ring).
Version 2 (the accumulators and the navigation's columns); a version 1 file is refused with what to do.

The active chain's (systems/live/active.py ``LiveActive``) is its own file (format ``sonartrack-live-active``,
version 1): its ``_Chain`` (tracker, MFTD stack, clutter map, sides, B-scan rows, the kept per-ping rows), the
pings waiting, the display's B-scan updates and target table, and the fixes (LiveNavigation.state()); its geometry
is pickled as a reference and rebuilt on restore from the fixes or the given navigation.

A checkpoint is read only from a path the operator gave (pickle runs code from the file: never load one from an
untrusted source).
"""

from __future__ import annotations

import pickle
from pathlib import Path

from sonartrack.core.errors import InputError, require
from sonartrack.io.atomic import atomic_path

#: the checkpoint's format name and version (bumped when the state's layout changes)
CHECKPOINT_FORMAT = "sonartrack-live-passive"
CHECKPOINT_VERSION = 2
#: the chain's attributes a checkpoint keeps as they are
_STATE = ("rows", "scans", "pending", "periods", "k_first", "k_next", "n_periods", "selected", "events", "gaps",
          "last_targets", "_no_heading")


def write_checkpoint(live, path) -> Path:
    """Write ``live``'s state (module doc) to ``path`` atomically; returns the path."""
    state = {name: getattr(live, name) for name in _STATE}
    state |= {"assembler": live.assembler.state(), "nav": live.nav.state(), "tracker": live.core.tracker,
              "heading_deg": live.core.heading_deg, "lofar": _lofar_state(live.core.front.lofar),
              "tonals": live.tonals.tracks}
    doc = {"format": CHECKPOINT_FORMAT, "version": CHECKPOINT_VERSION,
           "settings": live.settings.model_dump(mode="json"), "header": live.header, "history_s": live.history_s,
           "options": live.options, "fixed_nav": live.fixed_nav, "state": state}
    p = Path(path)
    with atomic_path(p) as tmp:
        tmp.write_bytes(pickle.dumps(doc, protocol=pickle.HIGHEST_PROTOCOL))
    return p


def _lofar_state(acc) -> dict | None:
    return None if acc is None else acc.state()


def read_checkpoint(cls, path):
    """The chain of a checkpoint file (module doc): InputError when it is missing, unreadable, or of another
    format or version."""
    from sonartrack.systems.passive.settings import PassiveSettings

    doc = _checkpoint_doc(path, CHECKPOINT_FORMAT, CHECKPOINT_VERSION, "passive")
    live = cls(PassiveSettings.model_validate(doc["settings"]), doc["header"], history_s=doc["history_s"],
               nav=doc["fixed_nav"], **doc["options"])
    state = doc["state"]
    for name in _STATE:
        setattr(live, name, state[name])
    live.assembler.restore(state["assembler"])
    live.nav.restore(state["nav"])
    live.core.tracker, live.core.heading_deg = state["tracker"], state["heading_deg"]
    if state["lofar"] is not None:
        live.core.front.lofar.restore(state["lofar"])
    live.tonals.tracks = state["tonals"]
    live.spill.skip_to(live.k_next)
    return live


#: the active chain's checkpoint format and version (systems/live/active.py)
ACTIVE_CHECKPOINT_FORMAT = "sonartrack-live-active"
#: 7: the CW ridge map's recurring places (hold, skirt density), the likelihood-ratio confirmation's per-track
#: odds; 6: the CW ridge map, K shapes by delay, side evidence over joins, the amplitude parts; 5: the merger reunites
#: told-apart pairs; 4: endfire alias test; 3: contact claims
ACTIVE_CHECKPOINT_VERSION = 7
#: LiveActive's attributes a checkpoint keeps as they are (the chain: its tracker, MFTD stack, clutter map, sides,
#: B-scan rows and the per-ping rows of its history)
_ACTIVE_STATE = ("chain", "pending", "pings", "last", "said", "shown", "targets", "newest")


class _ActivePickler(pickle.Pickler):
    """Pickles the chain with its geometry as a reference: the geometry is rebuilt from the fixes on restore (the
    fixes' map projection is rebuilt from its origin, not pickled)."""

    def __init__(self, file, geometry):
        super().__init__(file, protocol=pickle.HIGHEST_PROTOCOL)
        self.geometry = geometry

    def persistent_id(self, obj):
        return "geometry" if obj is not None and obj is self.geometry else None


class _ActiveUnpickler(pickle.Unpickler):
    def __init__(self, file, geometry):
        super().__init__(file)
        self.geometry = geometry

    def persistent_load(self, pid):
        require(pid == "geometry", "the checkpoint holds an unknown reference: delete it to start afresh")
        return self.geometry


def write_active_checkpoint(live, path) -> Path:
    """Write the live active chain's state (LiveActive: the chain, the pings waiting, the display's B-scan and
    target rows; the fixes as LiveNavigation.state()) to ``path`` atomically; returns the path."""
    import io

    buf = io.BytesIO()
    _ActivePickler(buf, live.geometry).dump({name: getattr(live, name) for name in _ACTIVE_STATE})
    doc = {"format": ACTIVE_CHECKPOINT_FORMAT, "version": ACTIVE_CHECKPOINT_VERSION,
           "settings": live.settings.model_dump(mode="json"), "header": live.header, "options": live.options,
           "fixes": None if live.fixes is None else live.fixes.state(), "state": buf.getvalue()}
    p = Path(path)
    with atomic_path(p) as tmp:
        tmp.write_bytes(pickle.dumps(doc, protocol=pickle.HIGHEST_PROTOCOL))
    return p


def read_active_checkpoint(cls, path):
    """The live active chain of a checkpoint file: InputError when it is missing, unreadable, or of another format
    or version."""
    import io

    from sonartrack.systems.active.settings import ActiveSettings

    doc = _checkpoint_doc(path, ACTIVE_CHECKPOINT_FORMAT, ACTIVE_CHECKPOINT_VERSION, "active")
    live = cls(ActiveSettings.model_validate(doc["settings"]), doc["header"], **doc["options"])
    if doc["fixes"] is not None:
        live.fixes.restore(doc["fixes"])
    state = _ActiveUnpickler(io.BytesIO(doc["state"]), live.geometry).load()
    for name in _ACTIVE_STATE:
        setattr(live, name, state[name])
    return live


def _checkpoint_doc(path, fmt: str, version: int, kind: str) -> dict:
    """The checked dictionary of a checkpoint file of ``fmt`` and ``version`` (InputError, one line, when the file is
    missing, unreadable, or of another format or version)."""
    p = Path(path)
    require(p.is_file(), f"checkpoint {p} not found: give the file a live run wrote with --checkpoint")
    try:
        doc = pickle.loads(p.read_bytes())  # noqa: S301 - the operator's own file (module doc)
    except Exception as exc:  # noqa: BLE001 - any damage reads as one message
        raise InputError(f"checkpoint {p} is unreadable ({type(exc).__name__}): delete it to start afresh") from None
    require(isinstance(doc, dict) and doc.get("format") == fmt,
            f"{p} is no live {kind} checkpoint: give the file a live run wrote, or delete it to start afresh")
    require(doc.get("version") == version,
            f"checkpoint {p} is version {doc.get('version')}, this sonartrack reads version {version}: "
            "delete it to start afresh")
    return doc
