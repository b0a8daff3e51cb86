#!/usr/bin/python3
"""Speed against accuracy of the deformable sphere (teleop_bench deformable).
usage: deformable_bench.py deformable.csv out.png
x: median step time [us] (log), y: RMS radial error of the probe vertex vs the reference [mm] (log).
Runs that blew up (error = inf) are drawn at the top edge with an x marker."""
import csv
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

COLOURS = {"explicit_euler": "tab:red", "symplectic_euler": "tab:blue", "implicit_euler": "tab:green"}
MARKERS = {"mass_spring": "o", "navier_linear": "s", "navier_corotational": "^"}


def main():
    src, out = sys.argv[1], sys.argv[2]
    rows = list(csv.DictReader(open(src)))
    fig, axes = plt.subplots(1, 2, figsize=(15, 6), sharey=True)
    finite = [float(r["error"]) * 1e3 for r in rows if math.isfinite(float(r["error"]))]
    top = max(finite) * 3 if finite else 10.0
    for ax, dt in zip(axes, sorted({r["dt_s"] for r in rows}, key=float, reverse=True)):
        for r in rows:
            if r["dt_s"] != dt:
                continue
            err = float(r["error"]) * 1e3
            x = float(r["step_us_median"])
            c = COLOURS[r["integrator"]]
            simd = r.get("kernel") == "simd"
            if math.isfinite(err):
                ax.scatter(x, err, color=c, marker="D" if simd else MARKERS[r["model"]], s=40,
                           alpha=0.8, facecolors="none" if simd else c)
                ax.annotate(r["level"], (x, err), fontsize=7, xytext=(3, 3), textcoords="offset points")
            else:
                ax.scatter(x, top, color=c, marker="x", s=30)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set(xlabel="median step time [us] (one core)", title=f"dt = {float(dt) * 1e3:g} ms")
        ax.axvline(100, color="gray", ls=":", lw=1)
        ax.axvline(1000, color="gray", ls="--", lw=1)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("RMS error of probe radius vs reference [mm] (x = blew up)")
    handles = [plt.Line2D([], [], color=c, marker="o", ls="", label=k) for k, c in COLOURS.items()]
    handles += [plt.Line2D([], [], color="k", marker=m, ls="", label=k) for k, m in MARKERS.items()]
    handles.append(plt.Line2D([], [], color="k", marker="D", ls="", fillstyle="none",
                              label="mass_spring, kernel simd"))
    axes[1].legend(handles=handles, fontsize=8, loc="lower right")
    fig.suptitle("Deformable sphere: step time against error (numbers = icosphere level; "
                 "reference = level 6, dt 62.5 us, symplectic)")
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main()
