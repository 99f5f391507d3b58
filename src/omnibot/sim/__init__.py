"""The simulator: rigid-body physics with motors, wheels, rollers and floor surfaces, sensors and a world."""
