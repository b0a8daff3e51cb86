#!/usr/bin/python3
"""Chart of `teleop_bench peers-fem`: our volumetric FEM ball and Bullet's deformable FEM on the
same tetrahedral meshes, each point one engine, level and Lamb mode: the step's median wall
time against the frequency's error against Lamb.
usage: peers_fem.py peers_fem.csv peers_fem.png"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    rows = list(csv.DictReader(open(sys.argv[1])))
    fig, ax = plt.subplots(figsize=(7.5, 5))
    style = {"ours": ("o", "tab:blue"), "bullet": ("s", "tab:red")}
    seen = set()
    for r in rows:
        marker, colour = style.get(r["engine"], ("x", "k"))
        name = "ours (co-rotated tets, symplectic)" if r["engine"] == "ours" else "Bullet (btDeformable linear elasticity, implicit)"
        ax.plot(float(r["step_us_median"]), abs(float(r["error_pct"])), marker, color=colour, ms=8,
                label=None if r["engine"] in seen else name)
        seen.add(r["engine"])
        ax.annotate(f"L{r['level']} {r['mode']}", (float(r["step_us_median"]), abs(float(r["error_pct"]))),
                    textcoords="offset points", xytext=(6, 4), fontsize=8)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("median wall time of a 1 ms world step [us]")
    ax.set_ylabel("|frequency error| against Lamb [%]")
    ax.set_title("Foam ball, same tetrahedral meshes and material")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=110)


if __name__ == "__main__":
    main()
