#!/usr/bin/python3
"""Chart of `teleop_bench robot`: step time per case, median and p99.

usage: robot_bench.py robot_bench.csv robot_bench.png
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    src, out = sys.argv[1], sys.argv[2]
    with open(src, newline="") as f:
        rows = list(csv.DictReader(f))
    labels = ["%s\n%s\n%s" % (r["scenario"], r["stepper"], r["part"]) for r in rows]
    med = [float(r["median_us"]) for r in rows]
    p99 = [float(r["p99_us"]) for r in rows]
    x = range(len(rows))
    fig, ax = plt.subplots(figsize=(max(8, 0.8 * len(rows)), 5))
    ax.bar([i - 0.2 for i in x], med, 0.4, label="median")
    ax.bar([i + 0.2 for i in x], p99, 0.4, label="p99")
    ax.set_xticks(list(x))
    ax.set_xticklabels(labels, fontsize=6)
    ax.set_ylabel("time per step [us]")
    ax.set_title("PUMA 560 slave robot step (ODE 0.16, dt = 1 ms, one core)")
    ax.legend()
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main()
