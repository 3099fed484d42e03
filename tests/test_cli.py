"""The footfall command line."""

from __future__ import annotations

import json
import math
import signal
import subprocess
import sys
import time
from unittest.mock import ANY

import pytest

from footfall.cli import build_parser, main
from processes import read_until, stop
from test_zenoh_bus import free_port

WALK_KEYS = {
    "distance_m",
    "mean_speed_mps",
    "commanded_speed_mps",
    "fell",
    "body_height_error_mean_m",
    "body_height_oscillation_ratio",
    "tilt_max_deg",
    "tilt_rms_deg",
    "sim_seconds",
    "wall_seconds",
    "realtime_factor",
}


def test_walk_writes_metrics_and_plot(tmp_path, capsys):
    """`footfall walk` writes metrics.json with the interface keys, and walk.png."""
    out = tmp_path / "walk"
    code = main(
        [
            "walk",
            "--terrain",
            "flat",
            "--seconds",
            "2",
            "--gait",
            "ripple",
            "--seed",
            "3",
            "--out",
            str(out),
        ]
    )
    assert code == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert WALK_KEYS <= metrics.keys()
    assert metrics["gait"] == "ripple" and metrics["seed"] == 3
    assert metrics["sim_seconds"] == pytest.approx(2.0)
    for name in ("walk.png", "footholds.png"):
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert {
        "reached_goal",
        "invalid_footholds",
        "footholds_adjusted",
        "frozen",
        "min_clearance_m",
    } <= metrics.keys()
    printed = capsys.readouterr().out
    assert "walk summary" in printed and str(out / "metrics.json") in printed
    # What each node cost: footfall's own, and the simulator's under names from "sim".
    cpu = metrics["cpu_per_node"]
    assert {"mapping", "movement", "servo", "pose_guard", "sim_camera", "sim_physics"} <= set(cpu)
    assert all(seconds >= 0 for seconds in cpu.values()) and cpu["mapping"] > 0
    own = sum(s for name, s in cpu.items() if not name.startswith("sim"))
    assert metrics["cpu_own_share"] == pytest.approx(own / metrics["sim_seconds"])
    assert (
        metrics["nodes"]["mapping"]["latency_p95_ms"]
        >= metrics["nodes"]["mapping"]["latency_median_ms"]
        > 0
    )


def test_walk_with_a_robot_file(tmp_path):
    """--robot accepts a TOML file."""
    from pathlib import Path

    source = Path(__file__).parents[1] / "src/footfall/robots/phantomx.toml"
    robot = tmp_path / "mine.toml"
    robot.write_text(source.read_text())
    assert (
        main(["walk", "--seconds", "1", "--robot", str(robot), "--out", str(tmp_path / "o")]) == 0
    )


def test_too_fast_is_a_clear_error(tmp_path, capsys):
    """A speed above the gait's top speed is refused, naming the limit."""
    code = main(["walk", "--gait", "wave", "--speed", "0.5", "--out", str(tmp_path)])
    assert code == 2
    assert "top speed" in capsys.readouterr().out


def test_walk_on_a_chosen_staircase(tmp_path, capsys):
    """--rise sets the stairs' step height (the terrain swept by `footfall bench terrain`);
    it is refused for another terrain."""
    out = tmp_path / "stairs"
    args = ["walk", "--terrain", "stairs", "--rise", "0.07", "--seconds", "1", "--out", str(out)]
    assert main(args) == 0
    assert json.loads((out / "metrics.json").read_text())["terrain_params"] == {"rise": 0.07}
    assert main(["walk", "--terrain", "flat", "--rise", "0.07", "--out", str(out)]) == 2
    assert "--rise applies to --terrain stairs only" in capsys.readouterr().out


def test_unknown_robot_is_a_clear_error(tmp_path, capsys):
    """An unknown robot name lists the built-in robots."""
    assert main(["walk", "--robot", "spider", "--out", str(tmp_path)]) == 2
    assert "phantomx" in capsys.readouterr().out


def test_help_explains_every_walk_option():
    """`footfall walk --help` documents each option of the interface."""
    parser = build_parser()
    walk = parser._subparsers._group_actions[0].choices["walk"]
    help_text = walk.format_help()
    for option in (
        "--terrain",
        "--seconds",
        "--speed",
        "--gait",
        "--robot",
        "--seed",
        "--out",
        "--blind",
        "--rise",
        "--groove",
    ):
        assert option in help_text
    assert all(action.help for action in walk._actions)


MAP_KEYS = {"height_rmse_m", "coverage", "frames", "map_update_ms_median"}


def test_map_writes_images_and_metrics(tmp_path):
    """`footfall map --terrain flat` writes heightmap.png, scoremap.png and metrics.json."""
    out = tmp_path / "map"
    code = main(
        [
            "map",
            "--terrain",
            "flat",
            "--seconds",
            "2",
            "--image-size",
            "160",
            "120",
            "--out",
            str(out),
        ]
    )
    assert code == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert MAP_KEYS <= metrics.keys()
    assert abs(metrics["frames"] - 30) <= 1 and metrics["height_rmse_m"] < 0.005
    for name in ("heightmap.png", "scoremap.png"):
        assert (out / name).read_bytes()[:4] == b"\x89PNG"


def test_map_of_a_recorded_sequence(tmp_path):
    """`footfall convert redwood` then `footfall map --tum` maps the Redwood room."""
    from conftest import shared_data

    source = shared_data("rgbd/redwood_livingroom")
    assert main(["convert", "redwood", str(source), str(tmp_path / "tum")]) == 0
    out = tmp_path / "map"
    code = main(
        [
            "map",
            "--tum",
            str(tmp_path / "tum"),
            "--intrinsics",
            "525",
            "525",
            "319.5",
            "239.5",
            "--up",
            "0",
            "1",
            "0",
            "--out",
            str(out),
        ]
    )
    assert code == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["frames"] == 5 and metrics["floor_height_spread_m"] < 0.02


def test_bench_mapping_writes_bench_json(tmp_path):
    """`footfall bench mapping` writes the figures and their baselines."""
    assert main(["bench", "mapping", "--repeats", "2", "--out", str(tmp_path)]) == 0
    bench = json.loads((tmp_path / "bench.json").read_text())
    for key in ("frame_ms", "points_per_s", "score_ms", "baseline_frame_ms", "baseline_score_ms"):
        assert bench[key] > 0


def test_map_bad_tum_folder_is_a_clear_error(tmp_path, capsys):
    """Mapping a folder that holds no sequence names the problem."""
    assert main(["map", "--tum", str(tmp_path), "--out", str(tmp_path / "o")]) == 2
    assert "depth" in capsys.readouterr().out


def test_bench_terrain_writes_its_table_and_chart(tmp_path, monkeypatch, capsys):
    """`footfall bench terrain` writes bench.json (per configuration and mode, and the
    overall rates of each mode) and bench.png for the terrains asked for; walks run in
    parallel processes with --jobs give the same outcomes; an unknown terrain is named."""
    from footfall.sim.terrain import Stairs

    monkeypatch.setattr(Stairs, "sweep", (0.04,))
    outs = []
    for jobs in ("1", "2"):
        out = tmp_path / f"jobs{jobs}"
        args = ["bench", "terrain", "--seeds", "1", "--seconds", "1", "--jobs", jobs]
        assert main([*args, "--terrains", "stairs,dead_end", "--out", str(out)]) == 0
        assert (out / "bench.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        outs.append(json.loads((out / "bench.json").read_text()))
    serial, parallel = outs
    assert [(r["terrain"], r["mode"]) for r in serial["results"]] == [
        (t, m) for t in ("stairs", "dead_end") for m in ("planned", "straight", "blind")
    ]
    assert all(r["runs"] == 1 and r["foothold_region_jumps"] >= 0 for r in serial["results"])
    assert {"planned_success_rate", "straight_success_rate", "blind_success_rate"} <= serial.keys()
    for a, b in zip(serial["results"], parallel["results"], strict=True):
        assert {k: v for k, v in a.items() if k != "wall_seconds"} == {
            k: v for k, v in b.items() if k != "wall_seconds"
        }
    out = tmp_path / "planned"
    args = ["bench", "terrain", "--seeds", "1", "--seconds", "1", "--terrains", "stairs"]
    assert main([*args, "--modes", "planned", "--out", str(out)]) == 0
    alone = json.loads((out / "bench.json").read_text())
    assert [r["mode"] for r in alone["results"]] == ["planned"]
    assert alone["results"][0] == {**serial["results"][0], "wall_seconds": ANY}
    assert math.isnan(alone["blind_success_rate"])
    capsys.readouterr()
    assert main(["bench", "terrain", "--terrains", "stairs,nowhere", "--out", str(tmp_path)]) == 2
    assert "nowhere" in capsys.readouterr().out
    assert main(["bench", "terrain", "--modes", "planned,asleep", "--out", str(tmp_path)]) == 2
    assert "asleep" in capsys.readouterr().out


def test_bench_terrain_walks_every_robot_and_gait(tmp_path, monkeypatch, capsys):
    """`footfall bench terrain --robot A,B --gait G,H` walks every pair over the sweep: a
    row per robot, gait and configuration, each pair's success rate, and each walk set up
    as `footfall walk` sets it up (the robot's own height and stride, the gait's speed)."""
    from footfall.motion.gait import GaitConfig
    from footfall.reliability.variants import Variant, walk_variant
    from footfall.robot.spec import load_spec
    from footfall.sim.terrain import Stairs

    monkeypatch.setattr(Stairs, "sweep", (0.04,))
    out = tmp_path / "variants"
    args = ["bench", "terrain", "--seeds", "1", "--seconds", "1", "--terrains", "stairs"]
    args += ["--modes", "planned", "--robot", "default,phantomx", "--gait", "tripod,wave"]
    assert main([*args, "--out", str(out)]) == 0
    bench = json.loads((out / "bench.json").read_text())
    pairs = [("default", "tripod"), ("default", "wave"), ("phantomx", "tripod")]
    pairs.append(("phantomx", "wave"))
    assert [(r["robot"], r["gait"]) for r in bench["results"]] == pairs
    assert [(v["robot"], v["gait"], v["runs"]) for v in bench["variants"]] == [
        (*pair, 1) for pair in pairs
    ]
    assert bench["robots"] == ["default", "phantomx"] and bench["gaits"] == ["tripod", "wave"]
    assert (out / "bench.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    spec = load_spec("phantomx")
    m = walk_variant(Variant("phantomx", "wave"), "stairs", seed=0, seconds=1.0).metrics
    top = GaitConfig(kind="wave").for_robot(spec).max_speed
    assert (m.setup.robot, m.setup.gait) == ("phantomx", "wave")
    assert m.setup.commanded_body_height_m == spec.body_height
    assert m.setup.stride_m == spec.stride_length
    assert m.gait.commanded_speed_mps == pytest.approx(min(0.1, 0.75 * top))
    capsys.readouterr()
    for option, name in (("--gait", "tripod,hop"), ("--robot", "default,nobody")):
        assert main(["bench", "terrain", option, name, "--out", str(tmp_path)]) == 2
        assert name.split(",")[1] in capsys.readouterr().out
    assert main(["bench", "faults", "--gait", "wave,wave", "--out", str(tmp_path)]) == 2
    assert "more than once" in capsys.readouterr().out


def test_walk_paced_to_the_wall_clock(tmp_path):
    """`footfall walk --realtime` runs the control loop on wall-clock deadlines: a second
    of walking takes about a second, and the overruns are counted."""
    out = tmp_path / "rt"
    args = ["walk", "--terrain", "flat", "--blind", "--seconds", "1.5", "--realtime"]
    assert main([*args, "--out", str(out)]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert 0.7 < metrics["realtime_factor"] <= 1.05
    assert metrics["control_overruns"] >= 0 and "control_max_late_s" in metrics
    times = [metrics[f"command_ms_{k}"] for k in ("median", "p99", "max")]
    assert 0 <= times[0] <= times[1] <= times[2]


def test_python_dash_m_footfall_is_the_command():
    """`python -m footfall` runs the command line, as the `footfall` script does, and
    `import footfall` loads its public names only when they are used."""
    import subprocess
    import sys

    done = subprocess.run(
        [sys.executable, "-m", "footfall", "--help"], capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 0 and done.stdout.startswith("usage: footfall")
    probe = "import sys, footfall; print('footfall.motion.walker' in sys.modules)"
    lazy = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=60)
    assert lazy.stdout.strip() == "False"
    import footfall

    assert footfall.WalkController.__module__ == "footfall.motion.walker"
    with pytest.raises(AttributeError, match="no attribute 'Nothing'"):
        footfall.Nothing  # noqa: B018


def test_the_command_list_loads_no_command():
    """`footfall --help` lists every command from the table alone: no command's module, the
    simulator, numba or MuJoCo is imported for it (start-up stays a blink)."""
    from footfall.cli.commands import COMMANDS

    heavy = ("numba", "mujoco", "scipy", "footfall.sim", "zenoh")
    script = (
        "import sys\n"
        "from footfall.cli import main\n"
        "try:\n"
        "    main(['--help'])\n"
        "except SystemExit:\n"
        "    pass\n"
        f"heavy = [m for m in {heavy!r} if m in sys.modules]\n"
        "loaded = [m for m in sys.modules if m.startswith('footfall.cli.')]\n"
        "loaded.remove('footfall.cli.commands')\n"
        "print('HEAVY', heavy, 'LOADED', loaded)\n"
    )
    command = [sys.executable, "-c", script]
    done = subprocess.run(command, capture_output=True, text=True, check=True)
    assert "HEAVY [] LOADED []" in done.stdout, done.stdout
    for name in COMMANDS:
        assert name in done.stdout


def test_every_commands_help_loads_no_heavy_library():
    """`footfall COMMAND --help` builds only that command's options: neither scipy, numba,
    MuJoCo, zenoh nor the message codec is imported for it (the robot's and the station's
    options list the backends and sources by name, and the endpoint from a plain constant)."""
    from footfall.cli.commands import COMMANDS

    heavy = ("numba", "mujoco", "scipy", "zenoh", "footfall.messages")
    script = (
        "import sys\n"
        "from footfall.cli import main\n"
        "try:\n"
        "    main([sys.argv[1], '--help'])\n"
        "except SystemExit:\n"
        "    pass\n"
        f"print('HEAVY', [m for m in {heavy!r} if m in sys.modules])\n"
    )
    for name in COMMANDS:
        done = subprocess.run(
            [sys.executable, "-c", script, name], capture_output=True, text=True, check=True
        )
        assert "HEAVY []" in done.stdout, (name, done.stdout)


def test_sigusr1_prints_every_threads_stack_and_the_process_runs_on(tmp_path):
    """`kill -USR1` on a running footfall command prints where each of its threads is (the
    way to see where a robot that will not stop is stuck); the command carries on and
    still ends cleanly on SIGINT."""
    stderr = tmp_path / "stderr.txt"
    command = [sys.executable, "-m", "footfall", "robot", "--biped", "--case", "1"]
    command += ["--listen", f"tcp/127.0.0.1:{free_port()}", "--seconds", "60"]
    with stderr.open("w") as err:
        robot = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=err, text=True)
        try:
            said = read_until(robot, "keys")  # ready once it says where it listens
            assert "listening on" in said, said
            robot.send_signal(signal.SIGUSR1)
            end = time.monotonic() + 10.0
            while "run_biped" not in stderr.read_text() and time.monotonic() < end:
                time.sleep(0.1)
            dump = stderr.read_text()
            assert "most recent call first" in dump and "run_biped" in dump, dump
            assert robot.poll() is None
        finally:
            assert stop(robot) == 0
