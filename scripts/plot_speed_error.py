#!/usr/bin/env python3
"""Error against rate per scene (issue 18), from the CSV that
./build/bench/speed_error --csv FILE writes: one panel per scene, the force error (RMS over the
three hand trajectories, against the converged reference at the same device poses) of every
setting against the rate the engine achieves with it, coloured by the per-tick iteration budget;
the settings on the Pareto front (error, rate, CPU share) ringed, the default starred, and the
settings the engine cannot keep at their nominal rate drawn hollow.

    python3 scripts/plot_speed_error.py build/speed_error.csv docs/img/speed_error.png
"""
import csv
import math
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

FLOOR = 1e-16  # N: errors below this (a reference run against itself) are drawn here


def pooled(rows):
    """Per scene and setting: RMS force error and the lowest achieved rate over the hands."""
    out = defaultdict(lambda: {"sq": 0.0, "n": 0, "achieved": math.inf})
    for r in rows:
        key = (r["scene"], int(r["rate"]), r["budget"], int(r["correctors"]), int(r["exact"]))
        p = out[key]
        ticks = max(1, int(r["ticks"]))
        p["sq"] += float(r["force_rms"]) ** 2 * ticks
        p["n"] += ticks
        p["achieved"] = min(p["achieved"], float(r["achieved"]))
        p["pareto"] = r["pareto"] == "1"
        p["default"] = r["default"] == "1"
    for p in out.values():
        p["rms"] = math.sqrt(p["sq"] / p["n"]) if p["n"] else 0.0
    return out


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: plot_speed_error.py SPEED_ERROR.csv OUT.png")
    with open(sys.argv[1]) as f:
        rows = list(csv.DictReader(f))
    if not rows:
        sys.exit(f"{sys.argv[1]}: no rows")
    settings = pooled(rows)
    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    budgets = list(dict.fromkeys(r["budget"] for r in rows))
    colours = dict(zip(budgets, plt.cm.viridis([i / max(1, len(budgets) - 1)
                                                for i in range(len(budgets))])))
    fig, axes = plt.subplots(1, len(scenes), figsize=(5.0 * len(scenes), 4.4), squeeze=False)
    for ax, scene in zip(axes[0], scenes):
        front = []
        for (sc, rate, budget, corr, exact), p in settings.items():
            if sc != scene:
                continue
            y = max(p["rms"], FLOOR)
            x = p["achieved"]
            # Tracking variants are squares, the default tracking circles.
            marker = "o" if (corr == 1 and exact == 1) else "s"
            keeps_rate = x >= 0.9 * rate
            ax.scatter([x], [y], marker=marker, s=28,
                       facecolors=colours[budget] if keeps_rate else "none",
                       edgecolors=colours[budget], linewidths=1.0, zorder=2)
            if p["pareto"]:
                front.append((x, y))
                ax.scatter([x], [y], marker="o", s=110, facecolors="none", edgecolors="red",
                           linewidths=1.0, zorder=3)
            if p["default"]:
                ax.scatter([x], [y], marker="*", s=260, facecolors="gold", edgecolors="black",
                           zorder=4, label="default (4 kHz, 10 it., 1 exact)")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("achieved servo rate (Hz)")
        ax.set_ylabel("force error, RMS (N)")
        ax.set_title(scene)
        ax.grid(True, which="both", alpha=0.3)
    handles = [plt.Line2D([], [], marker="o", ls="", color=colours[b], label=f"budget {b}")
               for b in budgets]
    handles += [
        plt.Line2D([], [], marker="s", ls="", color="grey", label="tracking 0–3 correctors, exact/tracked"),
        plt.Line2D([], [], marker="o", ls="", mfc="none", color="grey", label="rate not kept (hollow)"),
        plt.Line2D([], [], marker="o", ls="", mfc="none", mec="red", ms=10, label="Pareto front"),
        plt.Line2D([], [], marker="*", ls="", mfc="gold", mec="black", ms=14, label="default"),
    ]
    fig.legend(handles=handles, loc="lower center", ncol=5, fontsize=8)
    fig.suptitle(f"Speed against error (errors below {FLOOR:g} N drawn at {FLOOR:g})")
    fig.tight_layout(rect=(0, 0.1, 1, 0.95))
    fig.savefig(sys.argv[2], dpi=110)


if __name__ == "__main__":
    main()
