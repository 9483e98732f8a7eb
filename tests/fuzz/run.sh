#!/bin/sh
# run.sh FUZZ_BUILD SECONDS BUILD CORPUS NAME... - run each libFuzzer target
# FUZZ_BUILD/fuzz_NAME for SECONDS seconds (make fuzz, docs/reliability.md).
# Corpora: CORPUS/NAME (kept between runs, grows), seeded from
# tests/fuzz/seeds/NAME and the test fixtures (tests/data, printers/, the
# example model, generated meshes, X3G translated from the G-code fixtures).
# A crash leaves FUZZ_BUILD/crash-NAME-* and fails the run; every target runs.
# FUZZ_JOBS targets (default 2, one per core) run at a time; their reports
# follow in the order of the names.
set -u
fb=$1 secs=$2 build=$3 corpora=$4
shift 4
jobs=${FUZZ_JOBS:-2}
gen=$fb/fixture-seeds

# Fixture seeds, made once per run (cheap).
rm -rf "$gen" && mkdir -p "$gen/meshio" "$gen/profile" "$gen/gcode" "$gen/x3g"
cp docs/examples/bracket.stl "$gen/meshio/" 2>/dev/null
if [ -x "$build/bench/gen_mesh" ]; then
	"$build/bench/gen_mesh" box 20 10 5 "$gen/meshio/box.stl" >/dev/null
	"$build/bench/gen_mesh" cylinder 5 10 8 "$gen/meshio/cylinder.stl" >/dev/null
	"$build/bench/gen_mesh" torus 6 4 "$gen/meshio/torus.stl" >/dev/null
	"$build/bench/gen_mesh" soup 12 5 1 "$gen/meshio/soup.stl" >/dev/null
	"$build/bench/gen_mesh" twospheres 5 6 "$gen/meshio/twospheres.stl" >/dev/null
fi
cp printers/*.ini "$gen/profile/"
cp tests/data/*.gcode "$gen/gcode/"
for g in tests/data/*.gcode; do
	"$build/stratum" x3g "$g" -o "$gen/x3g/$(basename "$g" .gcode).x3g" \
		--printer flashforge-creator-pro >/dev/null 2>&1
done

# Fuzz one target; its report goes to FUZZ_BUILD/fuzz_NAME.report, and the
# file FUZZ_BUILD/fuzz_NAME.failed says it failed.
fuzz_one() {
	name=$1
	corpus=$corpora/$name
	mkdir -p "$corpus"
	case $name in
	meshio) extra="$gen/meshio" ;;
	profile) extra="$gen/profile" ;;
	gcode_reader | gcode_line | x3g_translate) extra="$gen/gcode" ;;
	x3g_decode | s3g_frame) extra="$gen/x3g" ;;
	*) extra="" ;;
	esac
	# Inputs as long as libFuzzer's default (4096 bytes), not the 30 KB of
	# the sliced cube among the G-code seeds: these two read every line,
	# so an input costs its length, and 4 KB hold a hundred lines.
	maxlen=""
	case $name in
	gcode_reader | x3g_translate) maxlen=-max_len=4096 ;;
	esac
	# the node's threads keep what they allocate past one input
	leaks=1
	[ "$name" = http ] && leaks=0
	log=$fb/fuzz_$name.log
	report=$fb/fuzz_$name.report
	rm -f "$fb/fuzz_$name.failed"
	"$fb/fuzz_$name" -max_total_time="$secs" -timeout=10 -print_final_stats=1 $maxlen \
		-detect_leaks=$leaks -artifact_prefix="$fb/crash-$name-" \
		"$corpus" "tests/fuzz/seeds/$name" $extra >"$log" 2>&1
	rc=$?
	execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
	cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1)
	if [ $rc -ne 0 ]; then
		{
			echo "fuzz $name: FAILED (exit $rc) after ${execs:-?} executions; see $log"
			grep -m 3 -E 'ERROR|SUMMARY|runtime error' "$log"
		} >"$report"
		: >"$fb/fuzz_$name.failed"
	else
		echo "fuzz $name: ${execs:-?} executions in $secs s, $cov, no crash" >"$report"
	fi
}

status=0
report() {
	for done_name in "$@"; do
		if [ -e "$fb/fuzz_$done_name.failed" ]; then
			cat "$fb/fuzz_$done_name.report" >&2
			status=1
		else
			cat "$fb/fuzz_$done_name.report"
		fi
	done
}
batch=""
n=0
for name in "$@"; do
	fuzz_one "$name" &
	batch="$batch $name"
	n=$((n + 1))
	if [ $n -ge "$jobs" ]; then
		wait
		report $batch
		batch="" n=0
	fi
done
wait
report $batch
exit $status
