"""Piecewise-straight paths written from kinematics alone (numpy), for tests that pose ships on legs."""

import numpy as np


def leg_positions(t, start_xy, legs):
    """Positions (n, 2) along piecewise-straight legs [(end time s, course deg, speed m/s), ...] from t = 0."""
    pos, p, t0 = np.zeros((len(t), 2)), np.asarray(start_xy, float), 0.0
    for k, (t1, course, speed) in enumerate(legs):
        v = speed * np.array([np.sin(np.deg2rad(course)), np.cos(np.deg2rad(course))])
        on = (t >= t0) & ((t < t1) | (k == len(legs) - 1))
        pos[on] = p + v * (t[on] - t0)[:, None]
        p, t0 = p + v * (t1 - t0), t1
    return pos
