#!/bin/sh
# The installed shortcrust, used as a program outside this tree would.
#   check.sh install BUILD PREFIX
#       cmake --install BUILD into a fresh PREFIX
#   check.sh pkgconfig-core PREFIX WORK
#   check.sh pkgconfig-client PREFIX WORK
#       build tests/install/*_consumer.c with `pkg-config --cflags --libs`
#       (PKG_CONFIG_PATH = the prefix's only) and run it; the client's
#       against the prefix's shortcrustd on a private socket
#   check.sh find-package PREFIX WORK
#       configure, build and run tests/install/consumer, which uses
#       find_package(shortcrust) and the targets shortcrust::core and
#       shortcrust::client
# From the environment: CMAKE, CC, CXX, SC_FLAGS (flags for every compile and link,
# the sanitizer's), SC_STATIC=1 when the libraries are static archives.
# SPDX-License-Identifier: GPL-3.0-or-later
set -eu

here=$(cd "$(dirname "$0")" && pwd)
what=$1
CC=${CC:-cc}
CXX=${CXX:-c++}
SC_FLAGS=${SC_FLAGS:-}
SC_STATIC=${SC_STATIC:-0}

die() {
  echo "FAIL: $*" >&2
  exit 1
}

if [ "$what" = install ]; then
  build=$2 prefix=$3
  rm -rf "$prefix"
  "${CMAKE:-cmake}" --install "$build" --prefix "$prefix" >/dev/null
  echo "installed into $prefix:"
  (cd "$prefix" && find . ! -type d | LC_ALL=C sort)
  exit 0
fi

prefix=$2 work=$3
[ -d "$prefix" ] || die "nothing installed in $prefix"
rm -rf "$work"
mkdir -p "$work"

# Only the prefix's .pc files, and where they are, whatever the libdir.
pcdir=$(dirname "$(find "$prefix" -name shortcrust.pc -o \
                        -name shortcrust-client.pc | head -n 1)")
[ -d "$pcdir" ] || die "no .pc file under $prefix"
PKG_CONFIG_PATH=$pcdir
export PKG_CONFIG_PATH
static=
[ "$SC_STATIC" = 1 ] && static=--static

# pkg-config flags of a module, and a run path to its libdir so that the
# program finds the shared library where it was installed.
pc_build() { # MODULE SOURCE OUTPUT
  flags=$(pkg-config $static --cflags --libs "$1") ||
    die "pkg-config $1 failed"
  libdir=$(pkg-config --variable=libdir "$1")
  echo "pkg-config $static --cflags --libs $1: $flags"
  # shellcheck disable=SC2086 # word splitting of the flags is intended
  "$CC" -std=c11 -Wall -Wextra -Werror $SC_FLAGS -o "$3" "$2" $flags \
    -Wl,-rpath,"$libdir" -lm || die "cannot build $2 against $1"
}

case $what in
pkgconfig-core)
  pc_build shortcrust "$here/core_consumer.c" "$work/core_consumer"
  "$work/core_consumer" || die "core_consumer"
  ;;

pkgconfig-client)
  pc_build shortcrust-client "$here/client_consumer.c" "$work/client_consumer"
  daemon=$prefix/bin/shortcrustd
  [ -x "$daemon" ] || die "no $daemon"
  sock=$(mktemp -d "${TMPDIR:-/tmp}/sc-install.XXXXXX")
  "$daemon" --socket "$sock/d.sock" --workers 1 --log-level warn \
    2>"$work/daemon.log" &
  pid=$!
  trap 'kill -TERM $pid 2>/dev/null; wait $pid 2>/dev/null; rm -rf "$sock"' EXIT
  if ! "$work/client_consumer" "$sock/d.sock"; then
    cat "$work/daemon.log" >&2
    die "client_consumer"
  fi
  ;;

find-package)
  # shellcheck disable=SC2086
  "${CMAKE:-cmake}" -S "$here/consumer" -B "$work" -DCMAKE_PREFIX_PATH="$prefix" \
    -DCMAKE_BUILD_TYPE=Release -DCMAKE_C_COMPILER="$CC" \
    -DCMAKE_CXX_COMPILER="$CXX" \
    -DCMAKE_C_FLAGS="-Wall -Wextra -Werror $SC_FLAGS" \
    -DCMAKE_CXX_FLAGS="-Wall -Wextra -Werror $SC_FLAGS" \
    -DCMAKE_EXE_LINKER_FLAGS="$SC_FLAGS" >"$work.log" 2>&1 || {
    cat "$work.log" >&2
    die "find_package(shortcrust) project did not configure"
  }
  "${CMAKE:-cmake}" --build "$work" >>"$work.log" 2>&1 || {
    cat "$work.log" >&2
    die "find_package(shortcrust) project did not build"
  }
  for p in core_consumer client_consumer both_consumer; do
    "$work/$p" || die "$p"
  done
  ;;

*)
  die "unknown check $what"
  ;;
esac
echo "PASS: $what"
