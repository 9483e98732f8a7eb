/*
 * gcode_writer_arc.c - arc_fitting (gcode_writer.h): the arcs of a run of
 * a path being simplified (arcfit.h), and an arc's time as Marlin prints
 * it, in chords (st_arc.h), for the estimate, the cooling and M73.
 */
#include "gcode_writer_int.h"

#include <math.h>

#include "st_arc.h"

int gcodew_arcs_run(struct gcodew *w, size_t i, size_t j, double tol,
		    int (*mark_lines)(struct gcodew *w, size_t a, size_t b, double tol))
{
	size_t count, prev = i;
	int rc = arcfit_find(&w->afit, w->sxy + 2 * i, j - i + 1, tol, &count, w->err);

	for (size_t n = 0; n < count && rc == 0; n++) {
		const struct arcfit_arc *a = &w->afit.arcs[n];
		size_t f = i + a->first, l = i + a->last;

		if (f > prev)
			rc = mark_lines(w, prev, f, tol);
		for (size_t k = f; k <= l; k++) {
			w->skeep[k] = k == f || k == l;
			w->smv[2 * k] = w->sxy[2 * k];
			w->smv[2 * k + 1] = w->sxy[2 * k + 1];
		}
		w->sarc[f] = (struct gcodew_arcseg){.arc = true,
						    .ccw = a->sweep > 0,
						    .cx = a->cx,
						    .cy = a->cy,
						    .len = a->radius * fabs(a->sweep)};
		prev = l;
	}
	if (rc == 0 && j > prev)
		rc = mark_lines(w, prev, j, tol);
	return rc;
}

int gcodew_arc_estimate(struct est_planner *p, const double from[EST_AXES],
			const double to[EST_AXES], double cx, double cy, bool ccw, double v,
			struct st_error *err)
{
	double rx = from[EST_X] - cx, ry = from[EST_Y] - cy;
	double ang = st_arc_sweep(rx, ry, to[EST_X] - cx, to[EST_Y] - cy, !ccw,
				  to[EST_X] == from[EST_X] && to[EST_Y] == from[EST_Y]);
	unsigned n = st_arc_segments(hypot(hypot(rx, ry) * fabs(ang), to[EST_Z] - from[EST_Z]));
	int rc = 0;

	for (unsigned k = 1; k <= n && rc == 0; k++) {
		double f = (double)k / n, c = cos(ang * f), s = sin(ang * f);
		struct est_move m = {cx + rx * c - ry * s, cy + rx * s + ry * c,
				     from[EST_Z] + (to[EST_Z] - from[EST_Z]) * f,
				     from[EST_E] + (to[EST_E] - from[EST_E]) * f, v};
		if (k == n) { /* the last chord ends on the target, as Marlin's */
			m.x = to[EST_X];
			m.y = to[EST_Y];
		}
		rc = est_planner_add(p, &m, err);
	}
	return rc;
}
