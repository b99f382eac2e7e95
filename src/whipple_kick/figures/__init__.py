"""Figures: the response plots and the animation of a run."""
