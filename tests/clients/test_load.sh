#!/bin/sh
# A short run of the load generator against the daemon on a private socket:
# every job done, every mesh verified, and a JSON summary with the promised
# fields on the last line.
#   test_load.sh SHORTCRUST-LOAD SHORTCRUSTD SHORTCRUST CLIENTS JOBS POINTS [K]
# SPDX-License-Identifier: GPL-3.0-or-later
set -u
load=$1 scd=$2 sc=$3 clients=$4 jobs=$5 points=$6 k=${7:-1}
. "$(dirname "$0")/daemon.sh"
fails=0
fail() { echo "FAIL: $*" >&2; fails=$((fails + 1)); }

start_daemon "$scd" "$sc"
"$load" --socket "$sock" --clients "$clients" --jobs "$jobs" --points "$points" \
  --jobs-in-flight "$k" --verify --json > "$tmp/out"
status=$?
cat "$tmp/out"
[ "$status" -eq 0 ] || fail "shortcrust-load exited $status"
json=$(tail -n 1 "$tmp/out")
for field in '"jobs": '"$jobs"',' '"jobs_done": '"$jobs"',' '"errors": 0,' \
             '"errors_by_code": {}' '"verify_failures": 0,' '"verified": '"$jobs"',' \
             '"jobs_per_s": [0-9]' '"points_per_s": [0-9]' '"latency_p50_ms": [0-9]' \
             '"latency_p90_ms": [0-9]' '"latency_p99_ms": [0-9]' '"latency_max_ms": [0-9]' \
             '"daemon_before": {' '"daemon_after": {'; do
  echo "$json" | grep -q "$field" || fail "JSON lacks $field"
done
# The daemon counted every job once.
after=$(echo "$json" | sed 's/.*"daemon_after": {[^}]*"jobs_done_total": \([0-9]*\).*/\1/')
[ "$after" = "$jobs" ] || fail "daemon counted $after jobs done, expected $jobs"

# The modes for scans: on the closed test surfaces they too must give
# closed meshes of the right genus.
for mode in boundary watertight auto; do
  "$load" --socket "$sock" --clients 1 --jobs 3 --points 2000 --mode "$mode" \
    --verify --json > "$tmp/outm"
  status=$?
  [ "$status" -eq 0 ] || fail "--mode $mode exited $status: $(cat "$tmp/outm")"
  tail -n 1 "$tmp/outm" | grep -q '"verified": 3, "verify_failures": 0,' ||
    fail "--mode $mode: $(tail -n 1 "$tmp/outm")"
done
"$load" --socket "$sock" --jobs 1 --points 1000 --mode bogus > "$tmp/outb" 2>&1
[ $? -eq 2 ] && grep -q "unknown mode 'bogus'" "$tmp/outb" || fail "--mode bogus: $(cat "$tmp/outb")"

# Bounded by time: a run with an unreachable job count stops by itself.
"$load" --socket "$sock" --clients 2 --jobs 1000000 --points 1000 --duration 1 --json > "$tmp/out2"
status=$?
[ "$status" -eq 0 ] || fail "the timed run exited $status: $(cat "$tmp/out2")"
tail -n 1 "$tmp/out2" | grep -q '"errors": 0,' || fail "timed run: $(tail -n 1 "$tmp/out2")"

# No daemon: every job is an error, by code.
stop_daemon
"$load" --socket "$sock" --clients 2 --jobs 4 --points 1000 --json > "$tmp/out3"
status=$?
[ "$status" -eq 1 ] || fail "without a daemon the run exited $status"
tail -n 1 "$tmp/out3" | grep -q '"errors": 4, "errors_by_code": {"NODAEMON": 4}' || fail "no daemon: $(tail -n 1 "$tmp/out3")"

[ "$fails" -eq 0 ] || { echo "$fails check(s) failed" >&2; cat "$tmp/daemon.log" >&2; exit 1; }
echo "load run passed"
