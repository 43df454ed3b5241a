#!/usr/bin/env bash
# The main job. For now: the NURBS kernel demo (primitives, tessellation bounds), the
# evaluation and contact benchmarks with Open CASCADE measured in the same run, as ratios.
# Later: the live tangentd + tangent-phantom demo.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
./build/bench/tangent_nurbs_demo --obj build/paperclip.obj
# Medians of 3 repetitions; the JSON (for scripts) goes to build/nurbs_eval_bench.json.
./build/bench/nurbs_eval_bench --benchmark_min_time=0.05 --benchmark_repetitions=3 \
  --benchmark_report_aggregates_only=true --benchmark_out=build/nurbs_eval_bench.json \
  --benchmark_out_format=json
# Contact kinematics: tracking step, closed-form u_q and Newton against Open CASCADE's local
# extremum, then convergence rates by seed distance (JSON: build/contact_bench.json).
./build/bench/contact_bench --benchmark_min_time=0.1 --benchmark_repetitions=3 \
  --benchmark_report_aggregates_only=true --benchmark_out=build/contact_bench.json \
  --benchmark_out_format=json
# The optimizer on the four-bar against IPOPT and NLopt SLSQP (identical problem and starts).
./build/bench/optimizer_bench --benchmark_min_time=0.1 --benchmark_out=build/optimizer_bench.json \
  --benchmark_out_format=json
