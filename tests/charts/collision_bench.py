"""Chart for `teleop_bench collision`: per-step time of each collision method against mesh
level (median with a bar to p99), log scale.

usage: /usr/bin/python3 collision_bench.py OUT_DIR
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    out = sys.argv[1]
    with open(os.path.join(out, "collision_bench.csv")) as f:
        rows = list(csv.DictReader(f))
    methods = []
    for r in rows:
        if r["method"] not in methods:
            methods.append(r["method"])
    fig, ax = plt.subplots(figsize=(9, 5.5))
    for m in methods:
        rs = [r for r in rows if r["method"] == m]
        tris = [int(r["triangles"]) for r in rs]
        med = [float(r["median_us"]) for r in rs]
        p99 = [float(r["p99_us"]) for r in rs]
        ax.errorbar(tris, med, yerr=[[0] * len(med), [p - q for p, q in zip(p99, med)]],
                    marker="o", capsize=3, label=m)
    ax.axhline(30.0, color="grey", ls="--", lw=1)
    ax.text(min(int(r["triangles"]) for r in rows), 33, "target: level 4 refit + query <= 30 us",
            fontsize=8, color="grey")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("triangles (icosphere levels 3-6)")
    ax.set_ylabel("time per step [us] (median, bar to p99)")
    ax.set_title("Collision upkeep on a deforming sphere, tip radius 0.05 m")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "collision_bench.png"), dpi=110)


if __name__ == "__main__":
    main()
