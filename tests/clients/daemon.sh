# Sourced by the client tests' scripts: starts shortcrustd on a private
# socket in a fresh temporary directory and stops it when the script exits.
#   start_daemon SHORTCRUSTD SHORTCRUST [DAEMON OPTIONS...]
# sets $tmp (the directory) and $sock; the daemon's log is $tmp/daemon.log.
# SPDX-License-Identifier: GPL-3.0-or-later

daemon_pid=
tmp=$(mktemp -d "${TMPDIR:-/tmp}/scc-test.XXXXXX")
sock=$tmp/d.sock

stop_daemon() {
  if [ -n "$daemon_pid" ]; then
    kill -TERM "$daemon_pid" 2>/dev/null
    wait "$daemon_pid" 2>/dev/null
    daemon_pid=
  fi
}

cleanup() {
  stop_daemon
  rm -rf "$tmp"
}
trap cleanup EXIT
trap 'exit 1' INT TERM

start_daemon() {
  _scd=$1 _sc=$2
  shift 2
  "$_scd" --socket "$sock" "$@" 2>"$tmp/daemon.log" &
  daemon_pid=$!
  # Sanitizer builds start slowly.
  _i=0
  until "$_sc" ping --socket "$sock" >/dev/null 2>&1; do
    _i=$((_i + 1))
    if [ "$_i" -gt 300 ] || ! kill -0 "$daemon_pid" 2>/dev/null; then
      echo "FAIL: the daemon did not start:" >&2
      cat "$tmp/daemon.log" >&2
      exit 1
    fi
    sleep 0.1
  done
}
