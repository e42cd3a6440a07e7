"""Scenes as data: the thesis' bench scenes, the pendulum's, the bench twin, perturbations."""
