#!/usr/bin/python3
"""Experiment 2 without the robot: the sphere dropped between walls settles on the floor.
usage: deformable_gravity.py sphere_gravity.csv out.png"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def main():
    src, out = sys.argv[1], sys.argv[2]
    cols = {}
    with open(src) as f:
        for row in csv.DictReader(f):
            for k, v in row.items():
                cols.setdefault(k, []).append(float(v))
    t = cols["t_s"]
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.5))
    ax[0].plot(t, [1e3 * z for z in cols["centroid_z_m"]], label="centroid z")
    ax[0].plot(t, [1e3 * z for z in cols["lowest_z_m"]], label="lowest node z")
    ax[0].axhline(250, color="gray", ls=":", label="rest radius")
    ax[0].set(xlabel="t [s]", ylabel="height z [mm]", title="height")
    ax[1].semilogy(t, [max(k, 1e-12) for k in cols["kinetic_j"]])
    ax[1].set(xlabel="t [s]", ylabel="kinetic energy [J]", title="kinetic energy (0 = asleep)")
    ax[2].plot(t, cols["plane_force_z_n"], label="floor (z)")
    ax[2].plot(t, cols["plane_force_x_n"], label="walls (x)")
    ax[2].plot(t, [10 * s for s in cols["sleeping"]], label="sleeping x10")
    ax[2].set(xlabel="t [s]", ylabel="plane contact force [N]", title="plane contact forces")
    for a in ax:
        a.grid(True, alpha=0.3)
    for a in (ax[0], ax[2]):
        a.legend(fontsize=10)
    fig.suptitle("Sphere dropped 0.15 m between walls onto the floor, g = 9.81 m/s^2")
    fig.tight_layout()
    fig.savefig(out, dpi=100)


if __name__ == "__main__":
    main()
