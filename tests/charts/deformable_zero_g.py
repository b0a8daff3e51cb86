#!/usr/bin/python3
"""Experiment 1 (paper Figs. 14-16): radius and force of a released surface point, zero g.
usage: deformable_zero_g.py sphere_zero_g.csv out.png"""
import sys

import matplotlib

from chartlib import load_columns_by

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def main():
    src, out = sys.argv[1], sys.argv[2]
    data = load_columns_by(src, "model")
    fig, ax = plt.subplots(2, 2, figsize=(12, 8))
    for model, d in data.items():
        t = d["t_s"]
        ax[0, 0].plot(t, [1e3 * r for r in d["radius_m"]], label=model, lw=1)
        ax[0, 1].plot(t, d["force_radial_n"], label=model, lw=1)
        ax[1, 0].plot([1e3 * x for x in d["deformation_m"]], d["force_radial_n"], label=model, lw=0.8)
        ax[1, 1].semilogy(t, [max(1e-9, 1e3 * e) for e in d["shape_error_m"]], label=model, lw=1)
    ax[0, 0].set(xlabel="t [s]", ylabel="radius at the point [mm]",
                 title="Fig. 14: position (radius) of the released point")
    ax[0, 1].set(xlabel="t [s]", ylabel="radial internal force [N]",
                 title="Fig. 15: force on the point (negative = inward)")
    ax[1, 0].set(xlabel="deformation r - r0 [mm]", ylabel="radial internal force [N]",
                 title="Fig. 16: force against deformation")
    ax[1, 1].set(xlabel="t [s]", ylabel="max shape error [mm]", title="shape recovery")
    for a in (ax[0, 0], ax[0, 1]):
        a.set_xlim(0, 0.08)
    for a in ax.flat:
        a.grid(True, alpha=0.3)
        a.legend(fontsize=8)
    fig.suptitle("Sphere r = 0.25 m, g = 0: one surface point 5 mm out, released")
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main()
