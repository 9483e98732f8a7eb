#!/bin/sh
# bench/thin_walls.sh BIN [prusa] - thin walls against the region verifier
# (issue 19 item 2): walls 20 mm long and 2 mm tall of 0.5, 0.8, 1.0, 1.2,
# 1.5 and 2.0 mm, a wedge (20 mm long, 2 mm wide at its base) and a tube (a
# 1.0 mm wall around a 38 mm hole, a 256-gon), sliced by BIN
# with the MK3S profile and, with "prusa", by PrusaSlicer with
# bench/out/prusa-full.ini (`bench/run.sh BIN thin` writes it and runs
# this); both centred on 125,105.  Prints one
# Markdown row per model and slicer: the bead widths region_check reads
# back, the gap (model area no bead covers), the overlap (area under two
# runs), and the part's filament volume over the model's volume.
set -eu
bin=${1:-build/stratum}
prusa=${2:-}
out=bench/out/thin
gen=build/bench/gen_mesh
rc=build/bench/region_check
mkdir -p "$out"

# The part's filament, mm^3: extruding moves outside skirt, brim and custom
# G-code, absolute or relative E (M82/M83, G92), 1.75 mm filament.
part_volume() {
	awk '
	/^;TYPE:/ { skip = ($0 ~ /Skirt|Brim|Custom|Wipe|Support/) }
	/^M82/ { rel = 0 } /^M83/ { rel = 1 }
	/^G92/ { for (i = 2; i <= NF; i++) if ($i ~ /^E/) last = substr($i, 2) + 0 }
	/^G[0-3] / {
		e = ""; xy = 0
		for (i = 2; i <= NF; i++) {
			if ($i ~ /^;/) break
			if ($i ~ /^E/) e = substr($i, 2) + 0
			if ($i ~ /^[XY]/) xy = 1
		}
		if (e == "") next
		d = rel ? e : e - last
		if (!rel) last = e
		if (d > 0 && xy && started && !skip) sum += d
	}
	/^;TYPE:/ { started = 1 }
	END { printf "%.4f\n", sum * 3.14159265358979 * 0.875 * 0.875 }' "$1"
}

json_field() {
	sed -n "s/^  \"$2\": \([^,]*\),\{0,1\}\$/\1/p" "$1"
}

models="0.5 0.8 1.0 1.2 1.5 2.0 wedge tube"
echo "| model | slicer | beads mm (narrowest–widest) | gap % | overlap % | filament / model volume |"
echo "|---|---|---|---|---|---|"
for t in $models; do
	if [ "$t" = wedge ]; then
		f=wedge; vol=40
		[ -f "$out/$f.stl" ] || "$gen" wedge 20 2 2 "$out/$f.stl" >/dev/null
	elif [ "$t" = tube ]; then
		f=tube; vol=$(awk 'BEGIN { printf "%.4f", 128 * sin(3.14159265358979 / 128) * (400 - 361) * 2 }')
		[ -f "$out/$f.stl" ] || "$gen" tube 20 19 2 256 "$out/$f.stl" >/dev/null
	else
		f=wall-$t; vol=$(echo "20 * $t * 2" | bc)
		[ -f "$out/$f.stl" ] || "$gen" box 20 "$t" 2 "$out/$f.stl" >/dev/null
	fi
	"$bin" slice "$out/$f.stl" -o "$out/$f-stratum.gcode" --printer prusa-i3-mk3s \
		--center 125,105 >/dev/null 2>&1 || echo "failed: stratum slice $f" >&2
	slicers=stratum
	if [ "$prusa" = prusa ]; then
		prusa-slicer --export-gcode --load bench/out/prusa-full.ini --center 125,105 \
			-o "$out/$f-prusa.gcode" "$out/$f.stl" >/dev/null 2>&1 ||
			echo "failed: prusa-slicer $f" >&2
		slicers="stratum prusa"
	fi
	for s in $slicers; do
		j="$out/$f-$s-region.json"
		"$rc" "$out/$f.stl" "$out/$f-$s.gcode" --center 125,105 --json >"$j" ||
			{ echo "failed: region_check $f $s" >&2; continue; }
		name=stratum; [ "$s" = prusa ] && name=PrusaSlicer
		gap=$(echo "100 * $(json_field "$j" gap)" | bc -l)
		ovl=$(echo "100 * $(json_field "$j" overlap)" | bc -l)
		v=$(part_volume "$out/$f-$s.gcode")
		printf '| %s | %s | %.3f–%.3f | %.2f | %.2f | %.3f |\n' "$f" "$name" \
			"$(json_field "$j" width_min)" "$(json_field "$j" width_max)" "$gap" "$ovl" \
			"$(echo "$v / $vol" | bc -l)"
	done
done
