"""What the base station's page shows of the robot: text, images and the 3-D scene."""

from __future__ import annotations

import math

import numpy as np

from footfall.biped.planner import FOOT_LENGTH, FOOT_WIDTH
from footfall.messages import Mode, ServoStatus
from footfall.nodes.navigation import NavigatorNode
from footfall.station.inbox import RobotView
from footfall.station.views import (
    circles_segments,
    depth_image,
    feet_segments,
    map_surface,
    polyline_segments,
    score_image,
)

# The link counts as up while the last message is younger than this [s].
LINK_TIMEOUT_S = 1.0


class PageView:
    """The page's read-outs and its 3-D scene, drawn from a :class:`RobotView`.

    Args:
        server: The viser server.
        biped: The biped's page (no mode is sent).
    """

    def __init__(self, server, biped: bool) -> None:
        self.server = server
        self.biped = biped
        self._route_line = None
        gui = server.gui
        self.link_text = gui.add_markdown("**link:** waiting for the robot")

    def add_readouts(self) -> None:
        """Add the status, pose, images and log (below the controls)."""
        gui = self.server.gui
        self.status_text = gui.add_markdown("**status:** -")
        self.pose_text = gui.add_markdown("**pose:** -")
        self.servo_text = gui.add_markdown("**servos:** -")
        self.depth_image = gui.add_image(np.zeros((24, 32, 3), np.uint8), label="depth")
        self.color_image = gui.add_image(np.zeros((24, 32, 3), np.uint8), label="colour")
        self.score_image = gui.add_image(np.zeros((32, 32, 3), np.uint8), label="score map")
        self.log_text = gui.add_markdown("**log:** -")

    def draw(
        self,
        now: float,
        robot: RobotView,
        mode: Mode,
        navigator: NavigatorNode | None,
        goal: tuple[float, float] | None,
    ) -> None:
        """Redraw everything from what the robot last said.

        Args:
            now: ``time.monotonic()`` [s].
            robot: What the robot said.
            mode: The mode being sent.
            navigator: The route planner (hexapod), or None.
            goal: The clicked goal being walked to, or None.
        """
        age = now - robot.last_heard
        up = age < LINK_TIMEOUT_S
        self.link_text.content = (
            f"**link:** {'connected' if up else 'lost'}, last message "
            + (f"{age:.2f} s ago" if math.isfinite(age) else "never")
            + f"; sending **{mode.value}**"
        )
        if robot.status is not None:
            s = robot.status
            why = f", **{s.frozen_reason}**" if s.frozen_reason else ""
            leg = f" (leg {s.frozen_leg})" if s.frozen_leg else ""
            route = ""
            if goal is not None and navigator is not None and navigator.no_route is not None:
                route = f"; **standing still: {navigator.no_route.reason}**"
            self.status_text.content = (
                f"**status:** {s.mode.value}, {s.state.value}{why}{leg}; "
                f"{s.steps_taken} steps, {s.footholds_adjusted} footholds adjusted{route}"
            )
            p = s.body_pose
            self.pose_text.content = (
                f"**pose:** x {p.x:.3f} m, y {p.y:.3f} m, yaw {math.degrees(p.yaw):.1f} deg, "
                f"body z {s.body_z:.3f} m"
            )
        if robot.biped is not None:
            b = robot.biped
            self.status_text.content = (
                f"**status:** {b.state}, {b.footsteps} footsteps, {b.collisions} collisions; "
                f"{b.text}"
            )
            self.pose_text.content = (
                f"**pose:** COM x {b.com[0]:.3f} m, y {b.com[1]:.3f} m, "
                f"heading {math.degrees(b.heading):.1f} deg"
            )
        if robot.servos is not None:
            self.servo_text.content = servo_readout(robot.servos)
        if robot.log:
            self.log_text.content = "**log:**\n\n" + "\n\n".join(robot.log)
        if robot.depth is not None:
            self.depth_image.image = depth_image(robot.depth)
        if robot.color is not None:
            self.color_image.image = np.ascontiguousarray(robot.color.image)
        self._draw_scene(robot)
        self._draw_route(None if navigator is None or goal is None else navigator.route)
        self._draw_biped(robot)

    def _draw_scene(self, robot: RobotView) -> None:
        """The map (walkable green, invalid red), the body, the feet and the footholds."""
        scene = self.server.scene
        if robot.map is not None:
            self.score_image.image = score_image(robot.map)
            vertices, walkable, other = map_surface(robot.map)
            for name, faces, color in (
                ("/map/walkable", walkable, (60, 180, 90)),
                ("/map/invalid", other, (210, 50, 50)),
            ):
                if len(faces):
                    scene.add_mesh_simple(name, vertices, faces, color=color, side="double")
        if robot.state is not None and robot.status is not None:
            p = robot.status.body_pose
            q = robot.state.orientation_body_in_world.as_quat()  # x, y, z, w
            scene.add_box(
                "/robot/body",
                color=(80, 120, 220),
                dimensions=(0.26, 0.16, 0.05),
                position=(p.x, p.y, robot.status.body_z),
                wxyz=(q[3], q[0], q[1], q[2]),
            )
        if robot.targets is not None:
            feet = np.asarray(robot.targets.feet_in_world, dtype=np.float32)
            colors = np.where(robot.targets.swinging[:, None], [[250, 160, 0]], [[20, 20, 20]])
            scene.add_point_cloud("/robot/feet", feet, colors.astype(np.uint8), point_size=0.04)
        if robot.footholds:
            holds = np.stack(robot.footholds)
            scene.add_point_cloud("/footholds", holds, (0, 220, 0), point_size=0.025)

    def _draw_route(self, route) -> None:
        if route is not None and len(route.points_in_world) >= 2:
            self._route_line = self.server.scene.add_line_segments(
                "/route", polyline_segments(route.points_in_world, 0.03), (30, 60, 230)
            )
        elif self._route_line is not None:
            self._route_line.remove()
            self._route_line = None

    def _draw_biped(self, robot: RobotView) -> None:
        """Obstacles red, path blue, footsteps green, the COM black (the dissertation's)."""
        scene = self.server.scene
        if robot.obstacles is not None:
            o = robot.obstacles
            scene.add_line_segments(
                "/biped/obstacles", circles_segments(o.x, o.y, o.r), (220, 30, 30)
            )
        if robot.plan is not None:
            p = robot.plan
            scene.add_line_segments("/biped/path", polyline_segments(p.waypoints), (30, 60, 230))
            feet = feet_segments(p.footsteps, FOOT_LENGTH, FOOT_WIDTH)
            scene.add_line_segments("/biped/footsteps", feet, (20, 170, 40))
            scene.add_line_segments("/biped/com", polyline_segments(p.com, 0.02), (0, 0, 0))
        if robot.biped is not None:  # where the walking biped's feet stand now
            b = robot.biped
            feet = feet_segments(np.asarray(b.feet), FOOT_LENGTH, FOOT_WIDTH)
            scene.add_line_segments("/biped/feet", feet, (250, 160, 0))
            scene.add_icosphere(
                "/biped/body", radius=0.05, color=(80, 120, 220), position=(*b.com, 0.6)
            )


def servo_readout(status: ServoStatus) -> str:
    """The servos line: posture, the hottest servo, the lowest voltage, the fault."""
    text = f"**servos:** {status.posture.value}"
    if status.temperatures_c is not None and np.isfinite(status.temperatures_c).any():
        hottest = int(np.nanargmax(status.temperatures_c))
        text += f"; hottest {status.temperatures_c[hottest]:.0f} °C (joint {hottest})"
    if status.voltages_v is not None and np.isfinite(status.voltages_v).any():
        text += f"; supply {np.nanmin(status.voltages_v):.1f} V"
    if status.fault:
        text += f"; **{status.fault}**"
    return text
