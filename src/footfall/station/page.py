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

What the robot says is kept by :class:`~footfall.station.inbox.RobotView` and drawn by
:class:`~footfall.station.drawing.PageView`; this module holds the operator's controls and
the loop that sends the commands.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

from footfall.errors import FootfallError
from footfall.messages import (
    Ack,
    Message,
    Mode,
    ModeCommand,
    PlanningGoal,
    Trigger,
    WalkCommand,
)
from footfall.nodes.navigation import NavigatorNode
from footfall.planning.navigation import NavigationConfig
from footfall.robot.spec import HexapodSpec, load_spec
from footfall.runtime.zenoh_bus import ZenohBus
from footfall.station.drawing import PageView
from footfall.station.inbox import RobotView
from footfall.station.views import ground_point

# Commands and the mode repeat this often [Hz]: well inside the robot's 0.5 s watchdog.
HEARTBEAT_HZ = 5.0
# Images and the 3-D map are redrawn at most this often [Hz].
DRAW_HZ = 5.0
# A clicked goal counts as reached within this distance [m].
GOAL_TOLERANCE_M = 0.1
# A goal given before the robot answers is sent this many times at most, a second apart.
PENDING_GOAL_TRIES = 10
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

    Attributes:
        robot: What the robot has said.
        page: The page's read-outs and 3-D scene.
        navigator: The route planner a clicked goal is walked to with (hexapod), or None.
        mode: The mode sent.
        goal: The clicked goal being walked to, or None.
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
        self.server = viser.ViserServer(host=host, port=port, verbose=False)
        self.robot = RobotView()
        # The biped walks the goals planned to while the station says walking.
        self.mode = Mode.WALKING if biped else Mode.TORQUE_OFF
        self.direction_deg = 0.0
        self.speed = 0.0
        self.goal: tuple[float, float] | None = None
        self._dirty = True
        self._next_beat = 0.0
        self._next_draw = 0.0
        self.pending_goal: tuple[float, float] | None = None  # sent once the robot is heard
        self.answered = True  # whether the last service asked answered (else: no reply)
        self._goal_tries = 0
        self._next_goal_try = 0.0
        self.page = PageView(self.server, biped)
        self._build_controls()
        self.page.add_readouts()
        self._build_biped_controls()
        self.robot.listen(bus)

    # The controls ------------------------------------------------------------------------
    def _build_controls(self) -> None:
        gui = self.server.gui
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

    def _build_biped_controls(self) -> None:
        gui = self.server.gui
        if self.biped:
            with gui.add_folder("biped"):
                for label, service in (
                    ("start capture", "start_capture"),
                    ("stop capture", "stop_capture"),
                    ("clear", "clear"),
                ):
                    button = gui.add_button(label)
                    button.on_click(lambda _event, s=service: self.call(s, Trigger()))
                for label, mode in (("stop walking", Mode.TORQUE_OFF), ("walk", Mode.WALKING)):
                    button = gui.add_button(label)
                    button.on_click(lambda _event, mode=mode: self._set_mode(mode))
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

    def set_goal(self, xy: tuple[float, float]) -> Ack:
        """Walk to a point on the ground (map frame) [m]; for the biped, plan to it."""
        self.server.scene.add_icosphere(
            "/goal", radius=0.03, color=(250, 200, 0), position=(xy[0], xy[1], 0.02)
        )
        if self.biped:
            return self.call("start_planning", PlanningGoal(xy[0], xy[1]))
        self.goal = (float(xy[0]), float(xy[1]))
        if self.navigator is not None:
            self.navigator.set_goal(self.goal)
        self._changed()
        return Ack(True, f"walking to ({xy[0]:.2f}, {xy[1]:.2f})")

    def _send_pending_goal(self, now: float) -> None:
        """The goal given before the robot was heard, once it is (a few tries)."""
        if self.pending_goal is None or now < self._next_goal_try:
            return
        if not math.isfinite(self.robot.last_heard):
            return
        self._goal_tries += 1
        self._next_goal_try = now + 1.0
        reply = self.set_goal(self.pending_goal)
        if reply.ok or self.answered or self._goal_tries >= PENDING_GOAL_TRIES:
            self.pending_goal = None  # walked, refused with a reason, or never answered

    def call(self, service: str, request: Message) -> Ack:
        """Ask one of the biped's services; the answer shows on the page."""
        self.answered = False
        try:
            reply = self.bus.request(service, request, timeout=3.0)
            self.answered = True
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

    # The loop ----------------------------------------------------------------------------
    def command(self) -> WalkCommand:
        """The walk command the controls (or the goal) ask for now."""
        height = float(self.height_slider.value)
        yaw_rate = float(self.yaw_slider.value)
        status = self.robot.status
        if self.goal is not None and status is not None:
            pose = status.body_pose
            dx, dy = self.goal[0] - pose.x, self.goal[1] - pose.y
            if math.hypot(dx, dy) < GOAL_TOLERANCE_M:
                self._clear_goal()
                return WalkCommand(speed=0.0, body_height=height)
            speed = float(self.speed_slider.value) or 0.1
            if self.navigator is not None and self.robot.map is not None:
                base = WalkCommand(speed=speed, body_height=height)
                return self.navigator.command(time.monotonic(), status, base)
            c, s = math.cos(pose.yaw), math.sin(pose.yaw)
            direction = (c * dx + s * dy, -s * dx + c * dy)
            return WalkCommand(direction, speed, height, yaw_rate)
        a = math.radians(self.direction_deg)
        return WalkCommand((math.cos(a), math.sin(a)), self.speed, height, yaw_rate)

    def step(self) -> None:
        """Take in what arrived, send the command (changed or due) and redraw the page."""
        self.bus.spin()
        now = time.monotonic()
        self._send_pending_goal(now)
        due = self._dirty or now >= self._next_beat or self.goal is not None
        if due:  # the biped's goals go through its services; it hears the mode alone
            stamp = time.time()
            self.bus.publish(ModeCommand.TOPIC, ModeCommand(self.mode, stamp))
            self._dirty = False
            self._next_beat = now + 1.0 / HEARTBEAT_HZ
        if due and not self.biped:
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
        if now >= self._next_draw:
            self.draw(now)
            self._next_draw = now + 1.0 / DRAW_HZ

    def draw(self, now: float) -> None:
        """Redraw the page from what the robot last said (``now``: ``time.monotonic()``)."""
        self.page.draw(now, self.robot, self.mode, self.navigator, self.goal)

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
