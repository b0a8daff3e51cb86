#!/usr/bin/python3
"""Stable/unstable map of the bilateral schemes against one-way delay, with the analytic
delay margin drawn over it. The passivity-based schemes (wave-variables, tdpa on
position-position, tdpa-fp on force-position) have one row each; for tdpa the line and the
shade are those of its base law without the passivity controller (dashed).

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
    present = {r["scheme"] for r in runs}
    schemes = [s for s in ["position-position", "force-position", "wave-variables", "tdpa",
                           "tdpa-fp", "model-mediated"] if s in present]
    # the analytic model a row is drawn against (tdpa: its base law, without the PC)
    base = {"position-position": "position-position", "force-position": "force-position",
            "tdpa": "position-position", "tdpa-fp": "force-position"}
    gain_axis = {"position-position": "K_pm = K_ps [N/m]", "force-position": "force gain K_f [-]",
                 "wave-variables": "K_ps [N/m] (b = K_ps x 25 ms, <= 20 N s/m)",
                 "tdpa": "K_pm = K_ps [N/m]", "tdpa-fp": "force gain K_f [-]",
                 "model-mediated": "(no gain: K_ps = 400 N/m)"}
    panels = [("gain", "sphere", "sphere k = 2000 N/m"),
              ("gain", "wall", "stiff wall k = 2e4 N/m"),
              ("stiffness", "sphere", "sphere, default gain")]
    style = {"stable": ("o", "tab:green"), "oscillating": ("s", "tab:orange"),
             "out-of-spec": ("D", "tab:purple"), "unstable": ("x", "tab:red")}
    max_delay = max(float(r["delay_ms"]) for r in runs) if runs else 200.0
    fig, axes = plt.subplots(len(schemes), 3, figsize=(15, 4.25 * len(schemes)), squeeze=False)
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
            model = base.get(scheme)
            dashed = model is not None and model != scheme
            b = [r for r in bounds if r["scheme"] == model and r["sweep"] == sweep
                 and r["environment"] == env]
            xs, ys = [], []
            for r in b:
                m = float(r["margin_ms"]) if r["margin_ms"] != "inf" else math.inf
                xs.append(min(m, 10 * max_delay))
                ys.append(float(r[ykey]))
            if xs:
                ax.plot(xs, ys, "k--" if dashed else "k-", lw=1.6,
                        label="base law's delay margin (no PC)" if dashed
                        else "analytic delay margin", zorder=2)
            # exact unstable region of the linear model (stability switches included)
            th = [r for r in theory if r["scheme"] == model and r["sweep"] == sweep
                  and r["environment"] == env]
            if th:
                ys_t = sorted({float(r["y"]) for r in th})
                ds_t = sorted({float(r["delay_ms"]) for r in th})
                z = [[0.0] * len(ds_t) for _ in ys_t]
                yi = {y: k for k, y in enumerate(ys_t)}
                di = {d: k for k, d in enumerate(ds_t)}
                for r in th:
                    z[yi[float(r["y"])]][di[float(r["delay_ms"])]] = 0.0 if r["stable"] == "1" else 1.0
                ax.contourf(ds_t, ys_t, z, levels=[0.5, 1.5], colors=["tab:red"],
                            alpha=0.06 if dashed else 0.12, zorder=0)
            ax.set_yscale("log")
            ax.set_xlim(-5, max_delay + 5)
            if sel:
                yv = [float(r[ykey]) for r in sel]
                ax.set_ylim(min(yv) / 1.3, max(yv) * 1.3)
            ax.set_xlabel("one-way delay [ms]")
            if sweep == "gain":
                ax.set_ylabel(gain_axis[scheme])
            else:
                ax.set_ylabel("environment stiffness k [N/m]")
            ax.set_title(f"{scheme}: {title}", fontsize=10)
            ax.grid(True, which="both", alpha=0.3)
            if j == 0 and (i == 0 or base.get(scheme) not in (None, scheme)):
                ax.legend(fontsize=8, loc="upper right")
    fig.suptitle("Delay robustness of the bilateral schemes (press-slip task, 1 kHz, in-process)\n"
                 "markers: simulated verdict; line: first delay margin of the linearised loop; "
                 "red shade: linear model unstable (exact, with stability switches);\n"
                 "tdpa rows: dashed line and light shade = the base law without the passivity "
                 "controller; wave-variables: passive for any delay", fontsize=11)
    fig.tight_layout(rect=(0, 0, 1, 1.0 - 0.6 / (4.25 * len(schemes))))
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
