/*
 * simplify.h - Douglas-Peucker simplification of a polyline to a
 * tolerance, with the bound exact: every dropped point lies within the
 * tolerance of the segment between the two kept points around it (the
 * segment, not its line, so a point past either end of a hairpin is
 * kept).  The G-code writer uses it for gcode_resolution
 * (gcode_writer.h); it works on integer coordinates, nm.
 *
 * The distances are computed in doubles: the differences of two
 * coordinates are exact while they stay below 2^53 nm, and the rounding of
 * the products and the division adds less than 0.01 nm to a distance for
 * points less than 10^13 nm (10 km) apart.  A point is dropped only when
 * its computed distance is at most the tolerance less SIMPLIFY_SLACK_NM,
 * so its true distance is within the tolerance.
 *
 * Thread safety: a struct simplify_work is used by one thread at a time.
 */
#ifndef STRATUM_SLICER_SIMPLIFY_H
#define STRATUM_SLICER_SIMPLIFY_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "st_error.h"

/* What the distance test keeps to spare for rounding, nm. */
#define SIMPLIFY_SLACK_NM 1.0

/* Scratch memory reused across calls: zero-initialise it, then
 * simplify_work_free once at the end. */
struct simplify_work {
	size_t *stack; /* pending ranges, pairs of point indices */
	size_t cap;    /* pairs allocated */
};

/*
 * simplify_mark - mark the points of the polyline xy[0 .. 2n) (x, y pairs,
 * nm) that a simplification within tol nm keeps: keep[0] and keep[n - 1]
 * are set, each other keep[k] set or cleared.  Every point whose keep is
 * cleared lies at most tol from the segment between the nearest kept
 * points before and after it.  A tol at most SIMPLIFY_SLACK_NM keeps
 * every point.  Returns 0, or ST_ERR_NOMEM (keep then unchanged past the
 * first and last point).
 */
int simplify_mark(struct simplify_work *wk, const int64_t *xy, size_t n, double tol, bool *keep,
		  struct st_error *err);

/*
 * simplify_balance - the kept points of the polyline xy[0 .. 2n) (keep
 * from simplify_mark at tol) into out (2 per kept point, in order), the
 * first and last as they are and each other moved along the bisector of
 * its two segments, by the mean of the offsets that would make each
 * segment enclose no area with the points it replaces: a chord of an arc
 * moves outward by about two thirds of its sagitta, so a round wall keeps
 * its area instead of shrinking by the chords' sagittas.  When a moved
 * segment would leave any point of the polyline (dropped or kept) farther
 * than tol less SIMPLIFY_SLACK_NM from it, out gets the kept points
 * unmoved and false is returned; true when they moved.
 */
bool simplify_balance(const int64_t *xy, size_t n, const bool *keep, double tol, int64_t *out);

/*
 * simplify_balance_loop - simplify_balance for a closed loop, xy's last
 * point being its first again: that point (a wall's seam) moves too, for
 * the loop's last and first segments, and out ends with it again; else a
 * round wall's seam stays where the balanced chords around it have moved
 * out from, a dent of about two thirds of their sagitta.
 */
bool simplify_balance_loop(const int64_t *xy, size_t n, const bool *keep, double tol,
			   int64_t *out);

/*
 * simplify_keep - the points of xy[0 .. 2n) whose keep is set into out, in
 * order; returns how many.  out may be xy (compaction in place).
 */
size_t simplify_keep(const int64_t *xy, size_t n, const bool *keep, int64_t *out);

/*
 * simplify_seg_dist - the distance (nm) from (px, py) to the segment from
 * (ax, ay) to (bx, by), computed as simplify_mark does; a segment of no
 * length is its end point.
 */
double simplify_seg_dist(int64_t px, int64_t py, int64_t ax, int64_t ay, int64_t bx, int64_t by);

/* simplify_work_free - release wk's memory and leave it empty; NULL is fine. */
void simplify_work_free(struct simplify_work *wk);

#endif /* STRATUM_SLICER_SIMPLIFY_H */
