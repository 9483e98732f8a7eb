/*
 * arcfit.h - circular arcs fitted to a polyline within a tolerance, with
 * the bound exact both ways: every point of the polyline (its vertices and
 * every point of its segments) lies within the tolerance of the arc, and
 * every point of the arc within the tolerance of the polyline.  The G-code
 * writer uses it for arc_fitting (gcode_writer.h); it works on integer
 * coordinates, nm.
 *
 * Why the test below is exact: seen from the arc's centre C, a segment
 * not through C sweeps its angle monotonically, and the distance from C
 * along it is largest at an end and smallest at its foot (the point
 * nearest C) when that lies inside it.  So when every segment turns the
 * arc's way, their angles add up to the arc's sweep (the polyline goes
 * round once, never back), and every vertex and every foot is within
 * tol of the radius r, then each ray from C inside the arc's wedge meets
 * the polyline at exactly one point Q with | |CQ| - r | <= tol, which is
 * the distance between Q and the arc's point on that ray.
 *
 * The arc is tested with the deviation at most tol less ARCFIT_SLACK_NM:
 * the writer rounds the end points and the centre to 1 um, which moves
 * the arc the firmware draws (around the rounded centre, with the radius
 * from the rounded start) by less than that.  Distances are computed in
 * doubles; for coordinates below 10^10 nm (10 m) their rounding is far
 * below 1 nm.
 *
 * Thread safety: a struct arcfit_work is used by one thread at a time.
 */
#ifndef STRATUM_SLICER_ARCFIT_H
#define STRATUM_SLICER_ARCFIT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "st_error.h"

/* What the tests keep to spare for the writer's rounding to 1 um, nm. */
#define ARCFIT_SLACK_NM 2500.0
/* Shortest chord an arc may have, nm: a shorter one's centre is ill
 * defined once rounded to 1 um (PrusaSlicer's ArcWelder refuses chords
 * under about 1.6 um for the same reason). */
#define ARCFIT_MIN_CHORD_NM 10000.0
/* Largest radius, nm: flatter arcs are left as lines. */
#define ARCFIT_MAX_RADIUS_NM 1e9

/* One arc: it replaces the polyline from point first to point last. */
struct arcfit_arc {
	size_t first, last; /* point indices, last >= first + 2 */
	double cx, cy;	    /* centre, nm */
	double radius;	    /* nm, from the centre to point first */
	double sweep;	    /* signed angle from first to last, rad; > 0 counter-clockwise */
};

/* Scratch memory reused across calls: zero-initialise it, then
 * arcfit_work_free once at the end. */
struct arcfit_work {
	struct arcfit_arc *arcs; /* arcfit_find's result */
	size_t cap;
};

/*
 * arcfit_find - arcs along the polyline xy[0 .. 2n) (x, y pairs, nm)
 * within tol nm (the bound at the top), found greedily from the start:
 * each arc is extended over as many points as still fit.  A stretch that
 * a straight segment already holds within tol is left to the lines, and
 * so is anything an arc fits only with a chord under ARCFIT_MIN_CHORD_NM
 * or a radius over ARCFIT_MAX_RADIUS_NM.  The arcs are in order and do
 * not overlap (one may start where the last ended); *count of them are in
 * wk->arcs.  A tol at most ARCFIT_SLACK_NM finds none.  Returns 0 or
 * ST_ERR_NOMEM.
 */
int arcfit_find(struct arcfit_work *wk, const int64_t *xy, size_t n, double tol, size_t *count,
		struct st_error *err);

/*
 * arcfit_deviation - the largest distance (nm) between the polyline
 * xy[2 first .. 2 last] and the arc around (cx, cy) from point first to
 * point last turning counter-clockwise when ccw, with the radius from the
 * centre to point first; INFINITY when the bound at the top does not
 * apply (a segment turns the other way or through the centre, or the
 * polyline goes round more or less than the arc).  *sweep (may be NULL)
 * gets the arc's signed angle.
 */
double arcfit_deviation(const int64_t *xy, size_t first, size_t last, double cx, double cy,
			bool ccw, double *sweep);

/* arcfit_work_free - release wk's memory and leave it empty; NULL is fine. */
void arcfit_work_free(struct arcfit_work *wk);

#endif /* STRATUM_SLICER_ARCFIT_H */
