#!/bin/sh
# bench/planar_simplify.sh BIN - what `stratum repair --simplify-planar`
# (docs/repair.md "Planar simplification") saves on CAD-like parts: the
# bundled bracket, gen_mesh's plate with two holes, and CGAL's CAD models
# and one scan from Debian's libcgal-demo (skipped without it), each
# scaled to 100 mm as bench/cgal_corpus.sh does.  For each: triangles the
# repair writes, triangles after simplification, faces re-triangulated
# and left as they were, the largest deviation, the time of the repair
# with and without simplification (best of 3, GNU time), and the verdict
# of `stratum check` on the simplified file.  Prints Markdown rows for
# docs/benchmarks.md.
set -eu
bin=${1:-build/stratum}
out=bench/out/planar
gen=${GEN_MESH:-build/bench/gen_mesh}
tarball=/usr/share/doc/libcgal-demo/data.tar.gz
mkdir -p "$out"

best_of3() {
	best=""
	for _ in 1 2 3; do
		/usr/bin/time -q -f '%e' -o "$out/time.txt" "$@" >"$out/report.json" 2>/dev/null || true
		t=$(cat "$out/time.txt")
		if [ -z "$best" ] || [ "$(echo "$t < $best" | bc)" = 1 ]; then best=$t; fi
	done
	echo "$best"
}

# field NAME: a number from the JSON report of the last run
field() {
	sed -n "s/^ *\"$1\": \\([0-9.e+-]*\\),\\{0,1\\}\$/\\1/p" "$out/report.json" | tail -1
}

models="docs/examples/bracket.stl"
"$gen" plate "$out/plate.stl" >/dev/null
models="$models $out/plate.stl"
if [ -f "$tarball" ]; then
	[ -d "$out/data/meshes" ] || tar -xzf "$tarball" -C "$out" data/meshes
	for m in cube-meshed joint pinion anchor_dense couplingdown fandisk fandisk_large \
		mech-holes-shark ALSTOM_TEST4 cylinder_locally_refined bunny00; do
		"$gen" convert "$out/data/meshes/$m.off" 100 "$out/$m.stl" >/dev/null
		models="$models $out/$m.stl"
	done
else
	echo "planar_simplify: $tarball missing (make bench installs libcgal-demo); CGAL's models skipped" >&2
fi

echo "| model | input | repaired | simplified | saved | faces re-triangulated | left as they were | largest deviation mm | repair s | with --simplify-planar s | check |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
for m in $models; do
	t0=$(best_of3 "$bin" repair "$m" -o "$out/repaired.stl" --json)
	t1=$(best_of3 "$bin" repair "$m" -o "$out/simplified.stl" --simplify-planar --json)
	input=$(field input_triangles)
	before=$(field triangles_before)
	after=$(field triangles_after)
	retri=$(field retriangulated)
	refused=$(( $(field refused_shape) + $(field refused_deviation) + $(field refused_topology) + $(field refused_crossing) ))
	dev=$(field max_deviation)
	verdict=$("$bin" check "$out/simplified.stl" 2>/dev/null | sed -n 's/^printable: //p')
	saved=$(echo "scale=1; 100 * ($before - $after) / $before" | bc)
	echo "| $(basename "$m" .stl) | $input | $before | $after | $saved % | $retri | $refused | $dev | $t0 | $t1 | $verdict |"
done
