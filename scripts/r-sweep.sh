#!/bin/bash
# r-sweep.sh: how often the shortcrust mode's criteria give the right
# closed surface, by r, on closed inputs that the cocone mode
# reconstructs right (README, "Parameters").
#
#   scripts/r-sweep.sh [BUILD_DIR [DATA_DIR]]
#
# BUILD_DIR defaults to build, DATA_DIR to ../shared/data (its files are
# left out, with a note, when it is absent). The inputs: the analytic
# test surfaces (sphere, ellipsoid, torus, genus 2) in three densities at
# 2 000 and 20 000 points and well spaced at 50 000; sparse torus and
# genus-2 samples of 1 000 to 5 000 points on four seeds; and the closed
# scans and models of DATA_DIR. An input counts where the cocone mode
# gives it closed, of its true genus, in one piece per part. For each r
# in R_VALUES (default 0.12 to 0.18), the shortcrust mode with
# --unchecked is right when it gives that surface; at each r in
# CHECKED_R (default 0.14 and 0.18) the mode as it runs by default (with
# its check) is right, in doubt (says so), or wrong.
#
# Copyright (C) 2026 the shortcrust authors.
# SPDX-License-Identifier: GPL-3.0-or-later
set -euo pipefail

build=${1:-build}
data=${2:-../shared/data}
r_values=${R_VALUES:-0.12 0.13 0.14 0.15 0.16 0.17 0.18}
checked_r=${CHECKED_R:-0.14 0.18}
sc="$build/bin/shortcrust"
gen="$build/bin/synthgen"
for b in "$sc" "$gen"; do
  [ -x "$b" ] || { echo "r-sweep: $b not built (make -C $build)" >&2; exit 1; }
done
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# name file components genus
inputs=()
add_synth() { # surface n density seed
  local genus components=1
  case $1 in
    sphere | ellipsoid) genus=0 ;;
    torus) genus=1 ;;
    genus2) genus=2 ;;
  esac
  local f="$work/$1-$2-$3-$4.xyz"
  "$gen" "$1" "$2" 0 "$4" "$f" "$3"
  inputs+=("$1-$2-$3-s$4 $f $components $genus")
}
for s in sphere ellipsoid torus genus2; do
  for d in uniform-random uniform adaptive; do
    for n in 2000 20000; do add_synth $s $n $d 1; done
  done
  add_synth $s 50000 uniform 1
done
for s in torus genus2; do
  for n in 1000 2000 3000 5000; do
    for seed in 2 3 4 5; do add_synth $s $n uniform $seed; done
  done
done
if [ -d "$data" ]; then
  for e in kitten_points:1 knot1_points:1 eight_points:2 eight_sampled20k:2 \
    cgal_kitten_normals:1 cgal_half:0 cgal_meshes/bear_points:0 \
    cgal_meshes/blobby_points:0 cgal_meshes/ellipe0_003_points:0 \
    cgal_meshes/knot_points:1; do
    f="$data/${e%%:*}.ply"
    [ -f "$f" ] && inputs+=("$(basename "${e%%:*}") $f 1 ${e##*:}")
  done
else
  echo "r-sweep: $data absent: the analytic surfaces alone" >&2
fi

# field NAME FILE: a number or true/false from a report.
field() { sed -n "s/^  \"$1\": \([^,]*\),\$/\1/p" "$2"; }
# run FILE REPORT ARGS...: reconstructs, and prints right, doubt or wrong
# against the components and genus in $want_c $want_g.
run() {
  local f=$1 rep=$2
  shift 2
  "$sc" reconstruct "$f" -o "$work/out.ply" --report "$rep" -q "$@" ||
    { echo failed; return; }
  local closed comps genus doubt
  closed=$(field closed "$rep")
  comps=$(field components "$rep")
  genus=$(field genus "$rep")
  doubt=$(field topology_doubt "$rep")
  if [ "$closed" = true ] && [ "$comps" = "$want_c" ] &&
    [ "$genus" = "$want_g" ]; then
    echo right
  elif [ "$doubt" = true ]; then
    echo doubt
  else
    echo wrong
  fi
}

declare -A right doubt
counted=0
misses=""
for entry in "${inputs[@]}"; do
  read -r name f want_c want_g <<<"$entry"
  if [ "$(run "$f" "$work/c.json" --mode cocone)" != right ]; then
    echo "r-sweep: $name: the cocone mode gets it wrong; left out" >&2
    continue
  fi
  counted=$((counted + 1))
  for r in $r_values; do
    res=$(run "$f" "$work/s.json" --mode shortcrust --r "$r" --unchecked)
    [ "$res" = right ] && right[$r]=$((${right[$r]:-0} + 1)) ||
      misses+=" $name@$r"
  done
  for r in $checked_r; do
    res=$(run "$f" "$work/s.json" --mode shortcrust --r "$r")
    case $res in
      right) right[c$r]=$((${right[c$r]:-0} + 1)) ;;
      doubt) doubt[c$r]=$((${doubt[c$r]:-0} + 1)) ;;
      *) misses+=" $name@checked$r" ;;
    esac
  done
  printf '.' >&2
done
echo >&2

echo "Closed inputs that the cocone mode gets right: $counted"
echo
echo "| r | right (--unchecked) | right (checked) | in doubt (checked) | wrong, unsaid (checked) |"
echo "| --- | ---: | ---: | ---: | ---: |"
for r in $r_values; do
  if [[ " $checked_r " == *" $r "* ]]; then
    c=${right[c$r]:-0} d=${doubt[c$r]:-0}
    echo "| $r | ${right[$r]:-0} | $c | $d | $((counted - c - d)) |"
  else
    echo "| $r | ${right[$r]:-0} | | | |"
  fi
done
echo
echo "Missed:${misses:- none}"
