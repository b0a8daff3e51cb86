#!/usr/bin/python3
"""Prints the CSV of `teleop_bench deformable` as a Markdown table (for docs).
usage: deformable_table.py deformable.csv [MODEL:LEVEL ...]
With arguments, only those rows (e.g. mass_spring:4 fem:2 bullet_fem:2); errors in %, signed
(+ too high or too stiff); "-" not measured, "none" blew up or no vibration."""
import csv
import math
import sys


def pct(text):
    if text in ("", "nan"):
        return "-"
    v = float(text)
    return f"{v:+.1f}" if math.isfinite(v) else "none"


def main():
    rows = list(csv.DictReader(open(sys.argv[1])))
    wanted = {tuple(a.split(":")) for a in sys.argv[2:]}
    print("| model | integrator | kernel | level | nodes / elements | sub-steps | step median [us] "
          "| step p99 [us] | S2 [%] | T2 [%] | S0 [%] | press 5 mm [%] | physical error [%] |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        if wanted and (r["model"], r["level"]) not in wanted:
            continue
        err = float(r["error_pct"])
        err_text = f"{err:.1f}" if math.isfinite(err) else "none"
        scaled = float(r.get("mass_scaling_step_s") or 0) > 0
        model = r["model"] + (" mass-scaled" if scaled else "")
        print(f"| {model} | {r['integrator']} | {r['kernel']} | {r['level']} | "
              f"{r['nodes']} / {r['elements']} | {r['substeps']} | "
              f"{float(r['step_us_median']):.1f} | {float(r['step_us_p99']):.1f} | "
              f"{pct(r['lamb_s2_pct'])} | {pct(r['lamb_t2_pct'])} | {pct(r['lamb_s0_pct'])} | "
              f"{pct(r['press_5mm_pct'])} | {err_text} |")


if __name__ == "__main__":
    main()
