#!/usr/bin/python3
"""Paper Figs. 4-5: a vertex of the Navier sphere pushed in and released; phase graph.
usage: deformable_navier_free.py navier_free_vertex.csv out.png"""
import sys

import matplotlib

from chartlib import load_columns_by

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def main():
    src, out = sys.argv[1], sys.argv[2]
    data = load_columns_by(src, "variant")
    fig, ax = plt.subplots(1, 2, figsize=(12, 5))
    for name, d in data.items():
        ax[0].plot([1e3 * x for x in d["displacement_m"]], d["velocity_mps"], lw=0.7, label=name)
        ax[1].plot(d["t_s"], [1e3 * x for x in d["displacement_m"]], lw=0.8, label=name)
    ax[0].set(xlabel="radial displacement [mm]", ylabel="radial velocity [m/s]",
              title="Fig. 5: phase graph of the released vertex")
    ax[1].set(xlabel="t [s]", ylabel="radial displacement [mm]",
              title="Fig. 4: the vertex moving around its equilibrium")
    for a in ax:
        a.grid(True, alpha=0.3)
        a.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main()
