#!/usr/bin/env python3
"""Plots of tangent-opt result files (docs/offline.md), PNGs from Debian's matplotlib.

  plot_design.py RESULT.json [--map MAP_RESULT.json] [-o DIR]

writes into DIR (default: next to RESULT.json):
  <name>.convergence.png  objective, constraint violation and KKT residual per iteration of the
                          best case (the other optima faint behind it);
  <name>.mechanism.png    the mechanism at the best optimum with its manipulability ellipsoid
                          {J u : |u| <= 1} at the end effector (scaled, the scale in the title);
                          for a run over configurations, the mechanism at each of them and the
                          objective at each with its worst case;
  <map>.map.png           with --map: the optimal objective over a result's 2-D grid, points
                          that cannot be reached (infeasible) shaded with their boundary drawn,
                          the grid's best point and RESULT's free optimum marked.
"""
import argparse
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def load(path):
    with open(path) as f:
        return json.load(f)


def label(result):
    terms = " + ".join(
        (f"{t['weight']:g} " if t["weight"] != 1 else "") + t["measure"] for t in result["objective"])
    return f"{result['sense']} {terms}"


def convergence(result, out):
    cases = [c for c in result["results"] if c["status"] == "optimum"]
    if not cases:
        return None
    best = next(c for c in result["results"] if c["case"] == result["best_case"])
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    for c in cases:
        rows = np.array(c["history"]["rows"])
        if c is best or len(rows) == 0:
            continue
        ax1.plot(rows[:, 0], rows[:, 1], color="0.8", lw=0.8)
    rows = np.array(best["history"]["rows"])
    ax1.plot(rows[:, 0], rows[:, 1], color="C0", lw=2, marker="o", ms=3,
             label=f"best case ({best['case']})")
    ax1.axhline(best["objective"], color="C0", ls=":", lw=1)
    ax1.set_ylabel(result["objective"][0]["measure"] if len(result["objective"]) == 1
                   else "objective F")
    ax1.set_title(f"{os.path.basename(result['run'])}: {label(result)}\n"
                  f"{len(cases)} optima of {len(result['results'])} cases (others in grey)")
    ax1.legend(loc="lower right")
    ax1.grid(alpha=0.3)
    floor = 1e-18
    ax2.semilogy(rows[:, 0], np.maximum(rows[:, 2], floor), color="C3", marker="o", ms=3,
                 label="constraint violation (m)")
    ax2.semilogy(rows[:, 0], np.maximum(rows[:, 3], floor), color="C2", marker="s", ms=3,
                 label="KKT residual")
    ax2.set_xlabel("iteration")
    ax2.set_ylabel("residual")
    ax2.grid(alpha=0.3, which="both")
    ax2.legend(loc="upper right")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def ellipsoid(J, scale, n=24):
    """Points of {J u : |u| <= 1} scaled: a 3-D ellipsoid (m >= 3), an ellipse (m = 2) or a
    segment (m = 1)."""
    J = np.array(J) * scale
    m = J.shape[1]
    if m == 1:
        return [np.stack([-J[:, 0], J[:, 0]], axis=1)]
    if m == 2:
        t = np.linspace(0, 2 * np.pi, 60)
        return [J @ np.stack([np.cos(t), np.sin(t)])]
    u, s, _ = np.linalg.svd(J)
    a, b = np.meshgrid(np.linspace(0, np.pi, n), np.linspace(0, 2 * np.pi, 2 * n))
    sphere = np.stack([np.sin(a) * np.cos(b), np.sin(a) * np.sin(b), np.cos(a)])
    return [np.einsum("ij,jkl->ikl", u[:, :3] * s[:3], sphere)]


def configurations(result, out):
    """A run over a range of motion: the mechanism at each configuration (one colour per body,
    darker for later configurations, the end effector's path through them), and each
    configuration's measure at the best design with the worst case marked."""
    geo = result["best_geometry"]
    conf = result["configurations"]
    best = next(c for c in result["results"] if c["case"] == result["best_case"])
    fig = plt.figure(figsize=(12, 5.5))
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    bases = []
    for b in geo["bodies"]:
        base = b["name"].split("@")[0]
        if base not in bases:
            bases.append(base)
    copies = max([int(b["name"].split("@")[1]) for b in geo["bodies"] if "@" in b["name"]] or [1])
    labelled = set()
    everything = []
    for b in geo["bodies"]:
        pts = np.array(b["points"])
        if len(pts) == 0:
            continue
        everything.append(pts)
        base = b["name"].split("@")[0]
        k = int(b["name"].split("@")[1]) if "@" in b["name"] else copies
        if len(pts) >= 3:
            pts = np.vstack([pts, pts[:1]])
        ax.plot(pts[:, 0], pts[:, 1], pts[:, 2], lw=1.5 if b["fixed"] else 3,
                color="0.3" if b["fixed"] else f"C{bases.index(base) % 10}",
                alpha=0.25 + 0.75 * k / copies, marker="o", ms=3,
                label=None if b["fixed"] or base in labelled else base)
        labelled.add(base)
    path = np.array([e["point"] for e in geo["end_effectors"]])
    ax.plot(path[:, 0], path[:, 1], path[:, 2], color="k", lw=1, ls="--", marker="o", ms=4,
            label="end effector at each configuration")
    everything = np.vstack(everything)
    centre, half = everything.mean(axis=0), 0.6 * float(np.ptp(everything, axis=0).max())
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    ax.set_zlim(centre[2] - half, centre[2] + half)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")
    ax.legend(loc="upper left", fontsize=8)
    design = ", ".join(f"{k} {v:.4g}" for k, v in best["design"].items())
    ax.set_title(f"the mechanism at its {copies} configurations\n(design: {design})", fontsize=9)

    ax2 = fig.add_subplot(1, 2, 2)
    unit = "deg" if "values_deg" in conf else "m"
    values = np.array(conf.get("values_deg", conf.get("values")))
    measure = result["objective"][0]["measure"]
    per = [list(m.values())[0] for m in best["measures"] if "@" in list(m.keys())[0]]
    terms = len(result["objective"])
    per = np.array(per).reshape(len(values), terms)
    weights = np.array([t["weight"] for t in result["objective"]])
    F = per @ weights
    worst = next(list(m.values())[0] for m in best["measures"] if "worst case" in m)
    ax2.plot(values, F, color="C0", marker="o", label="F at each configuration")
    ax2.axhline(worst, color="C3", ls="--", label=f"worst case {worst:.6g}")
    ax2.axhline(best["objective"], color="0.5", ls=":",
                label=f"smooth worst case (objective) {best['objective']:.6g}")
    ax2.set_xlabel(f"{conf['joint']} ({unit})")
    ax2.set_ylabel(measure if terms == 1 else "F = sum of weighted measures")
    ax2.set_title(f"{os.path.basename(result['run'])}: {label(result)}, worst case over "
                  f"{conf['joint']}\n(tolerance {conf['tolerance']:g})", fontsize=9)
    ax2.legend(fontsize=8)
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def mechanism(result, out):
    geo = result.get("best_geometry")
    if not geo:
        return None
    if "configurations" in result:
        return configurations(result, out)
    fig = plt.figure(figsize=(7.5, 6.5))
    ax = fig.add_subplot(projection="3d")
    for s in geo["surfaces"]:
        ax.plot_surface(np.array(s["x"]), np.array(s["y"]), np.array(s["z"]), cmap="Greys",
                        alpha=0.35, linewidth=0.2, edgecolor="0.5")
    everything = []
    for i, b in enumerate(geo["bodies"]):
        pts = np.array(b["points"])
        if len(pts) == 0:
            continue
        everything.append(pts)
        if len(pts) >= 3:
            pts = np.vstack([pts, pts[:1]])
        ax.plot(pts[:, 0], pts[:, 1], pts[:, 2], lw=4 if not b["fixed"] else 2,
                color="0.3" if b["fixed"] else f"C{i % 10}", marker="o", ms=5,
                label=b["name"] if not b["fixed"] else None)
    everything = np.vstack(everything)
    size = float(np.ptp(everything, axis=0).max()) or 1.0
    notes = []
    for e in geo["end_effectors"]:
        p = np.array(e["point"])
        ax.scatter(*p, color="k", s=30, zorder=5)
        if "jacobian" not in e:
            continue
        J = np.array(e["jacobian"])
        largest = np.linalg.svd(J, compute_uv=False).max()
        scale = 0.25 * size / largest if largest > 0 else 1.0
        for shape in ellipsoid(J, scale):
            if shape.ndim == 3:
                ax.plot_surface(p[0] + shape[0], p[1] + shape[1], p[2] + shape[2], color="m",
                                alpha=0.45, linewidth=0)
            else:
                ax.plot(p[0] + shape[0], p[1] + shape[1], p[2] + shape[2], color="m", lw=3,
                        label="J u, |u| <= 1 (manipulability)")
        sv = np.linalg.svd(J, compute_uv=False)
        notes.append(f"{e['measure']}: singular values of J " +
                     ", ".join(f"{x:.3g}" for x in sv) + f" m/rad (drawn x{scale:.3g})")
    centre = everything.mean(axis=0)
    half = 0.6 * size
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    ax.set_zlim(centre[2] - half, centre[2] + half)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")
    best = next(c for c in result["results"] if c["case"] == result["best_case"])
    joints = ", ".join(f"{k} {v:.1f}°" for k, v in best["joints_deg"].items())
    if best.get("design"):
        joints += "; design: " + ", ".join(f"{k} {v:.4g}" for k, v in best["design"].items())
    ax.set_title(f"{os.path.basename(result['run'])}: best {result['objective'][0]['measure']} "
                 f"{result['best_objective']:.6g}\n{joints}\n" + "\n".join(notes), fontsize=9)
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def grid_map(result, free, out):
    axes = result.get("grid", [])
    if len(axes) != 2:
        print(f"plot_design: {result['run']} has {len(axes)} grid axes; a map needs 2",
              file=sys.stderr)
        return None
    xs, ys = np.array(axes[0]["values"]), np.array(axes[1]["values"])
    best = np.full((len(ys), len(xs)), np.nan)
    reached = np.zeros((len(ys), len(xs)), dtype=bool)
    for c in result["results"]:
        x, y = c["grid"][axes[0]["name"]], c["grid"][axes[1]["name"]]
        i, j = int(np.argmin(abs(ys - y))), int(np.argmin(abs(xs - x)))
        if c["status"] != "optimum":
            continue
        reached[i, j] = True
        if np.isnan(best[i, j]) or (c["objective"] > best[i, j]) == (result["sense"] == "maximize"):
            best[i, j] = c["objective"]
    fig, ax = plt.subplots(figsize=(7, 6))
    extent = [xs[0], xs[-1], ys[0], ys[-1]]
    im = ax.imshow(best, origin="lower", extent=extent, aspect="equal", cmap="viridis",
                   interpolation="nearest")
    fig.colorbar(im, ax=ax, label=f"optimal {result['objective'][0]['measure']}")
    ax.contourf(xs, ys, (~reached).astype(float), levels=[0.5, 1.5], colors="none",
                hatches=["////"])
    ax.contour(xs, ys, reached.astype(float), levels=[0.5], colors="k", linewidths=1.5)
    k = np.nanargmax(best) if result["sense"] == "maximize" else np.nanargmin(best)
    i, j = np.unravel_index(k, best.shape)
    ax.plot(xs[j], ys[i], marker="*", color="w", mec="k", ms=16,
            label=f"best grid point {best[i, j]:.5g}")
    if free is not None and free.get("best_geometry"):
        p = free["best_geometry"]["end_effectors"][0]["point"]
        ax.plot(p[0], p[1], marker="X", color="C3", mec="k", ms=12,
                label=f"free optimum {free['best_objective']:.5g}")
    ax.set_xlabel(axes[0]["name"] + " (m)")
    ax.set_ylabel(axes[1]["name"] + " (m)")
    ax.set_title(f"{os.path.basename(result['run'])}\nhatched: not reachable (infeasible); "
                 "black line: the reachable region's boundary", fontsize=9)
    ax.legend(loc="lower left", fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("result")
    p.add_argument("--map", help="a result file with a 2-D grid to draw as a map")
    p.add_argument("-o", "--out", help="output folder (default: next to RESULT)")
    a = p.parse_args()
    result = load(a.result)
    out = a.out or os.path.dirname(os.path.abspath(a.result))
    os.makedirs(out, exist_ok=True)
    name = os.path.basename(a.result).replace(".result.json", "").replace(".json", "")
    made = [convergence(result, os.path.join(out, name + ".convergence.png")),
            mechanism(result, os.path.join(out, name + ".mechanism.png"))]
    if a.map:
        grid = load(a.map)
        mname = os.path.basename(a.map).replace(".result.json", "").replace(".json", "")
        made.append(grid_map(grid, result, os.path.join(out, mname + ".map.png")))
    for m in made:
        if m:
            print(f"plot_design: wrote {m}")


if __name__ == "__main__":
    main()
