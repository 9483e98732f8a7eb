#!/bin/sh
# bench/support_runs.sh GCODE - the support a G-code file prints, per
# ;TYPE: of support ("Support material", "Support material interface"):
# its runs (extruding moves joined end to start; each run is an extrusion
# start and stop), its extruding moves and its filament in mm (absolute or
# relative E, G92 resets followed), for comparing how Stratum and
# PrusaSlicer link support and raft lines (docs/benchmarks.md).
set -eu
[ $# -eq 1 ] || { echo "usage: bench/support_runs.sh GCODE" >&2; exit 2; }
awk '
/^;TYPE:/ { t = substr($0, 7); prev = 0 }
/^M82/ { rel = 0 }
/^M83/ { rel = 1 }
/^G92/ { for (i = 2; i <= NF; i++) if ($i ~ /^E/) last = substr($i, 2) + 0 }
/^G[0-3] / {
	e = ""; xy = 0
	for (i = 2; i <= NF; i++) {
		if ($i ~ /^;/) break
		if ($i ~ /^E/) e = substr($i, 2) + 0
		if ($i ~ /^[XY]/) xy = 1
	}
	d = 0
	if (e != "") { d = rel ? e : e - last; if (!rel) last = e }
	if (!xy) next
	if (d > 0) { if (!prev) runs[t]++; moves[t]++; fil[t] += d; prev = 1 } else prev = 0
}
END {
	for (k in runs)
		if (k ~ /^Support/)
			printf "%s: %d runs, %d moves, %.1f mm\n", k, runs[k], moves[k], fil[k]
}' "$1" | sort
