#!/bin/sh
# The local command end to end: formats, report, exit codes and messages.
#   test_reconstruct.sh SHORTCRUST MESHINFO DATADIR SYNTHGEN
# SPDX-License-Identifier: GPL-3.0-or-later
set -u
sc=$1 info=$2 data=$3 synthgen=$4
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
. "$(dirname "$0")/../support/expect.sh"

knot=$data/knot1_points.ply
expect 0 "usage: shortcrust reconstruct" "$sc" reconstruct --help
for opt in --output --mode --r --theta --max-hole --paper-pruning --unchecked --threads \
           --denoise --denoise-scale --smoothed-vertices --tiles --memory-limit \
           --report --ascii --no-normals --quiet .las .laz; do
  grep -q -- "$opt" "$tmp/out" || fail "--help does not mention $opt"
done
expect 0 "reconstruct" "$sc" --help
expect 0 "shortcrust [0-9]" "$sc" --version

# Every output format holds the same closed genus-1 surface.
for ext in ply off obj; do
  for ascii in "" --ascii; do
    out=$tmp/knot.$ext
    expect 0 "Closed 2-manifold, 1 component, genus 1" \
      "$sc" reconstruct "$knot" -o "$out" $ascii
    line=$("$info" "$out")
    case $line in
      *"manifold=1 closed=1 oriented=1 components=1 genus=1 unused=0 outward=1"*) ;;
      *) fail "$out: $line" ;;
    esac
  done
done
expect 0 "genus 1" "$sc" reconstruct "$knot" -o "$tmp/knot.stl"
tris=$("$info" "$tmp/knot.ply" | sed 's/.*triangles=\([0-9]*\).*/\1/')
"$info" "$tmp/knot.stl" | grep -q "triangles=$tris " || fail "STL triangle count"

# - is standard input and output: PLY or, failing its magic, the points of
# a text file in; PLY out, byte for byte what the file would hold, with the
# summary on stderr; errors name the stream and leave status 1.
"$sc" reconstruct "$knot" -o "$tmp/file.ply" -q || fail "reconstruct to a file"
"$sc" reconstruct "$knot" -o "$tmp/knot.obj" -q || fail "reconstruct to OBJ"
grep '^v ' "$tmp/knot.obj" | cut -c3- > "$tmp/knot.xyz"
"$sc" reconstruct - -o - < "$knot" > "$tmp/piped.ply" 2> "$tmp/err" ||
  fail "reconstruct - -o -: $(cat "$tmp/err")"
cmp -s "$tmp/piped.ply" "$tmp/file.ply" || fail "PLY through a pipe differs"
grep -q "standard input: 3200 points -> 6400 triangles in standard output" \
  "$tmp/err" || fail "summary on stderr: $(cat "$tmp/err")"
cat "$tmp/knot.xyz" | "$sc" reconstruct - -o - -q > "$tmp/piped2.ply" ||
  fail "text through a pipe"
cmp -s "$tmp/piped2.ply" "$tmp/file.ply" || fail "text through a pipe differs"
printf 'ply\nformat ascii 1.0\nelement vertex 1\n' > "$tmp/cut.ply"
expect 1 "standard input: line 3: file ends inside the header" \
  sh -c '"$1" reconstruct - -o "$2" < "$3"' sh "$sc" "$tmp/never.ply" "$tmp/cut.ply"
[ -e "$tmp/never.ply" ] && fail "a failed read wrote its output"
expect 1 "standard input: line 1: expected 3 numbers" \
  sh -c 'echo "1 2" | "$1" reconstruct - -o "$2"' sh "$sc" "$tmp/never.ply"
if [ -w /dev/full ]; then
  expect 1 "standard output: write failed" \
    sh -c '"$1" reconstruct "$2" -o - -q > /dev/full' sh "$sc" "$knot"
fi

# The input's per-point properties reach the mesh unchanged: a mesh read
# back as points keeps its normals (so a second run writes the same file),
# and colours added to it come out on the same vertices, in PLY and OBJ.
"$sc" reconstruct "$knot" -o "$tmp/attr1.ply" --ascii -q || fail "ascii PLY"
"$sc" reconstruct "$tmp/attr1.ply" -o "$tmp/attr2.ply" --ascii -q || fail "PLY with normals"
cmp -s "$tmp/attr1.ply" "$tmp/attr2.ply" || fail "the input's normals did not come through"
awk '/^property float nz$/ { print; print "property uchar red"; print "property uchar green"; print "property uchar blue"; next }
     /^end_header$/ { print; body = 1; next }
     body && NF == 6 { n++; print $0, n % 256, 7, 200; next }
     { print }' "$tmp/attr1.ply" > "$tmp/attr3.ply"
"$sc" reconstruct "$tmp/attr3.ply" -o "$tmp/attr4.ply" --ascii -q || fail "coloured PLY"
cmp -s "$tmp/attr3.ply" "$tmp/attr4.ply" || fail "colours were not carried unchanged"
"$sc" reconstruct "$tmp/attr3.ply" -o "$tmp/attr5.obj" -q || fail "coloured PLY to OBJ"
grep -q '^v .* 0.00392156863 0.0274509804 0.784313725$' "$tmp/attr5.obj" ||
  fail "OBJ lacks the colours: $(grep -m 1 '^v ' "$tmp/attr5.obj")"
"$sc" reconstruct "$tmp/attr3.ply" -o "$tmp/attr6.ply" --ascii -q --mesh-normals ||
  fail "--mesh-normals"
grep -q "property uchar red" "$tmp/attr6.ply" && [ "$(grep -c 'property float n' "$tmp/attr6.ply")" -eq 3 ] ||
  fail "--mesh-normals: $(grep property "$tmp/attr6.ply")"

# The report is JSON with the diagnostics; --quiet prints nothing.
expect 0 "" "$sc" reconstruct "$knot" -o "$tmp/q.ply" --quiet --report "$tmp/r.json"
[ -s "$tmp/out" ] && fail "--quiet printed: $(cat "$tmp/out")"
for field in '"points_in": 3200,' '"closed": true' '"genus": 1' '"component_genus": \[1\]' \
             '"triangles": '"$tris" '"mode": "cocone"' '"delaunay": '; do
  grep -q "$field" "$tmp/r.json" || fail "report lacks $field"
done
expect 0 "mode shortcrust (r = 0.14)" "$sc" reconstruct "$knot" -o "$tmp/s.ply" --mode shortcrust --r 0.14
expect 0 "" "$sc" reconstruct "$knot" -o "$tmp/t.ply" --threads 2 --quiet

# Noise: every summary gives the estimate; a clean sample is not smoothed
# even with --denoise, and says why.
expect 0 "Noise: 0.0[0-9] spacings" "$sc" reconstruct "$knot" -o "$tmp/d.ply"
expect 0 "below 0.08, not smoothed" "$sc" reconstruct "$knot" -o "$tmp/d.ply" --denoise
grep -q '"denoised": false' "$tmp/r.json" || fail "report lacks \"denoised\": false"
grep -q '"noise": ' "$tmp/r.json" || fail "report lacks the noise estimate"
# A torus with noise of half a spacing: broken without denoising, its
# genus with it, every sample used, and auto mode denoises by itself.
"$synthgen" torus 6000 0.5 3 "$tmp/noisy.xyz" || fail "synthgen failed"
expect 0 "Closed 2-manifold, 1 component, genus 1; 0 samples unused" \
  "$sc" reconstruct "$tmp/noisy.xyz" -o "$tmp/d.ply" --mode watertight --denoise \
  --report "$tmp/dn.json"
grep -q "; denoised at scale" "$tmp/out" || fail "--denoise did not say it smoothed: $(cat "$tmp/out")"
grep -q '"denoised": true' "$tmp/dn.json" || fail "report lacks \"denoised\": true"
line=$("$info" "$tmp/d.ply")
case $line in
  *"manifold=1 closed=1 oriented=1 components=1 genus=1 unused=0"*) ;;
  *) fail "noisy torus with --denoise: $line" ;;
esac
expect 0 "denoised by auto mode" "$sc" reconstruct "$tmp/noisy.xyz" -o "$tmp/d.ply" --mode auto
expect 0 "genus 1" "$sc" reconstruct "$tmp/noisy.xyz" -o "$tmp/d.ply" --mode auto
# The smoothed positions instead of the samples: the same triangles.
expect 0 "" "$sc" reconstruct "$tmp/noisy.xyz" -o "$tmp/d1.ply" --mode watertight --denoise --ascii
expect 0 "" "$sc" reconstruct "$tmp/noisy.xyz" -o "$tmp/d2.ply" --mode watertight --denoise --ascii \
  --smoothed-vertices
[ "$(grep -c . "$tmp/d1.ply")" = "$(grep -c . "$tmp/d2.ply")" ] || fail "--smoothed-vertices changed the mesh's size"
tail -n 100 "$tmp/d1.ply" > "$tmp/f1"; tail -n 100 "$tmp/d2.ply" > "$tmp/f2"
cmp -s "$tmp/f1" "$tmp/f2" || fail "--smoothed-vertices changed the triangles"
sed -n '/end_header/,$p' "$tmp/d1.ply" | sed -n 2p > "$tmp/v1"
sed -n '/end_header/,$p' "$tmp/d2.ply" | sed -n 2p > "$tmp/v2"
cmp -s "$tmp/v1" "$tmp/v2" && fail "--smoothed-vertices wrote the original positions"
# A scale given smooths even a clean sample.
expect 0 "denoised at scale 0.05" "$sc" reconstruct "$knot" -o "$tmp/d.ply" --denoise --denoise-scale 0.05

# Bad command lines: status 2, nothing written.
expect 2 "denoise-scale: must be positive, got -1" "$sc" reconstruct "$knot" -o "$tmp/x.ply" --denoise --denoise-scale -1
expect 2 "denoise-scale: 'abc' is not a finite number" "$sc" reconstruct "$knot" -o "$tmp/x.ply" --denoise-scale abc
expect 2 "denoise-scale: 'nan' is not a finite number" "$sc" reconstruct "$knot" -o "$tmp/x.ply" --denoise-scale nan

# --memory-limit: sizes with suffixes; the same mesh within the limit, or a
# clear refusal before the work starts.
"$sc" reconstruct "$data/bunny_points.ply" -o "$tmp/b0.ply" -q ||
  fail "bunny, no limit"
expect 0 "within the memory limit" "$sc" reconstruct "$data/bunny_points.ply" \
  -o "$tmp/b1.ply" --memory-limit 40M
cmp -s "$tmp/b0.ply" "$tmp/b1.ply" || fail "--memory-limit 40M: another mesh"
expect 0 "it fits the memory limit" "$sc" reconstruct "$knot" -o "$tmp/x.ply" --memory-limit 1GiB
rm -f "$tmp/x.ply"
expect 1 "need a memory limit of at least .* MB, got 1.0 MB" "$sc" reconstruct "$data/bunny_points.ply" -o "$tmp/x.ply" --memory-limit 1M
[ -e "$tmp/x.ply" ] && fail "a refused job wrote its output"
# The least limit a refusal names, given back as it is written, fits: the
# same mesh.
least=$("$sc" reconstruct "$data/bunny_points.ply" -o "$tmp/x.ply" \
  --memory-limit 1M 2>&1 | sed -n 's/.*at least \([0-9.]*\) MB.*/\1/p')
[ -n "$least" ] || fail "no least memory limit named"
expect 0 "within the memory limit" "$sc" reconstruct "$data/bunny_points.ply" \
  -o "$tmp/b1.ply" --memory-limit "${least}M"
cmp -s "$tmp/b0.ply" "$tmp/b1.ply" || fail "--memory-limit ${least}M: another mesh"
expect 0 "it fits the memory limit" "$sc" reconstruct "$knot" -o "$tmp/x.ply" --memory-limit 1.5GiB
for bad in abc 0 -5 12X 1MBs 99999999999999999999 1.5 .5M 1.M 0.0M; do
  expect 2 "memory-limit: expected a size in bytes" "$sc" reconstruct "$knot" -o "$tmp/x.ply" --memory-limit "$bad"
done
expect 2 "memory_limit works in the cocone and shortcrust modes only" "$sc" reconstruct "$knot" -o "$tmp/x.ply" --mode watertight --memory-limit 1G
rm -f "$tmp/b0.ply" "$tmp/b1.ply" "$tmp/x.ply"
expect 2 "no input file" "$sc" reconstruct -o "$tmp/x.ply"
expect 2 "no output file" "$sc" reconstruct "$knot"
expect 2 "unknown mode 'foo'" "$sc" reconstruct "$knot" -o "$tmp/x.ply" --mode foo
expect 2 "r must be in (0, 0.5)" "$sc" reconstruct "$knot" -o "$tmp/x.ply" --r 0.7
expect 2 "not a finite number" "$sc" reconstruct "$knot" -o "$tmp/x.ply" --r abc
expect 2 "out of range" "$sc" reconstruct "$knot" -o "$tmp/x.ply" --threads -3
expect 2 "unknown option '--bogus'" "$sc" reconstruct "$knot" -o "$tmp/x.ply" --bogus
expect 2 "unknown extension '.xyz'" "$sc" reconstruct "$knot" -o "$tmp/x.xyz"
expect 2 "unknown command 'frobnicate'" "$sc" frobnicate
[ -e "$tmp/x.ply" ] && fail "a failed command wrote its output"

# An open surface (the zippered bunny's small holes left open): the
# summary's genus is that of the whole surface, open components included,
# as the independent checker counts it.
expect 0 "Open 2-manifold" "$sc" reconstruct "$data/bunny_points.ply" \
  -o "$tmp/b.ply" --mode boundary --max-hole 0
said=$(sed -n 's/.*), genus \([0-9-]*\);.*/\1/p' "$tmp/out")
checked=$("$info" "$tmp/b.ply" | sed -n 's/.* genus_all=\([0-9-]*\).*/\1/p')
[ -n "$said" ] && [ "$said" = "$checked" ] ||
  fail "open bunny: summary says genus '$said', the checker '$checked'"

# Bad input: status 1, a message naming the file, an old output kept.
# Four points give the four faces of their hull; a mesh that is empty is
# written with status 0, but never silently (PROTOCOL.md 6.9).
printf '0 0 0\n1 0 0\n0 1 0\n0 0 1\n' > "$tmp/tet.xyz"
for mode in shortcrust cocone boundary watertight auto; do
  expect 0 "4 triangles" "$sc" reconstruct "$tmp/tet.xyz" -o "$tmp/tet.off" --mode $mode
  grep -q "Closed 2-manifold, 1 component, genus 0" "$tmp/out" || fail "tetrahedron, $mode: $(cat "$tmp/out")"
  [ -s "$tmp/err" ] && fail "tetrahedron, $mode: $(cat "$tmp/err")"
done
printf '0 0 0\n1 0 0\n0 1 0\n0 0 1\n0.3 0.3 0.3\n' > "$tmp/five.xyz"
expect 0 "" "$sc" reconstruct "$tmp/five.xyz" -o "$tmp/five.off" --quiet --report "$tmp/five.json"
grep -q "^shortcrust: warning: .*the mesh is empty" "$tmp/err" || fail "an empty mesh without a warning: $(cat "$tmp/err")"
grep -q '"mostly_unused": true' "$tmp/five.json" || fail "report lacks \"mostly_unused\": true"
rm -f "$tmp/tet.xyz" "$tmp/tet.off" "$tmp/five.xyz" "$tmp/five.off" "$tmp/five.json"

# Shortcrust mode checks its topology against the cocone test's surface
# (docs/algorithm.md section 6.5): at r = 0.24 the knot falls apart into 4
# open pieces, said on stderr even with --quiet, and in the report; at the
# default r it is right, and the check agrees.
expect 0 "Check: .*genus 1: the topology is in doubt" \
  "$sc" reconstruct "$knot" -o "$tmp/k18.off" --mode shortcrust --r 0.24
grep -q "^shortcrust: warning: .*the topology is in doubt: .*criteria with r = 0.24 give 4 components, [0-9]* closed where the cocone test, on the same triangulation, gives 1 closed component of genus 1" "$tmp/err" ||
  fail "a wrong topology without a warning: $(cat "$tmp/err")"
expect 0 "" "$sc" reconstruct "$knot" -o "$tmp/k18.off" --mode shortcrust --r 0.24 --quiet --report "$tmp/k18.json"
grep -q "topology is in doubt" "$tmp/err" || fail "--quiet hides the doubt"
grep -q '"topology_doubt": true' "$tmp/k18.json" || fail "report lacks \"topology_doubt\": true"
expect 0 "Check: .*genus 1, the same" \
  "$sc" reconstruct "$knot" -o "$tmp/k14.off" --mode shortcrust
[ -s "$tmp/err" ] && fail "a right topology with a warning: $(cat "$tmp/err")"
expect 0 "mode shortcrust (r = 0.24)" \
  "$sc" reconstruct "$knot" -o "$tmp/k18u.off" --mode shortcrust --r 0.24 --unchecked
grep -q "^Check:" "$tmp/out" && fail "--unchecked still checks: $(cat "$tmp/out")"
[ -s "$tmp/err" ] && fail "--unchecked still warns: $(cat "$tmp/err")"
cmp -s "$tmp/k18.off" "$tmp/k18u.off" || fail "--unchecked changed the mesh"
rm -f "$tmp/k18.off" "$tmp/k18u.off" "$tmp/k18.json" "$tmp/k14.off"

echo "keep" > "$tmp/old.ply"
expect 1 "missing.ply" "$sc" reconstruct "$tmp/missing.ply" -o "$tmp/old.ply"
expect 1 "scan.laz: LAZ (compressed LAS) is not supported: decompress it first" \
  "$sc" reconstruct "$tmp/scan.laz" -o "$tmp/old.ply"
printf '0 0 0\n1 0 0\n0 nan 1\n0 0 1\n1 1 1\n' > "$tmp/nan.xyz"
expect 1 "nan.xyz: point 2 has a non-finite y coordinate" \
  "$sc" reconstruct "$tmp/nan.xyz" -o "$tmp/old.ply"
printf '0 0 0\n1 0 0\n2 0 0\n3 0 0\n' > "$tmp/line.xyz"
expect 1 "collinear" "$sc" reconstruct "$tmp/line.xyz" -o "$tmp/old.ply"
printf 'ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 0\n' > "$tmp/trunc.ply"
expect 1 "trunc.ply" "$sc" reconstruct "$tmp/trunc.ply" -o "$tmp/old.ply"
[ "$(cat "$tmp/old.ply")" = keep ] || fail "a failed run replaced the old output"
ls "$tmp" | grep -q -v -E '^(old.ply|out|err|nan.xyz|line.xyz|trunc.ply|knot\..*|q.ply|r.json|s.ply|t.ply|b.ply|d.ply|d1.ply|d2.ply|dn.json|noisy.xyz|f1|f2|v1|v2|file.ply|piped.ply|piped2.ply|cut.ply|attr[1-6].(ply|obj))$' &&
  fail "temporary files left: $(ls "$tmp")"

[ "$fails" -eq 0 ] && echo "all passed"
exit $((fails != 0))
