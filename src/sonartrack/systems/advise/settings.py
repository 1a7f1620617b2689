"""The advise system's settings: the candidate legs, the bearings to come, and the ownship's legs.

``sonartrack advise --print-config`` prints the tree; the defaults are tma/advice.py's and tma/observer_legs.py's.
"""

from __future__ import annotations

from typing import Literal

from pydantic import NonNegativeFloat

from sonartrack.core.settings import Settings, setting
from sonartrack.tma import advice, observer_legs


class AdviceSettings(Settings):
    """What the advice assumes of the bearings to come and which legs it weighs."""

    sigma_bearing_deg: float = setting(1.0, "standard deviation of the bearings to come (and of a bearings file's, "
                                            "for its batch ML)", unit="deg", gt=0, le=30)
    interval_s: float | None = setting(None, "time between the bearings to come (default: the median interval of "
                                             "the bearings files, else 30 s)", unit="s", gt=0)
    horizon_s: float = setting(advice.HORIZON_S, "time from now at which every candidate's range sd is judged",
                               unit="s", gt=0, le=86_400)
    turn_delays_s: list[NonNegativeFloat] = setting(list(advice.TURN_DELAYS_S), "candidate times to turn, from now",
                                                    unit="s", min_length=1)
    course_step_deg: float = setting(advice.COURSE_STEP_DEG, "spacing of the candidate courses", unit="deg", gt=0,
                                     le=90)
    objective: Literal["max", "mean"] = setting("max", "with several targets: minimise the largest ('max') or the "
                                                       "mean ('mean') predicted range sd", unit="")
    min_leg_s: float = setting(observer_legs.MIN_LEG_S, "shortest ownship leg in the navigation (shorter steady "
                                                        "spans are pieces of a turn)", unit="s", gt=0)
