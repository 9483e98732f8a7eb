#!/bin/sh
# bench/accuracy_scan.sh BIN - `stratum analyze` and `stratum compare` on
# CGAL's data meshes (Debian's libcgal-demo), the figures and pictures of
# docs/accuracy.md:
# - bunny00.off, the Stanford bunny scan (75,408 triangles) scaled to 100 mm
#   (build/bench/gen_mesh convert): its cusp height in 0.2 mm layers, and
#   its distance to what `stratum repair` makes of it;
# - elephant.off (5,558 triangles) against refined_elephant.off (88,928, a
#   smoothed refinement of it), both scaled by the same factor 100 so they
#   still fit each other: the surface distance and the coarse facets'
#   chordal error, the facets over 0.3 mm isolated.
# - fandisk.off (12,946 triangles, a CAD part) scaled to 100 mm: what
#   `stratum repair --simplify-planar` moves, by `stratum compare`;
# - `stratum refine`: the cylinder, the elephants, a torus and the bunny
#   decimated, below.
# Works in bench/out/accuracy, writes its *.png there and prints each command's report with its
# wall time, CPU time and peak RSS from GNU time.
set -eu
bin=$(realpath "${1:-build/stratum}")
gen=$(realpath "${GEN_MESH:-build/bench/gen_mesh}")
out=bench/out/accuracy
tarball=/usr/share/doc/libcgal-demo/data.tar.gz
[ -f "$tarball" ] || { echo "accuracy_scan: $tarball missing (make deps EXTRA_PACKAGES=libcgal-demo)" >&2; exit 1; }
mkdir -p "$out"
cd "$out" # the pictures' titles name the files as given
tar -xzf "$tarball" data/meshes/bunny00.off data/meshes/elephant.off data/meshes/refined_elephant.off \
	data/meshes/fandisk.off

# OFF with every coordinate times 100 (the header, blank lines and faces unchanged)
scale_off() {
	awk 'NF == 0 || NR == 1 { print; next }
	     !nv { nv = $1; print; next }
	     done < nv { printf "%.9g %.9g %.9g\n", $1 * 100, $2 * 100, $3 * 100; done++; next }
	     { print }' "$1" > "$2"
}

timed() {
	label=$1; shift
	/usr/bin/time -f '%e %U %M' -o time.txt "$@"
	tail -n 1 time.txt > time.last # after "Command exited with non-zero status"
	read -r wall cpu kib < time.last
	echo "($label: ${wall} s wall, ${cpu} s CPU, $((kib / 1024)) MiB peak)" >&2
}

"$gen" convert data/meshes/bunny00.off 100 bunny.stl >/dev/null
scale_off data/meshes/elephant.off elephant.off
scale_off data/meshes/refined_elephant.off refined-elephant.off

timed "analyze, bunny" "$bin" analyze bunny.stl --layer-height 0.2 --png bunny-cusp.png \
	> bunny-cusp.txt
head -2 bunny-cusp.txt
"$bin" repair bunny.stl -o bunny-repaired.stl >/dev/null
timed "compare, bunny and its repair" "$bin" compare bunny.stl bunny-repaired.stl \
	> bunny-repair.txt
head -5 bunny-repair.txt
timed "compare, elephants: distance" "$bin" compare elephant.off refined-elephant.off \
	--png elephant-distance.png > elephant.txt
cat elephant.txt
timed "compare, elephants: chordal error" "$bin" compare elephant.off \
	--reference refined-elephant.off --tolerance 0.3 --png elephant-chordal.png \
	> elephant-chordal.txt
cat elephant-chordal.txt

"$gen" convert data/meshes/fandisk.off 100 fandisk.stl >/dev/null
"$bin" repair fandisk.stl -o fandisk-repaired.stl >/dev/null
"$bin" repair fandisk.stl -o fandisk-simplified.stl --simplify-planar | grep 'planar simplification'
timed "compare, fandisk simplified and repaired" "$bin" compare fandisk-simplified.stl \
	fandisk-repaired.stl --png fandisk-simplified.png > fandisk-simplified.txt
sed -n 4p fandisk-simplified.txt

# `stratum refine` (seed 003's vertex translation): a 16-sided cylinder
# (radius 10 mm, 20 mm tall) against a 256-sided one at 0.01 mm, and the
# coarse elephant against the refined one at 0.15 mm (its corners lie up to
# 0.62 mm off the refined surface: --move-vertices), each with --uniform,
# the uniform subdivision reaching the same tolerance, for its size.
"$gen" cylinder 10 20 16 cylinder16.stl >/dev/null
"$gen" cylinder 10 20 256 cylinder256.stl >/dev/null
timed "refine, cylinder" "$bin" refine cylinder16.stl --reference cylinder256.stl \
	--tolerance 0.01 -o cylinder-refined.stl --uniform --png cylinder-refined.png \
	> cylinder-refined.txt
cat cylinder-refined.txt
"$bin" compare cylinder-refined.stl cylinder256.stl | sed -n 4p
timed "refine, elephant" "$bin" refine elephant.off --reference refined-elephant.off \
	--tolerance 0.15 --move-vertices -o elephant-refined.stl --uniform \
	--png elephant-refined.png > elephant-refined.txt
cat elephant-refined.txt
"$bin" check elephant-refined.stl | tail -1
"$bin" compare elephant-refined.stl refined-elephant.off | sed -n 4p

# A surface curved both ways: a torus of 12 x 6 quads against one of
# 192 x 96 at 0.05 mm, with --uniform.  And a decimated scan: the bunny
# after `repair --simplify-planar` (its vertices on the scan) against the
# scan, at 0.3 mm (reached) and 0.1 mm (not reached: exit 1, the report
# says how far it got), with compare --reference's own count.
"$gen" torus 12 6 torus12.stl >/dev/null
"$gen" torus 192 96 torus192.stl >/dev/null
timed "refine, torus" "$bin" refine torus12.stl --reference torus192.stl --tolerance 0.05 \
	-o torus-refined.stl --uniform > torus-refined.txt
cat torus-refined.txt
"$bin" compare torus-refined.stl torus192.stl | sed -n 4p
"$bin" repair bunny.stl --simplify-planar --angle 30 --flatness 0.5 -o bunny-coarse.stl \
	>/dev/null
for tol in 0.3 0.1; do
	rm -f "bunny-refined-$tol.stl"
	timed "refine, bunny at $tol mm" "$bin" refine bunny-coarse.stl --reference bunny.stl \
		--tolerance "$tol" -o "bunny-refined-$tol.stl" > "bunny-refined-$tol.txt" 2>&1 ||
		true
	cat "bunny-refined-$tol.txt"
	[ ! -f "bunny-refined-$tol.stl" ] ||
		"$bin" compare "bunny-refined-$tol.stl" --reference bunny.stl --tolerance "$tol" |
		sed -n 2,3p
done
