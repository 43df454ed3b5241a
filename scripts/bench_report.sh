#!/usr/bin/env bash
# Regenerates the benchmark report, docs/benchmarks.md and its plots (issue 18), from the
# programs in bench/: speed against error, how cost grows, what idle parts cost, the peg's servo
# budget, the server's rate on two threads, and the peer comparisons (Open CASCADE, IPOPT, NLopt).
# Every figure in the report is what these programs printed in this run; the report names the
# date, the commit and the machine. Builds first. About 12 minutes on this 2-core machine.
#
#   bash scripts/bench_report.sh                 # the full report into docs/
#   bash scripts/bench_report.sh --quick --out D # a short run into D (ctest bench_report.quick):
#                                                # every program and the generator, minimal sizes
set -euo pipefail
cd "$(dirname "$0")/.."
quick=0
out=""
build=1
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) quick=1 ;;
    --out) out="$2"; shift ;;
    --no-build) build=0 ;;
    *) echo "bench_report.sh: unknown argument '$1' (use --quick, --out DIR, --no-build)" >&2; exit 2 ;;
  esac
  shift
done
build_dir=${TANGENT_BUILD_DIR:-build}
# The commit the programs are built from (and whether the tree differed from it), taken now.
commit_state="$(git rev-parse --short=12 HEAD 2>/dev/null || echo unknown)"
if [ -n "$(git status --porcelain --untracked-files=no 2>/dev/null)" ]; then
  commit_state+=" (with uncommitted changes)"
fi
if [ "$build" = 1 ]; then bash scripts/build.sh > /dev/null; fi
bench="$build_dir/bench"
if [ -z "$out" ]; then
  [ "$quick" = 1 ] && { echo "bench_report.sh: --quick needs --out DIR (docs/ holds the full report)" >&2; exit 2; }
  runs="$build_dir/bench-report"
  report=docs/benchmarks.md
  img=docs/img
else
  runs="$out"
  report="$out/benchmarks.md"
  img="$out/img"
fi
mkdir -p "$runs" "$img"
start=$(date +%s)
step() { echo "bench_report: $1 ($(( $(date +%s) - start )) s)" >&2; }

if [ "$quick" = 1 ]; then
  se_args=(--quick --seconds 0.1); cg_args=(--steps 100 --chains 1,2 --extra 0,2); mc_args=(--steps 200)
  pb_args=(--steps 200); sr_seconds=2; st_seconds=0.1; mp_args=(--poses 50 --tolerances 1e-3,1e-4)
  cg_steps=50; gb_args=(--benchmark_min_time=0.0005 --benchmark_color=false)
  ob_args=(--steps=20 --benchmark_min_time=0.0005 --benchmark_color=false)
else
  se_args=(--seconds 2); cg_args=(--steps 3000); mc_args=(); pb_args=(--steps 20000)
  sr_seconds=30; st_seconds=4; mp_args=(); cg_steps=3000; gb_args=(--benchmark_color=false); ob_args=(--benchmark_color=false)
fi

step "speed against error"
"$bench/speed_error" "${se_args[@]}" --csv "$runs/speed_error.csv" > "$runs/speed_error.txt"
step "stability suite"
# Exits 1 when a row fails; the report lists failing rows rather than stopping.
"$bench/stability_table" --seconds "$st_seconds" > "$runs/stability_table.txt" || true
step "cost growth"
"$bench/cost_growth" "${cg_args[@]}" --csv "$runs/cost_growth.csv" > "$runs/cost_growth.txt"
step "idle parts"
"$bench/model_cost" "${mc_args[@]}" > "$runs/model_cost.txt"
step "peg budget"
"$bench/peg_budget" "${pb_args[@]}" > "$runs/peg_budget.txt"
step "server rate (paperclips, peg-in-hole)"
"$bench/server_rate" --seconds "$sr_seconds" > "$runs/server_rate_paperclips.txt"
"$bench/server_rate" --seconds "$sr_seconds" --scene peg_in_hole > "$runs/server_rate_peg_in_hole.txt"
step "peers"
for peer in nurbs_eval_bench contact_bench optimizer_bench; do
  if [ -x "$bench/$peer" ]; then
    args=("${gb_args[@]}")
    [ "$peer" = optimizer_bench ] && args=("${ob_args[@]}")
    "$bench/$peer" "${args[@]}" > "$runs/$peer.txt" 2> "$runs/$peer.err" || {
      echo "bench_report: $peer failed (see $runs/$peer.err)" >&2; exit 1; }
  fi
done
step "FCL on meshes against the tracked contact"
"$bench/mesh_peer" "${mp_args[@]}" > "$runs/mesh_peer.txt"
step "instructions per servo tick (callgrind)"
# Only the ticks are counted (ServoLoop::Tick and what it calls): four per device state.
# servo_profile starts the instrumentation itself after loading the scene (--instr-atstart=no).
valgrind --tool=callgrind --instr-atstart=no --callgrind-out-file="$runs/callgrind.out" \
  --toggle-collect='tangent::server::ServoLoop::Tick*' \
  "$bench/servo_profile" --steps "$cg_steps" > "$runs/callgrind_profile.txt" 2> "$runs/callgrind.err"
echo "$(( 4 * cg_steps ))" > "$runs/callgrind_ticks.txt"
step "plots and report"
/usr/bin/python3 scripts/plot_speed_error.py "$runs/speed_error.csv" "$img/speed_error.png"
/usr/bin/python3 scripts/plot_cost_growth.py "$runs/cost_growth.csv" "$img/cost_growth.png"
/usr/bin/python3 scripts/bench_report.py "$runs" "$report" --img "$(realpath --relative-to="$(dirname "$report")" "$img")" \
  --elapsed "$(( $(date +%s) - start ))" --commit "$commit_state" $([ "$quick" = 1 ] && echo --quick)
step "done: $report"
