"""Simulated walks on flat ground at the thesis' parameters (§8.1)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from footfall.messages import WalkCommand
from footfall.motion.gait import GaitConfig
from footfall.robot.spec import load_spec
from footfall.sim.walk import simulate_walk
from footfall.sim.walk_settings import WalkSettings

SPEC = load_spec("default")
# Speeds at 3/4 of each gait's top speed, capped at 0.1 m/s (the CLI's default choice).
SPEEDS = {"tripod": 0.10, "ripple": 0.10, "wave": 0.0625}


@pytest.fixture(scope="module", params=sorted(SPEEDS))
def flat_walk(request):
    gait = request.param
    settings = WalkSettings(
        seconds=20.0,
        command=WalkCommand(speed=SPEEDS[gait], body_height=0.09),
        gait=GaitConfig(kind=gait),
    )
    return gait, simulate_walk(SPEC, settings)


def test_flat_walk_meets_the_thesis_figures(flat_walk):
    """20 s on flat ground: no fall, speed within 10 %, tilt < 0.5 deg, oscillation < 10 %."""
    gait, result = flat_walk
    m = result.metrics.to_json()
    assert not m["fell"] and not m["frozen"], m["frozen_reason"]
    assert m["mean_speed_mps"] == pytest.approx(SPEEDS[gait], rel=0.10)
    assert m["tilt_max_deg"] < 0.5
    assert m["body_height_oscillation_ratio"] < 0.10
    assert m["realtime_factor"] >= 2.0
    assert result.warnings == {}


def test_stance_feet_do_not_slip(flat_walk):
    """Supporting feet slip less than 5 mm per step on flat ground."""
    _, result = flat_walk
    assert result.metrics.gait.stance_slip_max_m < 0.005


def test_supporting_feet_touch_the_ground(flat_walk):
    """Feet the controller has in stance are in contact with the ground.

    So a tripod walk stands on at least three feet at every instant.
    """
    gait, result = flat_walk
    swinging = result.log.array("swinging")
    contact = result.log.array("contact")
    settled = np.ones_like(swinging)
    settled[1:] = ~swinging[1:] & ~swinging[:-1]  # stance, and not the touchdown tick
    stance_in_contact = contact[~swinging[:, :] & settled.astype(bool)]
    assert stance_in_contact.mean() > 0.99
    if gait == "tripod":
        assert np.all(contact.sum(axis=1) >= 3)


def test_seeded_walk_is_deterministic():
    """Two runs with the same settings produce identical trajectories."""
    settings = WalkSettings(seconds=2.0, command=WalkCommand(speed=0.1), seed=7)
    a, b = simulate_walk(SPEC, settings), simulate_walk(SPEC, settings)
    np.testing.assert_array_equal(
        a.log.array("body_position_in_world"), b.log.array("body_position_in_world")
    )
    np.testing.assert_array_equal(a.log.array("feet_in_world"), b.log.array("feet_in_world"))


def test_phantomx_walks_on_its_own_parameters():
    """Nothing is tied to one robot: the PhantomX Mark-4 walks a tripod on its own stride."""
    spec = load_spec("phantomx")
    settings = WalkSettings(
        seconds=8.0, command=WalkCommand(speed=0.08, body_height=spec.body_height)
    )
    m = simulate_walk(spec, settings).metrics.to_json()
    assert not m["fell"] and not m["frozen"], m["frozen_reason"]
    assert m["mean_speed_mps"] == pytest.approx(0.08, rel=0.15)
    assert m["tilt_max_deg"] < 1.0


def _stance_log(centres, rotations):
    from footfall.control_loop import WalkLog

    log = WalkLog()
    n = len(centres)
    for k in range(n):
        feet = np.zeros((6, 3))
        feet[0] = centres[k]
        rot = np.tile(np.eye(3), (6, 1, 1))
        rot[0] = rotations[k]
        swinging = np.zeros(6, dtype=bool)
        swinging[0] = k == 0 or k == n - 1  # one stance between a touchdown and a lift-off
        log.feet_in_world.append(feet)
        log.foot_orientations_in_world.append(rot)
        log.swinging.append(swinging)
    return log


def test_slip_metric_tells_rolling_from_sliding():
    """A foot rolling without sliding has no slip; one pivoting in place on its centre slides."""
    from scipy.spatial.transform import Rotation

    from footfall.metrics import stance_slip_m

    r = 0.012
    angles = np.linspace(0.0, 0.4, 30)  # foot rotates about the world y axis
    rotations = Rotation.from_euler("y", angles[:, None]).as_matrix()
    rolling = [[r * a, 0.0, r] for a in angles]  # centre advances r * angle: pure rolling
    pivoting = [[0.0, 0.0, r] for _ in angles]
    assert stance_slip_m(_stance_log(rolling, rotations), r)[0] < 1e-4
    # Measured from the tick after touchdown (index 2) to lift-off (index 28).
    expected = r * np.sin(angles[28] - angles[2])
    assert stance_slip_m(_stance_log(pivoting, rotations), r)[0] == pytest.approx(
        expected, rel=1e-6
    )


def test_fall_tells_a_collapse_from_a_body_lowered_on_purpose():
    """Low over the ground is a fall only when the body is also well below where the
    controller holds it; a large tilt is a fall."""
    from footfall.metrics import fallen

    commanded = 0.09
    # Lowered on purpose to 3.5 cm above a step's edge: the controller holds it there.
    assert not fallen(0.5, 0.035, 0.355, 0.356, commanded)
    # Collapsed: 2 cm above the ground, 7 cm below its reference.
    assert fallen(0.5, 0.02, 0.02, 0.09, commanded)
    assert fallen(35.0, 0.09, 0.09, 0.09, commanded)
    assert not fallen(1.0, 0.09, 0.09, 0.09, commanded)


def test_skipped_ticks_keep_the_physics_on_the_controller_clock(default_spec):
    """When a wall-clock scheduler skips ticks, the robot lives through the gap (holding its
    targets): the simulator's time stays the controller's."""
    from footfall.runtime.bus import InProcessBus
    from footfall.sim.assembly import WalkingRobot
    from footfall.sim.terrains import make_terrain
    from footfall.sim.walk_settings import WalkSettings

    settings = WalkSettings(terrain="flat", blind=True)
    robot = WalkingRobot.build(default_spec, settings, make_terrain("flat"), InProcessBus())
    start = robot.backend.data.time
    robot.step(0.0, 0.01)
    robot.step(0.05, 0.01)  # ticks 0.01 to 0.04 were skipped
    assert robot.backend.data.time - start == pytest.approx(0.06, abs=1e-9)
    robot.close()


def test_a_default_walk_has_the_time_to_reach_its_goal():
    """With no --seconds, a walk gets twice the straight line's time to the goal at its
    speed (at least 60 s): the slow wave gait as much as it needs."""
    from footfall.sim.walk_request import WalkRequest, prepare_walk

    for gait in ("tripod", "wave"):
        for terrain in ("stairs", "cobblestones", "course"):
            job = prepare_walk(WalkRequest(terrain=terrain, gait=gait))
            distance = math.dist(job.terrain.start, job.terrain.goal)
            assert job.settings.seconds >= max(60.0, 2.0 * distance / job.speed) - 1e-9
    assert prepare_walk(WalkRequest(seconds=5.0)).settings.seconds == 5.0
