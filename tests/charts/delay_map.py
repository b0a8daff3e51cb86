#!/usr/bin/python3
"""Stable/unstable map of the bilateral schemes against one-way delay, with the analytic
delay margin drawn over it.

usage: delay_map.py delay_map.csv delay_boundary.csv delay_theory.csv out.png
"""
import csv
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def main():
    runs, bounds, theory, out = (read(sys.argv[1]), read(sys.argv[2]), read(sys.argv[3]),
                                   sys.argv[4])
    schemes = ["position-position", "force-position"]
    panels = [("gain", "sphere", "sphere k = 2000 N/m"),
              ("gain", "wall", "stiff wall k = 2e4 N/m"),
              ("stiffness", "sphere", "sphere, default gain")]
    style = {"stable": ("o", "tab:green"), "oscillating": ("s", "tab:orange"),
             "unstable": ("x", "tab:red")}
    max_delay = max(float(r["delay_ms"]) for r in runs) if runs else 200.0
    fig, axes = plt.subplots(2, 3, figsize=(15, 8.5), squeeze=False)
    for i, scheme in enumerate(schemes):
        for j, (sweep, env, title) in enumerate(panels):
            ax = axes[i][j]
            ykey = "gain" if sweep == "gain" else "stiffness_n_per_m"
            sel = [r for r in runs if r["scheme"] == scheme and r["sweep"] == sweep
                   and r["environment"] == env and r["slave"] == "point"]
            for verdict, (marker, color) in style.items():
                pts = [(float(r["delay_ms"]), float(r[ykey])) for r in sel
                       if r["verdict"] == verdict]
                if pts:
                    ax.scatter([p[0] for p in pts], [p[1] for p in pts], marker=marker,
                               c=color, s=28, label=verdict, zorder=3)
            b = [r for r in bounds if r["scheme"] == scheme and r["sweep"] == sweep
                 and r["environment"] == env]
            xs, ys = [], []
            for r in b:
                m = float(r["margin_ms"]) if r["margin_ms"] != "inf" else math.inf
                xs.append(min(m, 10 * max_delay))
                ys.append(float(r[ykey]))
            if xs:
                ax.plot(xs, ys, "k-", lw=1.6, label="analytic delay margin", zorder=2)
            # exact unstable region of the linear model (stability switches included)
            th = [r for r in theory if r["scheme"] == scheme and r["sweep"] == sweep
                  and r["environment"] == env]
            if th:
                ys_t = sorted({float(r["y"]) for r in th})
                ds_t = sorted({float(r["delay_ms"]) for r in th})
                z = [[0.0] * len(ds_t) for _ in ys_t]
                yi = {y: k for k, y in enumerate(ys_t)}
                di = {d: k for k, d in enumerate(ds_t)}
                for r in th:
                    z[yi[float(r["y"])]][di[float(r["delay_ms"])]] = 0.0 if r["stable"] == "1" else 1.0
                ax.contourf(ds_t, ys_t, z, levels=[0.5, 1.5], colors=["tab:red"], alpha=0.12,
                            zorder=0)
            ax.set_yscale("log")
            ax.set_xlim(-5, max_delay + 5)
            if sel:
                yv = [float(r[ykey]) for r in sel]
                ax.set_ylim(min(yv) / 1.3, max(yv) * 1.3)
            ax.set_xlabel("one-way delay [ms]")
            if sweep == "gain":
                ax.set_ylabel("K_pm = K_ps [N/m]" if scheme == schemes[0] else "force gain K_f [-]")
            else:
                ax.set_ylabel("environment stiffness k [N/m]")
            ax.set_title(f"{scheme}: {title}", fontsize=10)
            ax.grid(True, which="both", alpha=0.3)
            if i == 0 and j == 0:
                ax.legend(fontsize=8, loc="upper right")
    fig.suptitle("Delay robustness of the bilateral schemes (press-slip task, 1 kHz, in-process)\n"
                 "markers: simulated verdict; line: first delay margin of the linearised loop; "
                 "red shade: linear model unstable (exact, with stability switches)", fontsize=11)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
