"""State estimation from the robot's own sensors (encoders, gyro); depends on robot and plain data only."""

__all__ = ["estimator", "odometry", "silence", "slip", "slipprobe", "spins", "stall"]
