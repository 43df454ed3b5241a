#!/usr/bin/env python3
"""Writes docs/benchmarks.md from the outputs scripts/bench_report.sh collected in RUNS (issue 18).
Every figure is copied or pooled from those files; nothing here is typed by hand. The header
names the date, the commit and the machine.

    python3 scripts/bench_report.py RUNS OUT.md --img RELATIVE_IMG_DIR [--elapsed S] [--quick]
"""
import argparse
import csv
import datetime
import math
import os
import platform
import re
import subprocess
from collections import defaultdict


def sh(*cmd):
    try:
        return subprocess.run(cmd, capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return ""


def machine():
    model = ""
    for line in sh("lscpu").splitlines():
        if line.startswith("Model name:"):
            model = line.split(":", 1)[1].strip()
    mem = ""
    try:
        with open("/proc/meminfo") as f:
            kb = int(f.readline().split()[1])
            mem = f"{kb / 1048576:.1f} GiB"
    except (OSError, ValueError, IndexError):
        pass
    try:
        load = " ".join(open("/proc/loadavg").read().split()[:3])
    except OSError:
        load = "?"
    return (f"{model or platform.processor()}, {os.cpu_count()} cores, {mem} memory, "
            f"Linux {platform.release()}; load average {load} when the report was written")


# Everything from this line on in the report is measured by hand (bench_report keeps it).
HAND_MARKER = ("<!-- Measured by hand below: kept as they are when the report above is "
               "regenerated. -->")

MISSING = []


def read(runs, name, required=True):
    path = os.path.join(runs, name)
    if not os.path.exists(path):
        if required:
            MISSING.append(name)
        return None
    with open(path) as f:
        return f.read().rstrip("\n")


def block(text):
    return "```\n" + text + "\n```\n"


def after_table(text):
    """A Google Benchmark program's own summary: the lines after its timing table."""
    lines = text.splitlines()
    last = 0
    for i, line in enumerate(lines):
        if re.match(r"^\S+/\S+\s+\d", line) or line.startswith("----"):
            last = i + 1
    return "\n".join(lines[last:]).strip("\n")


def speed_error_section(runs, img):
    rows = list(csv.DictReader(open(os.path.join(runs, "speed_error.csv"))))
    text = read(runs, "speed_error.txt") or ""
    out = ["## Speed against error\n"]
    out.append(
        "`build/bench/speed_error` drives each scene by three scripted hand trajectories (slow, "
        "fast, and the slow one with a sudden 5 mm step half-way) with device states at 1 kHz and "
        "a global pass every 4 ms, and sweeps the servo rate, the per-tick iteration budget, and "
        "the tracker's corrector steps (0–3) with the exact acceptance (the tracked point is the "
        "contact only at the extremal solver's tolerance, else a full solve) or the tracker's own "
        "(\"tracked\": its point taken as it stands). Each setting is compared with a fully "
        "converged run at the same device poses and tick times: force error over every answered "
        "wrench, contact-point error at every global pass (contacts more than 2 mm from any of "
        "the reference's on the same pair are counted as *unmatched*), and the setting's own "
        "constraint violation. The achieved rate is the nominal one when the tick p99 fits in a "
        "period; the CPU share is the time tangentd's servo thread would be awake at that rate "
        "(it sleeps until 150 µs before each deadline, then spins, and spins around each "
        "expected device state). The Pareto front is taken per scene over (force error ↓, "
        "achieved rate ↑, CPU share ↓), the three trajectories pooled; a setting whose rate "
        "cannot be kept is not on it.\n")
    first = text.splitlines()[0] if text else ""
    out.append(block(first))
    # Per scene: force RMS error pooled over the hands, settings by rate.
    pooled = defaultdict(lambda: [0.0, 0, math.inf, 0.0, False, False, 0])
    for r in rows:
        key = (r["scene"], r["budget"], r["correctors"], r["exact"], int(r["rate"]))
        p = pooled[key]
        n = max(1, int(r["ticks"]))
        p[0] += float(r["force_rms"]) ** 2 * n
        p[1] += n
        p[2] = min(p[2], float(r["achieved"]))
        p[3] = max(p[3], float(r["cpu"]))
        p[4] = r["pareto"] == "1"
        p[5] = r["default"] == "1"
        p[6] += int(r["unmatched"])
    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    rates = sorted({int(r["rate"]) for r in rows})
    for scene in scenes:
        out.append(f"### {scene}\n")
        out.append("Force error RMS (N) over the three trajectories, against the converged "
                   "reference; **bold**: on the Pareto front; ★ the default; † the rate is not "
                   "kept (tick p99 longer than the period); (u N): contacts unmatched.\n")
        out.append("| budget | tracking | " + " | ".join(f"{r} Hz" for r in rates) + " |")
        out.append("| --- | --- | " + " | ".join("---" for _ in rates) + " |")
        settings = list(dict.fromkeys(k[1:4] for k in pooled if k[0] == scene))
        for budget, corr, exact in settings:
            tracking = f"{corr} {'exact' if exact == '1' else 'tracked'}"
            cells = []
            for rate in rates:
                p = pooled.get((scene, budget, corr, exact, rate))
                if not p:
                    cells.append("")
                    continue
                rms = math.sqrt(p[0] / p[1]) if p[1] else 0.0
                cell = f"{rms:.1e}"
                if p[4]:
                    cell = f"**{cell}**"
                if p[5]:
                    cell += " ★"
                if p[2] < 0.9 * rate:
                    cell += " †"
                if p[6]:
                    cell += f" (u {p[6]})"
                cells.append(cell)
            out.append(f"| {budget} | {tracking} | " + " | ".join(cells) + " |")
        out.append("")
        cpu = [f"{rate} Hz: {pooled[(scene, '10', '1', '1', rate)][3]:.2f}" for rate in rates
               if (scene, "10", "1", "1", rate) in pooled]
        out.append("CPU share of the servo thread at the default budget and tracking: " +
                   ", ".join(cpu) + ".\n")
    verdicts = [line for line in text.splitlines() if "settings on the front" in line]
    out.append("The default settings against each scene's front (as printed by the program):\n")
    out.append(block("\n".join(verdicts)))
    out.append(f"![speed against error]({img}/speed_error.png)\n")
    table = [line for line in text.splitlines() if line.startswith("|")]
    out.append("<details><summary>Every run (scene, trajectory, setting)</summary>\n")
    out.append("\n".join(table) + "\n")
    out.append("</details>\n")
    return "\n".join(out)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("runs")
    ap.add_argument("out")
    ap.add_argument("--img", default="img")
    ap.add_argument("--elapsed", type=int, default=0)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--commit", default="", help="the commit the programs were built from")
    a = ap.parse_args()
    commit = a.commit
    if not commit:
        commit = sh("git", "rev-parse", "--short=12", "HEAD") or "unknown"
        if sh("git", "status", "--porcelain", "--untracked-files=no"):
            commit += " (with uncommitted changes)"
    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    parts = ["# Benchmarks\n"]
    parts.append(
        f"Generated by `bash scripts/bench_report.sh` on {now} from commit {commit}, in "
        f"{a.elapsed // 60} min {a.elapsed % 60} s, on {machine()}. "
        + ("**A quick run (CI smoke sizes): its figures are not the report's.** " if a.quick else "")
        + "Every figure below is what the programs in `bench/` printed in that run; the machine "
        "is shared, so timings are compared only within one run (ratios), never across reports.\n")
    parts.append(speed_error_section(a.runs, a.img))

    parts.append("## Stability suite\n")
    parts.append(
        "`build/bench/stability_table` (cases in `testing/stability.cc`): the hard cases of "
        "`docs/stability.md` through the servo's contact term (tracker, exactness check, "
        "extremal solve) from several seeds and along a path, each step against a fresh solve; "
        "and mechanism cases through the servo at 4 kHz with the hand scripted, the force held "
        "against the device's maximum and the rate limit. *Flagged* is a defined degenerate "
        "state the solver reports (singular, at a bound, invalid input); *degraded*: finite and "
        "bounded but short of its tolerance somewhere. Every row is a test "
        "(`tests/server/stability_test.cc`: finite, bounded, and the documented outcome).\n")
    text = read(a.runs, "stability_table.txt") or "(not run)"
    lines = text.splitlines()
    parts.append(block(lines[0]) if lines else "")
    parts.append("\n".join(line for line in lines if line.startswith("|")) + "\n")
    parts.append(block("\n".join(line for line in lines[1:]
                                  if line and not line.startswith("|"))))

    parts.append("## How cost grows\n")
    parts.append("`build/bench/cost_growth`: chains of moving paperclips hanging from a fixed one, "
                 "dragged by the last clip on one thread (four ticks per device state, one "
                 "global pass after them); then the spatial four-bar with 0–8 extra contacts "
                 "(balls on the crank's axis spinning in place on plates, always active), its "
                 "hand circling 1 cm: the bodies fixed, only the contacts grow.\n")
    text = read(a.runs, "cost_growth.txt") or "(not run)"
    # Two tables: the chains, then (after its own header line) the four-bar with extra contacts.
    chains, four = text, ""
    if "\nfour-bar + extra contacts" in text:
        chains, four = text.split("\nfour-bar + extra contacts", 1)
        four = "four-bar + extra contacts" + four
    for part in (chains, four):
        if not part:
            continue
        lines = part.splitlines()
        parts.append("\n".join(line for line in lines if line.startswith("|")) + "\n")
        parts.append(block("\n".join(line for line in lines if line and not line.startswith("|"))))
        if part is chains:
            parts.append(f"![cost growth]({a.img}/cost_growth.png)\n")
    parts.append("Model only what a scene needs (`build/bench/model_cost`: the three-clip scene "
                 "against the same scene with 17 idle clips declared, same run; the test "
                 "`ServoTest.IdlePartsAreNotModelled` shows the idle clips get no coordinates "
                 "and no offset mesh and the wrenches are the same bit for bit):\n")
    parts.append(block(read(a.runs, "model_cost.txt") or "(not run)"))

    parts.append("## The server's rate on two threads\n")
    parts.append("`build/bench/server_rate`: the engine's two threads (servo pinned to core 0 at "
                 "4 kHz, global stage on core 1), the hand fed at 1 kHz by the main thread, and "
                 "the machine's wake-up jitter measured in the same run.\n")
    for scene in ("paperclips", "peg_in_hole"):
        parts.append(f"**{scene}**\n")
        parts.append(block(read(a.runs, f"server_rate_{scene}.txt") or "(not run)"))
    parts.append("The peg-in-hole servo budget against the paperclips', in lockstep on one thread "
                 "(`build/bench/peg_budget`):\n")
    parts.append(block(read(a.runs, "peg_budget.txt") or "(not run)"))

    parts.append("## Peers, same run\n")
    for name, title in (("nurbs_eval_bench", "NURBS evaluation against Open CASCADE"),
                        ("contact_bench", "Extremal contact solves against Open CASCADE"),
                        ("optimizer_bench", "The servo's solver against IPOPT and NLopt SLSQP")):
        text = read(a.runs, f"{name}.txt", required=name == "optimizer_bench")
        parts.append(f"**{title}** (`build/bench/{name}`)\n")
        parts.append(block(after_table(text) if text else "(not built: Open CASCADE missing)"))

    parts.append("**What exactness buys: FCL's distance between certified meshes against the "
                 "tracked contact** (`build/bench/mesh_peer`, the same pair and poses)\n")
    text = read(a.runs, "mesh_peer.txt") or "(not run)"
    lines = text.splitlines()
    parts.append(block(lines[0]) if lines else "")
    parts.append("\n".join(line for line in lines if line.startswith("|")) + "\n")

    parts.append("## Instructions per servo tick\n")
    out = read(a.runs, "callgrind.out")
    ticks = read(a.runs, "callgrind_ticks.txt")
    total = None
    for line in (out or "").splitlines():
        m = re.match(r"^(?:totals|summary):\s*(\d+)", line)
        if m:
            total = int(m.group(1))
    if total and ticks:
        n = int(ticks)
        parts.append(
            f"callgrind over `build/bench/servo_profile` (the paperclip drag on one thread), "
            f"counting only `ServoLoop::Tick` and what it calls: **{total / n:,.0f} instructions "
            f"per tick** (mean over {n} ticks, {total:,} in all). Unlike the times above this "
            "does not depend on the machine's load, so reports from different days compare.\n")
    else:
        MISSING.append("callgrind totals")
    # The sections measured by hand after the generated ones (the issues' same-session
    # comparisons against older builds, which no program here reruns) are carried over from the
    # report being replaced, from their marker on.
    try:
        with open(a.out) as f:
            old = f.read()
    except OSError:
        old = ""
    kept = old[old.find(HAND_MARKER):] if HAND_MARKER in old else ""
    with open(a.out, "w") as f:
        f.write("\n".join(parts))
        if kept:
            f.write("\n" + kept)
    if MISSING:
        raise SystemExit(f"bench_report.py: no output from {', '.join(MISSING)} in {a.runs}")


if __name__ == "__main__":
    main()
