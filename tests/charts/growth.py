#!/usr/bin/python3
"""Cost against mesh size from `teleop_bench growth`: deformable step time against nodes and the
tip-mesh collision query against triangles, log-log, with the fitted power laws a n^b.

usage: growth.py GROWTH_CSV GROWTH_FIT_CSV OUT_PNG
"""
import csv
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(path, fit_path, out):
    data = defaultdict(lambda: defaultdict(list))
    kinds = {}
    for r in csv.DictReader(open(path)):
        d = data[r["series"]]
        kinds[r["series"]] = r["kind"]
        d["n"].append(float(r["n"]))
        d["med"].append(float(r["median_us"]))
        d["p99"].append(float(r["p99_us"]))
    fits = {r["series"]: r for r in csv.DictReader(open(fit_path))}
    fig, axes = plt.subplots(1, 2, figsize=(13, 5))
    for series, d in data.items():
        ax = axes[0] if kinds[series] == "deformable" else axes[1]
        f = fits.get(series)
        label = series
        if f:
            label += f"  (n^{float(f['exponent']):.2f})"
        line, = ax.plot(d["n"], d["med"], "o-", label=label)
        ax.plot(d["n"], d["p99"], "_", color=line.get_color(), markersize=12)
        if f:
            a, b = float(f["prefactor_us"]), float(f["exponent"])
            ax.plot(d["n"], [a * n ** b for n in d["n"]], ":", color=line.get_color(), linewidth=1)
    for ax, xl, title in ((axes[0], "surface nodes (levels 2-6)", "Deformable step"),
                          (axes[1], "triangles (levels 2-6)", "Tip-mesh collision (AABB tree)")):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(xl)
        ax.set_ylabel("wall time [us]: median (o), p99 (-), fit (:)")
        ax.set_title(title)
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], sys.argv[3])
