/*
 * exact.cpp - the CGAL side of exact.h: exact predicates (Epick) and the
 * self-intersection count of seed 000 Definition 3.6.
 *
 * Nothing C++ leaves this file: every extern "C" function validates its
 * arguments, catches every exception and answers with an st_status code.
 *
 * Self-intersection count, in three steps:
 *  1. One float box per usable triangle (24 bytes); skipped and degenerate
 *     triangles are not used, so they meet nothing.
 *  2. Pairs that share a vertex: stars.hpp, star by star, but for stars
 *     inside one flat patch (patches.hpp), proven free of intersections.
 *  3. Pairs that share nothing and no trusted patch: every pair of
 *     overlapping boxes once, from gridpairs.hpp or, where it declines,
 *     boxpairs.hpp (split over the cores along planes); each is decided
 *     by pairtest.hpp with exact predicates.
 */
#include "exact.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include "boxpairs.hpp"
#include "gridpairs.hpp"
#include "pairtest.hpp"
#include "patches.hpp"
#include "stars.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <exception>
#include <new>
#include <stdexcept>
#include <utility>
#include <vector>

namespace
{

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef K::Point_3 Point;
using boxpairs::Box;
using boxpairs::box_coord;

/* Whether all three coordinates of p are finite. */
bool finite3(const double p[3])
{
	return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

Point to_point(const double p[3])
{
	return Point(p[0], p[1], p[2]);
}

/* The stars a caller built (exact_count_self_intersections_stars). */
struct given_stars {
	const uint32_t *off, *tri;
};

/* The body of exact_count_self_intersections once arguments are checked;
 * given: NULL, or the caller's stars, skip then flagging every degenerate
 * triangle. */
int count_pairs(const double (*verts)[3], size_t nverts, const uint32_t (*tris)[3], size_t ntris,
		const uint8_t *skip, const given_stars *given, int threads, uint64_t *count,
		struct st_error *err)
{
	std::vector<Box> boxes(ntris);
	std::vector<uint32_t> use;
	std::vector<uint8_t> usable(ntris, 0);

	/* The boxes on all cores; the first triangle with a non-finite
	 * corner is the one reported, as a single pass would. */
	const size_t span = 16384;
	std::atomic<size_t> first_bad{ntris};
	boxpairs::for_each_index((ntris + span - 1) / span, threads, [&](size_t c) {
		for (size_t t = c * span; t < std::min(ntris, (c + 1) * span); t++) {
			const double *p[3];
			float lo[3], hi[3];

			if (skip && skip[t])
				continue;
			for (int k = 0; k < 3; k++)
				p[k] = verts[tris[t][k]];
			if (!finite3(p[0]) || !finite3(p[1]) || !finite3(p[2])) {
				size_t was = first_bad.load();
				while (t < was && !first_bad.compare_exchange_weak(was, t))
					;
				return;
			}
			if (!given &&
			    CGAL::collinear(to_point(p[0]), to_point(p[1]), to_point(p[2])))
				continue; /* degenerate: no box, as if skipped */
			for (int k = 0; k < 3; k++) {
				lo[k] = box_coord(std::min(std::min(p[0][k], p[1][k]), p[2][k]));
				hi[k] = box_coord(std::max(std::max(p[0][k], p[1][k]), p[2][k]));
			}
			boxes[t] = Box(lo, hi);
			usable[t] = 1;
		}
	});
	if (first_bad < ntris)
		return st_error_set(err, ST_ERR_ARG,
				    "exact: triangle %zu has a non-finite vertex "
				    "coordinate; check the input before counting",
				    first_bad.load());
	size_t nuse = 0;
	for (size_t t = 0; t < ntris; t++)
		nuse += usable[t];
	use.reserve(nuse);
	for (size_t t = 0; t < ntris; t++)
		if (usable[t])
			use.push_back(static_cast<uint32_t>(t));

	/* Patches proven flat (patches.hpp) and pairs that share a vertex:
	 * from the stars, never from the boxes; a star inside one patch
	 * needs no test of its own. */
	patches::table pt;
	patches::label(verts, nverts, tris, ntris, usable, threads, pt);
	stars::table st;
	if (!given)
		stars::build(tris, ntris, nverts, usable, st);
	auto star_size = [&](size_t v) -> size_t {
		return given ? given->off[v + 1] - given->off[v] : st.off[v + 1] - st.off[v];
	};
	auto star = [&](size_t v) {
		return given ? given->tri + given->off[v] : st.tri.data() + st.off[v];
	};
	auto get = [verts](uint32_t i) { return to_point(verts[i]); };
	std::atomic<uint64_t> near_hits{0};
	boxpairs::for_each_index(nverts, threads, [&](size_t v) {
		static thread_local stars::scratch s;
		static thread_local std::vector<uint32_t> sub;
		const size_t k = star_size(v);
		const uint32_t *list = star(v);
		if (patches::check_vertex(verts, static_cast<uint32_t>(v), list, k, tris, pt, s,
					  sub))
			return;
		const uint64_t h =
		    stars::count_in_star<K>(static_cast<uint32_t>(v), list, k, tris, get, s);
		if (h)
			near_hits += h;
	});
	if (given)
		patches::settle(verts, tris, given->off, given->tri, pt);
	else
		patches::settle(verts, tris, st.off.data(), st.tri.data(), pt);
	std::vector<size_t>().swap(st.off);
	std::vector<uint32_t>().swap(st.tri);
	std::vector<uint8_t>().swap(usable);
	patches::check_loops(verts, tris, ntris, pt);
	const std::vector<uint32_t> &patch = pt.tri;

	/* Pairs that share nothing and no patch: the boxes, on a grid where
	 * it is fast. */
	auto apart = [tris, &patch](size_t s, size_t t) {
		return (patch[s] == patches::NONE || patch[s] != patch[t]) &&
		       pairtest::no_common_corner(tris[s], tris[t]);
	};
	static_assert(patches::NONE == gridpairs::NO_GROUP, "a triangle in no patch is in no group");
	struct tag {
		uint32_t c[3], patch;
	};
	auto tag_of = [tris, &patch](uint32_t t) {
		return tag{{tris[t][0], tris[t][1], tris[t][2]}, patch[t]};
	};
	std::atomic<uint64_t> far_hits{0};
	if (gridpairs::for_each_pair(
		boxes, use, threads, tag_of, [](const tag &a) { return a.patch; },
		[](const tag &a, const tag &b) { return pairtest::no_common_corner(a.c, b.c); },
		[&](const tag &a, const tag &b) {
			if (pairtest::intersects<K>(a.c, b.c, get))
				far_hits++;
		})) {
		*count = near_hits + far_hits;
		return ST_OK;
	}
	std::vector<const Box *> all(use.size());
	for (size_t i = 0; i < use.size(); i++)
		all[i] = &boxes[use[i]];
	std::vector<uint32_t>().swap(use);
	std::vector<uint64_t> counts;
	boxpairs::for_each_pair(
	    boxes, std::move(all), threads, [&](size_t n) { counts.assign(n, 0); },
	    [&](size_t leaf, size_t s, size_t t) {
		    if (apart(s, t) && pairtest::intersects<K>(tris[s], tris[t], get))
			    counts[leaf]++;
	    });
	uint64_t total = near_hits;
	for (uint64_t c : counts)
		total += c;
	*count = total;
	return ST_OK;
}

} /* namespace */

extern "C" {

/* Exact collinearity; a non-finite coordinate counts as degenerate (true). */
bool exact_collinear(const double a[3], const double b[3], const double c[3])
{
	if (!a || !b || !c || !finite3(a) || !finite3(b) || !finite3(c))
		return true;
	try {
		return CGAL::collinear(to_point(a), to_point(b), to_point(c));
	} catch (...) {
		return true;
	}
}

/* Exact orientation sign; a non-finite coordinate counts as coplanar (0). */
int exact_orient3d(const double a[3], const double b[3], const double c[3], const double d[3])
{
	if (!a || !b || !c || !d || !finite3(a) || !finite3(b) || !finite3(c) || !finite3(d))
		return 0;
	try {
		switch (CGAL::orientation(to_point(a), to_point(b), to_point(c), to_point(d))) {
		case CGAL::POSITIVE:
			return 1;
		case CGAL::NEGATIVE:
			return -1;
		default:
			return 0;
		}
	} catch (...) {
		return 0;
	}
}

/* Check the arguments, then count with exceptions turned into codes. */
static int count_checked(const double (*verts)[3], size_t nverts, const uint32_t (*tris)[3],
			 size_t ntris, const uint8_t *skip, const given_stars *given, int threads,
			 uint64_t *count, struct st_error *err)
{
	if (!count)
		return st_error_set(err, ST_ERR_ARG, "exact: count output pointer is NULL");
	*count = 0;
	if (threads < 0)
		return st_error_set(err, ST_ERR_ARG,
				    "exact: thread count %d is negative; use 0 for all cores",
				    threads);
	if (ntris == 0)
		return ST_OK;
	if (!tris || (nverts && !verts))
		return st_error_set(err, ST_ERR_ARG,
				    "exact: NULL vertex or triangle array with nonzero count");
	for (size_t t = 0; t < ntris; t++)
		for (int k = 0; k < 3; k++)
			if (tris[t][k] >= nverts)
				return st_error_set(err, ST_ERR_ARG,
						    "exact: triangle %zu corner %d uses vertex %lu "
						    "but there are only %zu vertices",
						    t, k, (unsigned long)tris[t][k], nverts);
	try {
		return count_pairs(verts, nverts, tris, ntris, skip, given, threads, count, err);
	} catch (const std::bad_alloc &) {
		*count = 0;
		return st_error_set(err, ST_ERR_NOMEM,
				    "exact: out of memory counting self-intersections of %zu "
				    "triangles",
				    ntris);
	} catch (const std::length_error &) {
		*count = 0;
		return st_error_set(err, ST_ERR_NOMEM,
				    "exact: %zu triangles are too many to count "
				    "self-intersections for",
				    ntris);
	} catch (const std::exception &e) {
		*count = 0;
		return st_error_set(err, ST_ERR_INTERNAL,
				    "exact: self-intersection count failed inside CGAL/TBB: %s",
				    e.what());
	} catch (...) {
		*count = 0;
		return st_error_set(err, ST_ERR_INTERNAL,
				    "exact: self-intersection count failed with an unknown "
				    "exception");
	}
}

int exact_count_self_intersections(const double (*verts)[3], size_t nverts,
				   const uint32_t (*tris)[3], size_t ntris, const uint8_t *skip,
				   int threads, uint64_t *count, struct st_error *err)
{
	return count_checked(verts, nverts, tris, ntris, skip, NULL, threads, count, err);
}

int exact_count_self_intersections_stars(const double (*verts)[3], size_t nverts,
					 const uint32_t (*tris)[3], size_t ntris,
					 const uint8_t *skip, const uint32_t *star_off,
					 const uint32_t *star_tri, int threads, uint64_t *count,
					 struct st_error *err)
{
	if (ntris && (!skip || !star_off || !star_tri)) {
		if (count)
			*count = 0;
		return st_error_set(err, ST_ERR_ARG,
				    "exact: NULL skip flags or stars given to the count");
	}
	const given_stars given = {star_off, star_tri};
	return count_checked(verts, nverts, tris, ntris, skip, &given, threads, count, err);
}

} /* extern "C" */
