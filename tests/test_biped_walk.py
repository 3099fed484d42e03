"""Archie walking in MuJoCo: standing, the Kajita example, a map, a room, the CLI."""

from __future__ import annotations

import json

import mujoco
import numpy as np
import pytest

from footfall.biped.body import SIDES, leg_forward, leg_inverse, load_biped_spec
from footfall.biped.footsteps import footsteps_from_parameters
from footfall.biped.gait import GaitConfig, gait_pattern
from footfall.biped.lipm import LipmConfig, WalkParameter
from footfall.cli import main
from footfall.errors import ConfigError
from footfall.sim.biped_model import biped_mjcf
from footfall.sim.biped_room import ROUTE_CLEARANCE, make_room
from footfall.sim.biped_run import WalkBipedRequest, walk_biped
from footfall.sim.biped_sim import BipedSimulation
from footfall.sim.biped_walk import run_pattern, stand, start_pose

SPEC = load_biped_spec()
KAJITA = [WalkParameter(sx, 0.2) for sx in (0.0, 0.3, 0.3, 0.3, 0.0)]
FEET = {"left": (0.0, 0.1, 0.0), "right": (0.0, -0.1, 0.0)}


def _kajita_walk():
    sim = BipedSimulation(SPEC, mujoco.MjModel.from_xml_string(biped_mjcf(SPEC)))
    steps = footsteps_from_parameters(KAJITA, (0.0, 0.0), first_step_left=False)
    lipm = LipmConfig()
    pattern = gait_pattern(steps, FEET, stand(sim, FEET), GaitConfig(step_time=lipm.support_time))
    start_pose(sim, pattern)
    return sim, run_pattern(sim, pattern)


def test_the_model_stands_still_without_simulator_warnings():
    sim = BipedSimulation(SPEC, mujoco.MjModel.from_xml_string(biped_mjcf(SPEC)))
    steps = footsteps_from_parameters(KAJITA, (0.0, 0.0), first_step_left=False)
    pattern = gait_pattern(steps, FEET, 0.6)
    start_pose(sim, pattern)
    before = sim.com()
    for _ in range(250):  # 1 s holding the first pose
        sim.step(0.004)
    assert sim.warnings_seen == 0
    assert not sim.fallen()
    assert np.linalg.norm(sim.com() - before) < 0.01
    forces = sim.foot_forces()
    total = sum(f.sum() for f, _ in forces.values())
    assert total == pytest.approx(SPEC.mass * 9.81, rel=0.05)  # the corner sensors weigh it


def test_archie_walks_the_kajita_example_with_the_zmp_inside_the_support():
    """s_x = 0.3 m over 4 steps at T_sup = 0.8 s: no fall, ZMP inside, feet where planned;
    the same walk twice gives the same motion (the simulation is deterministic)."""
    sim, run = _kajita_walk()
    assert not run.fell and run.warnings == 0
    log = run.log.arrays()
    margin = log["zmp_margin"][np.isfinite(log["zmp_margin"])]
    assert len(margin) > 0.9 * len(log["zmp_margin"]) and margin.min() > 0.0
    planned = run.pattern.footholds[1:]
    assert len(run.actual_footholds) == len(planned)
    assert np.linalg.norm(run.actual_footholds - planned, axis=1).max() < 0.02
    np.testing.assert_allclose(sim.com()[:2], (0.9, 0.0), atol=0.03)
    _, again = _kajita_walk()
    np.testing.assert_array_equal(again.log.arrays()["joints"], log["joints"])


def test_executed_poses_round_trip_through_the_kinematics():
    """On the executed walk, FK of the measured joints from the measured hip pose puts each
    foot on its sole site, and the commanded targets survive FK then IK."""
    sim, run = _kajita_walk()
    targets = np.asarray(run.log.targets)
    for q in targets[::40]:
        for k, side in enumerate(SIDES):
            sole, rotation = leg_forward(SPEC, side, q[6 * k : 6 * k + 6])
            np.testing.assert_allclose(
                leg_inverse(SPEC, side, sole, rotation), q[6 * k : 6 * k + 6], atol=1e-8
            )
    mujoco.mj_kinematics(sim.model, sim.data)  # positions of the state the joints are in
    hip = sim.model.body("hip").id
    r_hip = sim.data.xmat[hip].reshape(3, 3)
    for k, side in enumerate(SIDES):
        sole, _ = leg_forward(SPEC, side, sim.joints[6 * k : 6 * k + 6])
        np.testing.assert_allclose(sim.data.xpos[hip] + r_hip @ sole, sim.sole(side), atol=1e-9)


def test_rooms_are_seeded_and_passable():
    from footfall.biped.avoidance import Circle, plan_path

    for seed in range(6):
        room = make_room(seed)
        assert room == make_room(seed)
        grown = [Circle(c.x, c.y, c.r + ROUTE_CLEARANCE) for c in room.circles()]
        assert plan_path(room.start, room.goal, grown).length > 0
        assert any(abs(o.y) < 0.3 for o in room.obstacles)  # something is in the way


def test_a_room_seen_only_through_the_camera_is_crossed():
    walk = walk_biped(WalkBipedRequest(room=0))
    m = walk.metrics()
    assert m["reached_goal"] and not m["fell"] and m["collisions"] == 0
    assert m["plans"] >= 2  # it looked again on the way
    assert len(walk.plan_map.obstacles) >= 1  # it saw obstacles


def test_a_goal_inside_an_obstacle_is_refused_and_the_robot_stays():
    m = walk_biped(WalkBipedRequest(case=3, goal=(1.5, 1.0))).metrics()
    assert not m["reached_goal"] and not m["fell"]
    assert "goal" in m["no_route"] and m["plans"] == 0


def test_a_request_needs_exactly_one_source():
    with pytest.raises(ConfigError, match="exactly one"):
        WalkBipedRequest(case=1, room=2)


def test_walk_biped_cli_walks_a_dissertation_map(tmp_path, capsys):
    out = tmp_path / "case1"
    assert main(["walk-biped", "--case", "1", "--out", str(out)]) == 0
    m = json.loads((out / "metrics.json").read_text())
    for key in (
        "reached_goal",
        "fell",
        "collisions",
        "zmp_margin_min_m",
        "footstep_error_mean_m",
        "com_tracking_error_max_m",
        "realtime_factor",
    ):
        assert key in m
    assert m["reached_goal"] and not m["fell"] and m["collisions"] == 0
    assert m["zmp_margin_min_m"] > 0
    for name in ("top.png", "balance.png", "joints.png"):
        assert (out / name).stat().st_size > 10_000


def test_a_look_keeps_all_its_own_circles_and_updates_the_remembered_ones():
    """Circles of one look that overlap each other (a cluster split in parts) all stay; a
    larger new circle replaces a remembered one it overlaps; a smaller one is dropped."""
    from footfall.biped.avoidance import Circle
    from footfall.sim.biped_look import merge_circles

    big, part = Circle(2.0, -0.7, 0.9), Circle(1.8, 0.0, 0.25)
    assert set(merge_circles([], [big, part])) == {big, part}
    remembered = Circle(4.0, 0.0, 0.2)
    grown = Circle(4.05, 0.0, 0.3)
    assert merge_circles([remembered], [grown]) == [grown]
    assert merge_circles([grown], [remembered]) == [grown]


def test_walk_biped_kajita_reaches_the_end_of_the_example():
    m = walk_biped(WalkBipedRequest(kajita=True)).metrics()
    assert m["reached_goal"] and not m["fell"] and m["footsteps"] == 4
    assert m["zmp_margin_min_m"] > 0 and m["footstep_error_mean_m"] < 0.02
