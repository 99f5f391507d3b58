"""Runnable demonstrations built on the public API (``omnibot tour``, ``omnibot demo``)."""

__all__ = ["directions", "seed000"]
