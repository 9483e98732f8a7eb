# bench/corpus_lib.sh - the stages the slicer corpora share (sourced by
# bench/prusa_corpus.sh and bench/cura_corpus.sh, issue 18 item 2): the
# model, and what each G-code a real slicer wrote must go through.  Uses $bin
# (the stratum binary).

# corpus_cube FILE: a 10 mm cube, ASCII STL (12 facets).
corpus_cube() {
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
	} >"$1"
}

# The commands of a G-code file as the simulator logs them, compared without
# blanks (the sender writes a line's words one blank apart: G28 XY is sent as
# G28 X Y) and with the command number as the sender writes it (G01 as G1):
# comments removed (`( )` ones too, but in the text of M0/M1/M117/M118 and
# the file commands), empty lines and OctoPrint's host commands
# (@BEDLEVELVISUALIZER: not for the printer) left out.
corpus_commands() {
	sed -e 's/;.*//' \
		-e '/^[[:space:]]*[Mm]\(0*0\|0*1\|117\|118\|23\|28\|30\|32\|33\)\([^0-9.]\|$\)/!s/([^)]*)//g' \
		-e 's/^\([[:space:]]*[GMTgmt]\)0*\([0-9]\)/\1\2/' -e 's/[[:space:]]//g' "$1" |
		tr -d '\r' | grep -v '^$' | grep -v '^@'
}

# corpus_node_prints DIR CONFIG GCODE: a `stratum serve` node for CONFIG on a
# test-instant port takes GCODE as PrusaSlicer uploads it (201) and prints it
# to the end (the job "done", every byte confirmed); why not in DIR/node.why.
corpus_node_prints() {
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
			# up to 180 s: the test double waits out each G4 dwell up to 60 s
			# (INAT's end G-code has G4 S180; Cura's Cartesio definition
			# dwells 20 + 20 + 9 s before the print and 7 + 90 s after)
			for _ in $(seq 1800); do
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

# corpus_stages DIR GCODE CONFIG DIALECT LAYERS [PREVIEW-OPTION ...]: GCODE
# (LAYERS layers) sliced for printer CONFIG
#  1. `stratum send` streams it to `stratum sim` (DIALECT: marlin or
#     sailfish) with --printer CONFIG: exit 0, and for Marlin the
#     simulator's log holds every command of the file once, in order;
#  2. `stratum preview` draws its middle layer (exit 0, a PNG), with the
#     PREVIEW-OPTIONs;
#  3. a node prints it (corpus_node_prints).
# Returns 0, or prints the failed stage with its detail and returns 1.
corpus_stages() {
	w=$1 gc=$2 ini=$3 dialect=$4 layers=$5
	shift 5
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
		echo "send exit $rc ($(tail -n 1 "$w/send.err" | head -c 300))"
		return 1
	fi
	if [ "$dialect" = marlin ]; then
		corpus_commands "$gc" >"$w/want.txt"
		want=$(wc -l <"$w/want.txt")
		# "- M105": the driver's own unnumbered probes when the board is
		# slow to answer (a loaded machine), not lines of the file
		grep -v '^- M105$' "$log" >"$w/sim-lines.log"
		got=$(wc -l <"$w/sim-lines.log")
		tail -n "$want" "$w/sim-lines.log" | cut -d' ' -f2- | sed 's/[[:space:]]//g' >"$w/got.txt"
		if [ "$got" -lt "$want" ] || [ $((got - want)) -gt 8 ] ||
			! cmp -s "$w/want.txt" "$w/got.txt"; then
			echo "the simulator's log is not the file ($got logged, $want in the file)"
			return 1
		fi
	fi
	mid=$((layers / 2 > 0 ? layers / 2 : 1))
	if ! "$bin" preview "$gc" --layer "$mid" -o "$w/mid.png" "$@" >/dev/null 2>"$w/preview.err" ||
		[ ! -s "$w/mid.png" ]; then
		echo "preview of layer $mid ($(tail -n 1 "$w/preview.err" | head -c 300))"
		return 1
	fi
	if ! corpus_node_prints "$w" "$ini" "$gc"; then
		echo "node upload ($(head -c 300 "$w/node.why"))"
		return 1
	fi
	return 0
}
