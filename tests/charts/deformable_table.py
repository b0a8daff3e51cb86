#!/usr/bin/python3
"""Prints the speed/accuracy CSV of `teleop_bench deformable` as a Markdown table (for docs).
usage: deformable_table.py deformable.csv [level ...]"""
import csv
import math
import sys


def main():
    rows = list(csv.DictReader(open(sys.argv[1])))
    levels = set(sys.argv[2:]) or {r["level"] for r in rows}
    print("| model | integrator | level | dt [ms] | step median [us] | step p99 [us] | error [mm] |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        if r["level"] not in levels:
            continue
        err = float(r["error"])
        err_text = "blew up" if not math.isfinite(err) else f"{err * 1e3:.3f}"
        print(f"| {r['model']} | {r['integrator']} | {r['level']} | {float(r['dt_s']) * 1e3:g} | "
              f"{float(r['step_us_median']):.1f} | {float(r['step_us_p99']):.1f} | {err_text} |")


if __name__ == "__main__":
    main()
