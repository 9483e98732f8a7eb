/*
 * gcode_writer_simplify.c - gcode_resolution: each path and each routed
 * travel simplified before it is planned (simplify.h, gcode_writer.h).
 * A path is simplified run by run, a run being the points between two
 * changes of bead width, so segments of different widths never merge; its
 * kept points are moved so that it encloses the area it did (a round
 * wall's chords would otherwise print it smaller), within the same bound;
 * each run's filament is kept by printing its simplified segments with
 * the run's original length over its simplified length.  With
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
 * the lines keep the area (simplify_balance); the ends stay. */
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
	for (size_t i = 0, j; i < segs; i = j) {
		for (j = i + 1; j < segs && p->pts[j].width == p->pts[i].width; j++)
			;
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
