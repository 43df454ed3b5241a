#!/usr/bin/env bash
# Fault injection against a running tangentd with tangent-phantom (docs/reliability.md "Faults
# under load"). Needs a build (bash scripts/build.sh, or either README command).
#   bash scripts/faults.sh [--smoke] [fault ...]
# faults: cpu_hog memory global_stall contact_burst lcm_down stop_client stop_server (default all)
# Each fault gets a fresh tangentd (--fault-injection) in a private network namespace and a
# tangent-phantom run of 8 s (--smoke: 4 s; it runs on to 2.5 s past the fault's end when a
# loaded machine made the fault end late) dragging the paperclips (contact_burst: pressing and
# lifting a plate on eight domes, scenes/contact_burst.json). The fault runs from t = 2 s for
# 1.5 s (--smoke: 0.5 s). Checked for every fault, else the script fails:
#   * tangentd is still running after the fault and exits 0 on SIGINT with its summary;
#   * every wrench the phantom received is finite, within max_force and within the rate limit
#     of the one before on the server's clock (phantom: over_max_force, over_rate_limit);
#   * the fault shows in the server's own counters (below) and its log;
#   * the accounting closes by counter (scripts/lib/accounting.sh);
#   * service resumed by itself, within a bound the protocol sets, not the machine's speed: a
#     state sent within one ramp time (the scene's ramp_time, 1 s) of the fault's end was
#     answered, and so was one sent in the run's last second.
# The full run (the documented command) also judges throughput: 90 % of the states sent in the
# last second answered. --smoke (ctest's faults_smoke, on whatever machine runs the tests)
# reports that figure without judging it (docs/reliability.md, "What the real-time tests
# assert"). The answered fraction and the round trip during the fault are measured from the
# phantom's per-step log and reported as they are. Logs: build/faults/<fault>/. Table:
# build/faults/table.md.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${TANGENT_BUILD_DIR:-$root/build}
# shellcheck source=lib/live_server.sh
source "$root/scripts/lib/live_server.sh"
# shellcheck source=lib/accounting.sh
source "$root/scripts/lib/accounting.sh"
in_private_netns "$0" "$@"

duration=8 fault_len=1.5 memory_cap_mib=512 judge_throughput=1
resume_bound_s=1.0  # the scene's ramp_time: a restarted client is served within it too
faults=()
for a in "$@"; do
  case $a in
    --smoke) duration=4 fault_len=0.5 memory_cap_mib=256 judge_throughput= ;;
    cpu_hog|memory|global_stall|contact_burst|lcm_down|stop_client|stop_server) faults+=("$a") ;;
    *) echo "faults.sh: unknown argument '$a'" >&2; exit 2 ;;
  esac
done
[ ${#faults[@]} -gt 0 ] ||
  faults=(cpu_hog memory global_stall contact_burst lcm_down stop_client stop_server)
out=$build/faults
mkdir -p "$out"
table=$out/table.md
echo "| fault | answered during the fault | round trip p50 / p99 during (ms) | max \|F\| (N) | over max / over rate | the fault in the server's counters | resumed: answered in the last 1 s |" > "$table"
echo "| --- | --- | --- | --- | --- | --- | --- |" >> "$table"

value() { grep -m1 "^$2=" "$1" | cut -d= -f2; }
failures=0
# Whatever ends the script, no server or client of a fault is left running (one left behind by
# a script error loaded every test after it).
live=()
trap 'for p in "${live[@]}"; do kill -9 "$p" 2>/dev/null || true; done' EXIT

run_fault() {
  local fault=$1 dir=$out/$1 scene=paperclips trajectory=drag run=$duration
  rm -rf "$dir" && mkdir -p "$dir"
  if [ "$fault" = memory ]; then run=$((duration + 2)); fi
  if [ "$fault" = contact_burst ]; then scene=contact_burst trajectory=pull; fi
  start_tangentd "$dir/server.out" --scene "$root/scenes/$scene.json" --fault-injection \
    --log "$dir/tangentd.log"
  local server=$server_pid
  # The phantom runs until stopped below (the duration is only a cap).
  "$build/server/tangent-phantom" --duration "$((run + 20))" --trajectory "$trajectory" \
    --log "$dir/phantom.csv" > "$dir/phantom.out" 2>&1 &
  local phantom=$! helpers=() t0 fault_start fault_end
  live=("$server" "$phantom")
  t0=$(date +%s.%N)
  sleep 2
  fault_start=$(date +%s.%N)
  case $fault in
    cpu_hog)  # two busy processes at normal priority, one per core
      for _ in 1 2; do (while :; do :; done) & helpers+=($!); done
      sleep "$fault_len"; kill "${helpers[@]}" ;;
    memory)  # 512 MiB (--smoke 256) written, then held for the fault's time. This VM writes
             # fresh pages at ~300 MB/s, so the writing is also a load on one core for ~1.5 s.
      python3 - "$fault_len" "$memory_cap_mib" <<'EOF' &
import sys, time
end = time.monotonic() + float(sys.argv[1])
avail = int(next(l for l in open("/proc/meminfo") if l.startswith("MemAvailable")).split()[1]) * 1024
block = b"\x01" * min(avail // 2, int(sys.argv[2]) << 20)  # written: every page resident
time.sleep(max(0.0, end - time.monotonic()))
EOF
      wait $! ;;
    global_stall)  # the global stage sleeps 100 ms, three times
      for _ in 1 2 3; do kill -USR1 "$server"; sleep "$(awk -v f="$fault_len" "BEGIN { print f / 3 }")"; done ;;
    contact_burst)  # the pull presses the plate onto all eight domes and lifts it off at once
      sleep "$fault_len" ;;
    lcm_down)  # the loopback (LCM's only interface here) goes away and comes back
      ip link set lo down; sleep "$fault_len"; ip link set lo up
      ip route add 224.0.0.0/4 dev lo 2>/dev/null || true ;;
    stop_client)
      kill -STOP "$phantom"; sleep "$fault_len"; kill -CONT "$phantom" ;;
    stop_server)
      kill -STOP "$server"; sleep "$fault_len"; kill -CONT "$server" ;;
  esac
  fault_end=$(date +%s.%N)
  # The client runs on for the run's length, and at least the resume window and a last second
  # past the fault's end: a loaded machine stretches a fault (the smoke's 0.5 s memory fault took
  # 0.7 s beside a build) and delays the phantom's start, and a run that ended inside the
  # resume window was once reported as a service that did not resume.
  local stop_at
  stop_at=$(awk -v t0="$t0" -v run="$run" -v e="$fault_end" -v b="$resume_bound_s" \
    'BEGIN { s = t0 + run; if (e + b + 1.5 > s) s = e + b + 1.5; printf "%.6f", s }')
  sleep "$(awk -v s="$stop_at" -v n="$(date +%s.%N)" 'BEGIN { d = s - n; printf "%.3f", (d > 0 ? d : 0) }')"
  kill -INT "$phantom" 2>/dev/null || true
  local phantom_status=0
  wait "$phantom" || phantom_status=$?
  local alive=yes
  kill -0 "$server" 2>/dev/null || alive=no
  kill -INT "$server" 2>/dev/null || true
  local server_status=0
  wait "$server" || server_status=$?
  local counters
  case $fault in
    cpu_hog|memory) counters="late ticks $(value "$dir/server.out" late), unanswered $(value "$dir/server.out" unanswered), lost $(value "$dir/server.out" lost_before_filter)" ;;
    global_stall) counters="global_stalls $(value "$dir/server.out" global_stalls), longest gap $(value "$dir/server.out" global_longest_gap_ms) ms" ;;
    contact_burst)
      local most
      most=$({ grep -o "tick [0-9]*: contact" "$dir/tangentd.log" || true; } | sort | uniq -c | sort -rn | head -1 | awk '{print $1}')
      counters="contact_events $(value "$dir/server.out" contact_events), most in one tick ${most:-0}, global stage's longest gap $(value "$dir/server.out" global_longest_gap_ms) ms" ;;
    lcm_down) counters="lost $(value "$dir/server.out" lost_before_filter), device_timeouts $(value "$dir/server.out" device_timeouts)" ;;
    stop_client) counters="device_timeouts $(value "$dir/server.out" device_timeouts), timeout wrenches $(value "$dir/server.out" timeout_wrenches)" ;;
    stop_server) counters="late ticks $(value "$dir/server.out" late), rejected_jump $(value "$dir/server.out" rejected_jump), phantom watchdog trips $(value "$dir/phantom.out" watchdog_trips)" ;;
  esac
  local verdict
  # The fault's window on the phantom's clock, which starts at its start_unix (a loaded machine
  # can start it well after t0).
  t0=$(value "$dir/phantom.out" start_unix || true)
  [ -n "$t0" ] || { echo "faults.sh: $fault: no start_unix from tangent-phantom" >&2; t0=$fault_start; }
  local from to
  from=$(awk -v a="$fault_start" -v b="$t0" 'BEGIN { print a - b }')
  to=$(awk -v a="$fault_end" -v b="$t0" 'BEGIN { print a - b }')
  verdict=$(python3 - "$dir/phantom.csv" "$run" "$from" "$to" "$resume_bound_s" <<'EOF'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
_, start, end, bound = map(float, sys.argv[2:6])
duration = max((float(r["t"]) for r in rows), default=0.0)  # where the phantom was stopped
def window(lo, hi):
    sent = {int(r["seq"]) for r in rows if lo <= float(r["t"]) < hi}
    answered, lat = set(), []
    for r in rows:
        s = int(r["answered_seq"])
        if s in sent and s not in answered and int(r["wrench_state"]) != 2:
            answered.add(s)
            lat.append(float(r["latency_us"]) / 1000)
    lat.sort()
    q = lambda p: lat[min(len(lat) - 1, int(p * len(lat)))] if lat else float("nan")
    return len(sent), len(answered), q(0.5), q(0.99)
s, a, p50, p99 = window(start, end)
s2, a2, _, _ = window(duration - 1.2, duration - 0.2)  # the last second (answers in flight at the end left out)
s3, a3, _, _ = window(end, end + bound)  # within the protocol's bound of the fault's end
print(f"{a}/{s} ({100 * a / max(s, 1):.0f} %, {end - start:.1f} s)|{p50:.2f} / {p99:.2f}|{a2}/{s2}|"
      f"{int(a2 >= 0.9 * s2 and s2 > 0 and end < duration - 1.2)}|"
      f"{int(a3 >= 1 and a2 >= 1 and end + bound <= duration - 0.2)}|{a3}/{s3}")
EOF
)
  IFS='|' read -r during rtt resumed throughput_ok resumed_ok resumed_soon <<< "$verdict"
  local fmax over_max over_rate
  fmax=$(value "$dir/phantom.out" wrench_force_max_n)
  over_max=$(value "$dir/phantom.out" over_max_force)
  over_rate=$(value "$dir/phantom.out" over_rate_limit)
  echo "| $fault | $during | $rtt | $fmax | $over_max / $over_rate | $counters | $resumed |" >> "$table"
  local problems=()
  [ "$alive" = yes ] || problems+=("tangentd was not running after the fault")
  [ "$server_status" -eq 0 ] || problems+=("tangentd exited with $server_status")
  grep -q "^tangentd summary:" "$dir/server.out" || problems+=("no tangentd summary")
  [ "$phantom_status" -eq 0 ] || problems+=("tangent-phantom exited with $phantom_status")
  [ "$(value "$dir/phantom.out" bad_wrenches)" = 0 ] || problems+=("non-finite wrenches")
  [ "$over_max" = 0 ] || problems+=("$over_max wrenches above max_force")
  [ "$over_rate" = 0 ] || problems+=("$over_rate force steps beyond the rate limit")
  [ "$resumed_ok" = 1 ] || problems+=("service did not resume: $resumed_soon answered within ${resume_bound_s} s of the fault's end, $resumed in the last second")
  [ -z "$judge_throughput" ] || [ "$throughput_ok" = 1 ] ||
    problems+=("throughput did not recover: $resumed answered in the last second (criterion 90 %)")
  check_accounting "$dir/server.out" "$dir/phantom.out" > "$dir/accounting.txt" ||
    problems+=("$(tail -1 "$dir/accounting.txt")")
  case $fault in
    global_stall) [ "$(value "$dir/server.out" global_stalls)" -ge 3 ] || problems+=("stalls not counted")
                  grep -q "global stage stalled" "$dir/tangentd.log" || problems+=("stall not logged") ;;
    # The burst is found by the global stage, which runs at nice 10 beside the bridge: a machine
    # whose other core is busy at normal priority can starve it past the 0.5 s press of the smoke
    # run (measured: a 1.7 s gap, no contact found, under scripts/test.sh --under-load). The
    # full run judges it; the smoke reports it (docs/reliability.md, "Faults under load").
    contact_burst)
      if [ "$(value "$dir/server.out" contact_events)" -lt 8 ]; then
        if [ -n "$judge_throughput" ]; then problems+=("no contact burst")
        else echo "     (reported) no contact burst found: the global stage's longest gap $(value "$dir/server.out" global_longest_gap_ms) ms"; fi
      fi ;;
    stop_client) [ "$(value "$dir/server.out" device_timeouts)" -ge 1 ] || problems+=("the silence was not a timeout") ;;
    stop_server) [ "$(value "$dir/phantom.out" watchdog_trips)" -ge 1 ] || problems+=("the driver's watchdog did not trip") ;;
  esac
  if [ ${#problems[@]} -gt 0 ]; then
    echo "FAIL $fault: ${problems[*]} (logs in $dir)"
    failures=$((failures + 1))
  else
    echo "ok   $fault: answered $during during, round trip $rtt ms, $counters;" \
      "$resumed_soon answered within ${resume_bound_s} s of the fault's end, $resumed in the last second"
    echo "     $(head -1 "$dir/accounting.txt")"
  fi
}

for f in "${faults[@]}"; do run_fault "$f"; done
echo
cat "$table"
[ "$failures" -eq 0 ] || { echo "faults.sh: $failures fault(s) failed" >&2; exit 1; }
echo "faults.sh: ${#faults[@]} faults survived: 0 over-limit forces, service resumed after each"
