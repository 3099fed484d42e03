"""MuJoCo simulation: the model generated from a robot spec, and the simulated robot backend.

Importing this package makes headless EGL the default OpenGL backend for MuJoCo's
renderer (``MUJOCO_GL=egl``) unless the user has chosen one.
"""

import os

os.environ.setdefault("MUJOCO_GL", "egl")
