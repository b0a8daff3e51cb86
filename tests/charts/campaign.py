#!/usr/bin/python3
"""Charts and summary of a campaign's results table (teleop_campaign run / merge).

  stability_map.png  one row per scheme, one panel per sweep: each run's verdict against the
                     one-way delay and the axis the sweep varies besides it (gain, stiffness,
                     loss, ...). Point-model runs also show the exact verdict of the linearised
                     loop (shaded cell: green stable, red unstable) and its first delay margin
                     (black line).
  transparency.png   felt stiffness over the environment's, and the force felt in free space,
                     against the one-way delay, per scheme and environment (median over the
                     stable runs at each delay).
  summary.txt        per scheme: runs, stable runs, agreement with the linear model.

usage: campaign.py results.csv OUT_DIR
"""
import math
import os
import statistics
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from chartlib import read_rows  # noqa: E402

SCHEMES = ["position-position", "force-position", "wave-variables", "tdpa", "tdpa-fp",
           "model-mediated"]
STYLE = {"stable": ("o", "tab:green"), "degraded": ("v", "tab:olive"),
         "oscillating": ("s", "tab:orange"), "out-of-spec": ("D", "tab:purple"),
         "unstable": ("x", "tab:red"), "error": ("*", "black")}
# the axis a panel puts on y: the first that varies within the (sweep, scheme) runs
Y_AXES = [("gain", "gain (K_pm = K_ps [N/m] or K_f [-])"), ("stiffness_n_per_m", "k [N/m]"),
          ("loss", "loss [-]"), ("jitter_ms", "jitter [ms]"), ("burst_p_gb", "burst p_gb [-]"),
          ("max_force_n", "device peak force [N]"), ("press_depth_m", "press depth [m]"),
          ("seed", "seed")]


def style(verdict):
    """Marker and colour of a verdict (a verdict this script does not know: grey plus)."""
    return STYLE.get(verdict, ("P", "tab:gray"))


def f(v):
    return float(v) if v not in ("", "-") else math.nan


def where(r):
    """The environment of a run: the point model's object, or the scene."""
    return r["environment"] if r["environment"] != "-" else os.path.basename(r["scene"])


def y_axis(rows):
    for key, label in Y_AXES:
        if len({r[key] for r in rows}) > 1:
            return key, label
    return None, ""


def panel(ax, scheme, sweep, sel, legend):
    """One stability panel: the runs of one (scheme, sweep); `legend`: the verdicts to list."""
    key, label = y_axis(sel)
    ys = [f(r[key]) if key else 0.0 for r in sel]
    xs = [f(r["delay_ms"]) for r in sel]
    if any(r.get("theory_stable", "-1") != "-1" for r in sel):
        for want, shade in (("1", "#c8ecc8"), ("0", "#f6c8c8")):
            pts = [(x, y) for r, x, y in zip(sel, xs, ys) if r["theory_stable"] == want]
            if pts:
                ax.scatter([p[0] for p in pts], [p[1] for p in pts], marker="s", s=110, c=shade,
                           zorder=1, linewidths=0)
        margin = defaultdict(lambda: math.inf)
        for r, y in zip(sel, ys):
            margin[y] = min(margin[y], f(r["analytic_margin_ms"]))
        line = sorted((y, m) for y, m in margin.items() if math.isfinite(m))
        if line:
            ax.plot([m for _, m in line], [y for y, _ in line], "k-", lw=1,
                    label="first delay margin", zorder=2)
    for verdict in dict.fromkeys(list(STYLE) + [r["verdict"] for r in sel]):
        marker, color = style(verdict)
        pts = [(x, y) for r, x, y in zip(sel, xs, ys) if r["verdict"] == verdict]
        if pts:
            ax.scatter([p[0] for p in pts], [p[1] for p in pts], marker=marker, c=color, s=18,
                       label=verdict, zorder=3)
    if key in ("gain", "stiffness_n_per_m") and min(ys) > 0:
        ax.set_yscale("log")
    ax.set_xlim(-5, max(xs) + 5)
    ax.set_title(f"{scheme}: {sweep} ({where(sel[0])})", fontsize=9)
    ax.set_xlabel("one-way delay [ms]")
    ax.set_ylabel(label)
    ax.grid(alpha=0.3)
    if legend:
        for verdict in legend:  # verdicts seen in other panels only
            if not any(r["verdict"] == verdict for r in sel):
                marker, color = style(verdict)
                ax.scatter([], [], marker=marker, c=color, s=18, label=verdict)
        ax.legend(fontsize=7, loc="upper right")


def stability_map(rows, out):
    schemes = [s for s in SCHEMES if any(r["scheme"] == s for r in rows)]
    panels = {s: list(dict.fromkeys(r["sweep"] for r in rows if r["scheme"] == s))
              for s in schemes}
    ncol = max(len(p) for p in panels.values())
    cells = []  # (row, column, scheme, sweep)
    if ncol == 1:  # one sweep per scheme: the schemes side by side, three to a row
        ncol = min(3, len(schemes))
        for k, s in enumerate(schemes):
            cells.append((k // ncol, k % ncol, s, panels[s][0]))
    else:
        for i, s in enumerate(schemes):
            cells += [(i, j, s, w) for j, w in enumerate(panels[s])]
    nrow = max(c[0] for c in cells) + 1
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.6 * ncol, 3.6 * nrow + 0.6), squeeze=False)
    used = set()
    verdicts = [v for v in dict.fromkeys(list(STYLE) + [r["verdict"] for r in rows])
                if any(r["verdict"] == v for r in rows)]
    for i, j, scheme, sweep in cells:
        sel = [r for r in rows if r["scheme"] == scheme and r["sweep"] == sweep]
        panel(axes[i][j], scheme, sweep, sel, [] if used else verdicts)
        used.add((i, j))
    for i in range(nrow):
        for j in range(ncol):
            if (i, j) not in used:
                axes[i][j].axis("off")
    fig.suptitle("Stability map per scheme\nmarkers: simulated verdict; shade: exact verdict of "
                 "the linear model (point model)", fontsize=10)
    fig.tight_layout(rect=(0, 0, 1, 1 - 0.5 / (3.6 * nrow + 0.6)))
    fig.savefig(out, dpi=90, metadata={"Software": None})
    plt.close(fig)


def transparency(rows, out):
    envs = list(dict.fromkeys(where(r) for r in rows))
    fig, axes = plt.subplots(2, len(envs), figsize=(min(18.0, max(9.0, 5.5 * len(envs))), 9.0),
                             squeeze=False)
    for j, env in enumerate(envs):
        for scheme in SCHEMES:
            sel = [r for r in rows if r["scheme"] == scheme and where(r) == env
                   and r["verdict"] == "stable"]
            by_delay = defaultdict(lambda: ([], []))
            for r in sel:
                ratio, free = f(r.get("stiffness_ratio", "nan")), f(r.get("free_force_mean_n",
                                                                          "nan"))
                if math.isfinite(ratio):
                    by_delay[f(r["delay_ms"])][0].append(ratio)
                if math.isfinite(free):
                    by_delay[f(r["delay_ms"])][1].append(free)
            ds = sorted(by_delay)
            for k, ax in enumerate((axes[0][j], axes[1][j])):
                pts = [(d, statistics.median(by_delay[d][k])) for d in ds if by_delay[d][k]]
                if pts:
                    ax.plot([p[0] for p in pts], [p[1] for p in pts], "o-", ms=3, label=scheme)
        axes[0][j].set_title(f"{env}: felt stiffness / environment's\n(median, stable runs)",
                             fontsize=11)
        axes[0][j].axhline(1.0, color="k", lw=0.8, ls=":")
        axes[0][j].set_ylabel("stiffness ratio [-]")
        axes[1][j].set_title(f"{env}: force felt in free space\n(median of means)", fontsize=11)
        axes[1][j].set_ylabel("force in free space [N]")
        for ax in (axes[0][j], axes[1][j]):
            ax.set_xlabel("one-way delay [ms]")
            ax.grid(alpha=0.3)
    handles, labels = axes[0][0].get_legend_handles_labels()
    ncol = max(1, min(len(labels), 3 * len(envs)))
    fig.legend(handles, labels, loc="lower center", ncol=ncol, frameon=False, fontsize=11)
    fig.tight_layout(rect=(0, 0.035 * math.ceil(len(labels) / ncol) + 0.01, 1, 1))
    fig.savefig(out, dpi=100, metadata={"Software": None})
    plt.close(fig)


def summary(rows):
    lines = []
    judged = agree = 0
    for scheme in SCHEMES:
        sel = [r for r in rows if r["scheme"] == scheme]
        if not sel:
            continue
        stable = sum(r["verdict"] == "stable" for r in sel)
        line = f"{scheme:18s} {len(sel):6d} runs, {stable:6d} stable"
        with_theory = [r for r in sel if r.get("theory_stable", "-1") != "-1"]
        if with_theory:
            a = sum((r["theory_stable"] == "1") == (r["verdict"] == "stable")
                    for r in with_theory)
            line += f", verdict = linear theory's in {a}/{len(with_theory)}"
            if scheme in ("position-position", "force-position"):
                judged += len(with_theory)
                agree += a
        lines.append(line)
    if judged:
        lines.append(f"position-position and force-position against the exact linear stability: "
                     f"{agree}/{judged} ({100.0 * agree / judged:.1f} %)")
    return "\n".join(lines) + "\n"


def main():
    rows = read_rows(sys.argv[1])
    out = sys.argv[2]
    text = summary(rows)
    with open(os.path.join(out, "summary.txt"), "w") as fh:
        fh.write(text)
    sys.stdout.write(text)
    stability_map(rows, os.path.join(out, "stability_map.png"))
    transparency(rows, os.path.join(out, "transparency.png"))


if __name__ == "__main__":
    main()
