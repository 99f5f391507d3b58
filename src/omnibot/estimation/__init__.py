"""State estimation from the robot's own sensors (encoders, gyro); depends on robot and plain data only."""
