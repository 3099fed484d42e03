"""MuJoCo simulation: the model generated from a robot spec, and the simulated robot backend."""
