#!/bin/sh
# bench/cura_corpus.sh BIN OUTDIR [DEFINITION[=PROFILE] ...] - the CuraEngine
# corpus (issue 18 item 2): a 10 mm cube sliced by CuraEngine with each Cura
# printer definition below (or only the ones named), Marlin flavour, and each
# G-code through the stages of bench/corpus_lib.sh: `stratum send` to `stratum
# sim` (exit 0, the simulator's log == the file), `stratum preview` of the
# middle layer, printed by a `stratum serve` node.
#
# PROFILE is the Stratum printer the G-code is sent with: the shipped profile
# of the same printer where there is one, else printers/generic-marlin.ini
# with the definition's bed (machine_width, machine_depth, machine_height).
# CuraEngine leaves the {key} (and {key, EXTRUDER}) placeholders of a
# definition's start and end
# G-code as they are (Cura's front end replaces them before it calls the
# engine); the script replaces them the same way, with the values the engine
# reports it used.
# Cura's Marlin header names no filament diameter: the preview is given the
# definition's (material_diameter) with --filament-diameter.
# One line per definition: "pass DEF" or "FAIL DEF: STAGE (detail)", then
# "cura corpus: P of N definitions pass".  Exit 0 when all pass.  make bench
# runs every definition below; the send suite (tests/check_send.c) three.
set -u
bin=$1
dir=$2
shift 2
res=${CURA_RESOURCES:-/usr/share/cura/resources}
here=$(dirname "$0")
mkdir -p "$dir"
. "$here/corpus_lib.sh"
[ $# -gt 0 ] || set -- creality_ender3=creality-ender-3 prusa_i3_mk3=prusa-i3-mk3s \
	fdmprinter=generic-marlin creality_ender3pro creality_ender5 creality_cr10 \
	anycubic_i3_mega artillery_sidewinder_x1 prusa_i3 ultimaker2
cube=$dir/cube.stl
corpus_cube "$cube"

# setting KEY LOG: the value CuraEngine used (its log lists -s key="value").
setting() {
	grep -o " -s $1=\"[^\"]*\"" "$2" | head -n 1 | sed 's/^[^"]*"//; s/"$//'
}

pass=0 total=0
for dp in "$@"; do
	def=${dp%%=*} profile=
	[ "$def" != "$dp" ] && profile=${dp#*=}
	total=$((total + 1))
	w=$dir/$def
	mkdir -p "$w"
	raw=$w/engine.gcode gc=$w/cube.gcode
	# ultimaker2's own flavour is UltiGCode (no temperatures in the file):
	# every definition is sliced as RepRap (Marlin/Sprinter)
	if ! CURA_ENGINE_SEARCH_PATH=$res/definitions:$res/extruders timeout 300 \
		CuraEngine slice -j "$res/definitions/$def.def.json" \
		-s machine_gcode_flavor="RepRap (Marlin/Sprinter)" -l "$cube" -o "$raw" \
		>"$w/engine.log" 2>&1 || [ ! -s "$raw" ]; then
		echo "FAIL $def: CuraEngine ($(grep -v '^\[' "$w/engine.log" | tail -n 1 | head -c 200))"
		continue
	fi
	# the front end's {key} and {key, EXTRUDER} replacement (one extruder:
	# the value the engine used)
	grep -o '{[a-z_0-9]*\(, *[0-9]*\)\?}' "$raw" | sort -u | while read -r ph; do
		key=$(echo "$ph" | sed 's/^{\([a-z_0-9]*\).*/\1/')
		v=$(setting "$key" "$w/engine.log")
		# the front end's own variable: the first extruder, T0
		[ "$key" = initial_extruder_nr ] && v=0
		printf 's|%s|%s|g\n' "$ph" "$v"
	done >"$w/keys.sed"
	sed -f "$w/keys.sed" "$raw" >"$gc"
	if [ -n "$profile" ]; then
		profile=$here/../printers/$profile.ini
	else
		x=$(setting machine_width "$w/engine.log") y=$(setting machine_depth "$w/engine.log")
		x0=0 y0=0
		if [ "$(setting machine_center_is_zero "$w/engine.log")" = true ]; then
			x0=$(echo "-$x / 2" | bc -l) y0=$(echo "-$y / 2" | bc -l)
		fi
		x1=$(echo "$x0 + $x" | bc -l) y1=$(echo "$y0 + $y" | bc -l)
		profile=$w/printer.ini
		sed -e "s/^name = .*/name = Cura $def/" \
			-e "s/^bed_shape = .*/bed_shape = ${x0}x$y0,${x1}x$y0,${x1}x$y1,${x0}x$y1/" \
			-e "s/^max_print_height = .*/max_print_height = $(setting machine_height "$w/engine.log")/" \
			"$here/../printers/generic-marlin.ini" >"$profile"
	fi
	if ! why=$(corpus_stages "$w" "$gc" "$profile" marlin "$(grep -c '^;LAYER:' "$gc")" \
		--filament-diameter "$(setting material_diameter "$w/engine.log")"); then
		echo "FAIL $def: $why"
		continue
	fi
	echo "pass $def"
	pass=$((pass + 1))
done
echo "cura corpus: $pass of $total definitions pass ($(CuraEngine help 2>&1 | sed -n 's/^Cura_SteamEngine version //p' | head -n 1))"
[ "$pass" -eq "$total" ]
