#!/bin/sh
# lanes.sh CHECK_ALL STRATUM "SUITE ..." - run every Check suite of
# CHECK_ALL (tests/check_main.c) once, in CHECK_LANES (default 2) lanes at
# once (make test, make test-asan).  Each lane takes the next suite not yet
# taken when it finishes one, the suites named first, in that order (list
# the longest first), then the others; so the lanes end close together
# whatever the machine's load, and no list has to be kept in balance by
# hand.  The output of each suite is shown whole, in the order they were
# taken, then one line per lane (its wall time and suites), one Check
# summary line for all suites, and last the lines of the checks that failed
# (CI shows only the tail of the output); the exit status is 1 when a suite
# failed.  Logs, Check's XML (each test's duration: tests/durations.sh
# sums them) and the exit statuses stay in the lanes/ folder beside
# CHECK_ALL.
set -u
bin=$1 stratum=$2 first=$3
nlanes=${CHECK_LANES:-2}
dir=$(dirname "$bin")/lanes
rm -rf "$dir" && mkdir -p "$dir" || exit 1

all=$(STRATUM_CHECK_LIST=1 "$bin" | tr '\n' ' ')
[ -n "$all" ] || { echo "lanes: $bin listed no suite"; exit 1; }
queue=""
for s in $first; do
	case " $all " in
	*" $s "*) queue="$queue $s" ;;
	*) echo "lanes: '$s' is no suite of tests/check_main.c"; exit 1 ;;
	esac
done
for s in $all; do
	case " $queue " in *" $s "*) ;; *) queue="$queue $s" ;; esac
done
n=0
for s in $queue; do
	n=$((n + 1))
	echo "$s" >"$dir/queue.$n"
done

# lane K: take suites in queue order (mkdir claims one atomically), each
# suite's output in NAME.log, its status in NAME.rc; then the line
# "lane K: S s, SUITE (S s) ..." in laneK.
lane() {
	t0=$(date +%s) took=""
	i=1
	while [ $i -le $n ]; do
		if mkdir "$dir/claim.$i" 2>/dev/null; then
			s=$(cat "$dir/queue.$i")
			ts=$(date +%s)
			env STRATUM_BIN="$stratum" STRATUM_CHECK_ONLY="$s" \
				CK_XML_LOG_FILE_NAME="$dir/$s.xml" "$bin" >"$dir/$s.log" 2>&1
			echo $? >"$dir/$s.rc"
			took="$took $s ($(($(date +%s) - ts)) s)"
		fi
		i=$((i + 1))
	done
	echo "lane $1: $(($(date +%s) - t0)) s,$took" >"$dir/lane$1"
}
t0=$(date +%s)
k=1
while [ $k -le "$nlanes" ]; do
	lane $k &
	k=$((k + 1))
done
wait
# CPU time of every suite against wall time: near $nlanes times the wall,
# the lanes share the cores; far below, they wait (on simulated printers,
# child processes) and more lanes would end sooner.
times >"$dir/times"
cpu=$(tail -n 1 "$dir/times" | awk '{ t = 0; for (i = 1; i <= 2; i++) { split($i, a, /[ms]/); t += a[1] * 60 + a[2] } printf "%.0f", t }')

status=0
logs=""
for s in $queue; do
	cat "$dir/$s.log"
	logs="$logs $dir/$s.log"
	[ "$(cat "$dir/$s.rc" 2>/dev/null)" = 0 ] || status=1
done
missing=""
for s in $queue; do
	grep -aq '^[0-9]*%: Checks: ' "$dir/$s.log" || missing="$missing $s (exit $(cat "$dir/$s.rc"))"
done
cat "$dir"/lane[0-9]*
echo "lanes: $nlanes lanes, $(($(date +%s) - t0)) s wall, $cpu s CPU (user + system)"
# shellcheck disable=SC2086 # the logs' paths have no spaces (build folders)
awk -v want="$n" -v missing="$missing" '/^[0-9]+%: Checks: / { gsub(",", ""); c += $3; f += $5; e += $7; k++ }
     END { if (k != want) { printf "lanes: ended without their summary line:%s\n", missing; exit 1 }
	   printf "%d%%: Checks: %d, Failures: %d, Errors: %d\n", c ? (c - f - e) * 100 / c : 0, c, f, e }' \
	$logs || exit 1
# shellcheck disable=SC2086
if grep -aq ':[EF]:' $logs; then
	echo "lanes: the checks that failed:"
	grep -ah ':[EF]:' $logs
fi
exit $status
