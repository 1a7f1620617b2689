"""What the navigation's own faults do to the chain's answers: a gap the ship turned in withholds the range of every
target tracked across it, and a batch ML faster than any ship is not determined (systems/passive/files.py runs
these on the chain's result; the gaps themselves are found by io/nav_checks.py).

Glossary of the parameters: ``result``, the chain's result (:class:`~sonartrack.systems.passive.chain.PassiveResult`).
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from sonartrack.systems.passive.chain import PassiveResult
    from sonartrack.systems.passive.files import RecordingNavigation


def recording_gaps(navr: RecordingNavigation, duration_s: float) -> list:
    """The navigation's gaps over the recording ``[0, duration_s]`` (io/nav_checks.py ``navigation_gaps``), each
    once, in time order.

    Parameters
    ----------
    navr : RecordingNavigation
        The navigation as read.
    duration_s : float
        The span the chain reads (s).

    Returns
    -------
    list of NavGap
        The gaps among the log's fixes and (a UTC log) its heading sentences.
    """
    from sonartrack.io.nav_checks import navigation_gaps

    found = {}
    for t in navr.sample_times_s:
        for g in navigation_gaps(t, navr.nav, 0.0, duration_s, lag_s=navr.lag_s):
            found.setdefault((g.start_s, g.end_s), g)
    return [found[k] for k in sorted(found)]


#: most gap lines printed (the rest counted in one more)
MAX_GAP_LINES = 5


def flag_navigation_gaps(result: PassiveResult, gaps: list, name: str) -> tuple[PassiveResult, list[str]]:
    """Withhold the range of every target tracked across a navigation gap the ship turned in (module doc), and
    one warning line per gap naming the targets it touches.

    The batch ML's rows are all flagged (one fit of the whole record); the sequential filter's from the gap's start
    (its earlier rows rest on navigation before the gap only). A row already not determined keeps its own reason.

    Parameters
    ----------
    result : PassiveResult
        The chain's result.
    gaps : list of NavGap
        The navigation's gaps over the recording (:func:`recording_gaps`).
    name : str
        The navigation file's name (for the lines).

    Returns
    -------
    (PassiveResult, list of str)
        The result with its targets' verdicts; the warning lines.
    """
    targets, lines = list(result.targets), []
    for g in gaps:
        hit = [k for k, tg in enumerate(targets) if len(tg.track.time_s) and tg.track.time_s[0] < g.array_end_s
               and tg.track.time_s[-1] > g.start_s]
        if not g.kept_course:
            for k in hit:
                tg = targets[k]
                targets[k] = replace(tg, ml=_withheld(tg.ml, g.reason(), -np.inf),
                                     sequential=_withheld(tg.sequential, g.reason(), g.start_s))
        ids = ", ".join(str(targets[k].target_id) for k in hit)
        tail = "" if not hit else (f"; target(s) {ids} tracked across it: range NOT DETERMINED (fill the gap in "
                                   "the log, or cut the recording at it)" if not g.kept_course
                                   else f"; target(s) {ids} tracked across it")
        lines.append(f"warning: navigation {name}: {g.describe()}{tail}")
    if len(lines) > MAX_GAP_LINES:
        lines = lines[:MAX_GAP_LINES] + [f"warning: navigation {name}: {len(lines) - MAX_GAP_LINES} more gap(s)"]
    return replace(result, targets=targets), lines


def _withheld(tma, why: str, from_s: float):
    """A TMA result whose rows from ``from_s`` on are not determined for ``why``, ahead of any reason of their own
    (a gap in the navigation is the cause, the solver's own verdict a consequence of it)."""
    sol = tma.solution
    reasons = np.where(np.asarray(sol.time_s) >= from_s, why, sol.reasons()).astype(object)
    return replace(tma, solution=replace(sol, range_determined=reasons == "", undetermined_reason=reasons))


def bound_batch_speed(result: PassiveResult) -> PassiveResult:
    """Withhold the batch ML range of a target faster than ``verdict.max_speed_mps`` (the bound the sequential
    filters' verdict applies, tma/verdict.py ``diverged_rows``): reason "diverged", and a warning line.

    Returns
    -------
    PassiveResult
        The result with those rows not determined.
    """
    from sonartrack.core.units import KNOT_MPS
    from sonartrack.tma.verdict import DIVERGED, with_reasons

    targets, lines = [], []
    for tg in result.targets:
        sol, limit = tg.ml.solution, tg.ml.settings.verdict.max_speed_mps
        speed = np.hypot(np.asarray(sol.state)[:, 2], np.asarray(sol.state)[:, 3])
        fast = sol.range_flags() & (speed > limit)
        if fast.any():
            lines.append(f"warning: target {tg.target_id}: the batch ML makes it {speed[fast].max() / KNOT_MPS:.0f} "
                         f"kn, faster than any ship ({limit / KNOT_MPS:.0f} kn, verdict.max_speed_mps): its range is "
                         "NOT DETERMINED (wrong navigation, or another target's bearings?)")
            tg = replace(tg, ml=replace(tg.ml, solution=with_reasons(sol, np.where(fast, DIVERGED, "").astype(object))))
        targets.append(tg)
    return replace(result, targets=targets, warnings=result.warnings + tuple(lines))
