/*
 * gcode_writer_simplify.c - gcode_resolution: each path and each routed
 * travel simplified before it is planned (simplify.h, gcode_writer.h).
 * A path is simplified run by run, a run being the points between two
 * changes of bead width, so segments of different widths never merge; its
 * kept points are moved so that it encloses the area it did (a round
 * wall's chords would otherwise print it smaller), within the same bound;
 * each run's filament is kept by printing its simplified segments with
 * the run's original length over its simplified length.  A closed loop
 * of one width is balanced whole, its seam moved too; the outer wall's
 * points then go on the written grid where they move its face least.  With
 * arc_fitting a run is first fitted with arcs (gcode_writer_arc.c) and
 * only the stretches between them are simplified to lines; its length
 * is then along the arcs.
 */
#include "gcode_writer_int.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "st_grow.h"

/* Out of memory for the scratch arrays. */
static int nomem(struct gcodew *w)
{
	return st_error_set(w->err, ST_ERR_NOMEM, "G-code: out of memory simplifying a path");
}

/* Grow w->f (capacity w->f##cap elements) to need elements, or return. */
#define GROW(f, need)                                                                              \
	do {                                                                                       \
		void *grown_ = st_grow(w->f, &w->f##cap, (need), sizeof(*w->f));                   \
		if (!grown_)                                                                       \
			return nomem(w);                                                           \
		w->f = grown_;                                                                     \
	} while (0)

/* Length (nm) of the polyline xy from point i to point j. */
static double run_length(const int64_t *xy, size_t i, size_t j)
{
	double len = 0;

	for (size_t k = i; k < j; k++)
		len += hypot((double)(xy[2 * k + 2] - xy[2 * k]), (double)(xy[2 * k + 3] - xy[2 * k + 1]));
	return len;
}

/* Length (nm) of the kept points (as moved, w->smv) from point i to point
 * j, along the arcs where arc_fitting fitted them. */
static double kept_length(const struct gcodew *w, size_t i, size_t j)
{
	const int64_t *xy = w->smv;
	double len = 0;

	for (size_t a = i, b = i + 1; b <= j; b++)
		if (w->skeep[b]) {
			if (gcodew_arcs(w) && w->sarc[a].arc)
				len += w->sarc[a].len;
			else
				len += hypot((double)(xy[2 * b] - xy[2 * a]),
					     (double)(xy[2 * b + 1] - xy[2 * a + 1]));
			a = b;
		}
	return len;
}

/* Mark the points i to j as lines within tol and move the kept ones so
 * the lines keep the area (simplify_balance); the ends stay, but for a
 * whole closed loop's seam (simplify_balance_loop). */
static int mark_lines(struct gcodew *w, size_t i, size_t j, double tol)
{
	size_t kept = 0;
	int rc = simplify_mark(&w->simp, w->sxy + 2 * i, j - i + 1, tol, w->skeep + i, w->err);

	if (rc)
		return rc;
	for (size_t k = i; k <= j; k++)
		kept += w->skeep[k];
	memcpy(w->smv + 2 * i, w->sxy + 2 * i, 2 * (j - i + 1) * sizeof(*w->smv));
	if (kept < j - i + 1) {
		GROW(sbal, 2 * kept);
		if (i == 0 && j == w->sloop)
			simplify_balance_loop(w->sxy, j + 1, w->skeep, tol, w->sbal);
		else
			simplify_balance(w->sxy + 2 * i, j - i + 1, w->skeep + i, tol, w->sbal);
		for (size_t k = i, c = 0; k <= j; k++)
			if (w->skeep[k]) {
				w->smv[2 * k] = w->sbal[2 * c];
				w->smv[2 * k + 1] = w->sbal[2 * c + 1];
				c++;
			}
	}
	return 0;
}

/*
 * Mark the run of segments [i, j) (points i to j): arcs where arc_fitting
 * fits them, lines between; then set its filament factor at each of its
 * points.
 */
static int mark_run(struct gcodew *w, size_t i, size_t j, double tol)
{
	double orig, now;
	size_t kept = 0;
	int rc;

	if (gcodew_arcs(w)) {
		for (size_t k = i; k <= j; k++)
			w->sarc[k].arc = false;
		rc = gcodew_arcs_run(w, i, j, tol, mark_lines);
	} else {
		rc = mark_lines(w, i, j, tol);
	}
	if (rc)
		return rc;
	for (size_t k = i; k <= j; k++)
		kept += w->skeep[k];
	orig = run_length(w->sxy, i, j);
	now = kept_length(w, i, j);
	if (kept == j - i + 1 || !(now > 0)) {
		/* Nothing dropped, or a run that would shrink to a point (a loop
		 * smaller than the tolerance): kept as it is. */
		for (size_t k = i; k <= j; k++)
			w->skeep[k] = true;
		if (gcodew_arcs(w))
			for (size_t k = i; k <= j; k++)
				w->sarc[k].arc = false;
		memcpy(w->smv + 2 * i, w->sxy + 2 * i, 2 * (j - i + 1) * sizeof(*w->smv));
		orig = now = 1;
	}
	for (size_t k = i; k < j; k++)
		w->sstretch[k] = orig / now;
	return 0;
}

/*
 * The part of gcode_resolution the outer wall (the part's face) is held
 * to.  At the full tolerance a round wall's chords, even balanced, leave
 * it up to 2/3 of the tolerance in and out of the surface: on a 20 mm
 * cylinder 6.4e-4 of the section's area, above the 5e-4 the printed
 * region is held to (docs/benchmarks.md, the region check); at half,
 * less than 4e-4.
 */
#define FACE_SHARE 0.5

/* Grid points on each side of the nearest one snap_face looks at. */
#define FACE_SNAP_REACH 2

/* Unit normal (*nx, *ny) of the segment from a to b; false when it has no length. */
static bool seg_normal(const struct path_point *a, const struct path_point *b, double *nx,
		       double *ny)
{
	double dx = (double)(b->x - a->x), dy = (double)(b->y - a->y), len = hypot(dx, dy);

	if (!(len > 0))
		return false;
	*nx = -dy / len;
	*ny = dx / len;
	return true;
}

/*
 * The outer wall's points (pts[0 .. n), a loop when closed) put on the
 * grid X and Y are written on (XYZ_UNITS): of the grid points within
 * FACE_SNAP_REACH of the nearest, the one that moves the point least
 * across the wall's segments on both sides of it.  Rounding to the nearest
 * grid point moves the part's face by up to 0.7 um, either way, which the
 * region check reads as the face standing out or in; along a smooth wall
 * the point may move along it instead (its beads' filament is planned on
 * the lengths as moved).  At a corner both segments hold it, so it goes
 * to the nearest grid point.
 */
static void snap_face(struct path_point *pts, size_t n, bool closed)
{
	const double g = SLICE_UNITS_PER_MM / XYZ_UNITS;
	struct path_point first = pts[0], prev = pts[closed ? n - 1 : 0];

	for (size_t k = 0; k < n; k++) {
		struct path_point here = pts[k];
		const struct path_point *next = k + 1 < n ? &pts[k + 1] : closed ? &first : NULL;
		double n1x = 0, n1y = 0, n2x = 0, n2y = 0;
		bool h1 = (k > 0 || closed) && seg_normal(&prev, &here, &n1x, &n1y);
		bool h2 = next && seg_normal(&here, next, &n2x, &n2y);
		if (!h1) {
			n1x = n2x;
			n1y = n2y;
		} else if (!h2) {
			n2x = n1x;
			n2y = n1y;
		}
		int64_t x0 = llround((double)here.x / g), y0 = llround((double)here.y / g);
		double best = INFINITY;
		for (int i = -FACE_SNAP_REACH; i <= FACE_SNAP_REACH && (h1 || h2); i++)
			for (int j = -FACE_SNAP_REACH; j <= FACE_SNAP_REACH; j++) {
				double dx = (double)(x0 + i) * g - (double)here.x;
				double dy = (double)(y0 + j) * g - (double)here.y;
				/* across first; of equals, the nearest */
				double cost = fmax(fabs(dx * n1x + dy * n1y), fabs(dx * n2x + dy * n2y)) +
					      1e-3 * hypot(dx, dy);
				if (cost < best) {
					best = cost;
					pts[k].x = (int64_t)((x0 + i) * (int64_t)g);
					pts[k].y = (int64_t)((y0 + j) * (int64_t)g);
				}
			}
		prev = here;
	}
}

int gcodew_simplify_path(struct gcodew *w, const struct toolpath *p, const struct toolpath **out)
{
	double tol = w->s->gcode_resolution * SLICE_UNITS_PER_MM *
		     (p->role == PATH_OUTER_PERIMETER ? FACE_SHARE : 1);
	size_t segs = p->closed ? p->n : p->n - 1, m = segs + 1, c = 0;
	int rc;

	*out = p;
	if (!(tol > 0) || p->n < 3)
		return 0;
	if (m > SIZE_MAX / 2)
		return nomem(w);
	GROW(sxy, 2 * m);
	GROW(smv, 2 * m);
	GROW(skeep, m);
	GROW(sidx, m);
	GROW(sstretch, m);
	GROW(spts, m);
	if (gcodew_arcs(w))
		GROW(sarc, m);
	for (size_t k = 0; k < m; k++) {
		w->sxy[2 * k] = p->pts[k % p->n].x;
		w->sxy[2 * k + 1] = p->pts[k % p->n].y;
	}
	w->sstretch[segs] = 1;
	w->sloop = 0;
	for (size_t i = 0, j; i < segs; i = j) {
		for (j = i + 1; j < segs && p->pts[j].width == p->pts[i].width; j++)
			;
		if (p->closed && i == 0 && j == segs)
			w->sloop = segs;
		if ((rc = mark_run(w, i, j, tol)))
			return rc;
	}
	/* The seam again at the end of a closed loop is its closing point,
	 * not a point of its own. */
	for (size_t k = 0; k < (p->closed ? segs : m); k++)
		if (w->skeep[k]) {
			w->spts[c] = p->pts[k];
			w->spts[c].x = w->smv[2 * k];
			w->spts[c].y = w->smv[2 * k + 1];
			w->sidx[c] = k;
			w->sstretch[c] = w->sstretch[k];
			if (gcodew_arcs(w))
				w->sarc[c] = w->sarc[k];
			c++;
		}
	if (p->role == PATH_OUTER_PERIMETER && !gcodew_arcs(w))
		snap_face(w->spts, c, p->closed);
	w->view = (struct toolpath){.role = p->role, .closed = p->closed, .n = c, .pts = w->spts};
	*out = &w->view;
	return 0;
}

int gcodew_simplify_route(struct gcodew *w, int64_t ax, int64_t ay)
{
	struct travel_route *r = &w->route;
	double tol = w->s->gcode_resolution * SLICE_UNITS_PER_MM;
	size_t m = r->n + 1, c = 0;
	int rc;

	if (!(tol > 0) || r->n < 2)
		return 0;
	if (m > SIZE_MAX / 2)
		return nomem(w);
	GROW(sxy, 2 * m);
	GROW(skeep, m);
	w->sxy[0] = ax;
	w->sxy[1] = ay;
	memcpy(w->sxy + 2, r->xy, 2 * r->n * sizeof(*r->xy));
	if ((rc = simplify_mark(&w->simp, w->sxy, m, tol, w->skeep, w->err)))
		return rc;
	for (size_t k = 1; k < m; k++)
		if (w->skeep[k]) {
			r->xy[2 * c] = w->sxy[2 * k];
			r->xy[2 * c + 1] = w->sxy[2 * k + 1];
			c++;
		}
	r->n = c;
	return 0;
}

void gcodew_simplify_free(struct gcodew *w)
{
	simplify_work_free(&w->simp);
	free(w->sxy);
	free(w->smv);
	free(w->sbal);
	free(w->skeep);
	free(w->sidx);
	free(w->sstretch);
	free(w->spts);
	free(w->sarc);
	arcfit_work_free(&w->afit);
}
