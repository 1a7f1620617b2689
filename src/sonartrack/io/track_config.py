"""The TOML configuration of ``sonartrack track --contacts`` (defaults: the P4 study's tracker).

Example::

    q = [1e-4, 0.05]            # one value: single-model IPDA; several: IMM-IPDA (m^2/s^3)
    pd = 0.8
    clutter_density_per_m2 = 1e-6
    default_sigma_m = 200.0     # only for Cartesian contacts without covariance columns

    [bistatic]                  # only for raw bistatic contacts
    sigma_bearing_deg = 0.5
"""

from __future__ import annotations

import numpy as np
from pydantic import BaseModel, ConfigDict, Field


class BistaticInputErrors(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")
    sigma_time_s: float = Field(0.01, ge=0)
    sigma_bearing_deg: float = Field(0.5, gt=0)
    sigma_heading_deg: float = Field(0.0, ge=0)
    sigma_sound_speed_mps: float = Field(7.5, ge=0)
    sigma_position_m: float = Field(30.0, ge=0)
    sound_speed_mps: float = Field(1500.0, gt=0)

    def errors(self):
        from sonartrack.models.bistatic import BistaticErrors

        return BistaticErrors(self.sigma_time_s, float(np.deg2rad(self.sigma_bearing_deg)),
                              float(np.deg2rad(self.sigma_heading_deg)), self.sigma_sound_speed_mps, self.sigma_position_m)


class TrackCommandConfig(BaseModel):
    """Tracker and input settings for tracking a user's contacts."""

    model_config = ConfigDict(frozen=True, extra="forbid")
    q: list[float] = Field(default_factory=lambda: [1e-4, 0.05], min_length=1)
    transition_diagonal: float = 0.99
    pd: float = Field(0.8, gt=0, le=1)
    gate_probability: float = Field(0.99, gt=0, lt=1)
    clutter_density_per_m2: float = Field(1e-6, gt=0)
    p_survive: float = Field(0.98, gt=0, le=1)
    initial_existence: float = 0.05
    confirm_threshold: float = 0.9
    terminate_threshold: float = 0.01
    init_velocity_std_mps: float = Field(5.0, gt=0)
    default_sigma_m: float | None = Field(None, gt=0)
    bistatic: BistaticInputErrors = Field(default_factory=BistaticInputErrors)

    def tracker_config(self):
        from sonartrack.tracking.tracker import TrackerConfig

        return TrackerConfig(q=tuple(self.q), transition_diagonal=self.transition_diagonal, pd=self.pd,
                             gate_probability=self.gate_probability, clutter_density_per_m2=self.clutter_density_per_m2,
                             p_survive=self.p_survive, initial_existence=self.initial_existence,
                             confirm_threshold=self.confirm_threshold, terminate_threshold=self.terminate_threshold,
                             init_velocity_std_mps=self.init_velocity_std_mps)
