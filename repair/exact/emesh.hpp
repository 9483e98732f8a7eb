/*
 * emesh.hpp - private to repair/exact: the layout of struct exact_mesh,
 * shared by the refinement (emesh.cpp), the queries (equery.cpp) and the
 * snap rounding (snap.cpp).
 */
#ifndef STRATUM_REPAIR_EXACT_EMESH_HPP
#define STRATUM_REPAIR_EXACT_EMESH_HPP

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <exception>
#include <mutex>
#include <new>
#include <stdexcept>
#include <unordered_map>
#include <vector>

#include "exact.h"
#include "st_error.h"

typedef CGAL::Epeck EK;
typedef CGAL::Epick IK;
typedef EK::Point_3 EPoint;
typedef EK::FT EFT;

/* For a point that cuts a triangle: not known to lie inside one of its
 * edges (else the edge's index k, from corner k to corner k + 1). */
static const int8_t NO_EDGE = -1;

/* Largest vertex or triangle count an exact mesh indexes (as struct mesh). */
static const size_t MESH_LIMIT = 0xfffffff0u;

/*
 * The caller's progress hook (exact_mesh_set_progress) counting a long
 * loop: called with 0 at the start, then about every 1 % from whichever
 * worker gets there, one call at a time (a worker finding another inside
 * the hook skips its turn rather than wait).
 */
struct exact_progress {
	exact_progress_fn fn = nullptr;
	void *ctx = nullptr;
};

class progress_count {
public:
	progress_count(const exact_progress &p, const char *stage, size_t total)
	    : p_(p), stage_(stage), total_(total), step_(total / 100 + 1)
	{
		if (p_.fn)
			p_.fn(p_.ctx, stage_, 0);
	}
	void one()
	{
		if (!p_.fn)
			return;
		const size_t d = ++done_;
		if (d % step_ == 0 && lock_.try_lock()) {
			p_.fn(p_.ctx, stage_, static_cast<double>(d) / static_cast<double>(total_));
			lock_.unlock();
		}
	}

private:
	const exact_progress &p_;
	const char *stage_;
	size_t total_, step_;
	std::atomic<size_t> done_{0};
	std::mutex lock_;
};

struct exact_mesh {
	exact_progress progress;		    /* exact_mesh_set_progress's hook */
	std::vector<std::array<double, 3>> approx; /* every vertex, mm */
	std::vector<int32_t> slot;		    /* -1: approx is exact; else index in ex */
	std::vector<EPoint> ex;			    /* exact positions of rational vertices */
	std::vector<std::array<uint32_t, 3>> tris;
	std::vector<uint32_t> origin;
	/* Per triangle: triangles with the same id lie exactly in one plane
	 * (pieces of one split triangle); different ids tell nothing. */
	std::vector<uint32_t> plane;
	uint32_t next_plane = 0; /* an id no triangle has yet */
	/* Per plane id of a triangle a refinement split: the corners of that
	 * triangle when they were doubles.  Its pieces lie exactly in their
	 * plane, so a test on them needs no rational cut point. */
	std::unordered_map<uint32_t, std::array<std::array<double, 3>, 3>> split_planes;
	/* Set by the last refinement only (empty after any other change):
	 * per triangle, the index before it of the triangle it is a piece of;
	 * per such index, 0 when a piece of it went to a coplanar overlap. */
	std::vector<uint32_t> parent;
	std::vector<uint8_t> parent_whole;

	void add_triangle(const std::array<uint32_t, 3> &t, uint32_t orig)
	{
		tris.push_back(t);
		origin.push_back(orig);
		plane.push_back(next_plane++);
		parent.clear();
		parent_whole.clear();
	}
};

namespace emesh
{

/*
 * The exact value of p, as CGAL::exact(p).  CGAL 5.5 guards the first
 * read of each lazy object's exact value with std::call_once, and glibc
 * ends every first call with a futex wake system call, even for a point
 * built from its exact value (a cut point) where there is nothing to
 * compute: about 3 % of a soup's repair.  A value that is already there
 * is read as call_once's fast path would, through an acquire load of the
 * pointer to it; anything else goes through CGAL::exact.
 */
template <class AT, class ET, class E2A> const ET &exact_of(const CGAL::Lazy<AT, ET, E2A> &x)
{
	if constexpr (CGAL::Lazy_rep_selector<AT>::value == 1) {
		const auto *rep = static_cast<const CGAL::Lazy_rep<AT, ET, E2A> *>(
		    static_cast<const CGAL::Rep *>(x.for_compact_container()));
		if (const ET *e = rep->ptr_.load(std::memory_order_acquire))
			return *e;
	}
	return CGAL::exact(x);
}

/* Vertex v of m as an exact point. */
inline EPoint epoint(const exact_mesh &m, uint32_t v)
{
	if (m.slot[v] >= 0)
		return m.ex[static_cast<size_t>(m.slot[v])];
	const std::array<double, 3> &a = m.approx[v];
	return EPoint(a[0], a[1], a[2]);
}

/* Vertex v of m as a double point (exact only for a double vertex). */
inline IK::Point_3 ipoint(const exact_mesh &m, uint32_t v)
{
	const std::array<double, 3> &a = m.approx[v];
	return IK::Point_3(a[0], a[1], a[2]);
}

/* Whether all three coordinates of p are finite. */
inline bool finite3(const double p[3])
{
	return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

/* Turn the current exception into an error class and message. */
inline int fail(struct st_error *err, const char *what)
{
	try {
		throw;
	} catch (const std::bad_alloc &) {
		return st_error_set(err, ST_ERR_NOMEM, "exact: out of memory in %s", what);
	} catch (const std::length_error &e) {
		return st_error_set(err, ST_ERR_NOMEM, "exact: %s: %s", what, e.what());
	} catch (const std::exception &e) {
		return st_error_set(err, ST_ERR_INTERNAL, "exact: %s failed: %s", what, e.what());
	} catch (...) {
		return st_error_set(err, ST_ERR_INTERNAL, "exact: %s failed with an unknown error",
				    what);
	}
}

} /* namespace emesh */

#endif /* STRATUM_REPAIR_EXACT_EMESH_HPP */
