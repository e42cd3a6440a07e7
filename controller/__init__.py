"""Discrete position controller, numerical derivators and reference trajectories of the 5R robot."""
