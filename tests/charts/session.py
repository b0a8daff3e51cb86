"""Chart of a teleoperation session from teleop_master's CSV log.

usage: session.py MASTER_CSV OUT_PNG
Top: master (commanded) and slave tip height over time. Middle: environment force and
rendered force (z). Bottom: round-trip time.
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(path, out):
    cols = {}
    with open(path) as f:
        for row in csv.DictReader(f):
            for k, v in row.items():
                cols.setdefault(k, []).append(float(v) if v not in ("", "nan") else float("nan"))
    t = cols["t_s"]
    fig, ax = plt.subplots(3, 1, figsize=(9, 8), sharex=True)
    ax[0].plot(t, cols["xm_z"], label="master command z")
    ax[0].plot(t, cols["xs_z"], label="slave tip z")
    ax[0].set_ylabel("height [m]")
    ax[0].legend(loc="upper right")
    ax[1].plot(t, cols["fe_z"], label="environment force z (slave)")
    ax[1].plot(t, cols["fm_z"], label="rendered force z (master)", linestyle="--")
    ax[1].set_ylabel("force [N]")
    ax[1].legend(loc="upper right")
    ax[2].plot(t, cols["rtt_ms"], ".", markersize=1)
    ax[2].set_ylabel("round trip [ms]")
    ax[2].set_xlabel("time [s]")
    fig.suptitle("teleoperation session (" + path.split("/")[-1] + ")")
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
