#!/usr/bin/python3
"""Prints the CSV of `teleop_experiment validate` as a Markdown table (docs/results.md): one row
per body, the error of each quantity in % against its reference (Lamb, CalculiX, Hertz), the sag
and the step cost.
usage: validation_table.py validation.csv"""
import csv
import math
import sys

# (quantity, travel_mm, reference source, header): the floor presses and the held press against
# the converged CalculiX ball (tests/reference/calculix), the press under the weight against Hertz
# as well (Hertz's own error there is in that reference's README), Lamb for the modes
COLUMNS = [("lamb_S2_hz", "", "lamb", "S2"), ("lamb_T2_hz", "", "lamb", "T2"),
           ("lamb_S0_hz", "", "lamb", "S0"),
           ("tip_force_floor_weight_n", "2", "calculix", "weight 2 mm"),
           ("tip_force_floor_weight_n", "5", "calculix", "5 mm"),
           ("tip_force_floor_weight_n", "10", "calculix", "10 mm"),
           ("tip_force_floor_weight_n", "20", "calculix", "20 mm"),
           ("tip_force_held_n", "2", "calculix", "held 2 mm"),
           ("tip_force_held_n", "10", "calculix", "held 10 mm"),
           ("tip_force_floor_n", "2", "calculix", "no weight 2 mm"),
           ("tip_force_floor_n", "10", "calculix", "no weight 10 mm"),
           ("tip_force_floor_weight_n", "2", "hertz", "weight 2 mm (Hertz)"),
           ("tip_force_floor_weight_n", "10", "hertz", "weight 10 mm (Hertz)"),
           ("sag_top_m", "", "calculix", "sag")]


def cell(rows, quantity, travel, source):
    for r in rows:
        if r["quantity"] == quantity and r["travel_mm"] == travel and r["reference_source"] == source:
            e = float(r["error_pct"]) if r["error_pct"] not in ("", "nan") else math.nan
            return "n/a" if not math.isfinite(e) else f"{e:+.0f}"
    return "-"


def main():
    rows = list(csv.DictReader(open(sys.argv[1])))
    bodies = []
    for r in rows:
        key = (r["model"], r["variant"], r["integrator"], r["mesh"], r["material"])
        if key not in bodies:
            bodies.append(key)
    print("| body | nodes / tets | " + " | ".join(c[3] for c in COLUMNS) + " | sag (top) | step [us] |")
    print("|---" * (len(COLUMNS) + 4) + "|")
    for b in bodies:
        sub = [r for r in rows if (r["model"], r["variant"], r["integrator"], r["mesh"], r["material"]) == b]
        integ = ("" if b[2] == "symplectic_euler" else " implicit") + (" element strain" if b[1] == "element_strain" else "")
        sag = next((float(r["value"]) for r in sub if r["quantity"] == "sag_top_m"), math.nan)
        us = next((float(r["step_us"]) for r in sub if r["quantity"] == "sag_top_m"), math.nan)
        print(f"| {b[0]}{integ} {b[3]} {b[4]} | {sub[0]['nodes']} / {sub[0]['tets']} | " +
              " | ".join(cell(sub, q, t, src) for q, t, src, _ in COLUMNS) +
              f" | {sag * 1e3:.1f} mm | {us:.0f} |")


if __name__ == "__main__":
    main()
