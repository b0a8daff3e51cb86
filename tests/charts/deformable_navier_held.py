#!/usr/bin/python3
"""Paper Figs. 6-7: a vertex held 5 mm in; distance and force of a neighbour.
usage: deformable_navier_held.py navier_held_vertex.csv out.png"""
import sys

import matplotlib

from chartlib import load_columns_by

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def main():
    src, out = sys.argv[1], sys.argv[2]
    data = load_columns_by(src, "model")
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.5))
    for name, d in data.items():
        ax[0].plot(d["t_s"], [1e3 * x for x in d["neighbour_displacement_m"]], lw=0.8, label=name)
        ax[1].plot(d["t_s"], d["neighbour_force_n"], lw=0.8, label=name)
        ax[2].plot(d["t_s"], d["held_force_n"], lw=0.8, label=name)
    ax[0].set(xlabel="t [s]", ylabel="neighbour radius - rest [mm]",
              title="Fig. 7: distance of a neighbour")
    ax[1].set(xlabel="t [s]", ylabel="radial force on neighbour [N]", title="force on the neighbour")
    ax[2].set(xlabel="t [s]", ylabel="force to hold the vertex [N]", title="holding force")
    for a in ax:
        a.grid(True, alpha=0.3)
        a.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main()
