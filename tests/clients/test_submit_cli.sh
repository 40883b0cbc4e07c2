#!/bin/sh
# `shortcrust submit`, `stats` and `ping` end to end, against the daemon on
# a private socket: submit writes the same mesh as reconstruct, in every
# format, with the same summary and report; errors give the right status
# and say why.
#   test_submit_cli.sh SHORTCRUST SHORTCRUSTD MESHCMP DATADIR SYNTHGEN
# SPDX-License-Identifier: GPL-3.0-or-later
set -u
sc=$1 scd=$2 meshcmp=$3 data=$4 synthgen=$5
. "$(dirname "$0")/daemon.sh"
data_noisy=$tmp/noisy.xyz
. "$(dirname "$0")/../support/expect.sh"

# Before any daemon: a clear message and status 1.
expect 1 "daemon is not running" "$sc" ping --socket "$sock"
expect 1 "daemon is not running" "$sc" stats --socket "$sock"
expect 1 "daemon is not running" "$sc" submit "$data/knot1_points.ply" -o "$tmp/x.ply" --socket "$sock"
[ -e "$tmp/x.ply" ] && fail "a failed submit wrote its output"

start_daemon "$scd" "$sc" --workers 2

expect 0 "usage: shortcrust submit" "$sc" submit --help
for opt in --output --mode --r --theta --max-hole --paper-pruning --labels --rho --alpha \
           --denoise --denoise-scale --smoothed-vertices --tiles --connections \
           --socket --report --ascii --no-normals --quiet .las .laz; do
  grep -q -- "$opt" "$tmp/out" || fail "submit --help does not mention $opt"
done
expect 0 "submit" "$sc" --help
grep -q "stats" "$tmp/out" && grep -q "ping" "$tmp/out" || fail "--help lacks stats or ping"
expect 0 "daemon alive, protocol 1 with job options" "$sc" ping --socket "$sock"

# The same mesh as the local command: the same vertices and the same
# triangles, and the same summary but for the times.
mkdir "$tmp/a" "$tmp/b"
# A noisy torus (half a spacing): the daemon smooths it as the local
# command does, with --denoise and in auto mode.
"$synthgen" torus 6000 0.5 5 "$data_noisy" || fail "synthgen failed"
for in in knot1_points kitten_points noisy; do
  # The last two send job options; the daemon must apply them as the
  # local command does (without them the meshes differ: knot1 in boundary
  # mode has 37 small holes that --max-hole 0 leaves open).
  file=$data/$in.ply
  modes="--mode_cocone --mode_shortcrust_--r_0.14 --mode_auto --mode_watertight
         --mode_boundary_--max-hole_0_--rho_1.2_--alpha_25
         --mode_watertight_--labels_--paper-pruning --mode_watertight_--patches
         --mode_cocone_--denoise"
  if [ "$in" = noisy ]; then
    file=$data_noisy
    # --smoothed-vertices: the daemon sends the positions it smoothed, and
    # none where it did not smooth (no --denoise).
    modes="--mode_watertight_--denoise --mode_auto --mode_cocone_--denoise_--denoise-scale_0.04
           --mode_watertight_--denoise_--smoothed-vertices --mode_cocone_--smoothed-vertices"
  fi
  for mode in $modes; do
    mode=$(echo "$mode" | tr _ ' ')
    expect 0 "" "$sc" submit "$file" -o "$tmp/a/m.ply" --socket "$sock" $mode --report "$tmp/a/r.json"
    head -n 4 "$tmp/out" | sed "s|$tmp/a/||" > "$tmp/a/sum"
    expect 0 "" "$sc" reconstruct "$file" -o "$tmp/b/m.ply" $mode --report "$tmp/b/r.json"
    head -n 4 "$tmp/out" | sed "s|$tmp/b/||" > "$tmp/b/sum"
    "$meshcmp" "$tmp/a/m.ply" "$tmp/b/m.ply" > "$tmp/cmp" || fail "$in $mode: $(cat "$tmp/cmp")"
    # The core lists triangles in a canonical order, so the files are
    # identical byte for byte.
    cmp -s "$tmp/a/m.ply" "$tmp/b/m.ply" || fail "$in $mode: the mesh files differ"
    cmp -s "$tmp/a/sum" "$tmp/b/sum" || fail "$in $mode: summaries differ: $(cat "$tmp/a/sum" "$tmp/b/sum")"
    # The reports agree on the parameters, the genera and every diagnostic
    # the protocol carries (PROTOCOL.md 6.12).
    keys='"(input|params|points_in|duplicates_merged|spacing|noise|curvature|denoised|denoise_scale|denoise_shift|delaunay_[a-z]*|hull_vertices|degenerate_cells|candidates|pruned|triangles|walk_rejected|holes_filled|hole_triangles|samples_unused|boundary_edges|boundary_loops|nonmanifold_[a-z]*|components|closed_components|boundary_samples|longest_loop|cells_relabelled|path|loops_by_length|closed|euler|genus|component_genus)":'
    grep -E "^  $keys" "$tmp/a/r.json" > "$tmp/a/diag"
    grep -E "^  $keys" "$tmp/b/r.json" > "$tmp/b/diag"
    [ "$(wc -l < "$tmp/a/diag")" -ge 30 ] || fail "report has too few diagnostics: $(cat "$tmp/a/r.json")"
    cmp -s "$tmp/a/diag" "$tmp/b/diag" || fail "$in $mode: reports differ: $(diff "$tmp/a/diag" "$tmp/b/diag")"
    grep -q '"command": "submit"' "$tmp/a/r.json" || fail "report lacks the command"
    grep -q '"transfer": ' "$tmp/a/r.json" || fail "report lacks the transfer time"
  done
done

# Through the daemon too, four points give their hull, and an empty mesh
# comes with a warning line and status 0 (PROTOCOL.md 6.9).
printf '0 0 0\n1 0 0\n0 1 0\n0 0 1\n' > "$tmp/tet.xyz"
expect 0 "4 triangles" "$sc" submit "$tmp/tet.xyz" -o "$tmp/tet.off" --socket "$sock"
[ -s "$tmp/err" ] && fail "submit of a tetrahedron: $(cat "$tmp/err")"
printf '0 0 0\n1 0 0\n0 1 0\n0 0 1\n0.3 0.3 0.3\n' > "$tmp/five.xyz"
expect 0 "" "$sc" submit "$tmp/five.xyz" -o "$tmp/five.off" --socket "$sock" --quiet
grep -q "^shortcrust: warning: .*the mesh is empty" "$tmp/err" || fail "submit of an empty mesh without a warning: $(cat "$tmp/err")"

# The smoothed positions are written, not the points of the file: the
# first vertex differs from the one written without --smoothed-vertices,
# while the triangles and the local command's file are the same.
expect 0 "" "$sc" submit "$data_noisy" -o "$tmp/s1.ply" --socket "$sock" --denoise --ascii
expect 0 "" "$sc" submit "$data_noisy" -o "$tmp/s2.ply" --socket "$sock" --denoise --ascii \
  --smoothed-vertices
expect 0 "" "$sc" reconstruct "$data_noisy" -o "$tmp/s3.ply" --denoise --ascii --smoothed-vertices
cmp -s "$tmp/s2.ply" "$tmp/s3.ply" || fail "submit --smoothed-vertices differs from reconstruct's"
sed -n '/end_header/,$p' "$tmp/s1.ply" | sed -n 2p > "$tmp/v1"
sed -n '/end_header/,$p' "$tmp/s2.ply" | sed -n 2p > "$tmp/v2"
[ -s "$tmp/v1" ] || fail "no vertex in $tmp/s1.ply"
cmp -s "$tmp/v1" "$tmp/v2" && fail "submit --smoothed-vertices wrote the original positions"
tail -n 100 "$tmp/s1.ply" > "$tmp/f1"; tail -n 100 "$tmp/s2.ply" > "$tmp/f2"
cmp -s "$tmp/f1" "$tmp/f2" || fail "submit --smoothed-vertices changed the triangles"

# Every output format, and the closed genus-1 knot in each.
for out in k.obj k.off k.stl; do
  expect 0 "Closed 2-manifold, 1 component, genus 1" \
    "$sc" submit "$data/knot1_points.ply" -o "$tmp/$out" --socket "$sock"
done
expect 0 "" "$sc" submit "$data/knot1_points.ply" -o "$tmp/k.ply" --socket "$sock" --ascii --no-normals
head -c 20 "$tmp/k.ply" | grep -q "format ascii" || head -n 2 "$tmp/k.ply" | grep -q "format ascii" || fail "--ascii did not write ascii PLY"
grep -q "property float nx" "$tmp/k.ply" && fail "--no-normals wrote normals"
expect 0 "" "$sc" submit "$data/knot1_points.ply" -o "$tmp/q.ply" --socket "$sock" --quiet
[ -s "$tmp/out" ] && fail "--quiet printed: $(cat "$tmp/out")"

# One job split into tile jobs (--tiles), merged here: the same file, byte
# for byte, as the local command's, normals included; too few points to
# split run as one triangulation, and say so.
for case in kitten_points:3:cocone bunny_points:4:shortcrust; do
  in=${case%%:*} rest=${case#*:}
  n=${rest%%:*} mode=${rest#*:}
  expect 0 "Tiles: $n; .* each a job of the daemons, merged here" \
    "$sc" submit "$data/$in.ply" -o "$tmp/t1.ply" --socket "$sock" --mode "$mode" \
    --tiles "$n" --connections 2
  "$sc" reconstruct "$data/$in.ply" -o "$tmp/t2.ply" --mode "$mode" -q ||
    fail "reconstruct $in"
  cmp -s "$tmp/t1.ply" "$tmp/t2.ply" || fail "$in in $n tile jobs differs from reconstruct"
done
# Shortcrust mode where r's topology is not the cocone test's: the tile
# jobs send the check's runs, and the merge takes the same nearby r.
expect 0 "mode shortcrust (r = 0.17: at 0.18 the topology" \
  "$sc" submit "$data/kitten_points.ply" -o "$tmp/t1.ply" --socket "$sock" \
  --mode shortcrust --r 0.18 --tiles 3
"$sc" reconstruct "$data/kitten_points.ply" -o "$tmp/t2.ply" --mode shortcrust \
  --r 0.18 -q || fail "reconstruct kitten --r 0.18"
cmp -s "$tmp/t1.ply" "$tmp/t2.ply" || fail "kitten at r 0.18 in 3 tile jobs differs"
# Denoised, the tile jobs and the merge smooth alike; the smoothed
# positions come from the merge.
for opt in "" --smoothed-vertices; do
  expect 0 "" "$sc" submit "$data_noisy" -o "$tmp/t1.ply" --socket "$sock" --tiles 2 \
    --denoise $opt -q
  "$sc" reconstruct "$data_noisy" -o "$tmp/t2.ply" --denoise $opt -q ||
    fail "reconstruct --denoise $opt"
  cmp -s "$tmp/t1.ply" "$tmp/t2.ply" || fail "noisy torus in 2 tile jobs ($opt) differs"
done
expect 0 "Tiles: none, one triangulation: too few points to split" \
  "$sc" submit "$tmp/tet.xyz" -o "$tmp/t1.off" --socket "$sock" --tiles 4
grep -q "4 triangles" "$tmp/out" || fail "a tetrahedron in tiles: $(cat "$tmp/out")"

# Bad command lines: status 2, before the daemon is asked anything.
expect 2 "--tiles" "$sc" submit "$data/knot1_points.ply" -o "$tmp/x.ply" --tiles 0 --socket "$sock"
expect 2 "--tiles" "$sc" submit "$data/knot1_points.ply" -o "$tmp/x.ply" --tiles 4097 --socket "$sock"
expect 2 "--connections goes with --tiles" "$sc" submit "$data/knot1_points.ply" -o "$tmp/x.ply" \
  --connections 2 --socket "$sock"
expect 2 "--tiles works in the cocone and shortcrust modes only" "$sc" submit \
  "$data/knot1_points.ply" -o "$tmp/x.ply" --tiles 2 --mode boundary --socket "$sock"
expect 2 "no input file" "$sc" submit -o "$tmp/x.ply" --socket "$sock"
expect 2 "no output file" "$sc" submit "$data/knot1_points.ply" --socket "$sock"
expect 2 "r must be in (0, 0.5)" "$sc" submit "$data/knot1_points.ply" -o "$tmp/x.ply" --r 0.7 --socket "$sock"
expect 2 "unknown mode 'foo'" "$sc" submit "$data/knot1_points.ply" -o "$tmp/x.ply" --mode foo
expect 2 "unknown option '--threads'" "$sc" submit "$data/knot1_points.ply" -o "$tmp/x.ply" --threads 2
expect 2 "--max-hole" "$sc" submit "$data/knot1_points.ply" -o "$tmp/x.ply" --max-hole 100001 --socket "$sock"
expect 2 "boundary_rho must be in (0, 10]" "$sc" submit "$data/knot1_points.ply" -o "$tmp/x.ply" --rho 11 --socket "$sock"
expect 2 "boundary_alpha must be in (0, pi/2]" "$sc" submit "$data/knot1_points.ply" -o "$tmp/x.ply" --alpha 120 --socket "$sock"
expect 2 "unknown extension '.xyz'" "$sc" submit "$data/knot1_points.ply" -o "$tmp/x.xyz"
expect 2 "unknown option '--bogus'" "$sc" stats --bogus
expect 2 "unknown option '--json'" "$sc" ping --json

# Bad input: status 1 and why, from the file module or the daemon.
expect 1 "missing.ply" "$sc" submit "$tmp/missing.ply" -o "$tmp/x.ply" --socket "$sock"
printf '0 0 0\n1 0 0\n0 nan 1\n0 0 1\n1 1 1\n' > "$tmp/nan.xyz"
expect 1 "NONFINITE" "$sc" submit "$tmp/nan.xyz" -o "$tmp/x.ply" --socket "$sock"
printf '0 0 0\n1 0 0\n2 0 0\n3 0 0\n' > "$tmp/line.xyz"
expect 1 "collinear" "$sc" submit "$tmp/line.xyz" -o "$tmp/x.ply" --socket "$sock"
[ -e "$tmp/x.ply" ] && fail "a failed submit wrote its output"

# The daemon's counters, as a table and as JSON.
expect 0 "jobs_done_total" "$sc" stats --socket "$sock"
grep -q "protocol 1" "$tmp/out" || fail "stats: no header line"
expect 0 '"jobs_done_total": ' "$sc" stats --socket "$sock" --json
[ "$(wc -l < "$tmp/out")" -eq 1 ] || fail "stats --json is not one line"
grep -q '^{"socket": ".*"connections": [0-9]*.*}$' "$tmp/out" || fail "stats --json: $(cat "$tmp/out")"
grep -q '"jobs_failed_total": 2[,}]' "$tmp/out" || fail "stats --json: two jobs failed: $(cat "$tmp/out")"

# Points that are floats travel as floats (12 bytes a point), others as
# doubles (24): the daemon's byte count says which went.
bytes_in() {
  "$sc" stats --socket "$sock" --json | sed -n 's/.*"bytes_in_total": \([0-9]*\).*/\1/p'
}
for case in "$data/kitten_points.ply:14472:12" "$data_noisy:6000:24"; do
  file=${case%%:*} rest=${case#*:}
  n=${rest%%:*} size=${rest#*:}
  before=$(bytes_in)
  "$sc" submit "$file" -o "$tmp/x.ply" --socket "$sock" -q || fail "submit $file"
  sent=$(($(bytes_in) - before))
  [ "$sent" -ge $((size * n)) ] && [ "$sent" -lt $(((size + 4) * n)) ] ||
    fail "$file: $sent bytes for $n points, want about $size a point"
done
rm -f "$tmp/x.ply"

# Standard input and output, as for reconstruct: the same bytes as a file.
"$sc" reconstruct "$data/knot1_points.ply" -o "$tmp/file.ply" -q || fail "reconstruct to a file"
"$sc" submit - -o - --socket "$sock" < "$data/knot1_points.ply" > "$tmp/piped.ply" 2> "$tmp/err" ||
  fail "submit - -o -: $(cat "$tmp/err")"
cmp -s "$tmp/piped.ply" "$tmp/file.ply" || fail "submit through a pipe differs"
grep -q "standard input: 3200 points" "$tmp/err" || fail "submit summary on stderr: $(cat "$tmp/err")"

# The input's properties (here its normals and added colours) come out on
# the same vertices, as reconstruct writes them; nothing new travels.
"$sc" reconstruct "$data/knot1_points.ply" -o "$tmp/attr1.ply" --ascii -q || fail "ascii PLY"
awk '/^property float nz$/ { print; print "property uchar red"; next }
     /^end_header$/ { print; body = 1; next }
     body && NF == 6 { n++; print $0, n % 256; next }
     { print }' "$tmp/attr1.ply" > "$tmp/attr2.ply"
"$sc" submit "$tmp/attr2.ply" -o "$tmp/attr3.ply" --ascii -q --socket "$sock" ||
  fail "submit of a coloured PLY"
cmp -s "$tmp/attr2.ply" "$tmp/attr3.ply" || fail "submit did not carry the properties"

stop_daemon
[ "$fails" -eq 0 ] || { echo "$fails check(s) failed" >&2; cat "$tmp/daemon.log" >&2; exit 1; }
echo "all submit, stats and ping checks passed"
