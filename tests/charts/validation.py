#!/usr/bin/python3
"""Chart of `teleop_experiment validate`: each deformable model against physics.
usage: validation.py validation.csv validation.png
Left: the tip's force against its travel for the ball on the floor under its weight, each body
beside the Hertz and CalculiX curves (foam ball). Middle: the error against physics of every body, quantity
by quantity (|error| in %, log scale), so one look shows which model is a material. Right: what
each body costs per 1 ms world step against its worst error against physics."""
import csv
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


MARKERS = {"fem": "o", "mass_spring": "s", "navier_linear": "^", "navier_corotational": "v"}
COLOURS = plt.get_cmap("tab20").colors


def label(r):
    nodal = {"element_strain": " element strain",
             "nodal_pressure_mass_scaled_1ms": " mass-scaled 1 ms"}.get(r.get("variant"), "")
    return f"{r['model']}{nodal} {r['mesh']}" + ("" if r["integrator"] == "symplectic_euler" else " (implicit)")


def best_source(rows, r):
    """The reference a row's quantity is judged against: Lamb for the modes; for the presses and
    the sag the converged CalculiX ball where the CSV has it for that body and travel, else
    Hertz."""
    if r["quantity"].startswith("lamb_"):
        return "lamb"
    for o in rows:
        if (o["reference_source"] == "calculix" and o["quantity"] == r["quantity"]
                and o["travel_mm"] == r["travel_mm"] and label(o) == label(r)
                and o["material"] == r["material"]):
            return "calculix"
    return "hertz"


def main():
    rows = list(csv.DictReader(open(sys.argv[1])))
    fig, (ax1, ax2, ax3) = plt.subplots(1, 3, figsize=(19, 5.8))
    # left: force against travel, foam, with the weight
    press = [r for r in rows if r["quantity"] == "tip_force_floor_weight_n" and r["material"] == "foam"]
    bodies = []
    for r in press:
        if label(r) not in bodies:
            bodies.append(label(r))
    for source, style, name in (("hertz", "k-", "Hertz (two contacts, weight preload)"),
                                ("calculix", "k--", "CalculiX (converged FEM)")):
        ref = sorted({(float(r["travel_mm"]), float(r["reference"])) for r in press
                      if r["reference_source"] == source})
        if ref:
            ax1.plot([t for t, _ in ref], [f for _, f in ref], style, lw=3, alpha=0.4, label=name)
    for i, b in enumerate(bodies):
        pts = sorted((float(r["travel_mm"]), float(r["value"])) for r in press
                     if label(r) == b and r["reference_source"] == "hertz")
        ax1.plot([t for t, _ in pts], [f for _, f in pts], "-", marker=MARKERS.get(b.split()[0], "o"),
                 ms=4, color=COLOURS[i % len(COLOURS)], label=b)
    ax1.set_xlabel("tip travel from the touch [mm]")
    ax1.set_ylabel("force on the tip [N]")
    ax1.set_title("Foam ball on the floor, pressed by the tip")
    ax1.grid(alpha=0.3)
    ax1.legend(fontsize=7, loc="upper left")
    # right: |error| per quantity, one row of markers per body
    quantities = ["lamb_S2_hz", "lamb_T2_hz", "lamb_S0_hz", "tip_force_floor_n",
                  "tip_force_floor_weight_n", "tip_force_held_n", "sag_top_m"]
    names = {"lamb_S2_hz": "S2", "lamb_T2_hz": "T2", "lamb_S0_hz": "S0",
             "tip_force_floor_n": "press\n(no weight)", "tip_force_floor_weight_n": "press\n(weight)",
             "tip_force_held_n": "press\n(held)", "sag_top_m": "sag"}
    all_bodies = []
    for r in rows:
        key = label(r) + " " + r["material"]
        if key not in all_bodies:
            all_bodies.append(key)
    for j, b in enumerate(all_bodies):
        xs, ys = [], []
        for q_i, q in enumerate(quantities):
            errs = [abs(float(r["error_pct"])) for r in rows
                    if label(r) + " " + r["material"] == b and r["quantity"] == q
                    and r["reference_source"] == best_source(rows, r)
                    and r["error_pct"] not in ("", "nan") and math.isfinite(float(r["error_pct"]))
                    and (r["travel_mm"] == "" or float(r["travel_mm"]) >= 2.0)]
            if errs:
                xs.append(q_i + (j - len(all_bodies) / 2) * 0.6 / max(1, len(all_bodies)))
                ys.append(max(max(errs), 0.01))
        ax2.plot(xs, ys, MARKERS.get(b.split()[0], "o"), ms=5, color=COLOURS[j % len(COLOURS)], label=b)
    ax2.axhline(10.0, color="k", ls="--", lw=1)
    ax2.text(-0.45, 11.0, "10 %", ha="left", fontsize=8)
    ax2.set_yscale("log")
    ax2.set_xticks(range(len(quantities)))
    ax2.set_xticklabels([names[q] for q in quantities], fontsize=8)
    ax2.set_ylabel("largest |error| against physics [%] (travel 2-20 mm)")
    ax2.set_title("Error against Lamb and the CalculiX ball (Hertz where it has none)")
    ax2.grid(alpha=0.3, which="both")
    # right: cost against the worst error (Lamb, and the press under the weight at 2-20 mm)
    for j, b in enumerate(all_bodies):
        sub = [r for r in rows if label(r) + " " + r["material"] == b]
        errs = [abs(float(r["error_pct"])) for r in sub
                if r["quantity"] in ("lamb_S2_hz", "lamb_T2_hz", "lamb_S0_hz", "tip_force_floor_weight_n")
                and r["reference_source"] == best_source(rows, r) and r["error_pct"] not in ("", "nan")
                and (r["travel_mm"] == "" or float(r["travel_mm"]) >= 2.0)]
        cost = [float(r["step_us"]) for r in sub if r["quantity"] == "sag_top_m"]
        if errs and cost:
            ax3.plot(cost[0], max(errs), MARKERS.get(b.split()[0], "o"), ms=7,
                     color=COLOURS[j % len(COLOURS)], label=b)
    ax3.axhline(10.0, color="k", ls="--", lw=1)
    ax3.set_xscale("log")
    ax3.set_yscale("log")
    ax3.set_xlabel("world step with the body, 1 ms of simulated time [us]")
    ax3.set_ylabel("worst |error|: Lamb, press under the weight [%]")
    ax3.set_title("Speed against physical accuracy")
    ax3.grid(alpha=0.3, which="both")
    ax3.legend(fontsize=6, loc="center left", bbox_to_anchor=(1.01, 0.5))
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=110)


if __name__ == "__main__":
    main()
