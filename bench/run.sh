#!/bin/sh
# bench/run.sh BIN [check|repair|intersect|slice|speed|region|thin|gcodesize|stream|soak|x3g|s3g|serve|corpus|all] - time `stratum check`
# against admesh, `stratum repair` on generated files, the exact pass of the
# repair on self-intersecting inputs (`intersect`: CGAL data meshes, spheres,
# scattered soups; build/bench/refine_time), `stratum slice` against
# PrusaSlicer's `--export-gcode` (`speed`: on CGAL's armadillo and
# ChineseDragon and a 1M-triangle sphere, at 1 and 2 threads, run
# alternately), and streaming to `stratum sim` with
# `stratum send` against Printrun's printcore (`soak`: 100k lines under
# faults, exactly once); `region` measures how well both
# slicers' printed regions match the models' cross-sections (issue 5, with
# build/bench/region_check), `thin` the gap and overlap of thin walls
# (bench/thin_walls.sh); `gcodesize` compares the G-code's lines, bytes
# and moves per second of print with PrusaSlicer's at gcode_resolution 0,
# at its default and with arc_fitting; `x3g` times G-code -> X3G translation against
# gpx -m fcp on a model sliced for the Creator Pro; `s3g` streams G-code to
# `stratum sim --dialect sailfish` with `stratum send` (translated on the fly)
# against `gpx -s`; `serve` loads a `stratum serve` node on loopback with
# ApacheBench (apache2-utils): bounded counts of multipart uploads and of
# status requests from concurrent clients; `corpus` runs the PrusaSlicer
# corpus (bench/prusa_corpus.sh: every printer preset of every installed
# vendor bundle, sliced by prusa-slicer, sent to the simulator, previewed)
# and the CuraEngine corpus (bench/cura_corpus.sh: ten Cura printer
# definitions) and prints their failures and pass counts; prints Markdown tables for
# docs/benchmarks.md.
# Wall time, CPU time and peak RSS come from GNU time;
# check and repair figures are the best of 3 runs; slice figures one run of
# PrusaSlicer and the better of two of stratum.
set -eu
bin=${1:-build/stratum}
what=${2:-all}
out=bench/out
mkdir -p "$out"
gen=build/bench/gen_mesh
refine=build/bench/refine_time

case $what in check|repair|intersect|slice|speed|region|thin|gcodesize|stream|soak|x3g|s3g|serve|corpus|all) ;; *) echo "usage: bench/run.sh BIN [check|repair|intersect|slice|speed|region|thin|gcodesize|stream|soak|x3g|s3g|serve|corpus|all]" >&2; exit 2;; esac

if [ "$what" != slice ] && [ "$what" != speed ] && [ "$what" != region ] && [ "$what" != thin ] && [ "$what" != stream ] && [ "$what" != soak ] && [ "$what" != x3g ] && [ "$what" != s3g ] && [ "$what" != serve ]; then
	[ -f "$out/torus-1m.stl" ] || "$gen" torus 1000 500 "$out/torus-1m.stl"
	[ -f "$out/torus-2m.stl" ] || "$gen" torus 1000 1000 "$out/torus-2m.stl"
	[ -f "$out/sphere-1m.stl" ] || "$gen" sphere 501 1000 "$out/sphere-1m.stl"
	[ -f "$out/spheres.stl" ] || "$gen" spheres 8 "$out/spheres.stl"
fi
if [ "$what" != check ] && [ "$what" != speed ] && [ "$what" != region ] && [ "$what" != thin ] && [ "$what" != stream ] && [ "$what" != soak ] && [ "$what" != x3g ] && [ "$what" != s3g ] && [ "$what" != serve ]; then
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
for f in torus-1m sphere-1m torus-2m spheres; do
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

# speed_models: CGAL's armadillo and ChineseDragon (Debian's libcgal-demo,
# scaled to 100 mm as bench/cgal_corpus.sh does) and the 1M-triangle sphere.
speed_models() {
	cgal=/usr/share/doc/libcgal-demo/data.tar.gz
	for m in armadillo ChineseDragon-10kv; do
		[ -f "$out/$m.stl" ] && continue
		tar -xzf "$cgal" -O "data/meshes/$m.off" >"$out/$m.off" &&
			"$gen" convert "$out/$m.off" 100 "$out/$m.stl" >/dev/null
	done
	[ -f "$out/sphere-1m.stl" ] || "$gen" sphere 501 1000 "$out/sphere-1m.stl"
}

# The whole `stratum slice` (repair included) against `prusa-slicer
# --export-gcode` at the same settings ("full" ini) and thread count (issue
# 19 item 5), run alternately, one run each: at 1 thread both pinned to
# one core with taskset (PrusaSlicer 2.5 has no thread option; its TBB pool
# follows the affinity mask), at 2 threads on both cores.  The load
# average before and after is printed: the machine is shared, so the CPU
# ratio is the steadier figure.
speed_table() {
if ! command -v prusa-slicer >/dev/null 2>&1; then
	echo "prusa-slicer is not installed (make bench installs it)" >&2
	return 1
fi
speed_models
prusa_ini full >"$out/prusa-full.ini"
pver=$(prusa-slicer --help 2>/dev/null | sed -n 's/^PrusaSlicer-\([0-9.]*\).*/\1/p')
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
echo
echo "| model | triangles | threads | stratum wall s | CPU s | peak MiB | PrusaSlicer $pver wall s | CPU s | peak MiB | wall ratio stratum/PrusaSlicer | CPU ratio | memory ratio |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
for f in ${SPEED_MODELS:-ChineseDragon-10kv armadillo sphere-1m}; do
	path="$out/$f.stl"
	tris=$(( ($(stat -c %s "$path") - 84) / 50 ))
	for t in ${SPEED_THREADS:-1 2}; do
		pin=""
		[ "$t" = 1 ] && pin="taskset -c 0"
		# shellcheck disable=SC2086 # $pin: words on purpose
		set -- $(once $pin "$bin" slice "$path" -o "$out/$f-speed-stratum.gcode" \
			--printer prusa-i3-mk3s --center 125,105 --threads "$t")
		st=$1; sc=$2; sm=$3
		# shellcheck disable=SC2086
		set -- $(once $pin prusa-slicer --export-gcode --load "$out/prusa-full.ini" \
			--center 125,105 -o "$out/$f-speed-prusa.gcode" "$path")
		pt=$1; pc=$2; pm=$3
		echo "| $f | $tris | $t | $st | $sc | $(echo "scale=1; $sm / 1024" | bc) | $pt | $pc | $(echo "scale=1; $pm / 1024" | bc) | $(ratio "$st" "$pt") | $(ratio "$sc" "$pc") | $(ratio "$sm" "$pm") |"
	done
done
echo
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
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
# 125,105 by both, so the check places the model there too.  REGION_SET
# (space-separated KEY=VALUE, e.g. per-role extrusion widths) is given to
# both: --set for stratum, lines of the ini for PrusaSlicer.
region_table() {
if ! command -v prusa-slicer >/dev/null 2>&1; then
	echo "prusa-slicer is not installed (make bench installs it)" >&2
	return 1
fi
rc=build/bench/region_check
region_models
prusa_ini full >"$out/prusa-full.ini"
sets=""
for kv in ${REGION_SET:-}; do
	echo "$kv" | sed 's/=/ = /' >>"$out/prusa-full.ini"
	sets="$sets --set $kv"
done
pver=$(prusa-slicer --help 2>/dev/null | sed -n 's/^PrusaSlicer-\([0-9.]*\).*/\1/p')
echo "| model | slicer | layers | p95 outer deviation mm | max mm | printed up to mm outside / inside | area error (voids filled) | area error (voids counted) |"
echo "|---|---|---|---|---|---|---|---|"
for f in cube20 cylinder20 wall2 wall-eps plate-holes overhang bridge; do
	path="$out/$f.stl"
	# shellcheck disable=SC2086 # $sets: words on purpose
	"$bin" slice "$path" -o "$out/$f-stratum.gcode" --printer prusa-i3-mk3s --center 125,105 \
		$sets >/dev/null 2>&1 || echo "failed: stratum slice $f" >&2
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

# Thin walls against PrusaSlicer's at the "full" settings (bench/thin_walls.sh).
thin_table() {
	prusa_ini full >"$out/prusa-full.ini"
	bench/thin_walls.sh "$bin" prusa
}

# lines_bytes_rate FILE -> "lines bytes mean peak": move lines (G1, G2,
# G3) per second of print (the file's "; estimated printing time",
# stratum's or PrusaSlicer's "(normal mode)" one), and the most move lines
# within one second of XY motion at the feed rates written, an arc's along
# its length (no acceleration, so the time is short and the peak an upper
# figure; the same rule for both slicers).
lines_bytes_rate() {
	moves=$(grep -c '^G[123] ' "$1" || true)
	secs=$(grep -m1 'estimated printing time' "$1" | sed 's/.*= *//' |
		awk '{ t = 0; for (i = 1; i <= NF; i++) { v = $i + 0; u = substr($i, length($i));
			t += v * (u == "d" ? 86400 : u == "h" ? 3600 : u == "m" ? 60 : 1) } print t }')
	peak=$(awk 'BEGIN { x = 0; y = 0; f = 1000; t = 0; n = 0; head = 0; best = 0 }
		/^G[123] / {
			nx = x; ny = y; ci = 0; cj = 0
			for (i = 2; i <= NF; i++) {
				c = substr($i, 1, 1); v = substr($i, 2) + 0
				if (c == ";") break
				if (c == "X") nx = v; else if (c == "Y") ny = v; else if (c == "F") f = v
				else if (c == "I") ci = v; else if (c == "J") cj = v
			}
			d = sqrt((nx - x) ^ 2 + (ny - y) ^ 2)
			if ($1 != "G1" && (ci != 0 || cj != 0)) { # an arc: its length
				a = atan2((-ci) * (ny - y - cj) - (-cj) * (nx - x - ci), \
					  (-ci) * (nx - x - ci) + (-cj) * (ny - y - cj))
				if ($1 == "G3" && a <= 0) a += 2 * 3.14159265358979
				if ($1 == "G2" && a >= 0) a -= 2 * 3.14159265358979
				d = sqrt(ci * ci + cj * cj) * (a < 0 ? -a : a)
			}
			x = nx; y = ny
			if (d > 0 && f > 0) t += d / (f / 60)
			ts[n++] = t
			while (ts[head] < t - 1) head++
			if (n - head > best) best = n - head
		}
		END { print best }' "$1")
	echo "$(wc -l <"$1") $(wc -c <"$1") $(echo "$moves / $secs" | bc) $peak"
}

# G-code size at gcode_resolution 0, at the default and with arc_fitting
# against PrusaSlicer
# ("full" ini, whose gcode_resolution is 0.0125 too), same models and
# settings as region_table plus a sphere.
gcodesize_table() {
if ! command -v prusa-slicer >/dev/null 2>&1; then
	echo "prusa-slicer is not installed (make bench installs it)" >&2
	return 1
fi
region_models
[ -f "$out/sphere100.stl" ] || "$gen" sphere 100 200 "$out/sphere100.stl"
prusa_ini full >"$out/prusa-full.ini"
pver=$(prusa-slicer --help 2>/dev/null | sed -n 's/^PrusaSlicer-\([0-9.]*\).*/\1/p')
echo "| model | slicer | lines | bytes | moves (G1, G2, G3) per s of print (mean) | peak moves in 1 s | lines / PrusaSlicer's | bytes / PrusaSlicer's |"
echo "|---|---|---|---|---|---|---|---|"
for f in cube20 cylinder20 plate-holes sphere100; do
	path="$out/$f.stl"
	prusa-slicer --export-gcode --load "$out/prusa-full.ini" --center 125,105 \
		-o "$out/$f-prusa.gcode" "$path" >/dev/null 2>&1 || echo "failed: prusa-slicer $f" >&2
	set -- $(lines_bytes_rate "$out/$f-prusa.gcode")
	pl=$1; pb=$2
	for r in 0 0.0125 arcs; do
		set -- --set gcode_resolution=$r
		what="gcode_resolution = $r"
		if [ $r = arcs ]; then
			set -- --set arc_fitting=emit_center
			what="gcode_resolution = 0.0125, arc_fitting = emit_center"
		fi
		"$bin" slice "$path" -o "$out/$f-r$r.gcode" --printer prusa-i3-mk3s --center 125,105 \
			"$@" >/dev/null 2>&1 || echo "failed: stratum slice $f" >&2
		set -- $(lines_bytes_rate "$out/$f-r$r.gcode")
		echo "| $f | stratum, $what | $1 | $2 | $3 | $4 | $(ratio "$1" "$pl") | $(ratio "$2" "$pb") |"
	done
	set -- $(lines_bytes_rate "$out/$f-prusa.gcode")
	echo "| $f | PrusaSlicer $pver | $1 | $2 | $3 | $4 | | |"
done
}

# dense_gcode SEGMENTS PATH - a dense curved surface: the wall of a 25 mm
# dome (domes stacked when SEGMENTS needs more than one) in 0.2 mm layers, each circle cut into chords of about 0.5 mm, like
# a slicer's output for a finely tessellated model.  Deterministic, so the
# file for fewer segments is a prefix of the one for more.
dense_gcode() {
	LC_ALL=C awk -v segs="$1" 'BEGIN {
		pi = 3.14159265358979; R = 25; n = 0; z = 0
		print "; dense curved surface for bench/run.sh stream"
		print "G28"; print "G90"; print "M83"; print "G92 E0"
		while (n < segs) {
			z += 0.2
			# past the top of the dome, the next dome sits on it
			zd = z - (R - 0.2) * int((z - 0.001) / (R - 0.2))
			r = sqrt(R * R - zd * zd)
			k = int(2 * pi * r / 0.5)
			printf ";LAYER_CHANGE\nG1 Z%.2f F600\nG1 X%.3f Y%.3f F3000\n", z, 100 + r, 100
			for (i = 1; i <= k && n < segs; i++) {
				a = 2 * pi * i / k
				printf "G1 X%.3f Y%.3f E%.5f\n", 100 + r * cos(a), 100 + r * sin(a), 0.0166
				n++
			}
		}
		print "M400"; print "M84"
	}' >"$2"
}

# json_any FILE KEY -> the value of "KEY": anywhere in FILE (any indentation)
json_any() {
	tr -d '\n' <"$1" | sed -n "s/.*\"$2\": *\([^,}]*\).*/\1/p"
}

# sim_start LATENCY_MS LOG - a fresh simulated Marlin at 115200 baud, motion
# sped up so only the link and the round trips cost time; sets sim_pid.
sim_start() {
	rm -f "$out/stream-tty"
	"$bin" sim --dialect marlin --baud 115200 --latency "$1" --speedup 1000000 \
		--link "$out/stream-tty" --log "$2" >"$out/stream-sim.out" 2>&1 &
	sim_pid=$!
	i=0
	while [ ! -L "$out/stream-tty" ] && [ $i -lt 100 ]; do sleep 0.05; i=$((i + 1)); done
}

sim_stop() {
	kill "$sim_pid" 2>/dev/null || true
	wait "$sim_pid" 2>/dev/null || true
}

# log_matches GCODE LOG -> "yes" when the simulator ran every command of
# GCODE once, in order, under consecutive line numbers (the hosts' own M110
# and unnumbered connect probes left out), else "no".
log_matches() {
	LC_ALL=C awk '{ sub(/;.*/, ""); gsub(/^[ \t]+|[ \t]+$/, ""); if ($0 != "") print }' \
		"$1" >"$out/stream-want.txt"
	# The host's own handshake (M110 line numbering; stratum send's M115
	# capability query and M155 auto-report request) is not file content.
	LC_ALL=C awk '$1 ~ /^[0-9]+$/ && $2 != "M110" && $2 != "M115" && $2 != "M155" {
		if (seen && $1 != prev + 1) print "line number " $1 " after " prev
		prev = $1; seen = 1; sub(/^[0-9]+ /, ""); print
	}' "$2" >"$out/stream-got.txt"
	if cmp -s "$out/stream-want.txt" "$out/stream-got.txt"; then echo yes; else echo no; fi
}

# Streaming (issue 6 item 8): printcore and `stratum send` against fresh
# simulators with the same settings.  Link capacity at 115200 baud, 10 bits
# a byte: 11 520 bytes/s.  Bytes are those written towards the printer,
# line numbers, checksums and newlines included.  The 16 ms rows stream the
# first 5000 segments only: printcore needs about 21 ms a line there, and the
# rate is the same over 5000 lines as over 20000.
stream_table() {
if [ ! -x /usr/bin/printcore ] || ! /usr/bin/python3 -c 'import printrun.printcore' 2>/dev/null; then
	echo "printcore is not installed (make bench installs Debian's printcore)" >&2
	return 1
fi
[ -f "$out/dense-20k.gcode" ] || dense_gcode 20000 "$out/dense-20k.gcode"
[ -f "$out/dense-5k.gcode" ] || dense_gcode 5000 "$out/dense-5k.gcode"
have_send=no
"$bin" send --help >/dev/null 2>&1 && have_send=yes
echo "| host | latency ms | file | lines | bytes | s | lines/s | bytes/s | link fraction | log == file | bytes/s ours/printcore |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
for lat in 2 16; do
	if [ "$lat" = 2 ]; then f=dense-20k; else f=dense-5k; fi
	gcode="$out/$f.gcode"
	log="$out/stream-printcore-$lat.log"
	sim_start "$lat" "$log"
	/usr/bin/python3 bench/printcore_stream.py "$out/stream-tty" "$gcode" 115200 \
		>"$out/stream-printcore-$lat.json" 2>"$out/stream-printcore-$lat.err" || true
	sim_stop
	j="$out/stream-printcore-$lat.json"
	pbps=$(json_any "$j" bytes_per_s)
	echo "| printcore 2.0.0rc8 | $lat | $f | $(json_any "$j" lines) | $(json_any "$j" bytes) | $(json_any "$j" seconds) | $(json_any "$j" lines_per_s) | ${pbps:-failed, see $out/stream-printcore-$lat.err} | $(json_any "$j" link_fraction) | $(log_matches "$gcode" "$log") | |"
	if [ "$have_send" = no ]; then
		echo "| stratum send | $lat | $f | not measured yet: stratum send is not in this build | | | | | | | |"
		continue
	fi
	log="$out/stream-stratum-$lat.log"
	j="$out/stream-stratum-$lat.json"
	sim_start "$lat" "$log"
	"$bin" send "$gcode" --port "$out/stream-tty" --printer generic-marlin --json \
		>"$j" 2>"$out/stream-stratum-$lat.err" || true
	sim_stop
	sbps=$(json_any "$j" bytes_per_s)
	r=""
	if [ -n "$sbps" ] && [ -n "$pbps" ]; then r=$(ratio "$sbps" "$pbps"); fi
	echo "| stratum send | $lat | $f | $(json_any "$j" lines) | $(json_any "$j" bytes) | $(json_any "$j" seconds) | $(json_any "$j" lines_per_s) | ${sbps:-failed, see $out/stream-stratum-$lat.err} | $(json_any "$j" link_fraction) | $(log_matches "$gcode" "$log") | $r |"
done
}

# G-code -> X3G: the two-sphere model (31 680 triangles; the scan and the
# tori are wider than the Creator Pro's 148 mm) sliced for the FlashForge
# Creator Pro at 0.07 mm layers, translated by stratum x3g and by gpx -m fcp
# (no .ini: -I), best of 3; "same bytes" says whether the X3G files are equal.
x3g_table() {
[ -f "$out/twospheres.stl" ] || "$gen" twospheres 100 80 "$out/twospheres.stl"
g="$out/x3g-twospheres.gcode"
[ -f "$g" ] || "$bin" slice "$out/twospheres.stl" -o "$g" --printer flashforge-creator-pro \
	--layer-height 0.07 >/dev/null 2>&1
mkdir -p "$out/x3g-ours" "$out/x3g-gpx"
lines=$(wc -l <"$g")
echo "| input | lines | translator | wall s | peak MiB | lines/s | X3G bytes | same bytes as gpx |"
echo "|---|---|---|---|---|---|---|---|"
set -- $(best_of3 "$bin" x3g "$g" -o "$out/x3g-ours/twospheres.x3g" --printer flashforge-creator-pro)
st=$1; sm=$2
ours=$(stat -c %s "$out/x3g-ours/twospheres.x3g")
if command -v gpx >/dev/null 2>&1; then
	set -- $(best_of3 gpx -I -q -m fcp "$g" "$out/x3g-gpx/twospheres.x3g")
	gt=$1; gm=$2
	same=no; cmp -s "$out/x3g-ours/twospheres.x3g" "$out/x3g-gpx/twospheres.x3g" && same=yes
fi
echo "| twospheres.stl, 0.07 mm layers | $lines | stratum x3g | $st | $(echo "scale=1; $sm / 1024" | bc) | $(echo "$lines / $st" | bc) | $ours | ${same:-n/a} |"
if [ -n "${gt:-}" ]; then
	echo "| twospheres.stl, 0.07 mm layers | $lines | gpx -m fcp | $gt | $(echo "scale=1; $gm / 1024" | bc) | $(echo "$lines / $gt" | bc) | $(stat -c %s "$out/x3g-gpx/twospheres.x3g") | |"
else
	echo "| twospheres.stl, 0.07 mm layers | $lines | gpx -m fcp | not installed | | | | |"
fi
}

# S3G streaming (issue 7 items 4 and 6): the same G-code to a fresh
# simulated Sailfish per host at 115200 baud, motion and heating sped up so
# only the link and the round trips cost time.  gpx -s and `stratum send`
# both translate and send in one pass; `stratum send` of gpx's own X3G file
# shows what the translation costs.  "bytes out" are those written towards
# the printer (framing and queries included; gpx's are its X3G file plus 3
# framing bytes a packet: it sends no queries); the link fraction counts
# both directions against 11 520 bytes/s.  "log == X3G" says whether the
# simulator ran the commands of the X3G file for that G-code (gpx's, or
# `stratum x3g`'s, which is byte-identical), each once and in order.
s3g_sim_start() {
	rm -f "$out/s3g-tty"
	"$bin" sim --dialect sailfish --baud 115200 --speedup 1000000 --link "$out/s3g-tty" \
		--log "$1" >"$out/s3g-sim.out" 2>&1 &
	sim_pid=$!
	i=0
	while [ ! -L "$out/s3g-tty" ] && [ $i -lt 100 ]; do sleep 0.05; i=$((i + 1)); done
}

# s3g_log_matches X3G LOG -> yes/no
s3g_log_matches() {
	"$bin" x3g --decode "$1" 2>/dev/null | awk '{ print $2 }' >"$out/s3g-want.txt"
	awk '$1 ~ /^[0-9]+$/ { if ($1 != NR) print "seq " $1 " at " NR; print $2 }' "$2" \
		>"$out/s3g-got.txt"
	if cmp -s "$out/s3g-want.txt" "$out/s3g-got.txt"; then echo yes; else echo no; fi
}

s3g_table() {
if ! command -v gpx >/dev/null 2>&1; then
	echo "gpx is not installed (make deps installs it)" >&2
	return 1
fi
[ -f "$out/dense-5k.gcode" ] || dense_gcode 5000 "$out/dense-5k.gcode"
(cd "$out" && gpx -m fcp dense-5k.gcode dense-5k.x3g >/dev/null 2>&1)
# dense_gcode is centred at 100,100, off the Creator Pro's bed: --force
# past the wrong-printer guard (the simulator has no bed to leave).
"$bin" x3g "$out/dense-5k.gcode" -o "$out/dense-5k-ours.x3g" --printer flashforge-creator-pro --force \
	>/dev/null 2>&1
echo "| host | input | commands | bytes out | s | commands/s | bytes/s | link fraction (both ways) | log == X3G |"
echo "|---|---|---|---|---|---|---|---|---|"
for host in gpx gcode x3g; do
	log="$out/s3g-$host.log"
	s3g_sim_start "$log"
	if [ "$host" = gpx ]; then
		t0=$(date +%s.%N)
		(cd "$out" && gpx -s -m fcp dense-5k.gcode "$(readlink s3g-tty)" >/dev/null 2>&1) || true
		t1=$(date +%s.%N)
		sleep 0.5
		n=$(grep -c '^[0-9]' "$log" || true)
		bytes=$(( $(stat -c %s "$out/dense-5k.x3g") + 3 * n ))
		secs=$(echo "$t1 - $t0" | bc)
		echo "| gpx -s $(dpkg-query -W -f='${Version}' gpx 2>/dev/null) | dense-5k.gcode | $n | $bytes | $(printf %.2f "$secs") | $(echo "$n / $secs" | bc) | $(echo "$bytes / $secs" | bc) | $(printf %.3f "$(echo "scale=4; ($bytes + 4 * $n) / $secs / 11520" | bc)") | $(s3g_log_matches "$out/dense-5k.x3g" "$log") |"
	else
		j="$out/s3g-stratum-$host.json"
		if [ "$host" = gcode ]; then in=dense-5k.gcode; ref=dense-5k-ours.x3g; else in=dense-5k.x3g; ref=dense-5k.x3g; fi
		"$bin" send "$out/$in" --port "$out/s3g-tty" --printer flashforge-creator-pro --force \
			--baud 115200 --json >"$j" 2>"$out/s3g-stratum-$host.err" || true
		n=$(json_any "$j" commands); bytes=$(json_any "$j" bytes_written); secs=$(json_any "$j" seconds)
		if [ -z "$n" ] || [ -z "$secs" ]; then
			echo "| stratum send | $in | failed, see $out/s3g-stratum-$host.err | | | | | | |"
		else
			echo "| stratum send | $in | $n | $bytes | $(printf %.2f "$secs") | $(echo "$n / $secs" | bc) | $(echo "$bytes / $secs" | bc) | $(printf %.3f "$(json_any "$j" link_fraction_both_ways)") | $(s3g_log_matches "$out/$ref" "$log") |"
		fi
	fi
	kill "$sim_pid" 2>/dev/null || true
	wait "$sim_pid" 2>/dev/null || true
done
}

# Exactly-once soak (issue 6 item 7 at full size): a 100 000-line file
# streamed by `stratum send` to a fresh simulator per fault, at 1 Mbaud with
# motion sped up so the run is short.  The check: every line number of the
# file executed once and in order, and how many executed lines differ from
# the file -- corruption Marlin's 8-bit XOR checksum cannot see (two flips
# of the same bit in one line), which no host can catch either.
soak_check() {
	LC_ALL=C awk '{ sub(/;.*/, ""); gsub(/^[ \t]+|[ \t]+$/, ""); if ($0 != "") print }' \
		"$1" >"$out/soak-want.txt"
	LC_ALL=C awk 'NR == FNR { want[++n] = $0; next }
		$1 ~ /^[0-9]+$/ && $2 != "M110" && $2 != "M115" && $2 != "M155" {
			k++; if (seen && $1 != prev + 1) gaps++
			prev = $1; seen = 1; sub(/^[0-9]+ /, ""); if ($0 != want[k]) diff++
		}
		END { printf "%s | %d | %d", (k == n && !gaps) ? "yes" : "NO", k, diff + 0 }' \
		"$out/soak-want.txt" "$2"
}
# soak_run DIALECT NAME FILE PROFILE SIM-OPTIONS... - one soak row's run: a
# fresh simulator, `stratum send` of FILE (bounded: the soak found ends of
# jobs that wait for ever), the simulator stopped; sets log and j.
soak_run() {
	dia=$1; name=$2; file=$3; prof=$4; shift 4
	log="$out/soak-$name.log"; j="$out/soak-$name.json"
	rm -f "$out/soak-tty"
	"$bin" sim --dialect "$dia" --baud 1000000 --speedup 1000000 --seed 7 "$@" \
		--link "$out/soak-tty" --log "$log" >"$out/soak-sim.out" 2>&1 &
	sim_pid=$!
	i=0
	while [ ! -L "$out/soak-tty" ] && [ $i -lt 100 ]; do sleep 0.05; i=$((i + 1)); done
	timeout 1800 "$bin" send "$file" --port "$out/soak-tty" --printer "$prof" --baud 1000000 \
		--json >"$j" 2>"$out/soak-$name.err" || true
	sim_stop
}
soak_table() {
[ -f "$out/dense-100k.gcode" ] || dense_gcode 100000 "$out/dense-100k.gcode"
sed 's/^rx_buffer_size = .*/rx_buffer_size = 32/' printers/generic-marlin.ini >"$out/marlin-rx32.ini"
echo "| fault | simulator | lines sent | every line once, in order | lines executed | changed lines the checksum missed | resends | s |"
echo "|---|---|---|---|---|---|---|---|"
# Each fault at 0.5 % and 2 % (issue 17 item 2), on the ring Marlin's AVR
# boards flush after a bad line and on the one 32-bit boards keep.
for v in clean rx32 rx32-adv \
	corrupt:0.005 corrupt:0.02 drop:0.005 drop:0.02 lose-ok:0.005 lose-ok:0.02 \
	keep-corrupt:0.005 keep-corrupt:0.02 keep-drop:0.005 keep-drop:0.02 \
	adv-corrupt:0.005 adv-corrupt:0.02; do
	prof=generic-marlin; extra=""; p=${v#*:}
	case $v in
	rx32) extra="--rx-buffer 32"; prof="$out/marlin-rx32.ini" ;;
	rx32-adv) extra="--rx-buffer 32 --advanced-ok"; prof="$out/marlin-rx32.ini" ;;
	corrupt:*) extra="--corrupt $p" ;;
	drop:*) extra="--drop $p" ;;
	lose-ok:*) extra="--lose-ok $p" ;;
	keep-corrupt:*) extra="--keep-rx --corrupt $p" ;;
	keep-drop:*) extra="--keep-rx --drop $p" ;;
	adv-corrupt:*) extra="--advanced-ok --corrupt $p --drop $p" ;;
	esac
	# shellcheck disable=SC2086
	soak_run marlin "$(echo "$v" | tr ':' '-')" "$out/dense-100k.gcode" "$prof" $extra
	echo "| $v | marlin ${extra:-defaults} | $(json_any "$j" lines) | $(soak_check "$out/dense-100k.gcode" "$log") | $(json_any "$j" resends) | $(json_any "$j" seconds) |"
done
# The Sailfish simulator: the same file translated to X3G, every command
# executed once and in order (its log against the X3G decoded).  It starts
# with M73 P0 as sliced files do, so the X3G starts a build (153): the line
# count of a running build is what settles a lost reply (docs/streaming.md).
{ echo "M73 P0"; cat "$out/dense-100k.gcode"; } >"$out/dense-100k-build.gcode"
"$bin" x3g "$out/dense-100k-build.gcode" -o "$out/dense-100k.x3g" --printer flashforge-creator-pro \
	--force >/dev/null 2>&1
echo
echo "| fault | simulator | commands sent | every command once, in order | retries | s |"
echo "|---|---|---|---|---|---|"
for v in clean corrupt:0.005 corrupt:0.02 drop:0.005 drop:0.02 replies:0.005 replies:0.02; do
	extra=""; p=${v#*:}
	case $v in
	corrupt:*) extra="--corrupt $p" ;;
	drop:*) extra="--drop $p" ;;
	replies:*) extra="--corrupt-replies $p" ;;
	esac
	# shellcheck disable=SC2086
	soak_run sailfish "sf-$(echo "$v" | tr ':' '-')" "$out/dense-100k.x3g" \
		flashforge-creator-pro $extra
	echo "| $v | sailfish ${extra:-defaults} | $(json_any "$j" commands) | $(s3g_log_matches "$out/dense-100k.x3g" "$log") | $(json_any "$j" retries) | $(json_any "$j" seconds) |"
done
}

# The farm node under load: a node with two test-instant printers on a
# loopback port, N uploads (a G-code file, multipart as PrusaSlicer sends
# it, stored with fsync, not queued) and M status requests, C concurrent
# clients each.  Counts and ab's -t bound keep it short.
serve_table() {
if ! command -v ab >/dev/null 2>&1; then echo "serve: ab (apache2-utils) is not installed: make bench installs it" >&2; return 0; fi
d="$out/serve-node"
rm -rf "$d"; mkdir -p "$d"
key=bench-key-0123456789abcdef
printf '[node]\nname = bench\nlisten = 127.0.0.1:0\ndata_dir = data\n[key bench]\nkey = %s\nroles = read, upload, control\n[printer mk3s]\nprofile = prusa-i3-mk3s\nport = test-instant\n[printer ender]\nprofile = creality-ender-3\nport = test-instant\n' "$key" >"$d/node.ini"
"$bin" serve --config "$d/node.ini" 2>"$d/node.log" &
node_pid=$!
port=""; i=0
while [ -z "$port" ] && [ $i -lt 200 ]; do
	port=$(sed -n 's/.*listening on 127.0.0.1:\([0-9]*\).*/\1/p' "$d/node.log" | head -n 1)
	sleep 0.05; i=$((i + 1))
done
b=------------------------d74496d66958873e
LC_ALL=C awk 'BEGIN { for (i = 0; i < 2048; i++) printf "G1 X%d.5 Y%d.25 E0.0123 F1800\n", i % 200, i % 190 }' >"$d/part.gcode"
{
	printf -- '--%s\r\nContent-Disposition: form-data; name="print"\r\n\r\nfalse\r\n' "$b"
	printf -- '--%s\r\nContent-Disposition: form-data; name="path"\r\n\r\n\r\n' "$b"
	printf -- '--%s\r\nContent-Disposition: form-data; name="file"; filename="part.gcode"\r\n' "$b"
	printf 'Content-Type: application/octet-stream\r\n\r\n'
	cat "$d/part.gcode"
	printf '\r\n--%s--\r\n' "$b"
} >"$d/upload.body"
size=$(stat -c %s "$d/part.gcode")
echo "| load (ab, $(nproc) cores, loopback) | requests | clients | requests/s | mean ms per request | failed | non-2xx |"
echo "|---|---|---|---|---|---|---|"
run_ab() { # label n c ab-args...
	label=$1; n=$2; c=$3; shift 3
	ab -q -t 60 -n "$n" -c "$c" -s 30 -H "X-Api-Key: $key" "$@" >"$d/ab.txt" 2>&1 || true
	rps=$(sed -n 's/^Requests per second: *\([0-9.]*\).*/\1/p' "$d/ab.txt")
	mean=$(sed -n 's/^Time per request: *\([0-9.]*\) \[ms\] (mean)$/\1/p' "$d/ab.txt")
	done_n=$(sed -n 's/^Complete requests: *\([0-9]*\)/\1/p' "$d/ab.txt")
	failed=$(sed -n 's/^Failed requests: *\([0-9]*\)/\1/p' "$d/ab.txt")
	non2xx=$(sed -n 's/^Non-2xx responses: *\([0-9]*\)/\1/p' "$d/ab.txt")
	echo "| $label | ${done_n:-0} | $c | ${rps:-?} | ${mean:-?} | ${failed:-?} | ${non2xx:-0} |"
}
run_ab "upload $size B G-code (multipart, fsync)" 500 4 -p "$d/upload.body" -T "multipart/form-data; boundary=$b" "http://127.0.0.1:$port/p/mk3s/api/files/local"
run_ab "GET /api/printer" 5000 8 "http://127.0.0.1:$port/api/printer"
run_ab "GET /api/job" 5000 8 "http://127.0.0.1:$port/p/ender/api/job"
run_ab "GET /api/stratum/node (status page poll)" 5000 8 "http://127.0.0.1:$port/api/stratum/node"
kill "$node_pid" 2>/dev/null || true
wait "$node_pid" 2>/dev/null || true
}

# The exact pass on self-intersecting input (issue 15 item 4): the pair
# search, the exact cuts and the re-triangulation (build/bench/refine_time,
# best of 3), then the whole `stratum repair` once (it may thicken sheets
# and run a second pass; bounded by 600 s).  Throughput = input triangles /
# wall s.
intersect_table() {
cgal=/usr/share/doc/libcgal-demo/data.tar.gz
for m in mannequin-devil ChineseDragon-10kv; do
	[ -f "$out/$m.off" ] || [ ! -f "$cgal" ] ||
		tar -xzf "$cgal" -O "data/meshes/$m.off" >"$out/$m.off" 2>/dev/null || rm -f "$out/$m.off"
done
[ -f "$out/soup-20k.stl" ] || "$gen" soup 20000 10 1 "$out/soup-20k.stl" >/dev/null
[ -f "$out/soup-200k.stl" ] || "$gen" soup 200000 10 1 "$out/soup-200k.stl" >/dev/null
echo "| file | triangles | intersecting pairs | triangles split | exact pass s (2 cores) | exact pass triangles/s | exact pass peak MiB | repair s | repair triangles/s | repair peak MiB | repair exit | printable |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
for f in mannequin-devil.off ChineseDragon-10kv.off spheres.stl twospheres.stl soup-20k.stl soup-200k.stl; do
	path="$out/$f"
	[ -f "$path" ] || continue
	best=""; bmem=""
	for _ in 1 2 3; do
		/usr/bin/time -q -f '%M' -o "$out/time.txt" "$refine" "$path" >"$out/refine.txt"
		read -r tris pairs split t rate < "$out/refine.txt"
		read -r mem < "$out/time.txt"
		if [ -z "$best" ] || [ "$(echo "$t < $best" | bc)" = 1 ]; then best=$t; brate=$rate; fi
		if [ -z "$bmem" ] || [ "$mem" -lt "$bmem" ]; then bmem=$mem; fi
	done
	rc=0
	/usr/bin/time -q -f '%e %M' -o "$out/time.txt" timeout 600 "$bin" repair --json "$path" \
		-o "$out/${f%.*}-repaired.stl" >"$out/${f%.*}-repair.json" 2>"$out/${f%.*}-repair.err" || rc=$?
	read -r rt rmem < "$out/time.txt"
	printable=$(json_field "$out/${f%.*}-repair.json" printable)
	[ "$rc" = 124 ] && rt="> 600"
	rrate=$( [ "$rc" != 124 ] && [ "$(echo "$rt > 0" | bc)" = 1 ] && echo "$tris / $rt" | bc || echo "n/a")
	echo "| ${f%.*} | $tris | $pairs | $split | $best | $brate | $(echo "scale=1; $bmem / 1024" | bc) | $rt | $rrate | $(echo "scale=1; $rmem / 1024" | bc) | $rc | ${printable:-n/a} |"
done
}

# The PrusaSlicer corpus: failures and skips listed, then the pass count.
corpus_table() {
	if ! command -v prusa-slicer >/dev/null 2>&1; then
		echo "prusa-slicer is not installed (make bench installs it)" >&2
		return 0
	fi
	bench/prusa_corpus.sh "$bin" "$out/prusa-corpus" >"$out/prusa-corpus.txt" 2>&1 || true
	grep -v '^pass ' "$out/prusa-corpus.txt"
}

# The CuraEngine corpus (bench/cura_corpus.sh): failures listed, then the pass count.
cura_table() {
	if ! command -v CuraEngine >/dev/null 2>&1 || [ ! -d /usr/share/cura/resources/definitions ]; then
		echo "CuraEngine or Cura's definitions are not installed (make bench installs them)" >&2
		return 0
	fi
	bench/cura_corpus.sh "$bin" "$out/cura-corpus" >"$out/cura-corpus.txt" 2>&1 || true
	grep -v '^pass ' "$out/cura-corpus.txt"
}

case $what in
corpus) corpus_table; echo; cura_table ;;
serve) serve_table ;;
x3g) x3g_table ;;
s3g) s3g_table ;;
region) region_table ;;
thin) thin_table ;;
gcodesize) gcodesize_table ;;
check) check_table ;;
repair) repair_table ;;
intersect) intersect_table ;;
slice) slice_table ;;
speed) speed_table ;;
stream) stream_table ;;
soak) soak_table ;;
all) check_table; echo; repair_table; echo; intersect_table; echo; slice_table; echo; speed_table; echo; region_table; echo; thin_table; echo; gcodesize_table; echo; stream_table; echo; soak_table; echo; x3g_table; echo; s3g_table; echo; serve_table; echo; corpus_table; echo; cura_table ;;
esac

