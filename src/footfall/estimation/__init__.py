"""State estimation: where the robot is from its own sensors (leg kinematics and an IMU)."""
