"""A run logged for the rerun viewer: what a person scrubs through on a time line.

A :class:`RerunLogger` taps a bus and logs, on the ``sim_time`` timeline:

- ``world/camera`` (the depth camera's pose and pinhole) with ``world/camera/depth``;
- ``world/points``: the depth frame's points in the world (subsampled);
- ``world/map/surface``: the height map as a mesh coloured by height, and ``map/score``:
  the score map as an image (valid green to yellow by score, invalid red, unknown grey);
- ``world/body`` and ``world/feet/<leg>``: the body and foot transforms; ``world/swing``:
  the swinging feet's paths; ``world/footholds/nominal`` and ``.../chosen``;
- ``plots/body_height_m`` and ``plots/tilt_deg``;
- for the biped: ``world/biped/obstacles``, ``.../path``, ``.../footsteps``, ``.../com``;

with a blueprint that lays out the 3-D view, the images and the plots side by side.
rerun-sdk is the ``footfall[viz]`` extra (it is several hundred MB).
"""

from __future__ import annotations

import math
from collections import deque
from pathlib import Path

import numpy as np
import numpy.typing as npt

from footfall.errors import ConfigError
from footfall.messages import (
    DepthFrame,
    EffectorTargets,
    MapUpdate,
    PoseEstimate,
    RobotState,
    Touchdown,
)
from footfall.messages.codec import Message
from footfall.recording.ros_types import LEG_NAMES

# Map surfaces are heavy (a mesh of up to 65 k cells): at most this often [s].
MAP_PERIOD_S = 0.5
SWING_TRAIL_S = 1.0
MAX_POINTS = 20000


def _rerun():
    try:
        import rerun as rr
    except ImportError as exc:  # the optional extra
        raise ConfigError(
            "--rerun needs the rerun SDK: install footfall[viz] (uv sync --extra viz)"
        ) from exc
    return rr


def height_colours(heights: npt.NDArray[np.float64]) -> npt.NDArray[np.uint8]:
    """RGB colours of heights, blue (low) to red (high) over their range."""
    h = np.asarray(heights, dtype=np.float64)
    lo, hi = (float(np.nanmin(h)), float(np.nanmax(h))) if np.isfinite(h).any() else (0.0, 1.0)
    t = np.clip((h - lo) / max(hi - lo, 1e-6), 0.0, 1.0)
    t = np.nan_to_num(t)
    rgb = np.stack([255 * t, 255 * (1 - np.abs(2 * t - 1)), 255 * (1 - t)], axis=-1)
    return rgb.astype(np.uint8)


def score_image(update: MapUpdate) -> npt.NDArray[np.uint8]:
    """The score map as an RGB image (row = y, up the image), shape (N, N, 3)."""
    score = np.nan_to_num(update.score, nan=0.0)
    shade = np.clip(score / 0.5, 0.0, 1.0)
    rgb = np.zeros((*score.shape, 3), dtype=np.uint8)
    rgb[..., 0] = (255 * shade).astype(np.uint8)
    rgb[..., 1] = 200
    rgb[~update.valid] = (220, 40, 40)
    rgb[~update.known] = (128, 128, 128)
    return np.ascontiguousarray(np.transpose(rgb, (1, 0, 2))[::-1])


def surface_mesh(
    update: MapUpdate,
) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.uint32], npt.NDArray[np.uint8]]:
    """Vertices, triangles and colours of the known cells' surface (two per known quad)."""
    n, m = update.heights.shape
    res = update.resolution
    i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    x = update.origin[0] + (i + 0.5) * res
    y = update.origin[1] + (j + 0.5) * res
    z = np.nan_to_num(update.heights, nan=0.0)
    vertices = np.stack([x, y, z], axis=-1).reshape(-1, 3).astype(np.float32)
    k = update.known
    quad = k[:-1, :-1] & k[1:, :-1] & k[:-1, 1:] & k[1:, 1:]
    a = (i[:-1, :-1] * m + j[:-1, :-1])[quad]
    b, c, d = a + m, a + 1, a + m + 1
    triangles = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]).astype(np.uint32)
    return vertices, triangles, height_colours(update.heights).reshape(-1, 3)


class RerunLogger:
    """Log bus messages to a rerun recording.

    Args:
        path: An ``.rrd`` file to write, or None.
        spawn: Also open a viewer.

    Raises:
        ConfigError: Neither a file nor a viewer, a file not ending in ``.rrd``, or no SDK.
    """

    def __init__(self, path: str | Path | None = None, spawn: bool = False) -> None:
        rr = _rerun()
        self.rr = rr
        if path is None and not spawn:
            raise ConfigError("rerun logging needs an .rrd file or a viewer to spawn")
        if path is not None and Path(path).suffix.lower() != ".rrd":
            raise ConfigError(f"--rerun needs a .rrd file, got {path}")
        self.rec = rr.RecordingStream("footfall")
        if spawn:
            self.rec.spawn()
        if path is not None:
            Path(path).parent.mkdir(parents=True, exist_ok=True)
            self.rec.save(str(path))
        self.rec.send_blueprint(self._blueprint())
        self.rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        self._last_map = -math.inf
        self._nominal: list[npt.NDArray] = []
        self._chosen: list[npt.NDArray] = []
        self._trail: deque[tuple[float, npt.NDArray, npt.NDArray]] = deque()
        self._camera_in_world = None

    def _blueprint(self):
        import rerun.blueprint as rrb

        return rrb.Blueprint(
            rrb.Horizontal(
                rrb.Spatial3DView(origin="world", name="world"),
                rrb.Vertical(
                    rrb.Spatial2DView(origin="world/camera", name="depth"),
                    rrb.Spatial2DView(origin="map", name="score map"),
                    rrb.TimeSeriesView(origin="plots", name="body"),
                ),
                column_shares=[3, 2],
            ),
            collapse_panels=True,
        )

    def tap(self, topic: str, message: Message) -> None:
        """Log one bus message (the signature of :meth:`InProcessBus.tap`)."""
        rr = self.rr
        stamp = getattr(message, "stamp", getattr(message, "time", None))
        if isinstance(stamp, int | float) and math.isfinite(stamp):
            self.rec.set_time("sim_time", duration=float(stamp))
        if isinstance(message, PoseEstimate):
            self._pose(message)
        elif isinstance(message, DepthFrame):
            self._depth(message)
        elif isinstance(message, MapUpdate):
            self.map(message)
        elif isinstance(message, EffectorTargets):
            self._feet(message)
        elif isinstance(message, Touchdown):
            self._nominal.append(np.asarray(message.nominal_in_world))
            self._chosen.append(np.asarray(message.chosen_in_world))
            self.rec.log(
                "world/footholds/nominal",
                rr.Points3D(self._nominal, radii=0.006, colors=(255, 200, 0)),
            )
            self.rec.log(
                "world/footholds/chosen",
                rr.Points3D(self._chosen, radii=0.008, colors=(0, 200, 255)),
            )
        elif isinstance(message, RobotState):
            self._state(message)
        elif type(message).__name__ in ("Obstacles", "BipedPlan"):
            self._biped(message)

    def _pose(self, estimate: PoseEstimate) -> None:
        rr = self.rr
        for entity, pose in (
            ("world/body", estimate.body_in_world),
            ("world/camera", estimate.camera_in_world),
        ):
            self.rec.log(
                entity,
                rr.Transform3D(
                    translation=pose.position,
                    quaternion=rr.Quaternion(xyzw=pose.rotation.as_quat()),
                ),
            )
        self._camera_in_world = estimate.camera_in_world

    def _depth(self, frame: DepthFrame) -> None:
        rr = self.rr
        c = frame.intrinsics
        self.rec.log(
            "world/camera", rr.Pinhole(image_from_camera=c.matrix, width=c.width, height=c.height)
        )
        metres = c.to_metres(np.asarray(frame.depth), frame.depth_scale).astype(np.float32)
        self.rec.log("world/camera/depth", rr.DepthImage(metres, meter=1.0))
        if self._camera_in_world is not None:
            stride = max(1, int(math.sqrt(c.width * c.height / MAX_POINTS)))
            points, _ = c.depth_to_points(frame.depth, frame.depth_scale, stride=stride)
            world = self._camera_in_world.apply(points)
            self.rec.log(
                "world/points", rr.Points3D(world, radii=0.003, colors=height_colours(world[:, 2]))
            )

    def map(self, update: MapUpdate, force: bool = False) -> None:
        """Log a map update (its surface at most every ``MAP_PERIOD_S`` unless forced)."""
        rr = self.rr
        if not force and update.stamp - self._last_map < MAP_PERIOD_S:
            return
        self._last_map = update.stamp
        self.rec.set_time("sim_time", duration=float(update.stamp))
        vertices, triangles, colours = surface_mesh(update)
        self.rec.log(
            "world/map/surface",
            rr.Mesh3D(vertex_positions=vertices, triangle_indices=triangles, vertex_colors=colours),
        )
        self.rec.log("map/score", rr.Image(score_image(update)))

    def _feet(self, targets: EffectorTargets) -> None:
        rr = self.rr
        for leg, p in zip(LEG_NAMES, targets.feet_in_world, strict=True):
            self.rec.log(f"world/feet/{leg}", rr.Transform3D(translation=p))
        self.rec.log(
            "world/feet", rr.Points3D(targets.feet_in_world, radii=0.01, colors=(240, 240, 240))
        )
        self._trail.append((targets.stamp, targets.feet_in_world.copy(), targets.swinging.copy()))
        while self._trail and targets.stamp - self._trail[0][0] > SWING_TRAIL_S:
            self._trail.popleft()
        strips = []
        for leg in range(6):
            path = [feet[leg] for _, feet, swinging in self._trail if swinging[leg]]
            if len(path) >= 2:
                strips.append(np.array(path))
        self.rec.log("world/swing", rr.LineStrips3D(strips, colors=(255, 120, 0)))

    def _state(self, state: RobotState) -> None:
        rr = self.rr
        if state.position_body_in_world is not None:
            self.rec.log("plots/body_height_m", rr.Scalars(float(state.position_body_in_world[2])))
        self.rec.log("plots/tilt_deg", rr.Scalars(math.degrees(state.tilt)))

    def _biped(self, message: Message) -> None:
        rr = self.rr
        if type(message).__name__ == "Obstacles":
            angles = np.linspace(0, 2 * np.pi, 33)
            circles = [
                np.stack([x + r * np.cos(angles), y + r * np.sin(angles), np.zeros_like(angles)], 1)
                for x, y, r in zip(message.x, message.y, message.r, strict=True)
            ]
            self.rec.log("world/biped/obstacles", rr.LineStrips3D(circles, colors=(220, 40, 40)))
            return
        flat = np.zeros((len(message.waypoints), 1))
        self.rec.log(
            "world/biped/path",
            rr.LineStrips3D([np.hstack([message.waypoints, flat])], colors=(40, 80, 255)),
        )
        steps = np.asarray(message.footsteps)
        colours = np.where(np.asarray(message.left)[:, None], (0, 200, 0), (0, 120, 0)).astype(
            np.uint8
        )
        self.rec.log(
            "world/biped/footsteps",
            rr.Boxes3D(
                centers=np.column_stack([steps[:, :2], np.zeros(len(steps))]),
                half_sizes=[(0.06, 0.03, 0.005)] * len(steps),
                rotation_axis_angles=[
                    rr.RotationAxisAngle(axis=(0, 0, 1), radians=h) for h in steps[:, 2]
                ],
                colors=colours,
            ),
        )
        com = np.hstack([message.com, np.zeros((len(message.com), 1))])
        self.rec.log("world/biped/com", rr.LineStrips3D([com], colors=(0, 0, 0)))

    def close(self) -> None:
        """Flush and finish the recording."""
        self.rec.flush()
        if hasattr(self.rec, "disconnect"):
            self.rec.disconnect()
