#!/usr/bin/env bash
# scripts/lib/accounting.sh on made-up summaries: the books that close pass, and each way of not
# closing fails with its reason (a check that cannot fail proves nothing).
set -euo pipefail
# shellcheck source=../../scripts/lib/accounting.sh
source "$(cd "$(dirname "$0")/../.." && pwd)/scripts/lib/accounting.sh"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failures=0

# summaries ACCEPTED REJECTED_JUMP LOST UNANSWERED SENT ANSWERED: tangentd's and one client's.
summaries() {
  printf 'device_messages=%s\nlost_before_filter=%s\nunanswered=%s\n' "$1" "$3" "$4" > "$work/server.out"
  for r in non_finite quaternion workspace device session sequence pending; do echo "rejected_$r=0"; done >> "$work/server.out"
  echo "rejected_jump=$2" >> "$work/server.out"
  printf 'sent=%s\nanswered=%s\n' "$5" "$6" > "$work/client.out"
}
expect() {  # expect pass|fail REASON_PATTERN CASE
  local want=$1 pattern=$2 name=$3 out status=0
  out=$(check_accounting "$work/server.out" "$work/client.out") || status=$?
  if [ "$want" = pass ] && [ "$status" -eq 0 ]; then echo "ok   $name"; return; fi
  if [ "$want" = fail ] && [ "$status" -ne 0 ] && grep -q "$pattern" <<< "$out"; then
    echo "ok   $name: $(tail -1 <<< "$out")"; return
  fi
  echo "FAIL $name (status $status):"; echo "$out"; failures=$((failures + 1))
}

summaries 1000 0 0 10 1000 990;  expect pass "" "every state accepted, every answer received"
summaries 900 50 50 0 1000 900;  expect pass "" "accepted + rejected + lost = sent"
summaries 900 100 1 0 1000 800;  expect pass "" "a repeated seq rejected and also a gap (L counts it)"
summaries 1000 0 0 0 1000 990;   expect pass "" "answers lost on the way back"
summaries 1000 1 0 0 1000 900;   expect fail "counted 1001 states of 1000 sent" "a state counted twice"
summaries 900 0 50 0 1000 900;   expect fail "50 of 1000 states" "states neither accepted, rejected nor lost"
summaries 1000 0 0 100 1000 901; expect fail "received 901 answers, the server gave 900" "more answers than the server gave"
summaries 1000 0 0 0 1000 0;     expect fail "received 0 answers" "no answer at all"

[ "$failures" -eq 0 ] || { echo "accounting_test: $failures case(s) failed"; exit 1; }
echo "accounting_test: 8 cases as expected"
