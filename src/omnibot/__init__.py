"""omnibot: drive omnidirectional (omni-wheel and mecanum) mobile robots, real or simulated."""

__version__ = "0.1.0"

__all__ = ["__version__"]
