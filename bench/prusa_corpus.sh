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
# slicecli suite (tests/check_slicecli.c) on a fixed sample.
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

# A 10 mm cube, ASCII STL (12 facets).
cube=$dir/cube.stl
{
	echo "solid cube"
	for f in "0 0 0 10 10 0 10 0 0" "0 0 0 0 10 0 10 10 0" "0 0 10 10 0 10 10 10 10" \
		 "0 0 10 10 10 10 0 10 10" "0 0 0 10 0 0 10 0 10" "0 0 0 10 0 10 0 0 10" \
		 "0 10 0 10 10 10 10 10 0" "0 10 0 0 10 10 10 10 10" "0 0 0 0 0 10 0 10 10" \
		 "0 0 0 0 10 10 0 10 0" "10 0 0 10 10 0 10 10 10" "10 0 0 10 10 10 10 0 10"; do
		set -- $f
		printf 'facet normal 0 0 0\nouter loop\nvertex %s %s %s\nvertex %s %s %s\nvertex %s %s %s\nendloop\nendfacet\n' "$@"
	done
	echo "endsolid cube"
} >"$cube"

# The commands of a G-code file as the simulator logs them, compared without
# blanks (the sender writes a line's words one blank apart: G28 XY is sent as
# G28 X Y): comments removed, empty lines and OctoPrint's host commands
# (@BEDLEVELVISUALIZER: not for the printer) left out.
commands() {
	sed -e 's/;.*//' -e 's/[[:space:]]//g' "$1" | tr -d '\r' | grep -v '^$' | grep -v '^@'
}

# Stage 5 in folder $1: a node for config $2, G-code $3 uploaded and printed.
node_prints() {
	key=corpus-upload-key-0123
	printf '[node]\nname = corpus\nlisten = 127.0.0.1:0\ndata_dir = %s/node\n\n[key up]\nkey = %s\nroles = read, upload\n\n[printer p]\nprofile = %s\nport = test-instant\n' \
		"$1" "$key" "$2" >"$1/node.ini"
	"$bin" serve --config "$1/node.ini" >/dev/null 2>"$1/node.log" &
	node=$!
	port=
	for _ in $(seq 100); do
		port=$(sed -n 's/.*listening on 127.0.0.1:\([0-9]*\).*/\1/p' "$1/node.log")
		[ -n "$port" ] && break
		sleep 0.1
	done
	ok=1
	if [ -z "$port" ]; then
		tail -n 1 "$1/node.log" >"$1/node.why"
	else
		code=$(curl -s -o "$1/upload.json" -w '%{http_code}' -H "X-Api-Key: $key" \
			-F print=true -F "file=@$3;filename=cube.gcode" \
			"http://127.0.0.1:$port/api/files/local")
		if [ "$code" != 201 ]; then
			echo "HTTP $code $(head -c 250 "$1/upload.json")" >"$1/node.why"
		else
			# up to 90 s: the test double waits out G4 dwells of up to 60 s
			# (INAT's end G-code has G4 S180)
			for _ in $(seq 900); do
				curl -s -H "X-Api-Key: $key" "http://127.0.0.1:$port/api/stratum/queue" \
					>"$1/queue.json"
				grep -q '"state":"\(done\|failed\|cancelled\)"' "$1/queue.json" && break
				sleep 0.1
			done
			size=$(wc -c <"$3")
			if grep -q "\"state\":\"done\".*\"filepos\":$size,\"size\":$size" "$1/queue.json"; then
				ok=0
			else
				head -c 300 "$1/queue.json" >"$1/node.why"
			fi
		fi
	fi
	kill "$node" 2>/dev/null
	wait "$node" 2>/dev/null
	return $ok
}

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
	link=$w/tty log=$w/sim.log
	"$bin" sim --dialect "$dialect" --baud 4000000 --speedup 100000 --link "$link" \
		--log "$log" >/dev/null 2>&1 &
	sim=$!
	for _ in $(seq 50); do [ -e "$link" ] && break; sleep 0.1; done
	timeout 600 "$bin" send "$gc" --port "$link" --printer "$ini" --baud 4000000 \
		>"$w/send.out" 2>"$w/send.err"
	rc=$?
	kill "$sim" 2>/dev/null
	wait "$sim" 2>/dev/null
	if [ $rc -ne 0 ]; then
		fail "send exit $rc ($(tail -n 1 "$w/send.err" | head -c 300))"
		continue
	fi
	if [ "$dialect" = marlin ]; then
		commands "$gc" >"$w/want.txt"
		want=$(wc -l <"$w/want.txt")
		got=$(wc -l <"$log")
		tail -n "$want" "$log" | cut -d' ' -f2- | sed 's/[[:space:]]//g' >"$w/got.txt"
		if [ "$got" -lt "$want" ] || [ $((got - want)) -gt 8 ] ||
			! cmp -s "$w/want.txt" "$w/got.txt"; then
			fail "the simulator's log is not the file ($got logged, $want in the file)"
			continue
		fi
	fi
	layers=$(grep -c '^;LAYER_CHANGE' "$gc")
	mid=$((layers / 2 > 0 ? layers / 2 : 1))
	if ! "$bin" preview "$gc" --layer "$mid" -o "$w/mid.png" >/dev/null 2>"$w/preview.err" ||
		[ ! -s "$w/mid.png" ]; then
		fail "preview of layer $mid ($(tail -n 1 "$w/preview.err" | head -c 300))"
		continue
	fi
	if ! node_prints "$w" "$ini" "$gc"; then
		fail "node upload ($(head -c 300 "$w/node.why"))"
		continue
	fi
	echo "pass $vendor: $preset"
	pass=$((pass + 1))
done <"$list"
echo "corpus: $pass of $((total - skipped)) presets pass ($skipped skipped: prusa-slicer refused the preset)"
[ "$pass" -eq $((total - skipped)) ]
