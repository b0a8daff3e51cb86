"""Bar chart of the physics step time per session phase from teleop_bench world's CSV.

usage: world_bench.py WORLD_CSV OUT_PNG
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(path, out):
    rows = list(csv.DictReader(open(path)))
    names = [r["phase"] for r in rows]
    x = range(len(rows))
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for off, key, label in ((-0.2, "step_us_median", "median"), (0.2, "step_us_p99", "p99")):
        ax.bar([i + off for i in x], [float(r[key]) for r in rows], width=0.4, label=label)
    dt_us = float(rows[0]["dt_s"]) * 1e6
    ax.axhline(250, color="k", linestyle="--", linewidth=1, label="p99 budget 250 us (4 kHz)")
    ax.axhline(dt_us, color="r", linestyle=":", linewidth=1, label=f"period {dt_us:.0f} us")
    ax.set_xticks(list(x))
    ax.set_xticklabels(names)
    ax.set_ylabel("step wall time [us]")
    pacing = rows[0].get("pacing", "back_to_back").replace("_", " ")
    ax.set_title(f"Assembled world, one step, one core ({pacing})")
    ax.legend(fontsize=8)
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
