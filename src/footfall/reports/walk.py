"""A simulated walk across a terrain, as ``footfall walk`` runs it."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from footfall.reports import write_json
from footfall.sim.truth import TrueScores
from footfall.sim.walk import simulate_walk
from footfall.sim.walk_request import WalkJob
from footfall.sim.walk_settings import WalkResult


@dataclass(frozen=True)
class WalkReport:
    """The outcome of a walk.

    Attributes:
        job: What was walked.
        result: The simulation's record and metrics.
    """

    job: WalkJob

    result: WalkResult

    def to_json(self) -> dict[str, object]:
        """The ``metrics.json`` content."""
        metrics = self.result.metrics.to_json()
        metrics["mujoco_warnings"] = self.result.warnings
        metrics["terrain_params"] = self.job.terrain_params
        return metrics

    def write(self, out: Path) -> list[Path]:
        """Write ``metrics.json``, ``walk.png`` and ``footholds.png`` to ``out``."""
        from footfall.plots import plot_footholds, plot_walk

        job, result = self.job, self.result
        out.mkdir(parents=True, exist_ok=True)
        paths = [out / "metrics.json", out / "walk.png", out / "footholds.png"]
        write_json(paths[0], self.to_json())
        if not result.log.time:  # nothing walked, nothing to draw
            return paths[:1]
        r = job.request
        title = f"{job.spec.name}: {r.gait} gait at {job.speed:.3f} m/s on {r.terrain} terrain"
        plot_walk(
            result.log,
            paths[1],
            leg=0,
            leg_name=job.spec.leg_names[0],
            ground=result.terrain.height,
            title=title + (" (blind)" if r.blind else ""),
        )
        if result.scores is not None:
            s = result.scores
            background = (s.score, s.valid, s.origin, s.resolution)
            label = "the robot's score map"
        else:
            goal_x = result.terrain.goal[0]
            truth = TrueScores(
                result.terrain,
                job.settings.map.resolution,
                job.settings.score,
                (-1.0, goal_x + 1.0, -1.5, 1.5),
            )
            background = (truth.score, truth.valid, truth.origin, truth.resolution)
            label = "the true terrain's score map"
        plot_footholds(
            result.touchdowns,
            *background,
            paths[2],
            result.log.array("body_position_in_world")[:, :2],
            title=f"footholds over {label}",
        )
        return paths


def run_walk(job: WalkJob, on_tick: Callable[[float], None] | None = None) -> WalkReport:
    """Simulate a prepared walk.

    Args:
        job: The walk (see :func:`prepare_walk`).
        on_tick: Progress callback with the walk time [s].
    """
    from footfall.recording.session import Recorders
    from footfall.runtime.bus import InProcessBus

    r = job.request
    with Recorders(r.record, r.rerun, r.rerun_spawn) as recorders:
        result = simulate_walk(
            job.spec,
            job.settings,
            on_tick=on_tick,
            terrain=job.terrain,
            bus=recorders.attach(InProcessBus()),
            on_build=lambda robot: (
                recorders.mapping_started(robot.mapping) if robot.mapping is not None else None
            ),
        )
    return WalkReport(job, result)
