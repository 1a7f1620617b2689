"""Clutter: a homogeneous Poisson point process over a rectangular surveillance region.

The number of false measurements per scan is Poisson with mean ``density * area``; their positions
are uniform over the region (Bar-Shalom, Daum, Huang 2009, "The probabilistic data association
filter", IEEE CSM, sec. "Clutter model").
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.errors import require


@dataclass(frozen=True, slots=True)
class Region:
    """Axis-aligned rectangle [x_min, x_max] x [y_min, y_max] (m)."""

    x_min_m: float
    x_max_m: float
    y_min_m: float
    y_max_m: float

    def __post_init__(self):
        require(self.x_max_m > self.x_min_m and self.y_max_m > self.y_min_m,
                "surveillance region must have x_max > x_min and y_max > y_min")

    @property
    def area_m2(self) -> float:
        """Area of the rectangle (m^2)."""
        return (self.x_max_m - self.x_min_m) * (self.y_max_m - self.y_min_m)

    def contains(self, xy) -> np.ndarray:
        """True where a point lies in the rectangle (edges included).

        Parameters
        ----------
        xy : array_like, shape (..., 2)
            Points [x, y] (m, x east, y north).

        Returns
        -------
        ndarray of bool, shape (...)
            Inside or on the boundary.
        """
        xy = np.asarray(xy, float)
        return ((xy[..., 0] >= self.x_min_m) & (xy[..., 0] <= self.x_max_m)
                & (xy[..., 1] >= self.y_min_m) & (xy[..., 1] <= self.y_max_m))


def poisson_clutter(rng: np.random.Generator, density_per_m2: float, region: Region) -> np.ndarray:
    """Clutter positions: n ~ Poisson(density * area) points, uniform over ``region``.

    Parameters
    ----------
    rng : numpy.random.Generator
        Random stream.
    density_per_m2 : float
        Mean number of false measurements per m^2 per scan.
    region : Region
        Surveillance region.

    Returns
    -------
    ndarray, shape (n, 2)
        Positions [x, y] (m).
    """
    n = rng.poisson(density_per_m2 * region.area_m2)
    x = rng.uniform(region.x_min_m, region.x_max_m, n)
    y = rng.uniform(region.y_min_m, region.y_max_m, n)
    return np.stack([x, y], axis=-1)
