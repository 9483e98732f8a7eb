#!/bin/sh
# bench/run.sh BIN [check|repair|slice|region|all] - time `stratum check`
# against admesh, `stratum repair` on generated files, and `stratum slice`
# against PrusaSlicer's `--export-gcode`; `region` measures how well both
# slicers' printed regions match the models' cross-sections (issue 5, with
# build/bench/region_check); prints Markdown tables for docs/benchmarks.md.  Wall time, CPU time and peak RSS come from GNU time;
# check and repair figures are the best of 3 runs; slice figures one run of
# PrusaSlicer and the better of two of stratum.
set -eu
bin=${1:-build/stratum}
what=${2:-all}
out=bench/out
mkdir -p "$out"
gen=build/bench/gen_mesh

case $what in check|repair|slice|region|all) ;; *) echo "usage: bench/run.sh BIN [check|repair|slice|region|all]" >&2; exit 2;; esac

if [ "$what" != slice ] && [ "$what" != region ]; then
	[ -f "$out/torus-1m.stl" ] || "$gen" torus 1000 500 "$out/torus-1m.stl"
	[ -f "$out/torus-2m.stl" ] || "$gen" torus 1000 1000 "$out/torus-2m.stl"
	[ -f "$out/spheres.stl" ] || "$gen" spheres 8 "$out/spheres.stl"
fi
if [ "$what" != check ] && [ "$what" != region ]; then
	[ -f "$out/torus-100k.stl" ] || "$gen" torus 250 200 "$out/torus-100k.stl"
	[ -f "$out/twospheres.stl" ] || "$gen" twospheres 100 80 "$out/twospheres.stl"
	[ -f "$out/scan.stl" ] || "$gen" scan 250 120 0.7 "$out/scan.stl"
	[ -f "$out/cube20.stl" ] || "$gen" box 20 20 20 "$out/cube20.stl"
fi

# best_of3 CMD... -> "seconds peak_kib" (exit status of CMD ignored: check exits 1
# for an unprintable mesh, which is a result, not a failure)
best_of3() {
	best_t=""; best_m=""
	for _ in 1 2 3; do
		/usr/bin/time -q -f '%e %M' -o "$out/time.txt" "$@" >/dev/null 2>&1 || true
		read -r t m < "$out/time.txt"
		if [ -z "$best_t" ] || [ "$(echo "$t < $best_t" | bc)" = 1 ]; then best_t=$t; fi
		if [ -z "$best_m" ] || [ "$m" -lt "$best_m" ]; then best_m=$m; fi
	done
	echo "$best_t $best_m"
}

check_table() {
echo "| file | triangles | stratum check s (2 cores) | 1 core s | peak MiB | B/triangle | admesh s | admesh MiB | time ratio stratum/admesh |"
echo "|---|---|---|---|---|---|---|---|---|"
for f in torus-1m torus-2m spheres; do
	path="$out/$f.stl"
	tris=$(( ($(stat -c %s "$path") - 84) / 50 ))
	set -- $(best_of3 "$bin" check "$path")
	st=$1; sm=$2
	set -- $(best_of3 "$bin" check --threads 1 "$path")
	st1=$1
	if command -v admesh >/dev/null 2>&1; then
		set -- $(best_of3 admesh "$path")
		at=$1; am=$2
		ratio=$(echo "scale=2; $st / $at" | bc)
		amib=$(echo "scale=1; $am / 1024" | bc)
	else
		at="n/a"; amib="n/a"; ratio="n/a"
	fi
	echo "| $f | $tris | $st | $st1 | $(echo "scale=1; $sm / 1024" | bc) | $(echo "$sm * 1024 / $tris" | bc) | $at | $amib | $ratio |"
done
}

# json_field FILE KEY -> the value of "KEY": in stratum's indented JSON
json_field() {
	sed -n "s/^  \"$2\": \([^,]*\),\{0,1\}\$/\1/p" "$1"
}

# `stratum repair` (seed 000 pipeline): throughput = input triangles / wall s.
repair_table() {
echo "| file | triangles | intersecting pairs | stratum repair s (2 cores) | triangles/s | peak MiB | B/triangle | output triangles | components | second pass | printable |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
for f in torus-100k torus-1m twospheres scan spheres; do
	path="$out/$f.stl"
	rep="$out/$f-repaired.stl"
	tris=$(( ($(stat -c %s "$path") - 84) / 50 ))
	"$bin" repair --json "$path" -o "$rep" >"$out/$f-repair.json" 2>"$out/$f-repair.err" || true
	pairs=$(json_field "$out/$f-repair.json" intersecting_pairs)
	otris=$(json_field "$out/$f-repair.json" output_triangles)
	comps=$(json_field "$out/$f-repair.json" components)
	second=$(json_field "$out/$f-repair.json" second_pass)
	printable=$(json_field "$out/$f-repair.json" printable)
	set -- $(best_of3 "$bin" repair "$path" -o "$rep")
	rt=$1; rmem=$2
	if [ "$(echo "$rt > 0" | bc)" = 1 ]; then
		rate=$(echo "$tris / $rt" | bc)
	else
		rate="n/a"
	fi
	echo "| $f | $tris | ${pairs:-n/a} | $rt | $rate | $(echo "scale=1; $rmem / 1024" | bc) | $(echo "$rmem * 1024 / $tris" | bc) | ${otris:-n/a} | ${comps:-n/a} | ${second:-n/a} | ${printable:-failed, see $out/$f-repair.err} |"
done
}

# PrusaSlicer settings matching printers/prusa-i3-mk3s.ini for what both
# slicers do: nozzle 0.4, layers 0.2, 2 perimeters 0.45 mm wide, the MK3S bed.
# $1 = walls: no infill, skins or skirt (what stratum prints at this commit);
# $1 = full: the profile's 15 % gyroid infill, 5 top / 4 bottom layers, 1 skirt.
prusa_ini() {
	cat <<EOF
bed_shape = 0x0,250x0,250x210,0x210
max_print_height = 210
gcode_flavor = marlin2
nozzle_diameter = 0.4
filament_diameter = 1.75
layer_height = 0.2
first_layer_height = 0.2
perimeters = 2
extrusion_width = 0.45
thin_walls = 1
gap_fill_enabled = 1
support_material = 0
brim_width = 0
EOF
	if [ "$1" = walls ]; then
		printf 'fill_density = 0%%\ntop_solid_layers = 0\nbottom_solid_layers = 0\nskirts = 0\n'
	else
		printf 'fill_density = 15%%\nfill_pattern = gyroid\ntop_solid_layers = 5\nbottom_solid_layers = 4\nskirts = 1\n'
	fi
}

# once CMD... -> "wall_s cpu_s peak_kib" of one run (GNU time)
once() {
	/usr/bin/time -q -f '%e %U %S %M' -o "$out/time.txt" "$@" >/dev/null 2>&1 || echo "failed: $*" >&2
	read -r t u s m < "$out/time.txt"
	echo "$t $(echo "$u + $s" | bc | sed 's/^\./0./') $m"
}

# ratio A B -> A / B with two decimals
ratio() {
	echo "scale=2; $1 / $2" | bc | sed 's/^\./0./'
}

# `stratum slice` (repair included) against `prusa-slicer --export-gcode`.
slice_table() {
if ! command -v prusa-slicer >/dev/null 2>&1; then
	echo "prusa-slicer is not installed (make bench installs it)" >&2
	return 1
fi
prusa_ini walls >"$out/prusa-walls.ini"
prusa_ini full >"$out/prusa-full.ini"
pver=$(prusa-slicer --help 2>/dev/null | sed -n 's/^PrusaSlicer-\([0-9.]*\).*/\1/p')
echo "| model | triangles | slicer | layers | wall s | CPU s | peak MiB | wall ratio stratum/this | CPU ratio | memory ratio |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for f in cube20 scan; do
	path="$out/$f.stl"
	tris=$(( ($(stat -c %s "$path") - 84) / 50 ))
	# stratum: the better of two runs (the machine is shared), by wall time
	st=""
	for _ in 1 2; do
		set -- $(once "$bin" slice "$path" -o "$out/$f-stratum.gcode" --printer prusa-i3-mk3s)
		if [ -z "$st" ] || [ "$(echo "$1 < $st" | bc)" = 1 ]; then st=$1; sc=$2; sm=$3; fi
	done
	sl=$(grep -c '^;LAYER_CHANGE' "$out/$f-stratum.gcode" || true)
	echo "| $f | $tris | stratum (full, repair included; best of 2) | $sl | $st | $sc | $(echo "scale=1; $sm / 1024" | bc) | | | |"
	for cfg in walls full; do
		set -- $(once prusa-slicer --export-gcode --load "$out/prusa-$cfg.ini" --center 125,105 \
			-o "$out/$f-prusa-$cfg.gcode" "$path")
		pt=$1; pc=$2; pm=$3
		pl=$(grep -c '^;LAYER_CHANGE' "$out/$f-prusa-$cfg.gcode" || true)
		echo "| $f | $tris | PrusaSlicer $pver ($cfg) | $pl | $pt | $pc | $(echo "scale=1; $pm / 1024" | bc) | $(ratio "$st" "$pt") | $(ratio "$sc" "$pc") | $(ratio "$sm" "$pm") |"
	done
done
}

# The issue 5 test models, written by gen_mesh (tests/fixtures.h).
region_models() {
	[ -f "$out/cube20.stl" ] || "$gen" box 20 20 20 "$out/cube20.stl"
	[ -f "$out/cylinder20.stl" ] || "$gen" cylinder 10 20 256 "$out/cylinder20.stl"
	[ -f "$out/wall2.stl" ] || "$gen" box 20 2 10 "$out/wall2.stl"
	[ -f "$out/wall-eps.stl" ] || "$gen" box 20 0.4 10 "$out/wall-eps.stl"
	[ -f "$out/plate-holes.stl" ] || "$gen" plate "$out/plate-holes.stl"
	[ -f "$out/overhang.stl" ] || "$gen" overhang "$out/overhang.stl"
	[ -f "$out/bridge.stl" ] || "$gen" bridge "$out/bridge.stl"
}

# Printed region against the model's cross-sections: both slicers at the
# profile's settings (PrusaSlicer's "full" ini above), the part centred on
# 125,105 by both, so the check places the model there too.
region_table() {
if ! command -v prusa-slicer >/dev/null 2>&1; then
	echo "prusa-slicer is not installed (make bench installs it)" >&2
	return 1
fi
rc=build/bench/region_check
region_models
prusa_ini full >"$out/prusa-full.ini"
pver=$(prusa-slicer --help 2>/dev/null | sed -n 's/^PrusaSlicer-\([0-9.]*\).*/\1/p')
echo "| model | slicer | layers | p95 outer deviation mm | max mm | printed up to mm outside / inside | area error (voids filled) | area error (voids counted) |"
echo "|---|---|---|---|---|---|---|---|"
for f in cube20 cylinder20 wall2 wall-eps plate-holes overhang bridge; do
	path="$out/$f.stl"
	"$bin" slice "$path" -o "$out/$f-stratum.gcode" --printer prusa-i3-mk3s --center 125,105 \
		>/dev/null 2>&1 || echo "failed: stratum slice $f" >&2
	prusa-slicer --export-gcode --load "$out/prusa-full.ini" --center 125,105 \
		-o "$out/$f-prusa.gcode" "$path" >/dev/null 2>&1 || echo "failed: prusa-slicer $f" >&2
	for s in stratum prusa; do
		"$rc" "$path" "$out/$f-$s.gcode" --center 125,105 --json >"$out/$f-$s-region.json" ||
			{ echo "failed: region_check $f $s" >&2; continue; }
		j="$out/$f-$s-region.json"
		name=stratum; [ "$s" = prusa ] && name="PrusaSlicer $pver"
		echo "| $f | $name | $(json_field "$j" layers) | $(json_field "$j" dev_p95) | $(json_field "$j" dev_max) | $(json_field "$j" outside_max) / $(json_field "$j" inside_max) | $(json_field "$j" area_error) | $(json_field "$j" area_error_raw) |"
	done
done
}

case $what in
region) region_table ;;
check) check_table ;;
repair) repair_table ;;
slice) slice_table ;;
all) check_table; echo; repair_table; echo; slice_table; echo; region_table ;;
esac

