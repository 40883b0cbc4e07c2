#!/usr/bin/env bash
# Shows that two builds of `shortcrust` write the same meshes, reports and
# summaries: every mode and the options that change a path, every output
# format, on the bundled scans and, when present, on ../shared/data.
#
#   scripts/same-output.sh OLD/bin/shortcrust NEW/bin/shortcrust [DIR...]
#
# DIR adds folders of inputs (*.ply, *.xyz; ground-truth meshes *_gt_mesh.ply
# are skipped). Meshes are compared byte for byte; reports and summaries
# with their timings left out. Prints one line per difference and a count;
# exits 1 when anything differs.
set -euo pipefail

if [ $# -lt 2 ]; then
  sed -n '2,12p' "$0" | sed 's/^# \{0,1\}//'
  exit 2
fi
old=$1
new=$2
shift 2
root=$(cd "$(dirname "$0")/.." && pwd)
dirs=("$root/tests/data")
if [ $# -gt 0 ]; then
  dirs+=("$@")
elif [ -d "$root/../shared/data" ]; then
  dirs+=("$root/../shared/data" "$root/../shared/data/cgal_meshes")
else
  echo "same-output: ../shared/data is absent; the bundled scans only" >&2
fi

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# A text copy of the kitten, so that the text reader is in the comparison.
"$old" reconstruct "$root/tests/data/kitten_points.ply" -o "$tmp/k.ply" \
  --ascii --quiet
awk 'body && n-- > 0 {print $1, $2, $3} /^element vertex/ {n = $3}
     /^end_header/ {body = 1}' "$tmp/k.ply" > "$tmp/kitten_text.xyz"

inputs=("$tmp/kitten_text.xyz")
for d in "${dirs[@]}"; do
  for f in "$d"/*.ply "$d"/*.xyz; do
    [ -e "$f" ] || continue
    case $f in *_gt_mesh.ply) continue ;; esac
    inputs+=("$f")
  done
done

variants=(
  "--mode cocone"
  "--mode shortcrust"
  "--mode shortcrust --r 0.14"
  "--mode boundary"
  "--mode watertight"
  "--mode watertight --labels"
  "--mode auto"
  "--mode cocone --paper-pruning --max-hole 0"
  "--mode boundary --rho 2 --alpha 30"
)

# Drops the timings: the report's "seconds" line and the summary's "Time:".
untimed() { grep -v -e '"seconds": ' -e '^Time: ' "$1" || true; }

runs=0
diffs=0
one() { # name, then the arguments after reconstruct IN
  local name=$1
  shift
  for side in old new; do
    local bin=$old
    [ $side = new ] && bin=$new
    local rc=0
    "$bin" reconstruct "$@" -o "$tmp/$side.$ext" --report "$tmp/$side.json" \
      > "$tmp/$side.out" 2> "$tmp/$side.err" || rc=$?
    echo "$rc" > "$tmp/$side.rc"
  done
  runs=$((runs + 1))
  local why=()
  cmp -s "$tmp/old.rc" "$tmp/new.rc" || why+=("exit status")
  cmp -s "$tmp/old.err" "$tmp/new.err" || why+=("stderr")
  if [ -e "$tmp/old.$ext" ] || [ -e "$tmp/new.$ext" ]; then
    cmp -s "$tmp/old.$ext" "$tmp/new.$ext" || why+=("mesh")
  fi
  if [ -e "$tmp/old.json" ] || [ -e "$tmp/new.json" ]; then
    cmp -s <(untimed "$tmp/old.json" | sed 's#/old\.#/OUT.#') \
      <(untimed "$tmp/new.json" | sed 's#/new\.#/OUT.#') || why+=("report")
  fi
  cmp -s <(untimed "$tmp/old.out" | sed 's#/old\.#/OUT.#') \
    <(untimed "$tmp/new.out" | sed 's#/new\.#/OUT.#') || why+=("summary")
  if [ ${#why[@]} -gt 0 ]; then
    diffs=$((diffs + 1))
    echo "DIFFERS ($(IFS=,; echo "${why[*]}")): $name"
  fi
  rm -f "$tmp"/old.* "$tmp"/new.*
}

for f in "${inputs[@]}"; do
  for v in "${variants[@]}"; do
    ext=ply
    # shellcheck disable=SC2086
    one "$(basename "$f") $v" "$f" $v
  done
done
# Every writer, on one input; and the README's three examples.
k=$root/tests/data/kitten_points.ply
for ext in ply off obj stl; do
  one "kitten -> .$ext" "$k"
  one "kitten -> .$ext --ascii --no-normals" "$k" --ascii --no-normals
done
ext=obj
one "README: xyz -> obj" "$tmp/kitten_text.xyz"
ext=stl
one "README: stl, shortcrust r 0.14" "$k" --mode shortcrust --r 0.14

echo "same-output: $runs runs, $diffs differ"
[ "$diffs" -eq 0 ]
