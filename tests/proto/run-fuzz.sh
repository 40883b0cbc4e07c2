#!/usr/bin/env bash
# Builds the protocol decoder's libFuzzer target with clang, ASan and UBSan,
# then fuzzes it for a fixed time over a copy of the seed corpus. Fails if
# the build fails or the fuzzer finds a crash, a sanitizer report, a leak or
# a timeout; the input that did it is left in <build-dir>/fuzz-run/artifacts.
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
CC=clang cmake -S . -B "$build" -DSC_MODULES="proto;tests" \
  -DSC_SANITIZE=address -DSC_FUZZ=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo
cmake --build "$build" --target fuzz_proto_decoder -j "$(nproc 2>/dev/null || echo 2)"

# The fuzzer adds the inputs it finds to its corpus directory; it works on a
# copy so the committed seeds stay as make_corpus wrote them.
work=$build/fuzz-run
rm -rf "$work"
mkdir -p "$work/corpus" "$work/artifacts"
cp "$root"/tests/proto/corpus/* "$work/corpus/"

export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1}
status=0
"$build/bin/fuzz_proto_decoder" -max_total_time="$seconds" -timeout=10 \
  -rss_limit_mb=2048 -print_final_stats=1 \
  -artifact_prefix="$work/artifacts/" "$work/corpus" || status=$?

if [ "$status" -ne 0 ] || [ -n "$(ls -A "$work/artifacts")" ]; then
  echo "run-fuzz.sh: the decoder fuzzer failed (status $status); inputs:" >&2
  ls -l "$work/artifacts" >&2
  exit 1
fi
echo "run-fuzz.sh: ${seconds}s of fuzzing, no failures"
