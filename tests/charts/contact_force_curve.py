"""Chart for `teleop_experiment contact-force-curve`: force against deformation (paper
Figs. 16-17) at each pressing speed, with the fitted linear law F = k x and Hertz law
F = c x^1.5 drawn for reference, and force against time.

usage: /usr/bin/python3 contact_force_curve.py OUT_DIR
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def load(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def main():
    out = sys.argv[1]
    rows = load(os.path.join(out, "contact_force_curve.csv"))
    fits = load(os.path.join(out, "contact_force_fit.csv"))
    speeds = sorted({float(r["speed_mps"]) for r in rows})
    fig, (ax, axt) = plt.subplots(1, 2, figsize=(12, 5))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    xmax = 0.0
    for i, s in enumerate(speeds):
        c = colors[i % len(colors)]
        rs = [r for r in rows if float(r["speed_mps"]) == s]
        for phase, style, label in ((0, "-", "press"), (2, ":", "release")):
            pr = [r for r in rs if int(float(r["phase"])) == phase]
            x = [1000 * float(r["deformation_m"]) for r in pr]
            f = [float(r["force_z_n"]) for r in pr]
            xmax = max([xmax] + x)
            ax.plot(x, f, style, color=c, lw=1.2, label=f"{s:g} m/s {label}")
        t = [float(r["t_s"]) for r in rs]
        axt.plot([v - t[0] for v in t], [float(r["force_z_n"]) for r in rs], color=c, lw=1,
                 label=f"{s:g} m/s")
    # reference laws fitted to the slowest press
    fit = min(fits, key=lambda r: float(r["speed_mps"]))
    k = float(fit["k_lin_n_per_m"])
    ch = float(fit["c_hertz_n_per_m1p5"])
    xs = [xmax * i / 100.0 for i in range(101)]
    ax.plot(xs, [k * x / 1000 for x in xs], "k--", lw=1,
            label=f"linear F = k x, k = {k:.0f} N/m (rms {float(fit['rms_lin_n']):.2f} N)")
    ax.plot(xs, [ch * (x / 1000) ** 1.5 for x in xs], "k-.", lw=1,
            label=f"Hertz F = c x^1.5, E* = {float(fit['estar_pa']):.0f} Pa "
                  f"(rms {float(fit['rms_hertz_n']):.2f} N)")
    better = "linear" if float(fit["rms_lin_n"]) <= float(fit["rms_hertz_n"]) else "Hertz"
    ax.set_title(f"Tip on the deformable sphere: force vs deformation\n"
                 f"(closer to the {better} law at {float(fit['speed_mps']):g} m/s)")
    ax.set_xlabel("deformation x = tip travel since first touch [mm]")
    ax.set_ylabel("reaction force on the tip, z [N]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    axt.set_title("Force against time (press, hold 0.1 s, release)")
    axt.set_xlabel("time since first touch [s]")
    axt.set_ylabel("force z [N]")
    axt.grid(alpha=0.3)
    axt.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "contact_force_curve.png"), dpi=110)


if __name__ == "__main__":
    main()
