#!/usr/bin/python3
"""Speed against physical accuracy of the deformable ball (teleop_bench deformable).
usage: deformable_bench.py deformable.csv out.png
x: median wall time of one 1 ms world step [us] (log), y: physical error [%] (log), the largest
|error| of Lamb's S2, T2, S0 frequencies and the 5 mm press against the CalculiX ball (Bullet: the
Lamb ones). One marker per model, one line per model / integrator (/ kernel) through its
resolutions (numbers: icosphere or tet-ball level). Rows without a result (blew up, no vibration)
are drawn hollow on the top line."""
import csv
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

MARKERS = {"mass_spring": "o", "navier_linear": "s", "navier_corotational": "^", "fem": "D",
           "bullet_fem": "P"}
COLOURS = {"explicit_euler": "tab:red", "symplectic_euler": "tab:blue",
           "implicit_euler": "tab:green", "implicit": "black", "explicit": "tab:gray"}
LABELS = {"implicit": "Bullet's implicit step", "explicit": "Bullet's explicit step"}
STYLES = {"mass_spring": "-", "navier_linear": "--", "navier_corotational": "-.", "fem": "-",
          "bullet_fem": ":"}


def main():
    src, out = sys.argv[1], sys.argv[2]
    rows = list(csv.DictReader(open(src)))
    finite = [float(r["error_pct"]) for r in rows if math.isfinite(float(r["error_pct"]))]
    top = max(finite) * 2.5 if finite else 100.0
    bottom = min(finite) / 2.0 if finite else 0.1
    fig, ax = plt.subplots(figsize=(13, 7.5))
    series = {}
    for r in rows:
        scaled = float(r.get("mass_scaling_step_s") or 0) > 0
        series.setdefault((r["model"], r["integrator"], r["kernel"], scaled), []).append(r)
    for (model, integ, kernel, scaled), rs in series.items():
        rs.sort(key=lambda r: int(r["level"]))
        c = "tab:orange" if scaled else COLOURS.get(integ, "tab:purple")
        simd = kernel == "simd"
        xs = [float(r["step_us_median"]) for r in rs]
        ys = [float(r["error_pct"]) for r in rs]
        ys_drawn = [y if math.isfinite(y) else top for y in ys]
        ax.plot(xs, ys_drawn, color=c, ls=STYLES[model], lw=1.0, alpha=0.6)
        for x, y, yd, r in zip(xs, ys, ys_drawn, rs):
            if math.isfinite(y):
                ax.scatter(x, y, color=c, marker=MARKERS[model], s=46, alpha=0.9,
                           facecolors="none" if simd else c, zorder=3)
            else:  # no result: the model's marker, hollow, on the top edge
                ax.scatter(x, yd, color=c, marker=MARKERS[model], s=46, facecolors="none",
                           zorder=3)
            ax.annotate(r["level"], (x, yd), fontsize=7, xytext=(3, 3), textcoords="offset points")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_ylim(bottom, top * 1.6)
    ax.axhline(top, color="gray", lw=0.8, ls=":")
    ax.text(ax.get_xlim()[0] * 1.1, top * 1.15, "no result: blew up, or no vibration", fontsize=8,
            color="gray")
    ax.axvline(1000, color="gray", ls="--", lw=1)
    ax.text(1000 * 1.05, bottom * 1.2, "1 ms: a 1 kHz world step", fontsize=8, color="gray")
    ax.axhline(10, color="gray", ls=":", lw=1)
    ax.set_xlabel("median wall time of one 1 ms world step, sub-steps included [us] (one core)")
    ax.set_ylabel("physical error [%]: largest |error| of Lamb S2, T2, S0 and the 5 mm press")
    ax.grid(True, which="both", alpha=0.3)
    handles = [plt.Line2D([], [], color="k", marker=m, ls=STYLES[k], label=k)
               for k, m in MARKERS.items()]
    handles += [plt.Line2D([], [], color=c, marker="o", ls="", label=LABELS.get(k, k))
                for k, c in COLOURS.items() if any(r["integrator"] == k for r in rows)]
    if any(float(r.get("mass_scaling_step_s") or 0) > 0 for r in rows):
        handles.append(plt.Line2D([], [], color="tab:orange", marker="D", ls="",
                                  label="fem symplectic, mass-scaled to one step per 1 ms"))
    handles.append(plt.Line2D([], [], color="tab:blue", marker="o", ls="", fillstyle="none",
                              label="hollow: mass_spring kernel simd; on the top line: no result"))
    ax.legend(handles=handles, fontsize=8, loc="lower left", ncol=2)
    ax.set_title("Deformable foam ball (E 6000 Pa, nu 0.3, 2 kg, r 0.25 m): cost against error "
                 "against physics\n(Lamb's frequencies; CalculiX ball pressed 5 mm on the floor; "
                 "numbers: mesh level; bullet_fem: Lamb only)", fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main()
