#!/bin/sh
# durations.sh [N] XML... - where the time of a Check run went, from the XML
# logs Check writes when CK_XML_LOG_FILE_NAME is set (tests/lanes.sh writes
# one per suite): each suite's total, longest first, the N (default 15)
# longest tests, and the tests that ran out of time.  The order of the
# suites in the lanes of make test and make test-asan comes from it.
set -u
n=15
case ${1:-} in [0-9]*) n=$1; shift ;; esac
awk '
/<title>/   { gsub(/.*<title>|<\/title>.*/, ""); suite = $0 }
/<id>/      { gsub(/.*<id>|<\/id>.*/, ""); id = $0 }
/<duration>/ && suite != "" && id != "" {
	gsub(/.*<duration>|<\/duration>.*/, "")
	count[suite]++
	if ($0 < 0)	# Check writes -1 for a test that ran out of time
		printf "late %s:%s\n", suite, id
	else {
		total[suite] += $0
		printf "test %10.2f %s:%s\n", $0, suite, id
	}
	id = ""
}
END { for (s in total) printf "suite %9.2f %4d %s\n", total[s], count[s], s }
' "$@" >"${TMPDIR:-/tmp}/durations.$$"
echo "suites (s, tests, name):"
grep '^suite' "${TMPDIR:-/tmp}/durations.$$" | sort -k2,2 -rn | cut -c7-
echo "the $n longest tests (s, suite:test):"
grep '^test' "${TMPDIR:-/tmp}/durations.$$" | sort -k2,2 -rn | head -n "$n" | cut -c6-
if grep -q '^late' "${TMPDIR:-/tmp}/durations.$$"; then
	echo "ran out of time (not in the sums above):"
	grep '^late' "${TMPDIR:-/tmp}/durations.$$" | cut -c6-
fi
rm -f "${TMPDIR:-/tmp}/durations.$$"
