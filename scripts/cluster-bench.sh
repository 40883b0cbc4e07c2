#!/usr/bin/env bash
# What the HAProxy front costs, with shortcrust-load: small jobs through
# the front over 1, 2 and 3 daemons (one worker each), against the same
# load on one daemon over a direct TCP connection and over its Unix
# socket; and the latency of one job at a time, and of a PING, on each
# path. Each figure is the median of ROUNDS runs. With INPUT, then one job
# of that point file split into TILES tile jobs (`shortcrust submit
# --tiles`) through the front over 1, 2 and 3 daemons, against the local
# command on the same file (one thread, and TILES tiles on two threads),
# the median wall time of ROUNDS runs each, and the meshes compared.
#   scripts/cluster-bench.sh [BUILD] [ROUNDS] [POINTS] [INPUT] [TILES]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
rounds=${2:-3}
points=${3:-1000}
input=${4:-}
tiles=${5:-4}
bin=$build/bin
command -v haproxy >/dev/null || {
  echo "cluster-bench: haproxy not found; scripts/setup.sh installs it" >&2
  exit 1
}
. scripts/cluster-lib.sh
trap cluster_stop EXIT

median() { sort -g | awk '{v[NR] = $1} END {print v[int((NR + 1) / 2)]}'; }
field() { tail -n 1 | sed -n "s/.*\"$1\": \([0-9.]*\).*/\1/p"; }

# load ADDR CLIENTS JOBS IN_FLIGHT FIELD: the median of the field.
load() {
  local r
  for r in $(seq 1 "$rounds"); do
    "$bin/shortcrust-load" --connect "$1" --token-file "$cl_token_file" \
      --clients "$2" --jobs "$3" --points "$points" --jobs-in-flight "$4" \
      --json | field "$5"
  done | median
}

# The median round trip of 20 PINGs, in ms, each on a new connection.
ping_ms() {
  for r in $(seq 1 20); do
    "$bin/shortcrust" ping --connect "$1" --token-file "$cl_token_file" |
      sed -n 's/.*round trip \([0-9.]*\) ms.*/\1/p'
  done | median
}

row() {
  printf '%-24s %16s %16s %10s\n' "$1" "$2" "$3" "$4"
}

# Numbers to the digits that mean something.
fmt() { awk -v d="$1" '{printf "%.*f", d, $1}'; }

echo "cluster-bench: jobs of $points points, median of $rounds runs;" \
  "load average $(cut -d' ' -f1-3 /proc/loadavg)"
row "path" "jobs/s" "p50 of a job" "PING"
row "" "(6 clients x 2)" "(1 at a time)" "(ms)"
for n in 1 2 3; do
  cluster_init "$bin" daemon/haproxy/shortcrust.cfg
  for i in $(seq 1 "$n"); do cluster_start_daemon "$i"; done
  cluster_start_haproxy
  if [ "$n" -eq 1 ]; then
    for path in "unix://$cl_dir/d1.sock" "tcp://127.0.0.1:${cl_port[1]}"; do
      row "direct ${path%%:*}, 1 daemon" \
        "$(load "$path" 6 240 2 jobs_per_s | fmt 1)" \
        "$(load "$path" 1 60 1 latency_p50_ms | fmt 2) ms" \
        "$(ping_ms "$path" | fmt 3)"
    done
  fi
  row "HAProxy, $n daemon$([ "$n" -gt 1 ] && echo s)" \
    "$(load "$cl_front" 6 240 2 jobs_per_s | fmt 1)" \
    "$(load "$cl_front" 1 60 1 latency_p50_ms | fmt 2) ms" \
    "$(ping_ms "$cl_front" | fmt 3)"
  cluster_stop
done

[ -n "$input" ] || exit 0

# wall CMD...: the median wall time of the command, in seconds.
wall() {
  local r t0 t1
  for r in $(seq 1 "$rounds"); do
    t0=$(date +%s.%N)
    "$@" >/dev/null || { echo "cluster-bench: $* failed" >&2; exit 1; }
    t1=$(date +%s.%N)
    awk -v a="$t0" -v b="$t1" 'BEGIN { print b - a }'
  done | median
}
ratio() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", a / b }'; }
out=$(mktemp -d "${TMPDIR:-/tmp}/shortcrust-tiles.XXXXXX")
trap 'cluster_stop; rm -rf "$out"' EXIT
echo
echo "cluster-bench: one job of $input in $tiles tiles;" \
  "load average $(cut -d' ' -f1-3 /proc/loadavg)"
local1=$(wall "$bin/shortcrust" reconstruct "$input" -o "$out/local.ply" -q)
local2=$(wall "$bin/shortcrust" reconstruct "$input" -o "$out/local2.ply" -q \
  --tiles "$tiles" --threads 2)
printf '%-36s %8s s\n' "reconstruct, 1 thread" "$(echo "$local1" | fmt 2)"
printf '%-36s %8s s  (%s of 1 thread)\n' "reconstruct, $tiles tiles on 2 threads" \
  "$(echo "$local2" | fmt 2)" "$(ratio "$local2" "$local1")"
for n in 1 2 3; do
  cluster_init "$bin" daemon/haproxy/shortcrust.cfg
  for i in $(seq 1 "$n"); do cluster_start_daemon "$i"; done
  cluster_start_haproxy
  t=$(wall "$bin/shortcrust" submit "$input" -o "$out/tiles.ply" -q \
    --connect "$cl_front" --token-file "$cl_token_file" --tiles "$tiles")
  same=same
  cmp -s "$out/local.ply" "$out/tiles.ply" || same=DIFFERENT
  printf '%-36s %8s s  (%s of 1 thread; mesh %s)\n' \
    "submit --tiles $tiles, $n daemon$([ "$n" -gt 1 ] && echo s)" \
    "$(echo "$t" | fmt 2)" "$(ratio "$t" "$local1")" "$same"
  cluster_stop
done
