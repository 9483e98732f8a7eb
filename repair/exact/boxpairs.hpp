/*
 * boxpairs.hpp - private to repair/exact: every pair of overlapping triangle
 * boxes, found with CGAL's box intersection, optionally on several cores.
 *
 * Used by the self-intersection count (exact.cpp) and by the exact
 * refinement (emesh.cpp); both then decide each candidate pair with exact
 * predicates.
 *
 * Why not box_self_intersection_d<Parallel_tag>: CGAL 5.5 copies the range
 * once for the self case and then 4 more times for each of its two ranges,
 * so ten pointer copies live at once (80 bytes per triangle plus the boxes),
 * and splits the work into 16 sub-problems of half the input each.  A plane
 * split keeps every box in about two pointer vectors (about 40 bytes per
 * triangle in all) and each box pair is looked at about once.  Measured on
 * a 1M-triangle torus, 2 cores: 105 vs 40 bytes per triangle, 0.75 vs 0.45 s.
 */
#ifndef STRATUM_REPAIR_EXACT_BOXPAIRS_HPP
#define STRATUM_REPAIR_EXACT_BOXPAIRS_HPP

#include <CGAL/box_intersection_d.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace boxpairs
{

typedef CGAL::Box_intersection_d::Box_d<float, 3, CGAL::Box_intersection_d::ID_FROM_BOX_ADDRESS>
    Box;

/* Below this many boxes a leaf is not split further (not worth a thread). */
const size_t MIN_SPLIT = 4096;

/* Below this many boxes CGAL's box intersection sweeps one axis instead
 * of splitting further (its default is 10).  On thickened soups, where
 * boxes of every size mix, the splits' sorting and partitioning were most
 * of the search: at 100 the box searches of soup-5k's repair took 0.61 of
 * their samples (one thread, perf), for the same pairs. */
const std::ptrdiff_t CUTOFF = 100;

/* Float box coordinates are clamped here so every box lies strictly inside
 * CGAL's float limits (+-FLT_MAX), which the segment tree treats as open. */
const float BOX_LIMIT = 1e38f;

/*
 * Round a double coordinate to float.  Rounding to nearest and clamping are
 * both monotone, so if two closed double intervals overlap (lo1 <= hi2 and
 * lo2 <= hi1) their rounded images overlap too: the float boxes never lose a
 * candidate pair.  They need not contain the double box for that.
 */
inline float box_coord(double x)
{
	float f = static_cast<float>(x);

	return std::min(std::max(f, -BOX_LIMIT), BOX_LIMIT);
}

/* A splitting plane: coordinate axis and position (mm). */
struct cut {
	int axis;
	double at;
};

/* Whether box b meets the plane c (closed, like the box overlap test). */
inline bool straddles(const Box *b, const cut &c)
{
	return b->min_coord(c.axis) <= c.at && c.at <= b->max_coord(c.axis);
}

/*
 * A share of the work: the boxes to intersect among themselves, and the
 * planes whose straddling pairs another leaf already reports.
 */
struct leaf {
	std::vector<const Box *> boxes;
	std::vector<cut> skip;
};

/*
 * Split a leaf into up to 2^depth leaves appended to out.  Cut X at the
 * median box centre on its widest axis into L (below the plane), S (meeting
 * it) and R (above).  L and R boxes cannot overlap, so the pairs of X are
 * those of L+S plus those of S+R that are not S-S: the right half gets the
 * plane in its skip list.  A split that would not shrink both halves much
 * (S over half of X) is not made.
 */
inline void split_leaf(leaf &&x, int depth, std::vector<leaf> &out)
{
	std::vector<const Box *> &v = x.boxes;
	const size_t n = v.size();
	double lo[3], hi[3];
	cut c;

	if (depth <= 0 || n < MIN_SPLIT) {
		out.push_back(std::move(x));
		return;
	}
	/* Centres are kept doubled (lo + hi), exact in double. */
	for (int k = 0; k < 3; k++) {
		lo[k] = HUGE_VAL;
		hi[k] = -HUGE_VAL;
	}
	for (const Box *b : v)
		for (int k = 0; k < 3; k++) {
			double m = (double)b->min_coord(k) + b->max_coord(k);
			lo[k] = std::min(lo[k], m);
			hi[k] = std::max(hi[k], m);
		}
	c.axis = 0;
	for (int k = 1; k < 3; k++)
		if (hi[k] - lo[k] > hi[c.axis] - lo[c.axis])
			c.axis = k;
	const int ax = c.axis;
	auto centre_less = [ax](const Box *a, const Box *b) {
		return (double)a->min_coord(ax) + a->max_coord(ax) <
		       (double)b->min_coord(ax) + b->max_coord(ax);
	};
	std::nth_element(v.begin(), v.begin() + n / 2, v.end(), centre_less);
	c.at = ((double)v[n / 2]->min_coord(ax) + v[n / 2]->max_coord(ax)) / 2;

	auto mid = std::partition(v.begin(), v.end(),
				  [&c](const Box *b) { return b->max_coord(c.axis) < c.at; });
	auto end_s = std::partition(mid, v.end(),
				    [&c](const Box *b) { return b->min_coord(c.axis) <= c.at; });
	const size_t nl = static_cast<size_t>(mid - v.begin());
	const size_t ns = static_cast<size_t>(end_s - mid);
	if (2 * ns > n) {
		out.push_back(std::move(x));
		return;
	}

	leaf right;
	right.boxes.assign(mid, v.end());
	right.skip = x.skip;
	right.skip.push_back(c);
	v.resize(nl + ns);
	v.shrink_to_fit();
	split_leaf(std::move(x), depth - 1, out);
	split_leaf(std::move(right), depth - 1, out);
}

/* Threads to use for a thread count as in exact.h (0 = all cores): more
 * threads than TBB has cores for only makes TBB print warnings. */
inline int concurrency(int threads)
{
	const int cores = tbb::this_task_arena::max_concurrency();

	return threads > 0 && threads < cores ? threads : cores;
}

/*
 * Call f(i) for every i < n on up to concurrency(threads) cores, in no
 * particular order; f must only write to what belongs to i.
 */
template <class F> void for_each_index(size_t n, int threads, F f)
{
	const int conc = concurrency(threads);

	if (conc <= 1 || n < 2) {
		for (size_t i = 0; i < n; i++)
			f(i);
		return;
	}
	tbb::task_arena arena(conc);
	arena.execute([&] {
		tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 16),
				  [&](const tbb::blocked_range<size_t> &r) {
					  for (size_t i = r.begin(); i != r.end(); i++)
						  f(i);
				  });
	});
}

/*
 * Call visit(leaf_index, s, t) once for every pair of overlapping boxes,
 * where s and t are indices into boxes; boxes not listed in use are left
 * out.  Calls with the same leaf_index come from one thread, so a visitor
 * may keep one unsynchronised output per leaf; nleaves receives how many
 * leaves there are (before the first call).  threads: 1 = this thread,
 * n > 1 = up to n cores, 0 = all.
 */
template <class Setup, class Visit>
void for_each_pair(const std::vector<Box> &boxes, std::vector<const Box *> &&use, int threads,
		   Setup setup, Visit visit)
{
	const Box *base = boxes.data();
	leaf all;

	all.boxes = std::move(use);
	const int conc = concurrency(threads);
	std::vector<leaf> leaves;
	if (conc <= 1) {
		leaves.push_back(std::move(all));
	} else {
		/* Twice as many leaves as threads, so an uneven split balances. */
		int depth = 1;
		while ((1 << depth) < 2 * conc && depth < 10)
			depth++;
		split_leaf(std::move(all), depth, leaves);
		/* Largest first: the long ones start early. */
		std::sort(leaves.begin(), leaves.end(), [](const leaf &a, const leaf &b) {
			return a.boxes.size() > b.boxes.size();
		});
	}
	setup(leaves.size());

	auto run = [&](size_t k) {
		leaf &l = leaves[k];
		auto cb = [&, k](const Box *a, const Box *b) {
			for (const cut &c : l.skip)
				if (straddles(a, c) && straddles(b, c))
					return;
			visit(k, static_cast<size_t>(a - base), static_cast<size_t>(b - base));
		};
		CGAL::box_self_intersection_d<CGAL::Sequential_tag>(
		    l.boxes.begin(), l.boxes.end(), cb, CUTOFF);
		std::vector<const Box *>().swap(l.boxes);
	};
	if (leaves.size() == 1) {
		run(0);
		return;
	}
	tbb::task_arena arena(conc);
	arena.execute([&] {
		tbb::task_group g;
		for (size_t k = 0; k < leaves.size(); k++)
			g.run([&, k] { run(k); });
		g.wait();
	});
}

} /* namespace boxpairs */

#endif /* STRATUM_REPAIR_EXACT_BOXPAIRS_HPP */
