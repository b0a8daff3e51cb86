#!/usr/bin/python3
"""Transparency against delay, next to stability: for each scheme at its default gain on the
elastic sphere (k = 2000 N/m) and the stiff wall (2e4 N/m), what the operator feels as the
one-way delay grows: the stiffness felt over the environment's (1 = transparent, below 1 the
object feels softer) and the force felt in free space. Runs that were not stable are drawn as
crosses at the bottom: there the scheme is not usable, whatever it feels like.

usage: transparency.py delay_map.csv out.png
"""
import csv
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

plt.rcParams.update({"font.size": 11, "axes.titlesize": 12, "xtick.labelsize": 10,
                     "ytick.labelsize": 10, "legend.fontsize": 11})

DEFAULT_GAIN = {"position-position": 400.0, "force-position": 1.0, "wave-variables": 400.0,
                "tdpa": 400.0, "tdpa-fp": 1.0, "model-mediated": 1.0}
COLORS = {"position-position": "tab:blue", "force-position": "tab:orange",
          "wave-variables": "tab:green", "tdpa": "tab:red", "tdpa-fp": "tab:purple",
          "model-mediated": "black"}


def number(text):
    try:
        v = float(text)
    except ValueError:
        return math.nan
    return v


def main():
    with open(sys.argv[1], newline="") as f:
        runs = list(csv.DictReader(f))
    out = sys.argv[2]
    envs = [("sphere", "elastic sphere, k = 2000 N/m"), ("wall", "stiff wall, k = 2e4 N/m")]
    fig, axes = plt.subplots(2, 2, figsize=(13, 9), squeeze=False)
    for j, (env, title) in enumerate(envs):
        for scheme, gain in DEFAULT_GAIN.items():
            sel = [r for r in runs if r["scheme"] == scheme and r["sweep"] == "gain"
                   and r["environment"] == env and r["slave"] == "point"
                   and abs(number(r["gain"]) - gain) < 1e-9]
            if not sel:
                continue
            sel.sort(key=lambda r: number(r["delay_ms"]))
            stable = [r for r in sel if r["verdict"] == "stable"]
            other = [r for r in sel if r["verdict"] != "stable"]
            c = COLORS[scheme]
            for i, (key, floor) in enumerate([("stiffness_ratio", 0.0), ("free_force_mean_n", 0.0)]):
                ax = axes[i][j]
                xs = [number(r["delay_ms"]) for r in stable]
                ys = [number(r[key]) for r in stable]
                ax.plot(xs, ys, "o-", color=c, ms=4, label=scheme)
                if other:
                    ax.scatter([number(r["delay_ms"]) for r in other], [floor] * len(other),
                               marker="x", color=c, s=30)
        axes[0][j].set_title(title)
        axes[0][j].set_ylabel("stiffness felt / environment's [-]")
        axes[0][j].axhline(1.0, color="gray", lw=0.8, ls="--")
        axes[0][j].set_ylim(bottom=-0.05)
        axes[1][j].set_ylabel("force in free space, mean [N]")
        for i in range(2):
            axes[i][j].set_xlabel("one-way delay [ms]")
            axes[i][j].grid(alpha=0.3)
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), frameon=False,
               title="stable runs; crosses at the bottom: runs that were not stable")
    fig.suptitle("On the sphere only model-mediated teleoperation feels the stiffness (ratio near "
                 "1) at any delay; the others feel it 6 to 50 times softer\n(teleop_bench delay, "
                 "each scheme at its default gain)")
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    fig.savefig(out, dpi=100, metadata={"Software": None})
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
