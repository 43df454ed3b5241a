#!/usr/bin/env python3
"""Log-log plot of how the servo's cost grows with the chain (issue 18), from the CSV that
./build/bench/cost_growth --csv FILE writes: mean and p99 tick and the global pass against the
number of bodies, with least-squares power-law fits (the exponents in the legend).

    python3 scripts/plot_cost_growth.py build/cost_growth.csv docs/img/cost_growth.png
"""
import csv
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def fit(xs, ys):
    """Slope and intercept of log y on log x."""
    lx = [math.log(x) for x in xs]
    ly = [math.log(y) for y in ys]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    sxx = sum((a - mx) ** 2 for a in lx)
    b = sum((a - mx) * (c - my) for a, c in zip(lx, ly)) / sxx if sxx else 0.0
    return b, my - b * mx


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: plot_cost_growth.py COST_GROWTH.csv OUT.png")
    with open(sys.argv[1]) as f:
        rows = list(csv.DictReader(f))
    if len(rows) < 2:
        sys.exit(f"{sys.argv[1]}: need at least two chains to fit")
    bodies = [float(r["bodies"]) for r in rows]
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for key, label, style in (("tick_mean_us", "servo tick, mean", "o-"),
                              ("tick_p99_us", "servo tick, p99", "s--"),
                              ("pass_mean_us", "global pass, mean", "^-.")):
        ys = [float(r[key]) for r in rows]
        b, a = fit(bodies, ys)
        ax.loglog(bodies, ys, style, label=f"{label}: ~ bodies^{b:.2f}")
        ax.loglog(bodies, [math.exp(a) * x ** b for x in bodies], ":", color="grey", lw=0.8)
    ax.set_xlabel("bodies (a fixed clip and the moving clips hanging from it)")
    ax.set_ylabel("time (µs)")
    ax.set_title("Paperclip chains dragged by the last clip (one thread)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=120)


if __name__ == "__main__":
    main()
