"""Core numerics shared by every layer: angles, Gaussian densities, small linear algebra, random streams."""
