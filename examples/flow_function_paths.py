"""Plot flow-function swing paths like thesis Figs. 5.15-5.19 (writes flow_paths.png)."""

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from footfall import FlowConfig, FlowSwing

STRIDE = 0.15  # [m]


def main() -> None:
    fig, axes = plt.subplots(1, 3, figsize=(14, 4), constrained_layout=True)
    for ax, dz, title in zip(
        axes, (0.0, 0.05, -0.05), ("level", "target above", "target below"), strict=True
    ):
        for ch in (1.0, 2.0, 3.0):
            for q in (0.0, 14.0):
                swing = FlowSwing(
                    [0, 0, 0], [STRIDE, 0, dz], 1.0, FlowConfig(step_height=ch, rise=q)
                )
                path = np.array([swing.position(t) for t in np.linspace(0, 1, 200)])
                ax.plot(100 * path[:, 0], 100 * path[:, 2], label=f"Ch={ch:g}, q={q:g}")
        ax.set_title(title)
        ax.set_xlabel("x [cm]")
        ax.set_ylabel("z [cm]")
        ax.set_aspect("equal")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.savefig("flow_paths.png", dpi=100)
    print("wrote flow_paths.png")


if __name__ == "__main__":
    main()
