"""Master round trip, overruns and link losses against the number of observer processes, from
teleop_bench observers' CSV: the rate-limited observers (the default) per round and their
median, the full-rate observers (--full-rate) for comparison.

usage: observers.py OBSERVERS_CSV OUT_PNG
"""
import csv
import statistics
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def num(v):
    try:
        return float(v)
    except ValueError:
        return float("nan")


def main(path, out):
    rows = list(csv.DictReader(open(path)))
    by = defaultdict(list)  # (mode, observers) -> rows
    for r in rows:
        by[(r["mode"], int(r["observers"]))].append(r)
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.8))
    ax_rtt, ax_over, ax_loss = axes
    styles = {"rate_limited": ("C0", "o", "rate-limited topics (default)"),
              "full_rate": ("C3", "s", "--full-rate observers"),
              "rate_limited_nice0": ("C2", "^", "rate-limited, observers at nice 0")}
    base = None
    for mode, (color, marker, label) in styles.items():
        ns = sorted(n for (m, n) in by if m == mode)
        if not ns:
            continue
        med50 = [statistics.median(num(r["rtt_ms_p50"]) for r in by[(mode, n)]) for n in ns]
        med99 = [statistics.median(num(r["rtt_ms_p99"]) for r in by[(mode, n)]) for n in ns]
        for n in ns:
            for r in by[(mode, n)]:
                ax_rtt.scatter(n, num(r["rtt_ms_p99"]), color=color, marker=marker, alpha=0.35,
                               s=18)
        ax_rtt.plot(ns, med99, color=color, marker=marker, label=f"p99, {label}")
        ax_rtt.plot(ns, med50, color=color, marker=marker, linestyle="--",
                    label=f"p50, {label}")
        if mode == "rate_limited" and 0 in ns:
            base = med99[ns.index(0)]
        over = [statistics.median(num(r["master_overruns"]) for r in by[(mode, n)]) for n in ns]
        sover = [statistics.median(num(r["server_overruns"]) for r in by[(mode, n)]) for n in ns]
        ax_over.plot(ns, over, color=color, marker=marker, label=f"master, {label}")
        ax_over.plot(ns, sover, color=color, marker=marker, linestyle=":",
                     label=f"server, {label}")
        loss = [sum(num(r["link_losses"]) for r in by[(mode, n)]) for n in ns]
        trips = [sum(num(r["server_watchdog_trips"]) for r in by[(mode, n)]) for n in ns]
        ax_loss.plot(ns, loss, color=color, marker=marker, label=f"link losses, {label}")
        ax_loss.plot(ns, trips, color=color, marker=marker, linestyle=":",
                     label=f"watchdog trips, {label}")
    if base is not None:
        ax_rtt.axhline(1.5 * base, color="grey", linestyle="-.", linewidth=1,
                       label="target: 1.5 x p99 at 0 observers")
    ax_rtt.set_xlabel("observer processes")
    ax_rtt.set_ylabel("master round trip [ms]")
    ax_rtt.set_yscale("log")
    ax_rtt.set_title("round trip (lines: median over rounds)")
    ax_rtt.grid(which="both", alpha=0.3)
    ax_rtt.legend(fontsize=7)
    ax_over.set_xlabel("observer processes")
    ax_over.set_ylabel("overruns per session (median)")
    ax_over.set_title("1 kHz loop overruns")
    ax_over.grid(alpha=0.3)
    ax_over.legend(fontsize=7)
    ax_loss.set_xlabel("observer processes")
    ax_loss.set_ylabel("count, all rounds")
    ax_loss.set_title("link losses and server watchdog trips")
    ax_loss.grid(alpha=0.3)
    ax_loss.legend(fontsize=7)
    fig.suptitle("Observers and the 1 kHz loop: teleop_server + teleop_master, default scene, "
                 "loopback, 2 cores", fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
