"""The base station in a real headless browser, driving `footfall robot` over zenoh."""

from __future__ import annotations

import re
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from test_robot_network import start_robot
from test_zenoh_bus import free_port

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
# Headless Chromium renders viser's WebGL scene here in software.
CHROMIUM_ARGS = [
    "--headless=new",
    "--no-sandbox",
    "--use-gl=swiftshader",
    "--enable-unsafe-swiftshader",
    "--disable-background-networking",
    "--disable-component-update",
    "--no-first-run",
]


def _pose_x(text: str) -> float:
    match = re.search(r"pose: x (-?[\d.]+) m", text)
    assert match, text
    return float(match.group(1))


@pytest.mark.skipif(CHROMIUM is None, reason="Debian's chromium is not installed (.ci/run does)")
def test_the_station_page_shows_the_robot_and_drives_it(tmp_path):
    """Chromium opens the station: it shows the link, the status and the score map; a click
    on "walking" and one on "forward" make the robot walk (its pose changes on the page)."""
    from playwright.sync_api import sync_playwright

    endpoint = f"tcp/127.0.0.1:{free_port()}"
    port = free_port()
    robot = start_robot(endpoint, "flat", tmp_path / "robot", 90.0)
    station_log = (tmp_path / "station.txt").open("w")  # a pipe nobody reads could fill up
    station = subprocess.Popen(
        [sys.executable, "-m", "footfall.cli", "station", "--connect", endpoint]
        + ["--port", str(port), "--seconds", "80"],
        stdout=station_log,
        stderr=subprocess.STDOUT,
    )
    try:
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            page = browser.new_page(viewport={"width": 1400, "height": 900})
            end = time.monotonic() + 60.0
            while True:  # the station serves once it has started
                try:
                    page.goto(f"http://127.0.0.1:{port}", timeout=5000)
                    break
                except Exception:
                    assert time.monotonic() < end, "the station never served its page"
                    time.sleep(1.0)
            page.get_by_text("link: connected").wait_for(timeout=60000)
            page.get_by_text("status: torque_off").wait_for(timeout=30000)
            assert page.get_by_text("score map").count() >= 1
            before = _pose_x(page.inner_text("body"))
            page.get_by_role("button", name="walking").click()
            page.get_by_role("button", name="forward").click()
            page.get_by_text("status: walking, stepping").wait_for(timeout=20000)
            page.wait_for_timeout(6000)
            after = _pose_x(page.inner_text("body"))
            page.screenshot(path=str(tmp_path / "station.png"))
            browser.close()
        assert after > before + 0.15, (before, after)
        assert (tmp_path / "station.png").stat().st_size > 10_000
    finally:
        station.send_signal(signal.SIGINT)
        robot.send_signal(signal.SIGINT)
        station.wait(timeout=30)  # Ctrl-C ends the station between two updates
        robot.wait(timeout=60)
        station_log.close()
    assert station.returncode == 0, (tmp_path / "station.txt").read_text()


def test_the_station_walks_to_a_clicked_goal_and_beats_its_heart():
    """A goal is turned into a walk command in the body frame, a standstill once reached;
    the mode and the command go out at once on a change and then as a heartbeat."""
    import math

    from footfall.messages import GaitState, GaitStatus, Mode
    from footfall.robot.planar import PlanarPose
    from footfall.runtime.zenoh_bus import ZenohBus, ZenohConfig
    from footfall.station import HEARTBEAT_HZ, Station

    with ZenohBus(ZenohConfig()) as bus:
        station = Station(bus, port=free_port())
        try:
            facing_left = PlanarPose(0.0, 0.0, math.pi / 2)
            station.robot.status = GaitStatus(
                0.0, Mode.WALKING, GaitState.REST, "", "", facing_left, 0.09, 0, 0, 0.0
            )
            station.set_goal((1.0, 0.0))
            command = station.command()
            assert command.speed > 0
            assert command.direction[0] == pytest.approx(0.0, abs=1e-9)
            assert command.direction[1] == pytest.approx(-1.0)  # the goal is on its right
            station.robot.status = GaitStatus(
                1.0, Mode.WALKING, GaitState.REST, "", "", PlanarPose(0.95, 0.0), 0.09, 0, 0, 0.0
            )
            assert station.command().speed == 0.0 and station.goal is None
            start = time.monotonic()
            while time.monotonic() - start < 1.0:
                station.step()
                time.sleep(0.01)
            sent = bus.stats["command"].messages
            assert HEARTBEAT_HZ - 1 <= sent <= HEARTBEAT_HZ + 2
            assert bus.stats["mode"].messages == sent
        finally:
            station.close()


def _walled_map(sequence: int, enclosed: bool = False):
    """A 3 x 3 m map around the origin, a 30 cm wall across x = 0.5 (|y| < 0.6), scored by
    the real scorer; ``enclosed`` rings the point (1, 0) with the wall instead."""
    from footfall.messages import MapUpdate
    from footfall.scoring.walkability import score_heights

    res = 0.02
    c = -1.5 + (np.arange(150) + 0.5) * res
    x, y = np.meshgrid(c, c, indexing="ij")
    if enclosed:
        ring = np.hypot(x - 1.0, y)
        wall = (ring > 0.3) & (ring < 0.36)
    else:
        wall = (np.abs(x - 0.5) < 0.03) & (np.abs(y) < 0.6)
    h = np.where(wall, 0.3, 0.0)
    slope, proximity, score, valid = score_heights(h, res)
    return MapUpdate(
        0.0,
        sequence,
        h,
        np.ones(h.shape, bool),
        None,
        slope,
        proximity,
        score,
        valid,
        (-1.5, -1.5),
        res,
    )


def test_a_clicked_goal_is_walked_to_round_a_wall_on_the_robots_map():
    """With the robot's map, a clicked goal behind a wall gets a route round it (never
    through it) and commands that follow the route, not the straight line; a goal walled
    in gets a standstill and the reason on the page."""
    from footfall.messages import GaitState, GaitStatus, MapUpdate, Mode
    from footfall.robot.planar import PlanarPose
    from footfall.runtime.zenoh_bus import ZenohBus, ZenohConfig
    from footfall.station import Station

    status = GaitStatus(0.0, Mode.WALKING, GaitState.REST, "", "", PlanarPose(0, 0), 0.09, 0, 0, 0)

    def command_once_planned(station, until):
        while time.monotonic() < until:
            station.bus.spin(0.05)
            command = station.command()
            if station.navigator.route is not None or station.navigator.no_route is not None:
                return command
        raise AssertionError("the station never planned")

    with ZenohBus(ZenohConfig()) as bus:
        station = Station(bus, port=free_port())
        try:
            station.robot.status = status
            bus.publish(MapUpdate.TOPIC, _walled_map(1))
            end = time.monotonic() + 10.0
            while station.robot.map is None and time.monotonic() < end:
                bus.spin(0.05)
            station.set_goal((1.5, 0.0))
            command = command_once_planned(station, time.monotonic() + 10.0)
            route = station.navigator.route
            assert route is not None
            a, b = route.points_in_world[:-1], route.points_in_world[1:]
            t = np.linspace(0.0, 1.0, 200)[None, :, None]
            dense = (a[:, None] + t * (b - a)[:, None]).reshape(-1, 2)
            crossing = dense[np.abs(dense[:, 0] - 0.5) < 0.04]
            assert len(crossing) and (np.abs(crossing[:, 1]) > 0.6).all()
            assert command.yaw_rate != 0.0 or abs(command.direction[1]) > 0.1
            station.set_goal((1.0, 0.0))
            end = time.monotonic() + 20.0
            sequence = 2
            while station.navigator.no_route is None and time.monotonic() < end:
                bus.publish(MapUpdate.TOPIC, _walled_map(sequence, enclosed=True))  # as a robot
                sequence += 1
                bus.spin(0.05)
                command = station.command()
                time.sleep(0.1)
            assert station.navigator.no_route is not None and command.speed == 0.0
            station.draw(time.monotonic())
            assert "standing still" in station.page.status_text.content
        finally:
            station.close()


def test_a_click_meets_the_ground_where_the_ray_does():
    """The goal of a click is the view ray's crossing of z = 0; a ray up or level has none."""
    from footfall.station import ground_point

    assert ground_point((0.0, 0.0, 2.0), (1.0, 0.5, -1.0)) == pytest.approx((2.0, 1.0))
    assert ground_point((0.0, 0.0, 2.0), (1.0, 0.0, 0.5)) is None
    assert ground_point((0.0, 0.0, 2.0), (1.0, 0.0, 0.0)) is None


def test_the_map_surface_covers_known_cells_only():
    """The 3-D surface meshes only squares of known cells, walkable and not apart, and its
    vertices sit at the cells' centres and heights."""
    from footfall.messages import MapUpdate
    from footfall.station.views import map_surface

    n = 8
    heights = np.full((n, n), np.nan)
    heights[:4, :] = 0.05  # a known strip
    known = np.isfinite(heights)
    valid = known.copy()
    valid[:2, :] = False
    zeros = np.zeros((n, n))
    update = MapUpdate(0.0, 1, heights, known, None, zeros, zeros, zeros, valid, (1.0, -1.0), 0.1)
    vertices, walkable, other = map_surface(update, step=1)
    assert vertices.shape == (n * n, 3)
    np.testing.assert_allclose(vertices[0], [1.05, -0.95, 0.05], atol=1e-6)
    assert len(walkable) == 2 * 1 * (n - 1) and len(other) == 2 * 2 * (n - 1)
    used = np.unique(np.concatenate([walkable, other]))
    assert known.ravel()[used].all()
