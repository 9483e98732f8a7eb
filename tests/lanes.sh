#!/bin/sh
# lanes.sh CHECK_ALL STRATUM "SUITE ..." - run the Check suites of CHECK_ALL
# in two lanes at once (make test, make test-asan): the suites named, and
# every other one (tests/check_main.c).  Most of the suites' time is spent
# waiting on simulated printers and child processes rather than on a core,
# so two lanes on two cores take little more than the longer one.  Each
# lane's output is shown whole, one after the other, then one Check summary
# line for both, and last the lines of the checks that failed (CI shows only
# the tail of the output); the exit status is 1 when either lane failed.
set -u
bin=$1 stratum=$2 lane=$3
dir=$(dirname "$bin")
# run_lane LOG VAR: the suites VAR=$lane selects, output in LOG, then a
# line "lane: S s" (its wall time) and the exit status in LOG.rc
run_lane() {
	t0=$(date +%s)
	env STRATUM_BIN="$stratum" "$2=$lane" "$bin" >"$1" 2>&1
	echo $? >"$1.rc"
	echo "lane: $(($(date +%s) - t0)) s" >>"$1"
}
run_lane "$dir/check-lane1.log" STRATUM_CHECK_ONLY &
p1=$!
run_lane "$dir/check-lane2.log" STRATUM_CHECK_EXCEPT &
p2=$!
wait $p1 $p2
r1=$(cat "$dir/check-lane1.log.rc")
r2=$(cat "$dir/check-lane2.log.rc")
echo "lanes: the first runs $lane"
cat "$dir/check-lane1.log" "$dir/check-lane2.log"
awk '/^[0-9]+%: Checks: / { gsub(",", ""); c += $3; f += $5; e += $7; n++ }
     END { if (n != 2) { print "lanes: a lane ended without its summary line"; exit 1 }
	   printf "%d%%: Checks: %d, Failures: %d, Errors: %d\n", c ? (c - f - e) * 100 / c : 0, c, f, e }' \
	"$dir/check-lane1.log" "$dir/check-lane2.log" || exit 1
if grep -aq ':[EF]:' "$dir/check-lane1.log" "$dir/check-lane2.log"; then
	echo "lanes: the checks that failed:"
	grep -ah ':[EF]:' "$dir/check-lane1.log" "$dir/check-lane2.log"
fi
[ $r1 -eq 0 ] && [ $r2 -eq 0 ]
