"""Bar chart of DDS round-trip medians and p99 from teleop_bench rtt's CSV.

usage: rtt.py RTT_CSV OUT_PNG
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(path, out):
    rows = list(csv.DictReader(open(path)))
    labels = [f"{r['profile']}\n{int(r['payload_bytes'])} B\n{r['mode']}" for r in rows]
    p50 = [float(r["rtt_us_p50"]) for r in rows]
    p99 = [float(r["rtt_us_p99"]) for r in rows]
    x = range(len(rows))
    fig, ax = plt.subplots(figsize=(11, 5))
    ax.bar([i - 0.2 for i in x], p50, width=0.4, label="median")
    ax.bar([i + 0.2 for i in x], p99, width=0.4, label="p99")
    ax.set_xticks(list(x))
    ax.set_xticklabels(labels, fontsize=8)
    ax.set_ylabel("round trip [us]")
    ax.set_yscale("log")
    ax.set_title("Fast DDS round trip between two processes on loopback")
    ax.legend()
    ax.grid(axis="y", which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
