#!/usr/bin/python3
"""Chart of `teleop_experiment robot-reach`: tip path vs target, contact force, tracking.

usage: robot_reach.py robot_reach.csv robot_reach.png
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
    col = lambda k: [float(r[k]) for r in rows]  # noqa: E731
    t = col("t_s")
    fig, ax = plt.subplots(4, 1, figsize=(12, 10), sharex=True)

    for k, c in (("x", "C0"), ("y", "C1"), ("z", "C2")):
        ax[0].plot(t, col("target_%s_m" % k), "--", color=c, lw=1, label="target %s" % k)
        ax[0].plot(t, col("tip_%s_m" % k), "-", color=c, lw=1.5, label="tip %s" % k)
    ax[0].axhline(0.05, color="grey", lw=0.8, ls=":")
    ax[0].axhline(0.55, color="grey", lw=0.8, ls=":")
    ax[0].text(t[0], 0.055, "tip on floor (z = r)", fontsize=9, color="grey")
    ax[0].text(t[0], 0.555, "tip on wall (y = 0.6 - r)", fontsize=9, color="grey")
    ax[0].set_ylabel("tip centre [m]")
    ax[0].legend(fontsize=10, loc="upper left", bbox_to_anchor=(1.01, 1))
    ax[0].set_title("PUMA 560 slave in ODE: tip follows a path, presses on floor and wall")

    ax[1].plot(t, col("force_x_n"), lw=1, label="Fx")
    ax[1].plot(t, col("force_y_n"), lw=1, label="Fy")
    ax[1].plot(t, col("force_z_n"), lw=1, label="Fz")
    ax[1].plot(t, col("force_n"), "k", lw=1.5, label="|F|")
    ax[1].set_ylabel("plane force on tip [N]")
    ax[1].legend(fontsize=10, loc="upper left", bbox_to_anchor=(1.01, 1))

    ax[2].semilogy(t, [max(e * 1e3, 1e-3) for e in col("error_m")], lw=1, label="position error")
    ax[2].semilogy(t, [max(p * 1e3, 1e-3) for p in col("penetration_m")], lw=1,
                   label="penetration")
    ax[2].set_ylabel("error, penetration [mm]")
    ax[2].legend(fontsize=10, loc="upper left", bbox_to_anchor=(1.01, 1))

    ax[3].plot(t, col("sigma_min_m"), lw=1, label="sigma_min of weighted J [m]")
    ax[3].plot(t, col("orientation_error_rad"), lw=1, label="orientation error [rad]")
    ax[3].set_xlabel("time [s]")
    ax[3].set_ylabel("sigma_min [m], angle [rad]")
    ax[3].legend(fontsize=10, loc="upper left", bbox_to_anchor=(1.01, 1))
    for a in ax:
        a.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=100)


if __name__ == "__main__":
    main()
