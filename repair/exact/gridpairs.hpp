/*
 * gridpairs.hpp - private to repair/exact: every pair of overlapping
 * triangle boxes, found with a hashed uniform grid when the triangles are
 * of similar size, as in a scanned or finely tessellated model.
 *
 * Why not always CGAL's box intersection (boxpairs.hpp): on such meshes it
 * spends about 0.4 s of one core per million triangles sorting, against
 * about a tenth of that here: each box goes into the few grid cells it
 * covers and only boxes sharing a cell are compared.  A grid is only good
 * while cells stay small, so for_each_pair() measures the work first and
 * declines (returns false) when boxes of very different sizes would put
 * too many boxes in a cell or a box in too many cells; the caller then
 * uses boxpairs.hpp.
 */
#ifndef STRATUM_REPAIR_EXACT_GRIDPAIRS_HPP
#define STRATUM_REPAIR_EXACT_GRIDPAIRS_HPP

#include "boxpairs.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>
#include <type_traits>
#include <vector>

namespace gridpairs
{

using boxpairs::Box;

/* What group() returns for a box that belongs to no group. */
const uint32_t NO_GROUP = UINT32_MAX;
/* Cells per axis at most (the cell key packs three 21-bit indices). */
const int64_t MAX_CELLS = (int64_t)1 << 21;
/* Declined above this many cell entries, or box comparisons, per box. */
const double MAX_ENTRIES_PER_BOX = 8, MAX_TESTS_PER_BOX = 48;
/* Cell side, in median largest box sides: each box covers about
 * 2-4 cells and a cell holds a handful of boxes. */
const double CELL_SIDE = 1.5;
/* Buckets with more entries than this are swept along x, not compared
 * all against all. */
const uint32_t SWEEP_ENTRIES = 32;
/* Side of the cells that sort out most boxes of one group first, in
 * grid cells: few cells per box and a table that stays in cache. */
const double COARSE_CELLS = 4;

struct grid {
	double origin[3], inv_side;
	uint64_t dim[2]; /* cells along x and y */
	uint64_t mask;	 /* buckets - 1 */
};

/* Cell index along axis k of x >= origin[k] (truncation is floor here;
 * through int64_t, which x86-64 converts in one instruction, the index
 * being far below 2^63). */
inline uint64_t cell_of(const grid &g, int k, float x)
{
	return (uint64_t)(int64_t)(((double)x - g.origin[k]) * g.inv_side);
}

/* Cells in raster order, wrapped onto the buckets: neighbouring cells get
 * neighbouring buckets, so walking the buckets walks through space. */
inline uint64_t bucket_of(const grid &g, uint64_t i, uint64_t j, uint64_t k)
{
	return (i + g.dim[0] * (j + g.dim[1] * k)) & g.mask;
}

/* Call f(bucket) for each cell box b covers. */
template <class F> void for_each_cell(const grid &g, const Box &b, F f)
{
	uint64_t lo[3], hi[3];

	for (int k = 0; k < 3; k++) {
		lo[k] = cell_of(g, k, b.min_coord(k));
		hi[k] = cell_of(g, k, b.max_coord(k));
	}
	for (uint64_t k = lo[2]; k <= hi[2]; k++)
		for (uint64_t j = lo[1]; j <= hi[1]; j++)
			for (uint64_t i = lo[0]; i <= hi[0]; i++)
				f(static_cast<uint32_t>(bucket_of(g, i, j, k)));
}

/* Whether two closed boxes meet; no early exit, as about half of the
 * pairs in a cell meet and a branch per axis would mispredict. */
inline bool overlap(const Box &a, const Box &b)
{
	return (a.max_coord(0) >= b.min_coord(0)) & (b.max_coord(0) >= a.min_coord(0)) &
	       (a.max_coord(1) >= b.min_coord(1)) & (b.max_coord(1) >= a.min_coord(1)) &
	       (a.max_coord(2) >= b.min_coord(2)) & (b.max_coord(2) >= a.min_coord(2));
}

/*
 * Of the boxes boxes[use[i]] with mixed[i] set, clear mixed[i] for those
 * whose buckets of grid g hold boxes (among those with mixed set) of
 * their own group only.  On all cores: each bucket's signature (its one
 * group, or NO_GROUP when mixed) ends the same whatever the order of the
 * updates.
 */
template <class TagOf, class Group>
void mark_mixed(const grid &g, const std::vector<Box> &boxes, const std::vector<uint32_t> &use,
		int threads, TagOf tag_of, Group group, std::vector<uint8_t> &mixed)
{
	const uint32_t EMPTY = NO_GROUP - 1;
	const size_t n = use.size(), nb = g.mask + 1, span = 16384;
	std::unique_ptr<std::atomic<uint32_t>[]> sig(new std::atomic<uint32_t>[nb]);
	boxpairs::for_each_index((nb + span - 1) / span, threads, [&](size_t c) {
		for (size_t b = c * span; b < std::min(nb, (c + 1) * span); b++)
			sig[b].store(EMPTY, std::memory_order_relaxed);
	});
	const size_t spans = (n + span - 1) / span;
	boxpairs::for_each_index(spans, threads, [&](size_t c) {
		for (size_t i = c * span; i < std::min(n, (c + 1) * span); i++) {
			if (!mixed[i])
				continue;
			const uint32_t gi = group(tag_of(use[i]));
			for_each_cell(g, boxes[use[i]], [&](uint32_t b) {
				uint32_t was = sig[b].load(std::memory_order_relaxed);
				while (was != gi && was != NO_GROUP &&
				       !sig[b].compare_exchange_weak(was, was == EMPTY ? gi : NO_GROUP,
								    std::memory_order_relaxed))
					;
			});
		}
	});
	boxpairs::for_each_index(spans, threads, [&](size_t c) {
		for (size_t i = c * span; i < std::min(n, (c + 1) * span); i++) {
			if (!mixed[i])
				continue;
			bool m = false;
			for_each_cell(g, boxes[use[i]], [&](uint32_t b) {
				m |= sig[b].load(std::memory_order_relaxed) == NO_GROUP;
			});
			mixed[i] = m;
		}
	});
}

/*
 * Call visit(tag_s, tag_t) once, from any thread, for every pair of
 * overlapping boxes (closed, as boxpairs.hpp) among boxes[use[..]] for which
 * keep(tag_s, tag_t) is true and group(tag_s) is NO_GROUP or differs from
 * group(tag_t), where tag_s = tag_of(s) is what the caller needs of box s
 * (a triangle's corners and patch).  The tags are copied beside the
 * sorted boxes: keep() runs for every overlapping pair (9 million on a
 * 1M-triangle UV sphere, most of them neighbours it turns away), and
 * looking the triangle up through its index missed the cache so often
 * that one load carried 17 % of the pair loop's samples.  Returns false,
 * having called nothing, when the grid would be slow for these boxes;
 * use then holds the indices still to be compared (perhaps fewer, in
 * another order: boxes that can meet none of another group are left
 * out), and boxes holds at least those.  On true, boxes and use are left empty: the boxes are
 * sorted into cell order (so that the pairs are walked through memory in
 * order), and keeping the unsorted copy as well would cost 24 bytes per
 * triangle.
 */
template <class TagOf, class Group, class Keep, class Visit>
bool for_each_pair(std::vector<Box> &boxes, std::vector<uint32_t> &use, int threads,
		   TagOf tag_of, Group group, Keep keep, Visit visit)
{
	typedef typename std::decay<decltype(tag_of(uint32_t()))>::type Tag;
	struct item {
		Box box;
		Tag tag;
	};
	size_t n = use.size();
	grid g;

	if (n < 2)
		return n == 1 || n == 0;
	/* Cell side from the median largest box side.  This pass and the
	 * next run on all cores, each span of boxes writing its own
	 * results (min, max and sums of whole numbers: the same whatever
	 * the order). */
	const size_t span = 16384, spans = (n + span - 1) / span;
	std::vector<float> side(n);
	std::vector<std::array<float, 6>> span_box(spans);
	boxpairs::for_each_index(spans, threads, [&](size_t c) {
		std::array<float, 6> &r = span_box[c];
		r = {HUGE_VALF, HUGE_VALF, HUGE_VALF, -HUGE_VALF, -HUGE_VALF, -HUGE_VALF};
		for (size_t i = c * span; i < std::min(n, (c + 1) * span); i++) {
			const Box &b = boxes[use[i]];
			float s = 0;
			for (int k = 0; k < 3; k++) {
				s = std::max(s, b.max_coord(k) - b.min_coord(k));
				r[k] = std::min(r[k], b.min_coord(k));
				r[3 + k] = std::max(r[3 + k], b.max_coord(k));
			}
			side[i] = s;
		}
	});
	float lo[3] = {HUGE_VALF, HUGE_VALF, HUGE_VALF}, hi[3] = {-HUGE_VALF, -HUGE_VALF, -HUGE_VALF};
	for (const std::array<float, 6> &r : span_box)
		for (int k = 0; k < 3; k++) {
			lo[k] = std::min(lo[k], r[k]);
			hi[k] = std::max(hi[k], r[3 + k]);
		}
	std::nth_element(side.begin(), side.begin() + n / 2, side.end());
	const double cell = CELL_SIDE * side[n / 2];
	std::vector<float>().swap(side);
	if (!(cell > 0) || !std::isfinite(cell))
		return false;
	g.inv_side = 1 / cell;
	for (int k = 0; k < 3; k++) {
		g.origin[k] = lo[k];
		if (!(((double)hi[k] - lo[k]) * g.inv_side < (double)(MAX_CELLS - 1)))
			return false;
	}
	g.dim[0] = cell_of(g, 0, hi[0]) + 1;
	g.dim[1] = cell_of(g, 1, hi[1]) + 1;

	/* Count cell entries first: decline before allocating much. */
	std::vector<double> span_entries(spans, 0);
	boxpairs::for_each_index(spans, threads, [&](size_t c) {
		for (size_t i = c * span; i < std::min(n, (c + 1) * span); i++) {
			const Box &b = boxes[use[i]];
			double e = 1;
			for (int k = 0; k < 3; k++)
				e *= (double)(cell_of(g, k, b.max_coord(k)) -
					      cell_of(g, k, b.min_coord(k)) + 1);
			span_entries[c] += e;
		}
	});
	double entries = 0;
	for (double e : span_entries)
		entries += e;
	if (entries > MAX_ENTRIES_PER_BOX * (double)n + 1024 || entries >= (double)UINT32_MAX)
		return false;
	/* A bucket per two entries: a cell holds about three, so most buckets
	 * still hold one cell, and the row table is half the size. */
	int bits = 10;
	while (((size_t)2 << bits) < (size_t)entries && bits < 31)
		bits++;
	const size_t nb = (size_t)1 << bits;
	g.mask = nb - 1;

	/*
	 * Sort the boxes into raster order of their low corner's cell (a
	 * counting sort on groups of 16 buckets, a table that stays in cache),
	 * keeping where each came from: the passes below then walk through
	 * memory in order whatever the order of the file.
	 */
	/*
	 * A bucket whose boxes all belong to one group gives no pair, and a
	 * box that only touches such buckets is left out before the sort:
	 * on a smooth surface cut into patches that is most of them.  Any
	 * two overlapping boxes share the cell of their overlap's low corner,
	 * so a pair of two groups always lands in a mixed bucket.  Cells of
	 * COARSE_CELLS a side go first (mark_mixed): both boxes of such a
	 * pair touch a coarse cell that is mixed, so a box whose coarse cells
	 * hold its own group only meets no other group's box; the fine cells
	 * are then signed by the boxes left alone.  Fewer boxes also mean
	 * fewer buckets mixed only by two cells sharing one (a 1M-triangle
	 * UV sphere: 86 000 boxes kept instead of 214 000, and the coarse
	 * table stays in cache).
	 */
	{
		grid coarse = g;
		coarse.inv_side = g.inv_side / COARSE_CELLS;
		coarse.dim[0] = cell_of(coarse, 0, hi[0]) + 1;
		coarse.dim[1] = cell_of(coarse, 1, hi[1]) + 1;
		const double ncoarse = (double)coarse.dim[0] * (double)coarse.dim[1] *
				       (double)(cell_of(coarse, 2, hi[2]) + 1);
		int coarse_bits = 10;
		while (coarse_bits < bits - 3 && (double)((size_t)1 << coarse_bits) < ncoarse)
			coarse_bits++;
		coarse.mask = ((size_t)1 << coarse_bits) - 1;
		std::vector<uint8_t> mixed(n, 1);
		mark_mixed(coarse, boxes, use, threads, tag_of, group, mixed);
		mark_mixed(g, boxes, use, threads, tag_of, group, mixed);
		size_t kept = 0;
		for (size_t i = 0; i < n; i++)
			if (mixed[i])
				use[kept++] = use[i];
		use.resize(kept);
		n = kept;
	}
	const int block_bits = bits > 4 ? 4 : 0;
	std::vector<uint32_t> id(n);
	{
		std::vector<uint32_t> first((nb >> block_bits) + 1, 0);
		auto block = [&](const Box &b) {
			return bucket_of(g, cell_of(g, 0, b.min_coord(0)), cell_of(g, 1, b.min_coord(1)),
					 cell_of(g, 2, b.min_coord(2))) >>
			       block_bits;
		};
		for (size_t i = 0; i < n; i++)
			first[block(boxes[use[i]]) + 1]++;
		for (size_t b = 0; b + 1 < first.size(); b++)
			first[b + 1] += first[b];
		for (size_t i = 0; i < n; i++)
			id[first[block(boxes[use[i]])]++] = use[i];
	}
	/* id holds the same indices as use: one copy is enough at the peak. */
	std::vector<uint32_t>().swap(use);
	/* The sorted copy replaces the given one (24 bytes per box less at
	 * the peak); it is put back if the grid declines below. */
	std::vector<item> sorted(n);
	/* Gathered on all cores: each read misses the cache (the file's order
	 * is not the cells'), and the second core is idle here. */
	const size_t gather = 16384;
	boxpairs::for_each_index((n + gather - 1) / gather, threads, [&](size_t c) {
		const size_t end_i = std::min(n, (c + 1) * gather);
		for (size_t i = c * gather; i < end_i; i++) {
			sorted[i].box = boxes[id[i]];
			sorted[i].tag = tag_of(id[i]);
		}
	});
	const size_t nboxes = boxes.size();
	std::vector<Box>().swap(boxes);

	/* Buckets in compressed rows; a box is listed once per cell, so twice
	 * in a bucket when two of its cells share it (then next to itself). */
	std::vector<uint32_t> off(nb + 1, 0);
	for (size_t i = 0; i < n; i++)
		for_each_cell(g, sorted[i].box, [&](uint32_t b) { off[b + 1]++; });
	double tests = 0;
	for (size_t b = 0; b < nb; b++) {
		tests += 0.5 * (double)off[b + 1] * (double)off[b + 1];
		off[b + 1] += off[b];
	}
	if (tests > MAX_TESTS_PER_BOX * (double)n + 4096) {
		boxes.resize(nboxes);
		for (size_t i = 0; i < n; i++)
			boxes[id[i]] = sorted[i].box;
		use = std::move(id);
		return false;
	}
	std::vector<uint32_t>().swap(id);
	std::vector<uint32_t> entry(off[nb]);
	for (size_t i = 0; i < n; i++)
		for_each_cell(g, sorted[i].box, [&](uint32_t b) { entry[off[b]++] = (uint32_t)i; });
	for (size_t b = nb; b > 0; b--)
		off[b] = off[b - 1];
	off[0] = 0;

	/* A pair is visited in the bucket of the cell holding the low corner
	 * of the two boxes' intersection: a cell both boxes cover.  keep()
	 * goes first: most overlapping pairs are neighbours it turns away,
	 * and finding that cell first cost three cell_of for each of them
	 * (2 % of the instructions of reading and counting a 1M-triangle
	 * sphere, 15 million overlapping pairs of which 2.3 million share
	 * no corner). */
	const size_t chunk = 4096;
	/* Whether the bucket's boxes all belong to one group (a patch whose
	 * pairs need no test): most buckets, on a smooth surface. */
	auto one_group = [&](uint32_t first, uint32_t last) {
		const uint32_t gr = group(sorted[entry[first]].tag);
		if (gr == NO_GROUP)
			return false;
		for (uint32_t i = first + 1; i < last; i++)
			if (group(sorted[entry[i]].tag) != gr)
				return false;
		return true;
	};
	boxpairs::for_each_index((nb + chunk - 1) / chunk, threads, [&](size_t c) {
		const size_t end_b = std::min(nb, (c + 1) * chunk);
		for (size_t b = c * chunk; b < end_b; b++) {
			const uint32_t first = off[b], last = off[b + 1];
			if (last - first < 2 || one_group(first, last))
				continue;
			/* A crowded bucket (the poles of a UV sphere put thousands
			 * of slivers in a few cells) is swept along x: sorted by
			 * low x, box i is compared only with the boxes that start
			 * before it ends.  The same pairs as comparing all, since
			 * min_x(i) <= min_x(j) makes that the only test on x that
			 * can fail; ties go by index, so a box listed twice stays
			 * next to itself. */
			const bool sweep = last - first > SWEEP_ENTRIES;
			if (sweep)
				std::sort(entry.begin() + first, entry.begin() + last,
					  [&](uint32_t u, uint32_t v) {
						  const float a = sorted[u].box.min_coord(0),
							      z = sorted[v].box.min_coord(0);
						  return a < z || (a == z && u < v);
					  });
			for (uint32_t i = first; i < last; i++) {
				const uint32_t s = entry[i];
				if (i > first && entry[i - 1] == s)
					continue;
				const item &is = sorted[s];
				const Box &bs = is.box;
				const uint32_t gs = group(is.tag);
				for (uint32_t j = i + 1; j < last; j++) {
					const uint32_t t = entry[j];
					if (t == entry[j - 1])
						continue;
					const item &it = sorted[t];
					const Box &bt = it.box;
					if (sweep && bt.min_coord(0) > bs.max_coord(0))
						break;
					if (gs != NO_GROUP && gs == group(it.tag))
						continue;
					if (!overlap(bs, bt) || !keep(is.tag, it.tag))
						continue;
					const uint64_t at = bucket_of(
					    g, cell_of(g, 0, std::max(bs.min_coord(0), bt.min_coord(0))),
					    cell_of(g, 1, std::max(bs.min_coord(1), bt.min_coord(1))),
					    cell_of(g, 2, std::max(bs.min_coord(2), bt.min_coord(2))));
					if (at == b)
						visit(is.tag, it.tag);
				}
			}
		}
	});
	return true;
}

} /* namespace gridpairs */

#endif /* STRATUM_REPAIR_EXACT_GRIDPAIRS_HPP */
