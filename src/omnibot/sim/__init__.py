"""The simulator: rigid-body physics with motors, wheels, rollers and floor surfaces, sensors and a world."""

__all__ = ["device", "emulator", "kernels", "physics", "simulator", "world"]
