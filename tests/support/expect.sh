# Shared by the command-line tests (sourced): fail MESSAGE... counts a
# failure; expect STATUS PATTERN CMD... runs CMD and checks its exit status
# and, unless PATTERN is empty, a line of its output or errors matching
# PATTERN. The caller sets $tmp (a scratch directory); CMD's output is left
# in $tmp/out and $tmp/err.
# SPDX-License-Identifier: GPL-3.0-or-later
fails=0
fail() { echo "FAIL: $*" >&2; fails=$((fails + 1)); }

expect() {
  want=$1 pat=$2
  shift 2
  "$@" >"$tmp/out" 2>"$tmp/err"
  got=$?
  [ "$got" -eq "$want" ] || fail "$* exited $got, expected $want: $(cat "$tmp/err")"
  [ -z "$pat" ] || grep -q -- "$pat" "$tmp/out" "$tmp/err" || fail "$*: no '$pat' in: $(cat "$tmp/out" "$tmp/err")"
}
