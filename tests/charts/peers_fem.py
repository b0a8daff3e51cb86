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
    fig, ax = plt.subplots(figsize=(7.5, 6.2))
    style = {"ours": ("o", "tab:blue", "ours (co-rotated tets, symplectic)"),
             "bullet-implicit": ("s", "tab:red", "Bullet btDeformable, implicit"),
             "bullet-explicit": ("^", "tab:orange", "Bullet btDeformable, explicit")}
    seen = set()
    failed = []
    for r in rows:
        marker, colour, name = style.get(r["engine"], ("x", "k", r["engine"]))
        err = float(r["error_pct"])
        if err != err:  # NaN: no vibration found (damped out or blew up)
            failed.append(f"{r['engine']} L{r['level']} {r['mode']}: no vibration "
                          f"({float(r['step_us_median']):.0f} us/step)")
            continue
        ax.plot(float(r["step_us_median"]), abs(err), marker, color=colour, ms=8,
                label=None if r["engine"] in seen else name)
        seen.add(r["engine"])
        ax.annotate(f"L{r['level']} {r['mode']}", (float(r["step_us_median"]), abs(err)),
                    textcoords="offset points", xytext=(6, 4), fontsize=8)
    if failed:
        fig.text(0.02, 0.01, "\n".join(failed), fontsize=7, va="bottom")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("median wall time of a 1 ms world step [us]")
    ax.set_ylabel("|frequency error| against Lamb [%]")
    ax.set_title("Foam ball, same tetrahedral meshes and material")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout(rect=(0, 0.05 + 0.025 * len(failed), 1, 1))
    fig.savefig(sys.argv[2], dpi=110)


if __name__ == "__main__":
    main()
