"""The simulated depth camera: MuJoCo's depth buffer, rendered headless (EGL)."""

from __future__ import annotations

import mujoco
import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from footfall.sensing.camera import PinholeCamera
from footfall.sensing.pose import Pose
from footfall.sim.model import ROBOT_GEOM_GROUP, CameraMount

# MuJoCo cameras look along -z with y up; the optical frame looks along +z with y down.
_MUJOCO_TO_OPTICAL = np.diag([1.0, -1.0, -1.0])


class SimDepthCamera:
    """Renders depth images from the ``depth`` camera of a model built with a mount.

    The depth is the distance along the optical axis [m], as a real depth camera reports it;
    pixels that see nothing within ``max_range`` read 0 (no return). The robot's own geoms
    are not rendered: the camera sees the terrain as a real pipeline does after its
    self-filter has removed the legs.

    Args:
        model: Compiled model containing a camera named ``depth``.
        mount: The camera's mount and intrinsics (image size sets the render size).
    """

    def __init__(self, model: mujoco.MjModel, mount: CameraMount) -> None:
        self.mount = mount
        self._model = model
        self._camera_id = model.camera("depth").id
        fx, fy = mount.focal_lengths
        # MuJoCo casts each pixel's ray through the pixel's centre, so with pixel indices
        # as coordinates the principal point sits at (W - 1) / 2, (H - 1) / 2.
        self.intrinsics = PinholeCamera(
            fx,
            fy,
            0.5 * (mount.width - 1),
            0.5 * (mount.height - 1),
            mount.width,
            mount.height,
            0.0,
            mount.max_range,
        )
        self._scene_option = mujoco.MjvOption()
        self._scene_option.geomgroup[ROBOT_GEOM_GROUP] = 0
        self._scene_option.sitegroup[:] = 0  # sites are markers, not surfaces
        self._open_renderer: mujoco.Renderer | None = None

    @property
    def _renderer(self) -> mujoco.Renderer:
        """The renderer, made on first use: its GL context belongs to the thread using it."""
        if self._open_renderer is None:
            mount, model = self.mount, self._model
            renderer = mujoco.Renderer(model, height=mount.height, width=mount.width)
            # Shadows and reflections change no depth but cost most of a colour frame's
            # time in a software renderer (40 ms -> 6 ms at 320 x 240); the operator's view
            # does without them.
            flags = renderer.scene.flags
            flags[mujoco.mjtRndFlag.mjRND_SHADOW] = False
            flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = False
            renderer.enable_depth_rendering()
            self._open_renderer = renderer
        return self._open_renderer

    def pose(self, data: mujoco.MjData) -> Pose:
        """True pose of the optical frame in the world."""
        rotation = data.cam_xmat[self._camera_id].reshape(3, 3) @ _MUJOCO_TO_OPTICAL
        return Pose(data.cam_xpos[self._camera_id].copy(), Rotation.from_matrix(rotation))

    def capture(self, data: mujoco.MjData) -> tuple[npt.NDArray[np.float32], Pose]:
        """A depth image, shape (height, width) [m], and the true camera pose."""
        self._renderer.update_scene(data, camera=self._camera_id, scene_option=self._scene_option)
        depth = self._renderer.render().astype(np.float32, copy=True)
        # Rays that leave the scene hit the far clipping plane: report no return.
        depth[depth > self.mount.max_range] = 0.0
        return depth, self.pose(data)

    def capture_color(self, data: mujoco.MjData) -> npt.NDArray[np.uint8]:
        """A colour image of the same view, shape (height, width, 3), ``uint8`` RGB."""
        self._renderer.disable_depth_rendering()
        try:
            self._renderer.update_scene(
                data, camera=self._camera_id, scene_option=self._scene_option
            )
            return self._renderer.render().copy()
        finally:
            self._renderer.enable_depth_rendering()

    def close(self) -> None:
        """Release the rendering context (on the thread that rendered)."""
        if self._open_renderer is not None:
            self._open_renderer.close()
            self._open_renderer = None
