#!/bin/sh
# bench/cgal_corpus.sh BIN [LIMIT_S] - `stratum repair` on CGAL's data meshes
# (Debian's libcgal-demo: real broken models), as a new user would run it.
#
# Each mesh (OFF, OBJ, STL) is scaled to a largest extent of 100 mm, as seed
# 000's experiments do, and written as binary STL (build/bench/gen_mesh
# convert).  `stratum check` sorts them into already printable and needing
# repair; each is repaired with a LIMIT_S second limit (default 120), and the
# written file is judged by `stratum check` again; an already printable one
# must come back with the same triangles, bit for bit (gen_mesh same).  Prints one Markdown row
# per mesh and a summary for docs/benchmarks.md.  Wall time and peak RSS
# come from GNU time.
set -eu
bin=${1:-build/stratum}
limit=${2:-120}
out=bench/out/cgal
gen=${GEN_MESH:-build/bench/gen_mesh}
tarball=/usr/share/doc/libcgal-demo/data.tar.gz
mkdir -p "$out"

if [ ! -d "$out/data/meshes" ]; then
	[ -f "$tarball" ] || { echo "cgal_corpus: $tarball missing (make bench installs libcgal-demo)" >&2; exit 1; }
	tar -xzf "$tarball" -C "$out" data/meshes
fi

echo "| mesh | triangles | before | repair exit | s | peak MiB | after (stratum check) |"
echo "|---|---|---|---|---|---|---|"
n_ok=0; n_fix=0; n_fixed=0; n_kept=0; n_same=0; n_warned=0; n_70=0; n_slow=0; n_other=0; n_unread=0
for src in "$out"/data/meshes/*.off "$out"/data/meshes/*.obj "$out"/data/meshes/*.stl; do
	[ -f "$src" ] || continue
	name=$(basename "$src")
	stl="$out/${name%.*}-100mm.stl"
	if ! "$gen" convert "$src" 100 "$stl" >/dev/null 2>"$out/convert.err"; then
		n_unread=$((n_unread + 1))
		echo "| $name | - | unreadable: $(head -c 80 "$out/convert.err") | | | | |"
		continue
	fi
	tris=$(( ($(stat -c %s "$stl") - 84) / 50 ))
	warns=""
	if "$bin" check "$stl" >"$out/check.txt" 2>&1; then
		before=printable
		# Orientation warnings: repair turns those triangles, so they differ.
		warns=$(sed -n 's/^  warning \([a-z_]*\).*/\1/p' "$out/check.txt" | tr '\n' ' ')
	else
		before=needs_repair
	fi
	rc=0
	/usr/bin/time -q -f '%e %M' -o "$out/time.txt" timeout "$limit" \
		"$bin" repair "$stl" -o "$out/repaired.stl" >/dev/null 2>"$out/repair.err" || rc=$?
	read -r secs kib < "$out/time.txt" || { secs=-; kib=0; }
	after=-
	if [ "$rc" = 0 ]; then
		if "$bin" check "$out/repaired.stl" >/dev/null 2>&1; then after=printable; else
			after="not printable: $("$bin" check "$out/repaired.stl" 2>&1 | sed -n 's/^  reason  \([a-z_]*\).*/\1/p' | head -1)"
		fi
	fi
	case $rc in
	0) ;;
	70) n_70=$((n_70 + 1)) ;;
	124) n_slow=$((n_slow + 1)); rc="timeout ${limit} s" ;;
	*) n_other=$((n_other + 1)) ;;
	esac
	if [ "$before" = printable ]; then
		n_ok=$((n_ok + 1))
		[ "$after" = printable ] && n_kept=$((n_kept + 1))
		if [ "$rc" = 0 ] && "$gen" same "$stl" "$out/repaired.stl"; then
			n_same=$((n_same + 1)); after="$after, unchanged"
		elif [ -n "$warns" ]; then
			n_warned=$((n_warned + 1)); after="$after, reoriented (was: ${warns% })"
		fi
	else
		n_fix=$((n_fix + 1))
		[ "$after" = printable ] && n_fixed=$((n_fixed + 1))
	fi
	echo "| $name | $tris | $before | $rc | $secs | $((kib / 1024)) | $after |"
done
echo
echo "Already printable: $n_ok, printable after repair: $n_kept, of them unchanged bit for bit: $n_same, reoriented (inside out or inconsistently oriented before): $n_warned."
echo "Needing repair: $n_fix, printable after repair: $n_fixed."
echo "Exit 70: $n_70; over ${limit} s: $n_slow; other non-zero exits: $n_other; unreadable: $n_unread."
