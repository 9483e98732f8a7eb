#!/bin/sh
# bench/prusa_corpus.sh BIN OUTDIR [VENDOR:PRESET ...] - the PrusaSlicer corpus
# (issue 18 item 2): for every printer preset of every vendor bundle
# PrusaSlicer ships (abstract *presets* and resin printers left out), or only
# the ones named,
#  1. `stratum printers --show --load BUNDLE --printer-preset P` resolves it
#     (inherits) into one flat config;
#  2. `prusa-slicer --export-gcode --load` that config slices a 10 mm cube;
#  3. `stratum send` streams the G-code to `stratum sim` (the preset's
#     protocol) with --printer that config: exit 0, and for Marlin the
#     simulator's log holds every command of the file once, in order;
#  4. `stratum preview` draws its middle layer (exit 0, a PNG);
#  5. a `stratum serve` node with that config on a test-instant port takes
#     the G-code as PrusaSlicer uploads it (201) and prints it to the end
#     (the job "done", every byte confirmed).
# One line per preset: "pass VENDOR: PRESET" or "FAIL VENDOR: PRESET: STAGE
# (detail)", then "corpus: P of N presets pass (S skipped: prusa-slicer
# refused the preset)".  Exit 0 when every preset that PrusaSlicer slices
# passes, 1 otherwise.  make bench runs it on the whole corpus; the
# send suite (tests/check_send.c) on a fixed sample.
set -u
bin=$1
dir=$2
shift 2
profiles=${PRUSA_PROFILES:-/usr/share/PrusaSlicer/profiles}
mkdir -p "$dir"

# The presets: "VENDOR<TAB>PRESET" lines (some bundles end their lines in CR LF).
list=$dir/presets.txt
if [ $# -gt 0 ]; then
	for vp in "$@"; do printf '%s\t%s\n' "${vp%%:*}" "${vp#*:}"; done >"$list"
else
	for b in "$profiles"/*.ini; do
		v=$(basename "$b" .ini)
		# resin printers (printer_technology = SLA) print no G-code: left out
		tr -d '\r' <"$b" | awk -v v="$v" '
			/^\[/ { if (name != "" && !sla) print v "\t" name; name = ""; sla = 0 }
			/^\[printer:[^*].*\]$/ { name = substr($0, 10, length($0) - 10) }
			/^printer_technology *= *SLA/ { sla = 1 }
			END { if (name != "" && !sla) print v "\t" name }'
	done >"$list"
fi

. "$(dirname "$0")/corpus_lib.sh"
cube=$dir/cube.stl
corpus_cube "$cube"

pass=0 total=0 skipped=0 n=0
tab=$(printf '\t')
while IFS=$tab read -r vendor preset; do
	n=$((n + 1))
	total=$((total + 1))
	w=$dir/p$n
	mkdir -p "$w"
	ini=$w/preset.ini gc=$w/cube.gcode
	fail() { echo "FAIL $vendor: $preset: $1"; }
	if ! "$bin" printers --show --load "$profiles/$vendor.ini" --printer-preset "$preset" \
		>"$ini" 2>"$w/show.err"; then
		fail "stratum printers --show ($(head -c 300 "$w/show.err"))"
		continue
	fi
	if ! timeout 300 prusa-slicer --export-gcode --load "$ini" -o "$gc" "$cube" \
		>"$w/prusa.log" 2>&1 || [ ! -s "$gc" ]; then
		echo "skip $vendor: $preset: prusa-slicer: $(grep -v '^\[' "$w/prusa.log" | tail -n 1 | head -c 200)"
		skipped=$((skipped + 1))
		continue
	fi
	dialect=marlin
	grep -q '^protocol = sailfish' "$ini" && dialect=sailfish
	if ! why=$(corpus_stages "$w" "$gc" "$ini" "$dialect" "$(grep -c '^;LAYER_CHANGE' "$gc")"); then
		fail "$why"
		continue
	fi
	echo "pass $vendor: $preset"
	pass=$((pass + 1))
done <"$list"
echo "corpus: $pass of $((total - skipped)) presets pass ($skipped skipped: prusa-slicer refused the preset)"
[ "$pass" -eq $((total - skipped)) ]
