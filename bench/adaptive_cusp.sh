#!/bin/sh
# bench/adaptive_cusp.sh - the cusp of adaptive against uniform layers at
# equal layer count (issue 21 item 3; build/bench/adaptive_cusp), on a UV
# sphere (gen_mesh sphere 129 256: 65536 triangles) and CGAL's bunny
# (libcgal-demo's data/meshes/bunny00.off, 75408 triangles), both scaled to
# 50 mm, for cusp bounds 0.05, 0.1 and 0.15 mm with a 0.4 mm nozzle's
# heights (0.07 to 0.3 mm), then 0.05 mm with a minimum of 0.04 mm.  Prints
# the Markdown table of docs/benchmarks.md.
set -eu
out=bench/out/adaptive
gen=${GEN_MESH:-build/bench/gen_mesh}
cusp=${ADAPTIVE_CUSP:-build/bench/adaptive_cusp}
tarball=/usr/share/doc/libcgal-demo/data.tar.gz
mkdir -p "$out"
[ -f "$out/data/meshes/bunny00.off" ] || {
	[ -f "$tarball" ] || { echo "adaptive_cusp: $tarball missing (make bench installs libcgal-demo)" >&2; exit 1; }
	tar -xzf "$tarball" -C "$out" data/meshes/bunny00.off
}
[ -f "$out/sphere-50mm.stl" ] || {
	"$gen" sphere 129 256 "$out/sphere.stl" >/dev/null
	"$gen" convert "$out/sphere.stl" 50 "$out/sphere-50mm.stl" >/dev/null
}
[ -f "$out/bunny-50mm.stl" ] || "$gen" convert "$out/data/meshes/bunny00.off" 50 "$out/bunny-50mm.stl" >/dev/null

echo "| mesh | triangles | bound mm | layers (adaptive / uniform) | adaptive max | adaptive mean | uniform h | uniform max | uniform mean | max reduction | mean reduction | plan ms |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
for mesh in sphere bunny; do
	for args in "0.05" "0.1" "0.15" "0.05 0.04 0.3"; do
		# shellcheck disable=SC2086
		printf '| %s (min %s) ' "$mesh" "$(echo $args | awk '{print ($2 == "" ? "0.07" : $2)}')"
		# shellcheck disable=SC2086
		"$cusp" "$out/$mesh-50mm.stl" $args
	done
done
