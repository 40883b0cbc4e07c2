#!/usr/bin/env bash
# Three daemons on loopback TCP behind a real HAProxy (the project's
# template, scripts/cluster-lib.sh): the token through the front and
# straight to a daemon (right, wrong, none, from SHORTCRUST_TOKEN); a
# verified load run through the front with one daemon SIGKILLed in the
# middle, which still completes every job, with retries; HAProxy's own
# health check marking that daemon down and, once it is back on its port,
# up again; a daemon stopped with SIGTERM during a run, drained without
# losing a job; one job split into tile jobs over the daemons (submit
# --tiles), the same mesh as the local command's, also when a daemon dies
# under it. Skips (77) without haproxy. Every process is stopped by its
# PID.
#   test_cluster.sh BIN_DIR TEMPLATE
# SPDX-License-Identifier: GPL-3.0-or-later
set -u
bin=$1 template=$2
if ! command -v haproxy >/dev/null 2>&1; then
  echo "SKIP: haproxy is not installed (scripts/setup.sh installs it)"
  exit 77
fi
. "$(dirname "$0")/../../scripts/cluster-lib.sh"
fails=0
fail() { echo "FAIL: $*" >&2; fails=$((fails + 1)); }
finish() {
  status=$?
  if [ "$fails" -ne 0 ] || [ "$status" -ne 0 ]; then
    for f in "$cl_dir"/*.log; do
      [ -f "$f" ] && { echo "--- $f" >&2; tail -n 40 "$f" >&2; }
    done
  fi
  cluster_stop
}
trap finish EXIT
trap 'exit 1' INT TERM

unset SHORTCRUST_TOKEN
cluster_init "$bin" "$template"
for i in 1 2 3; do cluster_start_daemon "$i" || exit 1; done
cluster_start_haproxy || exit 1
tok=$cl_token_file
sc=$bin/shortcrust

# A daemon's counter, read on its Unix socket (no token needed there).
stat_of() {
  "$sc" stats --socket "$cl_dir/d$1.sock" --json 2>/dev/null |
    sed -n "s/.*\"$2\": \([0-9]*\).*/\1/p"
}

# Waits up to a minute until daemon $1 has done at least $2 jobs.
wait_jobs() {
  local n=0
  until [ "$(stat_of "$1" jobs_done_total)" -ge "$2" ] 2>/dev/null; do
    n=$((n + 1))
    [ "$n" -gt 600 ] && return 1
    sleep 0.1
  done
}

# Waits up to $2 tenths of a second for the text $1 in HAProxy's log.
wait_log() {
  local n=0
  until grep -q "$1" "$cl_dir/haproxy.log"; do
    n=$((n + 1))
    [ "$n" -gt "$2" ] && return 1
    sleep 0.1
  done
}

# The token: through the front and straight to a daemon.
"$sc" ping --connect "$cl_front" --token-file "$tok" >/dev/null ||
  fail "ping through the front with the token"
(umask 077 && echo "0000000000000000000000000000000000000000" >"$cl_dir/wrong")
"$sc" ping --connect "$cl_front" --token-file "$cl_dir/wrong" >/dev/null 2>"$cl_dir/err"
[ $? -eq 1 ] && grep -q "AUTH" "$cl_dir/err" ||
  fail "a wrong token through the front: $(cat "$cl_dir/err")"
"$sc" ping --connect "tcp://127.0.0.1:${cl_port[1]}" --token-file "$cl_dir/wrong" \
  >/dev/null 2>"$cl_dir/err"
[ $? -eq 1 ] && grep -q "AUTH" "$cl_dir/err" ||
  fail "a wrong token to a daemon: $(cat "$cl_dir/err")"
"$sc" stats --connect "$cl_front" >/dev/null 2>"$cl_dir/err"
[ $? -eq 1 ] && grep -q "AUTH" "$cl_dir/err" && grep -q "SHORTCRUST_TOKEN" "$cl_dir/err" ||
  fail "no token: $(cat "$cl_dir/err")"
SHORTCRUST_TOKEN=$(head -n 1 "$tok") "$sc" ping --connect "$cl_front" >/dev/null ||
  fail "ping with SHORTCRUST_TOKEN"
# A token file others may read is not used.
cp "$tok" "$cl_dir/loose" && chmod 644 "$cl_dir/loose"
"$sc" ping --connect "$cl_front" --token-file "$cl_dir/loose" >/dev/null 2>"$cl_dir/err"
[ $? -eq 1 ] && grep -q "chmod 600" "$cl_dir/err" ||
  fail "a token file others may read: $(cat "$cl_dir/err")"
refused=0
for i in 1 2 3; do refused=$((refused + $(stat_of "$i" auth_refused_total))); done
[ "$refused" -eq 3 ] || fail "the daemons counted $refused refusals, want 3"
# The health checks pass: none of them was refused.
wait_log "is DOWN" 20 && fail "a daemon was marked down: $(grep DOWN "$cl_dir/haproxy.log")"

# One job split into tile jobs through the front (submit --tiles): spread
# over the daemons, and the same file as the local command's.
scan=$(dirname "$0")/../data/bunny_points.ply
"$sc" reconstruct "$scan" -o "$cl_dir/local.ply" -q || fail "reconstruct $scan"
for i in 1 2 3; do done_before[$i]=$(stat_of "$i" jobs_done_total); done
"$sc" submit "$scan" -o "$cl_dir/tiles.ply" --connect "$cl_front" --token-file "$tok" \
  --tiles 4 -q 2>"$cl_dir/err" || fail "submit --tiles 4 through the front: $(cat "$cl_dir/err")"
cmp -s "$cl_dir/local.ply" "$cl_dir/tiles.ply" ||
  fail "submit --tiles 4 through the front differs from reconstruct"
served=0 total=0
for i in 1 2 3; do
  d=$(($(stat_of "$i" jobs_done_total) - done_before[$i]))
  total=$((total + d))
  [ "$d" -gt 0 ] && served=$((served + 1))
done
[ "$total" -eq 4 ] || fail "the daemons did $total jobs for 4 tiles"
[ "$served" -ge 2 ] || fail "the 4 tile jobs went to $served daemon(s), want 2 or more"

# A load run through the front; daemon 2 dies in the middle of it.
jobs=150
"$bin/shortcrust-load" --connect "$cl_front" --token-file "$tok" --clients 6 \
  --jobs "$jobs" --points 4000 --jobs-in-flight 2 --retries 5 \
  --retry-backoff 100 --timeout 120 --verify --json >"$cl_dir/load.out" 2>&1 &
load=$!
wait_jobs 2 5 || fail "daemon 2 did no job"
cluster_kill_daemon 2 KILL
wait_log "d2 is DOWN" 150 || fail "HAProxy did not mark daemon 2 down"
wait "$load"
status=$?
json=$(tail -n 1 "$cl_dir/load.out")
[ "$status" -eq 0 ] || fail "the load run exited $status: $(cat "$cl_dir/load.out")"
for field in "\"jobs_done\": $jobs," '"errors": 0,' '"jobs_lost": 0' \
             "\"verified\": $jobs," '"verify_failures": 0,'; do
  echo "$json" | grep -q "$field" || fail "load: no $field in $json"
done
retries=$(echo "$json" | sed -n 's/.*"retries": \([0-9]*\).*/\1/p')
[ "${retries:-0}" -gt 0 ] || fail "no retry counted although daemon 2 died: $json"
grep "^retries" "$cl_dir/load.out"

# Daemon 2 back on its port: the health check marks it up, and it serves.
cluster_start_daemon 2 "${cl_port[2]}" || exit 1
wait_log "d2 is UP" 150 || fail "HAProxy did not mark daemon 2 up again"
"$bin/shortcrust-load" --connect "$cl_front" --token-file "$tok" --clients 6 \
  --jobs 30 --points 2000 --verify >"$cl_dir/load2.out" 2>&1 ||
  fail "the run after the restart: $(cat "$cl_dir/load2.out")"
[ "$(stat_of 2 jobs_done_total)" -gt 0 ] || fail "the restarted daemon got no job"

# Daemon 3 stops with SIGTERM during a run: HAProxy drains it (no new
# connection), its jobs finish or run again elsewhere, none is lost.
"$bin/shortcrust-load" --connect "$cl_front" --token-file "$tok" --clients 6 \
  --jobs 90 --points 4000 --jobs-in-flight 2 --retries 5 --retry-backoff 100 \
  --timeout 120 --verify --json >"$cl_dir/load3.out" 2>&1 &
load=$!
before=$(stat_of 3 jobs_done_total)
wait_jobs 3 $((before + 3)) || fail "daemon 3 did no job"
cluster_kill_daemon 3 TERM
wait_log "d3 is DOWN" 150 || fail "HAProxy did not mark daemon 3 down"
wait "$load" || fail "the run with a draining daemon: $(cat "$cl_dir/load3.out")"
tail -n 1 "$cl_dir/load3.out" | grep -q '"jobs_done": 90, "errors": 0,' ||
  fail "draining: $(tail -n 1 "$cl_dir/load3.out")"

# Daemon 1 dies while the tile jobs of one job run: its tiles run again
# on daemon 2, and the mesh is still the local command's.
before=$(stat_of 1 jobs_done_total)
"$sc" submit "$scan" -o "$cl_dir/tiles2.ply" --connect "$cl_front" --token-file "$tok" \
  --tiles 12 --connections 2 -q 2>"$cl_dir/tiles2.err" &
tiles=$!
wait_jobs 1 $((before + 1)) || fail "daemon 1 did no tile job"
cluster_kill_daemon 1 KILL
wait "$tiles" || fail "submit --tiles with a daemon killed: $(cat "$cl_dir/tiles2.err")"
cmp -s "$cl_dir/local.ply" "$cl_dir/tiles2.ply" ||
  fail "submit --tiles with a daemon killed differs from reconstruct"
grep -q "submitted again" "$cl_dir/tiles2.err" ||
  fail "no tile job ran again although daemon 1 died: $(cat "$cl_dir/tiles2.err")"

[ "$fails" -eq 0 ] || { echo "$fails check(s) failed" >&2; exit 1; }
echo "cluster test passed"
