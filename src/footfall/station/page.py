"""The base station (thesis H7.2): a browser page over the robot's messages, with viser.

It shows what the robot sends, the depth image, the height and score maps (as images, and as
a coloured 3-D surface with the robot's body, feet and footholds on it), the pose, the gait
status (state, why it froze, which leg), the log, and the link (last message's age); and it
sends the operator's mode and walk command, each on change and repeated at
``HEARTBEAT_HZ`` as the robot's watchdog expects. A goal clicked on the ground is walked to
along the route planner's routes on the robot's map (the navigation node, replanning on a
worker thread so the page never waits for a plan), as ``footfall walk`` does; it stands
still and says why when no route is open. Until a map has come (a robot without a camera)
the command points straight at the goal. Either way it ends at the goal.

It is one module: the page's widgets, the handlers that fill them and the loop that sends
the commands share one station's state.
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Callable

import numpy as np

from footfall.biped.planner import FOOT_LENGTH, FOOT_WIDTH
from footfall.errors import FootfallError
from footfall.messages import (
    Ack,
    BipedPlan,
    ColorImage,
    DepthFrame,
    EffectorTargets,
    GaitStatus,
    LogLine,
    MapUpdate,
    Message,
    Mode,
    ModeCommand,
    Obstacles,
    PlanningGoal,
    RobotState,
    Touchdown,
    Trigger,
    WalkCommand,
)
from footfall.nodes.navigation import NavigatorNode
from footfall.planning.navigation import NavigationConfig
from footfall.robot.spec import HexapodSpec, load_spec
from footfall.runtime.zenoh_bus import ZenohBus
from footfall.station.views import (
    circles_segments,
    depth_image,
    feet_segments,
    ground_point,
    map_surface,
    polyline_segments,
    score_image,
)

# Commands and the mode repeat this often [Hz]: well inside the robot's 0.5 s watchdog.
HEARTBEAT_HZ = 5.0
# Images and the 3-D map are redrawn at most this often [Hz].
DRAW_HZ = 5.0
# The link counts as up while the last message is younger than this [s].
LINK_TIMEOUT_S = 1.0
# A clicked goal counts as reached within this distance [m].
GOAL_TOLERANCE_M = 0.1
DIRECTIONS = {"forward": 0.0, "left": 90.0, "back": 180.0, "right": -90.0}


class Station:
    """The base station's page and its link to the robot.

    Args:
        bus: The network bus to the robot.
        host: Address the page is served on.
        port: Port of the page.
        biped: The biped's page (its services) rather than the hexapod's.
        spec: The hexapod (its legs' span sizes the routes' clearance); the default robot
            unless given.
    """

    def __init__(
        self,
        bus: ZenohBus,
        host: str = "127.0.0.1",
        port: int = 8080,
        biped: bool = False,
        spec: HexapodSpec | None = None,
    ) -> None:
        import viser

        self.bus = bus
        self.biped = biped
        self.navigator = (
            None
            if biped
            else NavigatorNode(
                bus,
                spec or load_spec("default"),
                config=NavigationConfig(goal_tolerance_m=GOAL_TOLERANCE_M),
                background=True,
            )
        )
        self.obstacles: Obstacles | None = None
        self.plan: BipedPlan | None = None
        self.server = viser.ViserServer(host=host, port=port, verbose=False)
        self.mode = Mode.TORQUE_OFF
        self.direction_deg = 0.0
        self.speed = 0.0
        self.goal: tuple[float, float] | None = None
        self.last_heard = -math.inf
        self.status: GaitStatus | None = None
        self.state: RobotState | None = None
        self.targets: EffectorTargets | None = None
        self.depth: DepthFrame | None = None
        self.color: ColorImage | None = None
        self.map: MapUpdate | None = None
        self.footholds: deque[np.ndarray] = deque(maxlen=120)
        self.log: deque[str] = deque(maxlen=8)
        self._dirty = True
        self._next_beat = 0.0
        self._next_draw = 0.0
        self._route_line = None
        self._build_page()
        for topic, handler in (
            (GaitStatus.TOPIC, self._on_status),
            (RobotState.TOPIC, self._on_state),
            (EffectorTargets.TOPIC, self._on_targets),
            (DepthFrame.TOPIC, self._on_depth),
            (ColorImage.TOPIC, self._on_color),
            (MapUpdate.TOPIC, self._on_map),
            (Touchdown.TOPIC, self._on_touchdown),
            (LogLine.TOPIC, self._on_log),
            (Obstacles.TOPIC, self._on_obstacles),
            (BipedPlan.TOPIC, self._on_plan),
        ):
            bus.subscribe(topic, handler)

    # The page ----------------------------------------------------------------------------
    def _build_page(self) -> None:
        gui = self.server.gui
        self.link_text = gui.add_markdown("**link:** waiting for the robot")
        with gui.add_folder("mode", visible=not self.biped):
            for label, mode in (("torque off", Mode.TORQUE_OFF), ("walking", Mode.WALKING)):
                button = gui.add_button(label)
                button.on_click(lambda _event, mode=mode: self._set_mode(mode))
        with gui.add_folder("walk", visible=not self.biped):
            for label, degrees in DIRECTIONS.items():
                button = gui.add_button(label)
                button.on_click(lambda _event, d=degrees: self._set_direction(d))
            gui.add_button("stop").on_click(lambda _event: self._stop())
            self.speed_slider = gui.add_slider("speed [m/s]", 0.0, 0.2, 0.01, 0.1)
            self.height_slider = gui.add_slider("body height [m]", 0.06, 0.14, 0.005, 0.09)
            self.yaw_slider = gui.add_slider("yaw rate [rad/s]", -0.5, 0.5, 0.05, 0.0)
            for slider in (self.speed_slider, self.height_slider, self.yaw_slider):
                slider.on_update(lambda _event: self._changed())
        self.status_text = gui.add_markdown("**status:** -")
        self.pose_text = gui.add_markdown("**pose:** -")
        self.depth_image = gui.add_image(np.zeros((24, 32, 3), np.uint8), label="depth")
        self.color_image = gui.add_image(np.zeros((24, 32, 3), np.uint8), label="colour")
        self.score_image = gui.add_image(np.zeros((32, 32, 3), np.uint8), label="score map")
        self.log_text = gui.add_markdown("**log:** -")
        if self.biped:
            with gui.add_folder("biped"):
                for label, service in (
                    ("start capture", "start_capture"),
                    ("stop capture", "stop_capture"),
                    ("clear", "clear"),
                ):
                    button = gui.add_button(label)
                    button.on_click(lambda _event, s=service: self.call(s, Trigger()))
                self.biped_text = gui.add_markdown("**biped:** click the ground to plan to it")
        self.server.scene.add_grid("/ground", width=6.0, height=6.0, position=(2.0, 0.0, 0.0))

        @self.server.scene.on_click()
        def clicked(event) -> None:
            point = ground_point(event.ray_origin, event.ray_direction)
            if point is not None:
                self.set_goal(point)

    def _set_mode(self, mode: Mode) -> None:
        self.mode = mode
        self._changed()

    def _clear_goal(self) -> None:
        self.goal = None
        if self.navigator is not None:
            self.navigator.set_goal(None)

    def _set_direction(self, degrees: float) -> None:
        self._clear_goal()
        self.direction_deg = degrees
        self.speed = float(self.speed_slider.value)
        self._changed()

    def _stop(self) -> None:
        self._clear_goal()
        self.speed = 0.0
        self._changed()

    def set_goal(self, xy: tuple[float, float]) -> None:
        """Walk to a point on the ground (map frame) [m]; for the biped, plan to it."""
        self.server.scene.add_icosphere(
            "/goal", radius=0.03, color=(250, 200, 0), position=(xy[0], xy[1], 0.02)
        )
        if self.biped:
            self.call("start_planning", PlanningGoal(xy[0], xy[1]))
            return
        self.goal = (float(xy[0]), float(xy[1]))
        if self.navigator is not None:
            self.navigator.set_goal(self.goal)
        self._changed()

    def call(self, service: str, request: Message) -> Ack:
        """Ask one of the biped's services; the answer shows on the page."""
        try:
            reply = self.bus.request(service, request, timeout=3.0)
        except FootfallError as exc:
            reply = Ack(False, str(exc))
        if not isinstance(reply, Ack):
            reply = Ack(False, f"{service} answered a {type(reply).__name__}")
        if self.biped:
            verdict = "done" if reply.ok else "refused"
            self.biped_text.content = f"**biped:** {service} {verdict}: {reply.text}"
        return reply

    def _changed(self) -> None:
        self._dirty = True

    # What the robot says -----------------------------------------------------------------
    def _heard(self) -> None:
        self.last_heard = time.monotonic()

    def _on_status(self, m: GaitStatus) -> None:
        self._heard()
        self.status = m

    def _on_state(self, m: RobotState) -> None:
        self._heard()
        self.state = m

    def _on_targets(self, m: EffectorTargets) -> None:
        self.targets = m

    def _on_depth(self, m: DepthFrame) -> None:
        self._heard()
        self.depth = m

    def _on_color(self, m: ColorImage) -> None:
        self.color = m

    def _on_map(self, m: MapUpdate) -> None:
        self.map = m

    def _on_touchdown(self, m: Touchdown) -> None:
        self.footholds.append(np.asarray(m.chosen_in_world, dtype=np.float32))

    def _on_obstacles(self, m: Obstacles) -> None:
        self._heard()
        self.obstacles = m

    def _on_plan(self, m: BipedPlan) -> None:
        self._heard()
        self.plan = m

    def _on_log(self, m: LogLine) -> None:
        self.log.append(f"`{m.stamp:8.2f}` {m.node} {m.level}: {m.text}")

    # The loop ----------------------------------------------------------------------------
    def command(self) -> WalkCommand:
        """The walk command the controls (or the goal) ask for now."""
        height = float(self.height_slider.value)
        yaw_rate = float(self.yaw_slider.value)
        if self.goal is not None and self.status is not None:
            pose = self.status.body_pose
            dx, dy = self.goal[0] - pose.x, self.goal[1] - pose.y
            if math.hypot(dx, dy) < GOAL_TOLERANCE_M:
                self._clear_goal()
                return WalkCommand(speed=0.0, body_height=height)
            speed = float(self.speed_slider.value) or 0.1
            if self.navigator is not None and self.map is not None:
                base = WalkCommand(speed=speed, body_height=height)
                return self.navigator.command(time.monotonic(), self.status, base)
            c, s = math.cos(pose.yaw), math.sin(pose.yaw)
            direction = (c * dx + s * dy, -s * dx + c * dy)
            return WalkCommand(direction, speed, height, yaw_rate)
        a = math.radians(self.direction_deg)
        return WalkCommand((math.cos(a), math.sin(a)), self.speed, height, yaw_rate)

    def step(self) -> None:
        """Take in what arrived, send the command (changed or due) and redraw the page."""
        self.bus.spin()
        now = time.monotonic()
        due = self._dirty or now >= self._next_beat or self.goal is not None
        if due and not self.biped:  # the biped is driven through its services
            stamp = time.time()
            self.bus.publish(ModeCommand.TOPIC, ModeCommand(self.mode, stamp))
            command = self.command()
            self.bus.publish(
                WalkCommand.TOPIC,
                WalkCommand(
                    command.direction,
                    command.speed,
                    command.body_height,
                    command.yaw_rate,
                    stamp,
                ),
            )
            self._dirty = False
            self._next_beat = now + 1.0 / HEARTBEAT_HZ
        if now >= self._next_draw:
            self._draw(now)
            self._next_draw = now + 1.0 / DRAW_HZ

    def _draw(self, now: float) -> None:
        age = now - self.last_heard
        up = age < LINK_TIMEOUT_S
        self.link_text.content = (
            f"**link:** {'connected' if up else 'lost'}, last message "
            + (f"{age:.2f} s ago" if math.isfinite(age) else "never")
            + ("" if self.biped else f"; sending **{self.mode.value}**")
        )
        if self.status is not None:
            s = self.status
            why = f", **{s.frozen_reason}**" if s.frozen_reason else ""
            leg = f" (leg {s.frozen_leg})" if s.frozen_leg else ""
            route = ""
            navigator = self.navigator
            if self.goal is not None and navigator is not None and navigator.no_route is not None:
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
        if self.log:
            self.log_text.content = "**log:**\n\n" + "\n\n".join(self.log)
        scene = self.server.scene
        if self.depth is not None:
            self.depth_image.image = depth_image(self.depth)
        if self.color is not None:
            self.color_image.image = np.ascontiguousarray(self.color.image)
        if self.map is not None:
            self.score_image.image = score_image(self.map)
            vertices, walkable, other = map_surface(self.map)
            for name, faces, color in (
                ("/map/walkable", walkable, (60, 180, 90)),
                ("/map/invalid", other, (210, 50, 50)),
            ):
                if len(faces):
                    scene.add_mesh_simple(name, vertices, faces, color=color, side="double")
        if self.state is not None and self.status is not None:
            p = self.status.body_pose
            q = self.state.orientation_body_in_world.as_quat()  # x, y, z, w
            scene.add_box(
                "/robot/body",
                color=(80, 120, 220),
                dimensions=(0.26, 0.16, 0.05),
                position=(p.x, p.y, self.status.body_z),
                wxyz=(q[3], q[0], q[1], q[2]),
            )
        if self.targets is not None:
            feet = np.asarray(self.targets.feet_in_world, dtype=np.float32)
            colors = np.where(self.targets.swinging[:, None], [[250, 160, 0]], [[20, 20, 20]])
            scene.add_point_cloud("/robot/feet", feet, colors.astype(np.uint8), point_size=0.04)
        if self.footholds:
            holds = np.stack(self.footholds)
            scene.add_point_cloud("/footholds", holds, (0, 220, 0), point_size=0.025)
        route = None if self.navigator is None or self.goal is None else self.navigator.route
        if route is not None and len(route.points_in_world) >= 2:
            self._route_line = scene.add_line_segments(
                "/route", polyline_segments(route.points_in_world, 0.03), (30, 60, 230)
            )
        elif self._route_line is not None:
            self._route_line.remove()
            self._route_line = None
        self._draw_biped()

    def _draw_biped(self) -> None:
        """Obstacles red, path blue, footsteps green, the COM black (the dissertation's)."""
        scene = self.server.scene
        if self.obstacles is not None:
            o = self.obstacles
            scene.add_line_segments(
                "/biped/obstacles", circles_segments(o.x, o.y, o.r), (220, 30, 30)
            )
        if self.plan is not None:
            p = self.plan
            scene.add_line_segments("/biped/path", polyline_segments(p.waypoints), (30, 60, 230))
            feet = feet_segments(p.footsteps, FOOT_LENGTH, FOOT_WIDTH)
            scene.add_line_segments("/biped/footsteps", feet, (20, 170, 40))
            scene.add_line_segments("/biped/com", polyline_segments(p.com, 0.02), (0, 0, 0))

    def run(
        self,
        seconds: float | None = None,
        rate_hz: float = 50.0,
        stop: Callable[[], bool] | None = None,
    ) -> None:
        """Serve the page and keep the link until the time is up (forever by default).

        Args:
            seconds: Longest run [s].
            rate_hz: Rate of the page's updates and the commands' heartbeat [Hz].
            stop: Asked between two updates; True ends the run (a signal caught).
        """
        end = math.inf if seconds is None else time.monotonic() + seconds
        while time.monotonic() < end and not (stop is not None and stop()):
            self.step()
            self.bus.spin(1.0 / rate_hz)

    def close(self) -> None:
        """Stop serving the page (and the route planner's worker)."""
        if self.navigator is not None:
            self.navigator.close()
        self.server.stop()
