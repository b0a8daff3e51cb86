"""Charts of a teleoperation session (experiment 3) from teleop_master's CSV log.

usage: session.py MASTER_CSV OUT_DIR [TITLE]
Writes OUT_DIR/session.png (positions, forces, deformation and delays over time) and
OUT_DIR/force_deformation.png (environment force against the indentation of the sphere,
the paper's Fig. 17, with a least-squares F = k x line for reference).
"""
import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def load(path):
    cols = {}
    with open(path) as f:
        for row in csv.DictReader(f):
            for k, v in row.items():
                try:
                    cols.setdefault(k, []).append(float(v))
                except ValueError:
                    cols.setdefault(k, []).append(float("nan"))
    return cols


def main(path, out_dir, title):
    c = load(path)
    t = c["t_s"]
    fig, ax = plt.subplots(4, 1, figsize=(10, 10), sharex=True)
    ax[0].plot(t, c["xm_z"], label="master command z (slave frame)")
    ax[0].plot(t, c["xs_z"], label="slave tip z")
    ax[0].set_ylabel("height [m]")
    ax[0].legend(loc="upper right", fontsize=8)
    fe = [math.sqrt(x * x + y * y + z * z) for x, y, z in zip(c["fe_x"], c["fe_y"], c["fe_z"])]
    fm = [math.sqrt(x * x + y * y + z * z) for x, y, z in zip(c["fm_x"], c["fm_y"], c["fm_z"])]
    ax[1].plot(t, fe, label="|environment force| on the slave tip")
    ax[1].plot(t, fm, "--", label="|force rendered| at the master")
    ax[1].set_ylabel("force [N]")
    ax[1].legend(loc="upper right", fontsize=8)
    ax[2].plot(t, [d * 1e3 for d in c["deformation_m"]], label="indentation of the sphere")
    ax[2].plot(t, [d * 1e3 for d in c["penetration_m"]], label="contact spring compression")
    ax[2].set_ylabel("[mm]")
    ax[2].legend(loc="upper right", fontsize=8)
    ax[3].plot(t, c["loop_delay_ms"], ".", markersize=1, label="loop delay (command in -> echo used)")
    ax[3].plot(t, c["rtt_ms"], ".", markersize=1, label="network round trip")
    ax[3].set_ylabel("[ms]")
    ax[3].set_xlabel("time [s]")
    ax[3].legend(loc="upper right", fontsize=8)
    for a in ax:
        a.grid(alpha=0.3)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(os.path.join(out_dir, "session.png"), dpi=100)

    # Fig. 17: force against deformation while in contact during the session
    xs, fs = [], []
    for ph, ic, d, f in zip(c["phase"], c["in_contact"], c["deformation_m"], fe):
        if ph == 1 and ic == 1 and d > 0:
            xs.append(d)
            fs.append(f)
    fig, ax = plt.subplots(figsize=(7, 5))
    if xs:
        ax.plot([x * 1e3 for x in xs], fs, ".", markersize=2, label="networked run (server)")
        sxx = sum(x * x for x in xs)
        k = sum(x * f for x, f in zip(xs, fs)) / sxx if sxx > 0 else 0.0
        xmax = max(xs)
        ax.plot([0, xmax * 1e3], [0, k * xmax], "k--", label=f"least squares F = k x, k = {k:.0f} N/m")
        ax.legend()
    else:
        ax.text(0.5, 0.5, "no contact in this run", ha="center", transform=ax.transAxes)
    ax.set_xlabel("indentation of the sphere x [mm]")
    ax.set_ylabel("|reaction force| [N]")
    ax.set_title("Force against deformation (paper Fig. 17)")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(out_dir, "force_deformation.png"), dpi=100)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], sys.argv[3] if len(sys.argv) > 3 else "teleoperation session")
