"""The Stone Soup components start from the declarations of sonartrack's tracker (tracking/settings.py): the
same defaults today, and a changed declaration changes the component (checked in a fresh interpreter)."""

import json
import subprocess
import sys

import pytest

pytest.importorskip("stonesoup", reason="Stone Soup not installed (pip install sonartrack[stonesoup])")

from sonartrack.stonesoup import (  # noqa: E402
    ExistenceDeleter,
    ExistenceInitiator,
    IMMIPDAHypothesiser,
    IMMIPDATracker,
    IPDAHypothesiser,
)
from sonartrack.tracking.settings import PositionTrackerSettings  # noqa: E402

#: (component, its Property, the PositionTrackerSettings field it takes its default from)
DECLARED = [
    (IMMIPDAHypothesiser, "prob_detect", "pd"),
    (IMMIPDAHypothesiser, "prob_gate", "gate_probability"),
    (IMMIPDAHypothesiser, "prob_survive", "p_survive"),
    (IMMIPDAHypothesiser, "prob_birth", "p_birth"),
    (IMMIPDATracker, "velocity_std", "init_velocity_std_mps"),
    (IMMIPDATracker, "initial_existence", "initial_existence"),
    (IMMIPDATracker, "confirm_threshold", "confirm_threshold"),
    (IMMIPDATracker, "terminate_threshold", "terminate_threshold"),
    (IMMIPDATracker, "max_tracks", "max_tracks"),
    (ExistenceInitiator, "initial_existence", "initial_existence"),
    (ExistenceDeleter, "deletion_threshold", "terminate_threshold"),
    (ExistenceDeleter, "confirmation_threshold", "confirm_threshold"),
    (IPDAHypothesiser, "prob_survive", "p_survive"),
    (IPDAHypothesiser, "prob_birth", "p_birth"),
]


@pytest.mark.parametrize("component, prop, field", DECLARED, ids=[f"{c.__name__}.{p}" for c, p, _ in DECLARED])
def test_component_default_is_the_declaration(component, prop, field):
    declared = PositionTrackerSettings.model_fields[field].default
    # Probability keeps its value as a log: equal to round-off
    assert float(component.properties[prop].default) == pytest.approx(float(declared), rel=1e-12, abs=1e-300)


# In a fresh interpreter: every declaration of DECLARED moved to another valid value before sonartrack.stonesoup
# is imported; each component's default must follow.
DRIFT = """
import json, sys
from sonartrack.tracking.settings import PositionTrackerSettings as S
new = json.loads(sys.argv[1])
for field, value in new.items():
    S.model_fields[field].default = value
import sonartrack.stonesoup as ss
out = {f"{c}.{p}": float(getattr(ss, c).properties[p].default) for c, p in json.loads(sys.argv[2])}
print(json.dumps(out))
"""

MOVED = {"pd": 0.7, "gate_probability": 0.95, "p_survive": 0.97, "p_birth": 0.001, "init_velocity_std_mps": 7.0,
         "initial_existence": 0.07, "confirm_threshold": 0.85, "terminate_threshold": 0.02, "max_tracks": 123}


def test_a_changed_declaration_changes_the_component():
    pairs = [(c.__name__, p) for c, p, _ in DECLARED]
    run = subprocess.run([sys.executable, "-c", DRIFT, json.dumps(MOVED), json.dumps(pairs)],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    got = json.loads(run.stdout)
    for c, p, field in DECLARED:
        assert got[f"{c.__name__}.{p}"] == pytest.approx(MOVED[field], rel=1e-12), f"{c.__name__}.{p} <- {field}"


def test_existence_initiator_starts_where_the_tracker_does():
    """The tracker's new tracks start at P(E) = initial_existence (0.05, P4); so do the initiator's."""
    assert float(ExistenceInitiator.properties["initial_existence"].default) == pytest.approx(
        PositionTrackerSettings().initial_existence, rel=1e-12)
