#!/usr/bin/env bash
# The main job on a bundled sample scan: reconstruct the kitten and write
# the mesh to BUILD/demo/kitten.ply.
#   scripts/demo.sh [BUILD]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
bin=$build/bin
out=$build/demo
mkdir -p "$out"

in=tests/data/kitten_points.ply
echo "demo: reconstructing $in" >&2
"$bin/shortcrust" reconstruct "$in" -o "$out/kitten.ply" --report "$out/kitten.json"
echo "demo: mesh in $out/kitten.ply, diagnostics in $out/kitten.json" >&2
