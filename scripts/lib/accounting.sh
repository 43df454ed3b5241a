# Shared by tests/server/integration.sh, scripts/faults.sh and scripts/soak.sh (sourced, not
# run): the accounting of one live run, closed by counter between the clients and the server.
# It holds on any machine, however slow or loaded (docs/reliability.md, "What the real-time
# tests assert"); what depends on the machine's speed (the answered fraction) is printed only.
#
#   check_accounting SERVER_OUT PHANTOM_OUT [PHANTOM_OUT ...]
# SERVER_OUT is tangentd's output (its summary after SIGINT), each PHANTOM_OUT a tangent-phantom
# summary of a client of that server. With S the states the clients sent, A the states the
# server accepted, R those it rejected (every reason), L the gaps in sequence numbers it saw
# (states that never reached it), U the accepted states it never answered and P the answers the
# clients received:
#   * A + R <= S <= A + R + L: every state that reached the server was counted once, as accepted
#     or rejected, and every state sent reached it or left a gap (a state injected with a
#     repeated seq is rejected and also leaves the gap of the seq it skipped, so L may count it);
#   * 1 <= P <= A - U: the clients were answered, and never more often than the server answered.
# Prints one line of figures; returns 1 (with the reason on the line after) if either fails.
_accounting_value() { grep -m1 "^$2=" "$1" | cut -d= -f2; }

check_accounting() {
  local server_out=$1
  shift
  local sent=0 answered=0 f
  for f in "$@"; do
    sent=$((sent + $(_accounting_value "$f" sent)))
    answered=$((answered + $(_accounting_value "$f" answered)))
  done
  local accepted lost unanswered rejected=0 reason
  accepted=$(_accounting_value "$server_out" device_messages)
  lost=$(_accounting_value "$server_out" lost_before_filter)
  unanswered=$(_accounting_value "$server_out" unanswered)
  for reason in non_finite quaternion workspace device session sequence jump pending; do
    rejected=$((rejected + $(_accounting_value "$server_out" "rejected_$reason")))
  done
  local served=$((accepted - unanswered))
  echo "accounting: sent $sent; accepted $accepted + rejected $rejected + lost $lost" \
    "(= $((accepted + rejected + lost))); the server answered $served, the clients received" \
    "$answered ($(awk -v a="$answered" -v s="$accepted" \
      'BEGIN { printf "%.2f", 100 * a / (s > 0 ? s : 1) }') % of accepted: reported, not judged)"
  if [ $((accepted + rejected)) -gt "$sent" ]; then
    echo "accounting does not close: the server counted $((accepted + rejected)) states of $sent sent"
    return 1
  fi
  if [ "$sent" -gt $((accepted + rejected + lost)) ]; then
    echo "accounting does not close: $((sent - accepted - rejected - lost)) of $sent states" \
      "neither accepted, rejected nor counted lost"
    return 1
  fi
  if [ "$answered" -lt 1 ] || [ "$answered" -gt "$served" ]; then
    echo "accounting does not close: the clients received $answered answers, the server gave $served"
    return 1
  fi
  return 0
}
