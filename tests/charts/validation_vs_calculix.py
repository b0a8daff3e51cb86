#!/usr/bin/python3
"""Compares `teleop_experiment validate`'s FEM rows with the CalculiX reference of
tests/reference/calculix/ball_reference.csv (fine mesh; geometrically nonlinear where it
converged, else small strain): sag of the top, the tip's force on the ball on the floor with and
without the weight, and held at its centre (25 mm clamp). Prints a Markdown table.
usage: validation_vs_calculix.py validation.csv ball_reference.csv"""
import csv
import math
import sys

# validation quantity -> (calculix case, calculix quantity)
PAIRS = {
    "sag_top_m": ("sag_floor", "top_descent"),
    "tip_force_floor_n": ("tip_floor_nogravity", "tip_force"),
    "tip_force_floor_weight_n": ("tip_floor_gravity", "tip_force"),
    "tip_force_held_n": ("tip_centre_held", "tip_force_clamp25mm"),
}


def travel(text):
    return "" if text == "" else f"{float(text):g}"


def main():
    ref = {}
    for r in csv.DictReader(open(sys.argv[2])):
        if r["mesh"] != "fine" or r["value"] in ("", "nan"):
            continue
        key = (r["material"], r["case"], r["quantity"], travel(r["travel_mm"]))
        if r["theory"] == "nlgeom" or key not in ref:
            ref[key] = (float(r["value"]), r["theory"])
    rows = [r for r in csv.DictReader(open(sys.argv[1])) if r["model"] == "fem"]
    print("| body | quantity | travel [mm] | ours | CalculiX (theory) | error |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        if r["quantity"] not in PAIRS or r["reference_source"] == "calculix":
            continue
        case, quantity = PAIRS[r["quantity"]]
        key = (r["material"], case, quantity, travel(r["travel_mm"]))
        if key not in ref:
            continue
        value, theory = ref[key]
        ours = float(r["value"])
        err = 100.0 * (ours / value - 1.0) if value else math.nan
        body = f"fem {r['variant']} {r['integrator'].split('_')[0]} {r['mesh']} {r['material']}"
        print(f"| {body} | {r['quantity']} | {r['travel_mm']} | {ours:.4g} | {value:.4g} ({theory}) | {err:+.1f} % |")


if __name__ == "__main__":
    main()
