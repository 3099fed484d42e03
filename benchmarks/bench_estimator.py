"""footfall's own pose (``--pose estimator``): its drift on flat ground and its cost a tick.

Walks the simulated robot across flat ground for ``--seconds`` on its own pose, once per
seed of the simulated sensors' noise, each walk in its own process, and reads each walk's
``metrics.json``: the position drift as a share of the distance walked, its height part, the
heading drift per metre. Then times the estimator's update on the recorded states of one
walk against the same states read exactly (``noise=none``: the cost of the simulated
sensors' noise apart) and against forward kinematics alone (the least a leg odometry
computes), in the same run.

Run with ``uv run python benchmarks/bench_estimator.py [--seeds N] [--seconds S]``; it writes
``benchmarks/results/estimator.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def flat_walk(seed: int, seconds: float, out: Path) -> dict:
    """One flat walk on the estimator, its metrics."""
    env = {**os.environ, "MUJOCO_GL": "egl"}
    command = [sys.executable, "-m", "footfall", "walk", "--terrain", "flat", "--pose"]
    command += ["estimator", "--pose-option", f"seed={seed}", "--seconds", str(seconds)]
    command += ["--goal", str(1.0 + 0.1 * seconds), "0", "--out", str(out)]
    subprocess.run(command, cwd=ROOT, env=env, check=True, capture_output=True)
    return json.loads((out / "metrics.json").read_text())


def tick_costs(ticks: int = 2000) -> dict[str, float]:
    """Microseconds a tick: the estimator with and without sensor noise, and kinematics."""
    from scipy.spatial.transform import Rotation

    from footfall.estimation.leg_inertial import BodyReading, LegInertialEstimator
    from footfall.estimation.sensor_noise import NoisySensors, SensorNoiseConfig
    from footfall.messages import RobotState
    from footfall.robot.kinematics import LegKinematics
    from footfall.robot.spec import load_spec
    from footfall.sensing.pose import Pose

    spec = load_spec("default")
    kin = LegKinematics(spec)
    rest = kin.inverse_in_body(spec.rest_feet_in_body() + [0.0, 0.0, spec.foot_radius])
    rng = np.random.default_rng(0)
    states = [
        RobotState(
            time=0.01 * k,
            joint_positions=rest + rng.normal(0.0, 1e-4, (6, 3)),
            joint_velocities=rng.normal(0.0, 0.1, (6, 3)),
            orientation_body_in_world=Rotation.from_euler("z", 0.001 * k),
            angular_velocity_body_in_body=np.array([0.0, 0.0, 0.1]),
        )
        for k in range(ticks)
    ]
    standing = np.array([True, False, True, False, True, False])
    start = Pose(np.array([0.0, 0.0, spec.body_height]), Rotation.identity())

    def run(noise: NoisySensors | None) -> float:
        estimator = LegInertialEstimator(kin, start)
        t0 = time.perf_counter()
        for state in states:
            read = noise.read(state) if noise is not None else state
            estimator.update(
                BodyReading(
                    read.time,
                    read.joint_positions,
                    read.joint_velocities,
                    read.angular_velocity_body_in_body,
                    read.orientation_body_in_world,
                    standing,
                )
            )
        return 1e6 * (time.perf_counter() - t0) / ticks

    t0 = time.perf_counter()
    for state in states:
        kin.forward_in_body(state.joint_positions)
    kinematics = 1e6 * (time.perf_counter() - t0) / ticks
    return {
        "estimator_us": run(None),
        "estimator_with_noise_us": run(NoisySensors(SensorNoiseConfig(), rng)),
        "forward_kinematics_us": kinematics,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=6, help="seeds of the sensors' noise")
    parser.add_argument("--seconds", type=float, default=60.0, help="length of each walk [s]")
    args = parser.parse_args()
    walks = []
    with tempfile.TemporaryDirectory() as tmp:
        for seed in range(args.seeds):
            m = flat_walk(seed, args.seconds, Path(tmp) / f"walk{seed}")
            walked = m["distance_m"]
            walks.append(
                {
                    "seed": seed,
                    "distance_m": walked,
                    "drift_m": m["estimator_position_drift_m"],
                    "drift_share": m["estimator_position_drift_m"] / walked,
                    "height_drift_m": m["estimator_height_drift_m"],
                    "heading_drift_deg": m["estimator_heading_drift_deg"],
                    "heading_deg_per_m": m["estimator_heading_drift_deg"] / walked,
                    "pose_node_share": m["nodes"]["pose"]["cpu_share"],
                    "invalid_footholds": m["invalid_footholds"],
                    "fell": m["fell"],
                }
            )
            w = walks[-1]
            print(
                f"seed {seed}: {w['distance_m']:.2f} m walked, drift {100 * w['drift_m']:.2f} cm "
                f"({100 * w['drift_share']:.2f} %, height {100 * w['height_drift_m']:+.2f} cm), "
                f"heading {w['heading_drift_deg']:.2f} deg ({w['heading_deg_per_m']:.3f} deg/m)"
            )
    costs = tick_costs()
    shares = [w["drift_share"] for w in walks]
    print(
        f"drift: median {100 * statistics.median(shares):.2f} %, largest {100 * max(shares):.2f} %"
        f" of the distance; heading largest {max(w['heading_deg_per_m'] for w in walks):.3f}"
        " deg/m"
    )
    kin = costs["forward_kinematics_us"]
    print(
        f"a tick: estimator {costs['estimator_us']:.0f} us "
        f"({costs['estimator_us'] / kin:.1f}x forward kinematics alone, {kin:.0f} us), "
        f"with the simulated sensors' noise {costs['estimator_with_noise_us']:.0f} us"
    )
    out = ROOT / "benchmarks" / "results" / "estimator.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"walks": walks, "tick": costs}, indent=2))
    print(f"wrote {out.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
