"""Plotting helpers (matplotlib, Agg backend); models never import this package."""

__all__ = ["figure"]
