#!/bin/bash
# resample-sweep.sh: how often each mode gives the right closed surface on
# other samplings of the closed models than their vertex sets: points
# spread uniformly at random over each ground-truth mesh, as many as it has
# vertices and three times as many, on several seeds (README, "Closed
# models").
#
#   scripts/resample-sweep.sh [BUILD_DIR [DATA_DIR]]
#
# BUILD_DIR defaults to build, DATA_DIR to ../shared/data; every
# NAME_gt_mesh.ply of DATA_DIR/cgal_meshes and DATA_DIR (closed meshes
# only) is sampled with `synthgen MESH N 0 SEED` (scs_sample_mesh()).
# MODES (default "watertight auto cocone"; MODE:OPTION adds --OPTION, as in
# watertight:patches), SEEDS (default "1 2") and SCALES (default "1 3")
# choose the runs. A run is right where the output
# is closed, of the mesh's components and genus, with at most one sample
# in a thousand unused. Prints one row per model and sampling, the totals
# per mode, and the runs that missed with what they gave.
#
# Copyright (C) 2026 the shortcrust authors.
# SPDX-License-Identifier: GPL-3.0-or-later
set -euo pipefail

build=${1:-build}
data=${2:-../shared/data}
modes=${MODES:-watertight auto cocone}
seeds=${SEEDS:-1 2}
scales=${SCALES:-1 3}
sc="$build/bin/shortcrust"
gen="$build/bin/synthgen"
info="$build/bin/meshinfo"
for b in "$sc" "$gen" "$info"; do
  [ -x "$b" ] || { echo "resample-sweep: $b not built (make -C $build)" >&2; exit 1; }
done
if [ ! -d "$data" ]; then
  echo "resample-sweep: $data absent: nothing to sample" >&2
  exit 0
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# field NAME FILE: a number or true/false from a report.
field() { sed -n "s/^  \"$1\": \([^,]*\),\$/\1/p" "$2"; }
# meshfield NAME LINE: a number from meshinfo's line.
meshfield() { sed -n "s/.* $1=\([0-9]*\).*/\1/p" <<<" $2"; }

declare -A right
total=0
misses=""
printf '| model | points | %s |\n' "$(sed 's/ / | /g' <<<"$modes")"
printf '| --- | ---: |%s\n' "$(for m in $modes; do printf ' --- |'; done)"
for mesh in "$data"/cgal_meshes/*_gt_mesh.ply "$data"/*_gt_mesh.ply; do
  [ -f "$mesh" ] || continue
  line=$("$info" "$mesh")
  [ "$(meshfield closed "$line")" = 1 ] || continue
  name=$(basename "$mesh" _gt_mesh.ply)
  nv=$(meshfield points "$line")
  want_c=$(meshfield components "$line")
  want_g=$(meshfield genus "$line")
  for scale in $scales; do
    n=$((nv * scale))
    for seed in $seeds; do
      "$gen" "$mesh" "$n" 0 "$seed" "$work/p.xyz"
      total=$((total + 1))
      row="| $name, seed $seed | $n |"
      for mode in $modes; do
        rep="$work/r.json"
        args=(--mode "${mode%%:*}")
        [[ $mode == *:* ]] && args+=("--${mode#*:}")
        if ! "$sc" reconstruct "$work/p.xyz" -o "$work/o.ply" "${args[@]}" \
          --report "$rep" -q 2>/dev/null; then
          row+=" failed |"
          misses+=" $name-$n-s$seed@$mode(failed)"
          continue
        fi
        closed=$(field closed "$rep")
        comps=$(field components "$rep")
        genus=$(field genus "$rep")
        unused=$(field samples_unused "$rep")
        if [ "$closed" = true ] && [ "$comps" = "$want_c" ] &&
          [ "$genus" = "$want_g" ] && [ $((unused * 1000)) -le "$n" ]; then
          right[$mode]=$((${right[$mode]:-0} + 1))
          row+=" right |"
        else
          got="closed $closed, $comps pieces, genus $genus, $unused unused"
          row+=" $got |"
          misses+=" $name-$n-s$seed@$mode($got)"
        fi
      done
      echo "$row"
    done
  done
done
echo
for mode in $modes; do
  echo "$mode: ${right[$mode]:-0} of $total right"
done
echo
echo "Missed:${misses:- none}" | sed 's/) /)\n  /g'
