#!/usr/bin/python3
"""Stable/unstable maps of the bilateral schemes against one-way delay, with the analytic delay
margin drawn over them: three figures of six panels each, one message each.

  OUT                  position-position and force-position: the simulation against the
                       analytic margin of the linearised loop
  OUT_STEM_tdpa.png    tdpa on position-position and on force-position: stable beyond their
                       base law's margin (the base law's line and shade are dashed / light)
  OUT_STEM_passive.png wave variables and model-mediated teleoperation: stable at every delay

Each row is one scheme; its panels are the gain sweep on the elastic sphere, the gain sweep on
the stiff wall and the stiffness sweep on the sphere at the default gain. Each title states the
figure's finding, counted from the CSV.

usage: delay_map.py delay_map.csv delay_boundary.csv delay_theory.csv out.png
"""
import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402
from matplotlib.ticker import FixedLocator, FuncFormatter, NullFormatter  # noqa: E402

plt.rcParams.update({"font.size": 11, "axes.titlesize": 12, "axes.labelsize": 11,
                     "xtick.labelsize": 10, "ytick.labelsize": 10, "legend.fontsize": 11,
                     "figure.titlesize": 14})

# the analytic model a row is drawn against (tdpa: its base law, without the passivity controller)
BASE = {"position-position": "position-position", "force-position": "force-position",
        "tdpa": "position-position", "tdpa-fp": "force-position"}
GAIN_AXIS = {"position-position": "coupling gain K_pm = K_ps [N/m]",
             "force-position": "force gain K_f [-]",
             "wave-variables": "coupling gain K_ps [N/m]",
             "tdpa": "coupling gain K_pm = K_ps [N/m]", "tdpa-fp": "force gain K_f [-]",
             "model-mediated": "gain [-]: none to sweep"}
PANELS = [("gain", "sphere", "elastic sphere, k = 2000 N/m"),
          ("gain", "wall", "stiff wall, k = 2e4 N/m"),
          ("stiffness", "sphere", "sphere of stiffness k, default gain")]
STYLE = {"stable": ("o", "tab:green"), "oscillating": ("s", "tab:orange"),
         "out-of-spec": ("D", "tab:purple"), "unstable": ("x", "tab:red")}
NAMES = {"position-position": "position-position", "force-position": "force-position",
         "wave-variables": "wave variables", "tdpa": "tdpa on position-position",
         "tdpa-fp": "tdpa on force-position", "model-mediated": "model-mediated"}


def read(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def number(text):
    return math.inf if text == "inf" else float(text)


def plain_log_axis(ax, lo, hi):
    """Log scale with plain tick labels (0.1, 0.2, 0.5, 1, ...; no 8x10^-1)."""
    ax.set_yscale("log")
    ax.set_ylim(lo, hi)
    ticks = [m * 10.0 ** e for e in range(-3, 6) for m in (1, 2, 3, 5) if lo <= m * 10.0 ** e <= hi]
    if len(ticks) > 8:
        ticks = [t for t in ticks if round(t / 10.0 ** math.floor(math.log10(t))) in (1, 2, 5)]
    ax.yaxis.set_major_locator(FixedLocator(ticks))
    ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    ax.yaxis.set_minor_formatter(NullFormatter())


def draw_panel(ax, scheme, sweep, env, title, runs, bounds, theory, max_delay):
    ykey = "gain" if sweep == "gain" else "stiffness_n_per_m"
    sel = [r for r in runs if r["scheme"] == scheme and r["sweep"] == sweep
           and r["environment"] == env and r["slave"] == "point"]
    ax.set_title(f"{NAMES[scheme]}: {title}")
    ax.set_xlabel("one-way delay [ms]")
    ax.set_ylabel(GAIN_AXIS[scheme] if sweep == "gain" else "environment stiffness k [N/m]")
    ax.set_xlim(-5, max_delay + 5)
    ax.grid(True, which="major", alpha=0.3)
    if not sel:
        ax.text(0.5, 0.5, "not in this run (--quick)", ha="center", va="center",
                transform=ax.transAxes)
        ax.set_yticks([])
        return
    for verdict, (marker, color) in STYLE.items():
        pts = [(float(r["delay_ms"]), float(r[ykey])) for r in sel if r["verdict"] == verdict]
        if pts:
            ax.scatter([p[0] for p in pts], [p[1] for p in pts], marker=marker, c=color, s=30,
                       zorder=3)
    model = BASE.get(scheme)
    dashed = model is not None and model != scheme
    xs, ys = [], []
    for r in bounds:
        if r["scheme"] == model and r["sweep"] == sweep and r["environment"] == env:
            xs.append(min(number(r["margin_ms"]), 10 * max_delay))
            ys.append(float(r[ykey]))
    if xs:
        ax.plot(xs, ys, "k--" if dashed else "k-", lw=1.6, zorder=2)
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
                    alpha=0.06 if dashed else 0.14, zorder=0)
    yv = [float(r[ykey]) for r in sel]
    plain_log_axis(ax, min(yv) / 1.4, max(yv) * 1.4)
    if GAIN_AXIS[scheme].endswith("none to sweep") and sweep == "gain":
        ax.set_yticks([])


def legend_handles(with_margin, with_base):
    h = [Line2D([], [], ls="", marker=m, color=c, markersize=8, label=f"simulated: {v}")
         for v, (m, c) in STYLE.items()]
    if with_margin:
        h.append(Line2D([], [], color="k", lw=1.6, label="analytic delay margin"))
        h.append(Patch(color="tab:red", alpha=0.14, label="linear model unstable"))
    if with_base:
        h.append(Line2D([], [], color="k", ls="--", lw=1.6,
                        label="base law's delay margin (no passivity controller)"))
        h.append(Patch(color="tab:red", alpha=0.06, label="base law unstable"))
    return h


def point_runs(runs, schemes):
    return [r for r in runs if r["scheme"] in schemes and r["slave"] == "point"]


def rigid_message(runs):
    sel = point_runs(runs, ("position-position", "force-position"))
    agree = sum((r["theory_stable"] == "1") == (r["verdict"] == "stable") for r in sel)
    return (f"Position-position and force-position go unstable where the linear model says: "
            f"the simulated verdict agrees in {agree} of {len(sel)} runs")


def tdpa_message(runs):
    counts = []
    for scheme in ("tdpa-fp", "tdpa"):
        sel = [r for r in point_runs(runs, (scheme,))
               if float(r["delay_ms"]) > number(r["analytic_margin_ms"])]
        counts.append((sum(r["verdict"] == "stable" for r in sel), len(sel)))
    (fp, n_fp), (pp, n_pp) = counts
    return (f"Past the base law's delay margin tdpa stays stable on force-position ({fp} of {n_fp} "
            f"runs), less often on position-position ({pp} of {n_pp}: out of spec or unstable)")


def passive_message(runs):
    sel = point_runs(runs, ("wave-variables", "model-mediated"))
    stable = sum(r["verdict"] == "stable" for r in sel)
    top = max((float(r["delay_ms"]) for r in sel), default=0.0)
    return (f"Wave variables and model-mediated teleoperation are stable at every delay: "
            f"{stable} of {len(sel)} runs up to {top:g} ms one way")


def figure(schemes, message, out, runs, bounds, theory):
    schemes = [s for s in schemes if any(r["scheme"] == s for r in runs)]
    if not schemes:
        return
    max_delay = max(float(r["delay_ms"]) for r in runs)
    fig, axes = plt.subplots(len(schemes), 3, figsize=(17, 4.2 * len(schemes) + 1.6),
                             squeeze=False)
    for i, scheme in enumerate(schemes):
        for j, (sweep, env, title) in enumerate(PANELS):
            draw_panel(axes[i][j], scheme, sweep, env, title, runs, bounds, theory, max_delay)
    with_margin = any(BASE.get(s) == s for s in schemes)
    with_base = any(BASE.get(s) not in (None, s) for s in schemes)
    fig.suptitle(message + "\n(teleop_bench delay: press task, 1 kHz, in-process)")
    handles = legend_handles(with_margin, with_base)
    fig.legend(handles=handles, loc="lower center", ncol=min(4, len(handles)), frameon=False)
    rows = 2 if len(handles) > 4 else 1
    fig.tight_layout(rect=(0, 0.045 * rows * 2 / len(schemes) + 0.01, 1, 0.95))
    fig.savefig(out, dpi=100, metadata={"Software": None})
    print(f"wrote {out}")


def main():
    runs, bounds, theory, out = (read(sys.argv[1]), read(sys.argv[2]), read(sys.argv[3]),
                                 sys.argv[4])
    if not runs:
        sys.exit(f"delay_map.py: {sys.argv[1]} has no runs")
    stem, ext = os.path.splitext(out)
    figure(["position-position", "force-position"], rigid_message(runs), out, runs, bounds,
           theory)
    figure(["tdpa", "tdpa-fp"], tdpa_message(runs), f"{stem}_tdpa{ext or '.png'}", runs, bounds,
           theory)
    figure(["wave-variables", "model-mediated"], passive_message(runs),
           f"{stem}_passive{ext or '.png'}", runs, bounds, theory)


if __name__ == "__main__":
    main()
