"""Figures of the reliability benchmarks: the fault table and the soak's trends."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from footfall.plots import plt, save_figure


def plot_fault_benchmark(bench: dict, path: Path) -> Path:
    """Success rate of every fault class on every terrain, with falls and invalid footholds.

    Left, a fault x terrain grid (a line per variant and fault where the benchmark walked
    several robots, gaits or settings) coloured by success rate, each cell labelled
    ``successes/runs`` (and ``F`` falls, ``I`` invalid footholds when any); right, the map's
    height RMSE under SLAM noise without and with drift compensation.
    """
    rows = bench["results"]
    several = len({r["variant"] for r in rows}) > 1

    def line(r: dict) -> str:
        return f"{r['variant']} {r['fault']}" if several else r["fault"]

    faults = list(dict.fromkeys(line(r) for r in rows))
    terrains = list(dict.fromkeys(r["terrain"] for r in rows))
    rate = np.full((len(faults), len(terrains)), np.nan)
    fig, (ax, ax_rmse) = plt.subplots(
        1, 2, figsize=(11, 0.45 * len(faults) + 2.5), width_ratios=(3, 1), constrained_layout=True
    )
    for r in rows:
        i, j = faults.index(line(r)), terrains.index(r["terrain"])
        rate[i, j] = r["successes"] / max(r["runs"], 1)
        label = f"{r['successes']}/{r['runs']}"
        if r["falls"]:
            label += f" F{r['falls']}"
        if r["invalid_footholds"]:
            label += f" I{r['invalid_footholds']}"
        ax.text(j, i, label, ha="center", va="center", fontsize=9)
    ax.imshow(rate, cmap="RdYlGn", vmin=0.0, vmax=1.0, aspect="auto")
    ax.set_xticks(range(len(terrains)), terrains)
    ax.set_yticks(range(len(faults)), faults)
    ax.set_title(
        f"success over {bench['seeds']} seeds: {bench['success_rate']:.0%}; falls "
        f"{bench['falls']}, invalid footholds {bench['invalid_footholds']}"
    )
    rmse = bench["map_rmse"]
    values = [1e3 * rmse["without_compensation_m"], 1e3 * rmse["with_compensation_m"]]
    ax_rmse.bar([0, 1], values, color=["C3", "C2"])
    ax_rmse.set_xticks([0, 1], ["without", "with"])
    ax_rmse.set_ylabel("map height RMSE [mm]")
    ax_rmse.set_title("map under SLAM noise:\ndrift compensation", fontsize=10)
    for k, v in enumerate(values):
        ax_rmse.text(k, v, f"{v:.1f}", ha="center", va="bottom")
    return save_figure(fig, path)


def plot_soak(soak: dict, path: Path) -> Path:
    """Memory, live objects, per-frame and per-tick times, and the reference ratios of a soak.

    The reference is the fixed workload timed at each sample (the machine's own speed).
    """
    samples = soak["samples"]
    minutes = [s["wall_minutes"] for s in samples]
    panels = (
        (("rss_mb",), "resident memory [MiB]"),
        (("objects",), "live Python objects"),
        (("map_ms", "map_cpu_ms"), "mapping per frame [ms]"),
        (("control_ms", "control_cpu_ms"), "control per tick [ms]"),
        (("reference_cpu_ms",), "reference workload [ms]"),
        (("map_per_reference", "control_per_reference"), "CPU time / reference"),
    )
    kinds = {
        "map_per_reference": "mapping",
        "control_per_reference": "control",
        "reference_cpu_ms": "CPU",
    }
    fig, axes = plt.subplots(3, 2, figsize=(11, 10), sharex=True, constrained_layout=True)
    slopes = soak.get("slope_per_minute", {})
    growth = soak.get("growth", {})
    for ax, (keys, label) in zip(axes.ravel(), panels, strict=True):
        titles = []
        for key in keys:
            kind = kinds.get(key, "CPU" if "cpu" in key else "wall")
            ax.plot(minutes, [s.get(key, float("nan")) for s in samples], ".-", ms=3, label=kind)
            if key in slopes:
                titles.append(f"{kind} {slopes[key]:+.3g}/min, {growth[key]:+.1%}")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        if len(keys) > 1:
            ax.legend(fontsize=8)
        if titles:
            ax.set_title(
                "; ".join(titles) + f" (first to last {soak['window_minutes']:.3g} min)",
                fontsize=8,
            )
    for ax in axes[-1]:
        ax.set_xlabel("wall time [min]")
    fig.suptitle(
        f"soak: {soak['minutes']:g} min of laps on {soak['terrain']}, {soak['laps']} laps, "
        f"{soak['sim_seconds'] / 60:.0f} simulated minutes"
    )
    return save_figure(fig, path)
