"""The pages' table of the settings that differ from the defaults (core/settings_diff.py): name, value, default, unit.

One run's settings: :func:`settings_table_html`. Several runs of one system (a survey's recordings): each run's
changes merged by name (:func:`merged_settings_table_html`), with the runs that hold each value.
"""

from __future__ import annotations

import html
import json

from sonartrack.core.settings_diff import SettingChange, settings_changes

_HEAD = "<tr><th>setting</th><th>value</th><th>default</th><th>unit</th>{extra}</tr>"
_ALL_DEFAULT = "<p class='settings-default'>Every setting at its default.</p>"


def show_value(v) -> str:
    """A setting's value as short text: numbers in ``repr`` precision trimmed to 6 significant digits, lists in
    brackets, ``None`` as ``none``, groups as compact JSON."""
    if v is None:
        return "none"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, list):
        return "[" + ", ".join(show_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return json.dumps(v, separators=(", ", ": "))
    return str(v)


def _cells(c: SettingChange) -> str:
    unit = "" if c.unit in ("", "1") else c.unit
    return (f"<td title='{html.escape(c.doc, quote=True)}'><code>{html.escape(c.name)}</code></td>"
            f"<td>{html.escape(show_value(c.value))}</td><td>{html.escape(show_value(c.default))}</td>"
            f"<td>{html.escape(unit)}</td>")


def settings_table_html(settings, default=None) -> str:
    """The HTML table of the settings of a run that differ from the defaults (a paragraph when none does).

    Parameters
    ----------
    settings : pydantic.BaseModel
        The run's settings tree (e.g. ``result.settings``).
    default : pydantic.BaseModel, optional
        What to compare with (core/settings_diff.py :func:`settings_changes`).

    Returns
    -------
    str
        ``<table class="settings-diff">`` with one row per changed setting (its doc as the name's tooltip).
    """
    changes = settings_changes(settings, default)
    if not changes:
        return _ALL_DEFAULT
    rows = "".join(f"<tr>{_cells(c)}</tr>" for c in changes)
    return f"<table class='settings-diff'>{_HEAD.format(extra='')}{rows}</table>"


def merged_settings_table_html(runs: dict) -> str:
    """The settings that differ from the defaults in any of several runs, one row per setting and value.

    Parameters
    ----------
    runs : dict
        Run name -> its settings tree (all of one class).

    Returns
    -------
    str
        ``<table class="settings-diff">``: setting, value, default, unit and the runs that hold that value
        (``all`` when every run does); a paragraph when every run is at the defaults.
    """
    rows: dict[tuple[str, str], tuple[SettingChange, list[str]]] = {}
    for name, settings in runs.items():
        for c in settings_changes(settings):
            rows.setdefault((c.name, show_value(c.value)), (c, []))[1].append(name)
    if not rows:
        return _ALL_DEFAULT
    body = "".join(f"<tr>{_cells(c)}<td>{'all' if len(names) == len(runs) else html.escape(', '.join(names))}</td>"
                   "</tr>" for c, names in rows.values())
    return f"<table class='settings-diff'>{_HEAD.format(extra='<th>recordings</th>')}{body}</table>"
