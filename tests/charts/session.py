"""Charts of a teleoperation session (experiment 3) from teleop_master's CSV log.

usage: session.py MASTER_CSV OUT_DIR [TITLE]
Writes OUT_DIR/session.png (positions, forces, deformation and delays over time) and
OUT_DIR/force_deformation.png (the body's force against the slave's depth, the paper's Fig. 17,
and the force felt against the master's depth, each with the summary's line F = k x + b over the
loading phase, read from master.json beside the log: one definition of the stiffness felt).
"""
import csv
import json
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


def load_summary(csv_path):
    """The master's summary JSON written beside the log (master.json), or None."""
    p = os.path.join(os.path.dirname(os.path.abspath(csv_path)), "master.json")
    try:
        with open(p) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def delay_text(summary):
    """The injected delay and loss each way, from the master's summary, for the title."""
    if not summary:
        return ""
    try:
        gains = summary["tuning"]["in_force"]
        fwd, bwd = summary["delay"]["forward"], summary["delay"]["backward"]
        return ("\none-way delay %g / %g ms (forward / backward; measured p99 %.1f / %.1f ms), "
                "loss %.1f / %.1f %%" % (gains["forward_delay_ms"], gains["backward_delay_ms"],
                                         fwd["delay_p99_ms"], bwd["delay_p99_ms"],
                                         100.0 * fwd["loss_fraction"], 100.0 * bwd["loss_fraction"]))
    except (KeyError, TypeError):
        return ""


def main(path, out_dir, title):
    c = load(path)
    summary = load_summary(path)
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
    ax[2].set_ylabel("depth [mm]")
    ax[2].legend(loc="upper right", fontsize=8)
    ax[3].plot(t, c["loop_delay_ms"], ".", markersize=1, label="loop delay (command in -> echo used)")
    ax[3].plot(t, c["rtt_ms"], ".", markersize=1, label="network round trip")
    ax[3].set_ylabel("delay [ms]")
    ax[3].set_xlabel("time [s]")
    ax[3].legend(loc="upper right", fontsize=8)
    for a in ax:
        a.grid(alpha=0.3)
    fig.suptitle(title + delay_text(summary))
    fig.tight_layout()
    fig.savefig(os.path.join(out_dir, "session.png"), dpi=100)

    force_deformation(c, fe, summary, os.path.join(out_dir, "force_deformation.png"))


def fit_line(ax, fit, xs_loading, label):
    """Draws the summary's line F = k x + b over the depths of its loading samples."""
    k, b = fit
    if k is None or b is None or not xs_loading:
        return
    lo, hi = min(xs_loading), max(xs_loading)
    ax.plot([lo * 1e3, hi * 1e3], [k * lo + b, k * hi + b], "k--", linewidth=1.5,
            label=f"{label}: F = k x + b, k = {k:.0f} N/m, b = {b:.2f} N")


def force_deformation(c, fe, summary, path):
    """The paper's Fig. 17 (the body's force against its indentation) and the force the
    operator felt against the master's depth, each with the summary's loading-phase line."""
    tr = summary.get("transparency", {}) if summary else {}
    env = (tr.get("environment_stiffness_n_per_m"), tr.get("environment_offset_n"))
    felt = (tr.get("felt_stiffness_n_per_m"), tr.get("felt_offset_n"))
    have_cols = "loading" in c
    fig, ax = plt.subplots(1, 2, figsize=(12, 5))
    panels = [
        (ax[0], 1, "slave_depth_m" if have_cols else "deformation_m", fe, env,
         "environment (server)", "depth of the slave's tip in the body x [mm]",
         "|contact force on the tip| [N]"),
        (ax[1], 2, "master_depth_m", c.get("felt_force_n"), felt, "felt (master)",
         "depth of the master's command along the contact normal [mm]",
         "force felt along the normal [N]"),
    ]
    for a, bit, xcol, ys, fit, label, xlabel, ylabel in panels:
        a.set_xlabel(xlabel)
        a.set_ylabel(ylabel)
        a.grid(alpha=0.3)
        if xcol not in c or ys is None:
            a.text(0.5, 0.5, "not in this log", ha="center", transform=a.transAxes)
            continue
        pts = [(x, y, ld) for ph, ic, x, y, ld in
               zip(c["phase"], c["in_contact"], c[xcol], ys, c.get("loading", [0] * len(ys)))
               if ph == 1 and ic == 1 and x > 0]
        if not pts:
            a.text(0.5, 0.5, "no contact in this run", ha="center", transform=a.transAxes)
            continue
        a.plot([p[0] * 1e3 for p in pts], [p[1] for p in pts], ".", color="0.75", markersize=2,
               label="in contact")
        loading = [p for p in pts if int(p[2]) & bit]  # this side's loading samples
        a.plot([p[0] * 1e3 for p in loading], [p[1] for p in loading], ".", color="C0",
               markersize=3, label="loading phase (the fit's samples)")
        fit_line(a, fit, [p[0] for p in loading], "summary's fit")
        a.legend(loc="upper left", fontsize=8)
    k_felt, k_env = felt[0], env[0]
    ratio = f" (felt / environment {k_felt / k_env:.2f})" if k_felt and k_env else ""
    fig.suptitle("Force against depth in contact, paper Fig. 17" + ratio)
    fig.tight_layout()
    fig.savefig(path, dpi=100)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], sys.argv[3] if len(sys.argv) > 3 else "teleoperation session")
