#!/usr/bin/env bash
# Several daemons behind HAProxy: start N shortcrustd on loopback TCP ports
# with a fresh token, HAProxy in front of them (daemon/haproxy/shortcrust.cfg,
# the token written into the generated configuration for its health
# check), run a short verified shortcrust-load through the front, print
# what HAProxy saw, and stop everything by its PID (also when a step
# fails).
#   scripts/cluster-demo.sh [BUILD] [N]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
n=${2:-3}
bin=$build/bin

for prog in shortcrustd shortcrust shortcrust-load; do
  if [ ! -x "$bin/$prog" ]; then
    echo "cluster-demo: $bin/$prog not found; build first (make build)" >&2
    exit 1
  fi
done
if ! command -v haproxy >/dev/null; then
  echo "cluster-demo: haproxy not found; scripts/setup.sh installs it" >&2
  exit 1
fi

. scripts/cluster-lib.sh
cluster_init "$bin" daemon/haproxy/shortcrust.cfg
trap cluster_stop EXIT
trap 'exit 1' INT TERM

for i in $(seq 1 "$n"); do
  cluster_start_daemon "$i"
  echo "cluster-demo: daemon $i on tcp://127.0.0.1:${cl_port[$i]} (pid ${cl_pid[$i]})"
done
cluster_start_haproxy
echo "cluster-demo: HAProxy on $cl_front (pid $cl_haproxy), token in $cl_token_file"

"$bin/shortcrust-load" --connect "$cl_front" --token-file "$cl_token_file" \
  --clients $((2 * n)) --jobs $((20 * n)) --points 3000 --jobs-in-flight 2 \
  --verify

echo "cluster-demo: jobs done per daemon:"
for i in $(seq 1 "$n"); do
  done_i=$("$bin/shortcrust" stats --socket "$cl_dir/d$i.sock" --json |
    sed 's/.*"jobs_done_total": \([0-9]*\).*/\1/')
  echo "  daemon $i: $done_i"
done
