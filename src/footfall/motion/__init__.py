"""Motion: leg kinematics, gaits, swing trajectories and the walking controller."""
