# Sourced by scripts/cluster-demo.sh and the cluster test: N shortcrustd on
# loopback TCP ports with a fresh token, and HAProxy in front of them made
# from daemon/haproxy/shortcrust.cfg. Every process is started here, in the
# background, and stopped by its PID.
#
#   cluster_init BIN TEMPLATE     a private directory ($cl_dir) and a token
#                                 ($cl_token_file); BIN holds the programs
#   cluster_start_daemon I [PORT] daemon I on 127.0.0.1:PORT (default: a
#                                 port the system picks), socket $cl_dir/dI.sock,
#                                 log $cl_dir/dI.log; sets cl_pid[I], cl_port[I]
#   cluster_kill_daemon I [SIG]   SIGTERM (or SIG) and wait
#   cluster_start_haproxy         the front on $cl_front (tcp://127.0.0.1:P);
#                                 log $cl_dir/haproxy.log
#   cluster_stop                  everything still running, then the directory
# Safe under set -e: a process stopped by a signal is not a failure here.
# SPDX-License-Identifier: GPL-3.0-or-later

cl_pid=()
cl_port=()
cl_haproxy=
cl_dir=
cl_front=

cluster_init() {
  cl_bin=$1 cl_template=$2
  cl_dir=$(mktemp -d "${TMPDIR:-/tmp}/shortcrust-cluster.XXXXXX")
  chmod 700 "$cl_dir"
  cl_token_file=$cl_dir/token
  # 32 random bytes as 64 hex digits: printable, so it also fits in
  # SHORTCRUST_TOKEN.
  (umask 077 && od -An -N32 -tx1 /dev/urandom | tr -d ' \n' >"$cl_token_file" &&
    echo >>"$cl_token_file")
}

# The port daemon I logged for its TCP listener.
cluster_logged_port() {
  sed -n 's/.*listening on tcp:\/\/127\.0\.0\.1:\([0-9]*\).*/\1/p' \
    "$cl_dir/d$1.log" | tail -n 1
}

cluster_start_daemon() {
  local i=$1 port=${2:-0} n=0
  : >"$cl_dir/d$i.log"
  "$cl_bin/shortcrustd" --socket "$cl_dir/d$i.sock" --workers 1 \
    --listen "tcp://127.0.0.1:$port" --token-file "$cl_token_file" \
    2>>"$cl_dir/d$i.log" &
  cl_pid[$i]=$!
  until "$cl_bin/shortcrust" ping --socket "$cl_dir/d$i.sock" >/dev/null 2>&1; do
    n=$((n + 1))
    if [ "$n" -gt 300 ] || ! kill -0 "${cl_pid[$i]}" 2>/dev/null; then
      echo "cluster: daemon $i did not start:" >&2
      cat "$cl_dir/d$i.log" >&2
      return 1
    fi
    sleep 0.1
  done
  cl_port[$i]=$(cluster_logged_port "$i")
}

cluster_kill_daemon() {
  local i=$1 sig=${2:-TERM}
  if [ -n "${cl_pid[$i]:-}" ]; then
    kill "-$sig" "${cl_pid[$i]}" 2>/dev/null
    wait "${cl_pid[$i]}" 2>/dev/null || true
    cl_pid[$i]=
  fi
}

# u32 little-endian in hex.
cluster_hex32() {
  printf '%02x%02x%02x%02x' $(($1 & 255)) $((($1 >> 8) & 255)) \
    $((($1 >> 16) & 255)) $((($1 >> 24) & 255))
}

# The health check's HELLO with the token (PROTOCOL.md 5.1).
cluster_hello_hex() {
  local token len
  token=$(head -n 1 "$cl_token_file")
  len=${#token}
  # header; "SCRU", versions 1 to 1; features TOKEN; max_frame 4096,
  # reserved; token_len and the token.
  printf '01000000%s%s%s%s%s%s' "$(cluster_hex32 $((28 + len)))" \
    5343525501000100 0200000000000000 0010000000000000 \
    "$(cluster_hex32 "$len")" \
    "$(printf '%s' "$token" | od -An -tx1 | tr -d ' \n')"
}

# A free loopback port in a high range: nothing answers on it now.
cluster_free_port() {
  local p
  while :; do
    p=$((20000 + RANDOM % 40000))
    (exec 3<>"/dev/tcp/127.0.0.1/$p") 2>/dev/null || break
  done
  echo "$p"
}

cluster_start_haproxy() {
  local servers="" i attempt port n
  for i in "${!cl_port[@]}"; do
    servers="$servers    server d$i 127.0.0.1:${cl_port[$i]}"$'\n'
  done
  for attempt in 1 2 3 4 5; do
    port=$(cluster_free_port)
    cl_front=tcp://127.0.0.1:$port
    # The configuration holds the token: made private before it is written.
    (umask 077 && sed -e "s|@FRONT@|127.0.0.1:$port|" \
      -e "s|@RUN_DIR@|$cl_dir|" \
      -e "s|@HELLO_HEX@|$(cluster_hello_hex)|" \
      -e "/^@SERVERS@$/{
r /dev/stdin
d
}" "$cl_template" >"$cl_dir/haproxy.cfg" <<<"$servers")
    : >"$cl_dir/haproxy.log"
    haproxy -db -f "$cl_dir/haproxy.cfg" 2>>"$cl_dir/haproxy.log" &
    cl_haproxy=$!
    n=0
    until "$cl_bin/shortcrust" ping --connect "$cl_front" \
      --token-file "$cl_token_file" >/dev/null 2>&1; do
      n=$((n + 1))
      if ! kill -0 "$cl_haproxy" 2>/dev/null || [ "$n" -gt 100 ]; then
        break
      fi
      sleep 0.1
    done
    if kill -0 "$cl_haproxy" 2>/dev/null && [ "$n" -le 100 ]; then
      return 0
    fi
    # Most likely someone took the port meanwhile: another one.
    kill -TERM "$cl_haproxy" 2>/dev/null
    wait "$cl_haproxy" 2>/dev/null || true
    cl_haproxy=
  done
  echo "cluster: HAProxy did not start:" >&2
  cat "$cl_dir/haproxy.log" >&2
  return 1
}

cluster_stop() {
  local i
  if [ -n "$cl_haproxy" ]; then
    kill -TERM "$cl_haproxy" 2>/dev/null
    wait "$cl_haproxy" 2>/dev/null || true
    cl_haproxy=
  fi
  for i in "${!cl_pid[@]}"; do
    cluster_kill_daemon "$i"
  done
  if [ -n "$cl_dir" ]; then
    rm -rf "$cl_dir"
    cl_dir=
  fi
}
