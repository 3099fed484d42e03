"""The camera's path from its own depth images: registration-based odometry."""
