#!/usr/bin/python3
"""Our sphere against Bullet's soft body, from `teleop_bench peers`: step time (median, p99) per
engine, level and world step; the released node's radial offset and the volume error over time.

usage: peers.py PEERS_CSV PEERS_TRACE_CSV OUT_PNG
"""
import csv
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

COLOURS = {"ours-scalar": "tab:blue", "ours-simd": "tab:green", "bullet": "tab:red"}


def main(path, trace_path, out):
    rows = list(csv.DictReader(open(path)))
    trace = defaultdict(lambda: defaultdict(list))
    for r in csv.DictReader(open(trace_path)):
        key = (r["engine"], r["level"], r["dt_s"])
        trace[key]["t"].append(float(r["t_s"]))
        trace[key]["probe"].append(float(r["probe_mm"]))
        trace[key]["vol"].append(float(r["volume_pct"]))
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.8))
    ax = axes[0]
    groups = sorted({(int(r["level"]), float(r["dt_s"])) for r in rows}, key=lambda g: (g[0], -g[1]))
    engines = [e for e in COLOURS if any(r["engine"] == e for r in rows)]
    width = 0.8 / len(engines)
    for k, e in enumerate(engines):
        med, p99 = [], []
        for lv, dt in groups:
            r = next(r for r in rows if r["engine"] == e and int(r["level"]) == lv
                     and float(r["dt_s"]) == dt)
            med.append(float(r["step_us_median"]))
            p99.append(float(r["step_us_p99"]))
        xs = [i + (k - (len(engines) - 1) / 2) * width for i in range(len(groups))]
        ax.bar(xs, med, width=width, color=COLOURS[e], label=f"{e} median")
        ax.scatter(xs, p99, color="k", marker="_", s=120, zorder=3,
                   label="p99" if k == 0 else None)
    ax.set_xticks(range(len(groups)))
    ax.set_xticklabels([f"level {lv}\ndt {dt * 1e3:g} ms" for lv, dt in groups])
    ax.set_yscale("log")
    ax.set_ylabel("wall time per world step [us] (log)")
    ax.set_title("Time per step (ours: with the sub-steps it needs)")
    ax.legend(fontsize=8)
    ax.grid(axis="y", alpha=0.3, which="both")
    # traces at the finest level shown, dt = 1 ms
    lv = max(int(r["level"]) for r in rows)
    dt = max(float(r["dt_s"]) for r in rows)
    for e in engines:
        key = next((k for k in trace if k[0] == e and int(k[1]) == lv and float(k[2]) == dt), None)
        if key is None:
            continue
        d = trace[key]
        axes[1].plot(d["t"], d["probe"], color=COLOURS[e], label=e, linewidth=1)
        axes[2].plot(d["t"], d["vol"], color=COLOURS[e], label=e, linewidth=1)
    axes[1].axhline(0, color="k", linewidth=0.6)
    axes[1].set_xlabel("time [s]")
    axes[1].set_ylabel("released node: radial offset from rest [mm]")
    axes[1].set_title(f"Node pulled 5 mm out, released (level {lv}, dt {dt * 1e3:g} ms)")
    axes[1].set_xscale("symlog", linthresh=0.02)
    axes[1].set_xlim(0, max(max(d["t"]) for d in trace.values()))
    axes[1].legend(fontsize=8)
    axes[1].grid(alpha=0.3)
    axes[2].axhline(0, color="k", linewidth=0.6)
    axes[2].set_xlabel("time [s]")
    axes[2].set_ylabel("volume error (V - V0) / V0 [%]")
    axes[2].set_title("Enclosed volume")
    axes[2].legend(fontsize=8)
    axes[2].grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], sys.argv[3])
