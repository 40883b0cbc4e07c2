#!/usr/bin/env bash
# Builds the libFuzzer targets of the protocol decoder and of the file
# readers with clang, ASan and UBSan, then fuzzes each for a fixed time over
# a copy of its seed corpus. Fails if
# the build fails or the fuzzer finds a crash, a sanitizer report, a leak or
# a timeout; the input that did it is left in
# <build-dir>/fuzz-run/{decoder,files}/artifacts.
#
# Usage: tests/proto/run-fuzz.sh [BUILD_DIR [SECONDS]]
#        BUILD_DIR defaults to build-fuzz, SECONDS to 60.
#
# Copyright (C) 2026 the shortcrust authors.
# SPDX-License-Identifier: GPL-3.0-or-later
set -euo pipefail

root=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:-build-fuzz}
seconds=${2:-60}
case $build in
  /*) ;;
  *) build=$PWD/$build ;;
esac
case $seconds in
  '' | *[!0-9]*) echo "run-fuzz.sh: SECONDS must be a whole number" >&2; exit 2 ;;
esac

if ! command -v clang >/dev/null; then
  echo "run-fuzz.sh: clang is needed for libFuzzer" >&2
  exit 1
fi

cd "$root"
CC=clang cmake -S . -B "$build" -DSC_MODULES="proto;clients;tests" \
  -DSC_SANITIZE=address -DSC_FUZZ=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo
cmake --build "$build" --target fuzz_proto_decoder fuzz_files_reader \
  -j "$(nproc 2>/dev/null || echo 2)"

export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1}

# fuzz NAME TARGET SEEDS: SECONDS of TARGET over a copy of the seeds (the
# fuzzer adds the inputs it finds to its corpus directory, and the
# committed seeds stay as they were written).
fuzz() {
  local name=$1 target=$2 seeds=$3 work=$build/fuzz-run/$1 status=0
  rm -rf "$work"
  mkdir -p "$work/corpus" "$work/artifacts"
  cp "$seeds"/* "$work/corpus/"
  "$build/bin/$target" -max_total_time="$seconds" -timeout=10 \
    -rss_limit_mb=2048 -print_final_stats=1 \
    -artifact_prefix="$work/artifacts/" "$work/corpus" || status=$?
  if [ "$status" -ne 0 ] || [ -n "$(ls -A "$work/artifacts")" ]; then
    echo "run-fuzz.sh: the $name fuzzer failed (status $status); inputs:" >&2
    ls -l "$work/artifacts" >&2
    exit 1
  fi
}
fuzz decoder fuzz_proto_decoder "$root/tests/proto/corpus"
fuzz files fuzz_files_reader "$root/tests/files/corpus"
echo "run-fuzz.sh: ${seconds}s of fuzzing each of the decoder and the file readers, no failures"
