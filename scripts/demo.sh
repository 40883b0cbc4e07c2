#!/usr/bin/env bash
# The main job on a bundled sample scan, through the daemon: start
# shortcrustd on a private socket, submit the kitten with `shortcrust
# submit`, write the mesh to BUILD/demo/kitten.ply and its report to
# BUILD/demo/kitten.json, print the summary, and stop the daemon (also when
# a step fails).
#   scripts/demo.sh [BUILD]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
bin=$build/bin
out=$build/demo
mkdir -p "$out"

for prog in shortcrustd shortcrust; do
  if [ ! -x "$bin/$prog" ]; then
    echo "demo: $bin/$prog not found; build first (make build)" >&2
    exit 1
  fi
done

# A private socket in a temporary directory, so the demo never meets (or
# disturbs) a daemon that is already running.
tmp=$(mktemp -d "${TMPDIR:-/tmp}/shortcrust-demo.XXXXXX")
sock=$tmp/shortcrust.sock
log=$tmp/shortcrustd.log
daemon=

stop_daemon() {
  if [ -n "$daemon" ] && kill -0 "$daemon" 2>/dev/null; then
    kill -TERM "$daemon"
    wait "$daemon" || echo "demo: the daemon exited with status $?" >&2
  fi
  daemon=
}

on_exit() {
  status=$?
  stop_daemon
  if [ "$status" -ne 0 ] && [ -s "$log" ]; then
    echo "demo: failed; the daemon's log:" >&2
    sed 's/^/  /' "$log" >&2
  fi
  rm -rf "$tmp"
}
trap on_exit EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

echo "demo: starting shortcrustd on $sock" >&2
"$bin/shortcrustd" --socket "$sock" 2>"$log" &
daemon=$!
tries=0
until "$bin/shortcrust" ping --socket "$sock" >/dev/null 2>&1; do
  tries=$((tries + 1))
  if [ "$tries" -gt 100 ] || ! kill -0 "$daemon" 2>/dev/null; then
    echo "demo: the daemon did not start" >&2
    exit 1
  fi
  sleep 0.1
done

in=tests/data/kitten_points.ply
echo "demo: submitting $in" >&2
"$bin/shortcrust" submit "$in" -o "$out/kitten.ply" --report "$out/kitten.json" \
  --socket "$sock"
stop_daemon
echo "demo: mesh in $out/kitten.ply, diagnostics in $out/kitten.json" >&2
