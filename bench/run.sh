#!/bin/sh
# bench/run.sh BIN - time `stratum check` against admesh on the same
# generated files; prints a Markdown table for docs/benchmarks.md.
# Wall time and peak RSS come from GNU time; each figure is the best of 3 runs.
set -eu
bin=${1:-build/stratum}
out=bench/out
mkdir -p "$out"
gen=build/bench/gen_mesh

[ -f "$out/torus-1m.stl" ] || "$gen" torus 1000 500 "$out/torus-1m.stl"
[ -f "$out/torus-2m.stl" ] || "$gen" torus 1000 1000 "$out/torus-2m.stl"
[ -f "$out/spheres.stl" ] || "$gen" spheres 8 "$out/spheres.stl"

# best_of3 CMD... -> "seconds peak_kib" (exit status of CMD ignored: check exits 1
# for an unprintable mesh, which is a result, not a failure)
best_of3() {
	best_t=""; best_m=""
	for _ in 1 2 3; do
		/usr/bin/time -q -f '%e %M' -o "$out/time.txt" "$@" >/dev/null 2>&1 || true
		read -r t m < "$out/time.txt"
		if [ -z "$best_t" ] || [ "$(echo "$t < $best_t" | bc)" = 1 ]; then best_t=$t; fi
		if [ -z "$best_m" ] || [ "$m" -lt "$best_m" ]; then best_m=$m; fi
	done
	echo "$best_t $best_m"
}

echo "| file | triangles | stratum check s (2 cores) | 1 core s | peak MiB | B/triangle | admesh s | admesh MiB | time ratio stratum/admesh |"
echo "|---|---|---|---|---|---|---|---|---|"
for f in torus-1m torus-2m spheres; do
	path="$out/$f.stl"
	tris=$(( ($(stat -c %s "$path") - 84) / 50 ))
	set -- $(best_of3 "$bin" check "$path")
	st=$1; sm=$2
	set -- $(best_of3 "$bin" check --threads 1 "$path")
	st1=$1
	if command -v admesh >/dev/null 2>&1; then
		set -- $(best_of3 admesh "$path")
		at=$1; am=$2
		ratio=$(echo "scale=2; $st / $at" | bc)
		amib=$(echo "scale=1; $am / 1024" | bc)
	else
		at="n/a"; amib="n/a"; ratio="n/a"
	fi
	echo "| $f | $tris | $st | $st1 | $(echo "scale=1; $sm / 1024" | bc) | $(echo "$sm * 1024 / $tris" | bc) | $at | $amib | $ratio |"
done
