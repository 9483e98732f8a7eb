/*
 * ironing.c - the area and lines of ironing (see ironing.h).
 */
#include "ironing.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "patterns.h"
#include "settings.h"
#include "st_grow.h"
#include "toolpath.h"

/* Chord error of the inward offset, nm. */
#define IRON_ARC_NM 2000.0
/* Lines are linked when their ends are at most this many spacings apart
 * (PrusaSlicer's link_max_length for ironing). */
#define IRON_LINK_SPACINGS 3.0

int iron_type_parse(const char *name, enum iron_type *out, struct st_error *err)
{
	const struct setting *d = settings_find("ironing_type");

	for (size_t i = 0; d && name && i < d->nnames; i++)
		if (!strcmp(d->names[i], name)) {
			*out = (enum iron_type)i;
			return 0;
		}
	return st_error_set(err, ST_ERR_ARG,
			    "ironing: ironing_type \"%.32s\" is unknown; use top, topmost or solid",
			    name ? name : "(none)");
}

/* Whether the region inside the walls is filled solid throughout: what the
 * solid classes leave of it is less than a nozzle's square. */
static int solid_throughout(const struct clip_paths *inner, const struct clip_paths *solid,
			    double nozzle, bool *all, struct st_error *err)
{
	struct clip_paths rest = {0};
	double area = 0;
	int rc = clip_boolean(CLIP_DIFFERENCE, inner, solid, CLIP_NONZERO, &rest, err);

	if (!rc)
		rc = clip_paths_area(&rest, &area, err);
	*all = !rc && area < nozzle * nozzle * SLICE_UNITS_PER_MM * SLICE_UNITS_PER_MM;
	clip_paths_free(&rest);
	return rc;
}

int iron_area(enum iron_type type, bool top_layers, const struct slice_stack *st, size_t i,
	      const struct clip_paths *inner, const struct clip_paths *solid, double nozzle,
	      struct clip_paths *out, struct st_error *err)
{
	const struct clip_paths *S = &st->layers[i].regions.paths;
	const struct clip_paths *above = i + 1 < st->n ? &st->layers[i + 1].regions.paths : NULL;
	struct clip_paths A = {0}, inset = {0};
	bool all = false;
	int rc = 0;

	clip_paths_clear(out);
	if (type == IRON_SOLID)
		rc = solid_throughout(inner, solid, nozzle, &all, err);
	else if (!top_layers || (type == IRON_TOPMOST && above))
		return 0;
	if (!rc && all) {
		rc = clip_paths_append(&A, S, err);
	} else if (!rc) {
		rc = clip_boolean(CLIP_DIFFERENCE, S, above, CLIP_NONZERO, &A, err);
		if (!rc && type == IRON_SOLID) /* the first layer, and solid infill */
			rc = clip_paths_append(&A, i == 0 ? S : solid, err);
	}
	if (!rc)
		rc = clip_offset(S, -nozzle / 2 * SLICE_UNITS_PER_MM, CLIP_JOIN_ROUND, 0.0,
				 IRON_ARC_NM, &inset, err);
	if (!rc)
		rc = clip_boolean(CLIP_INTERSECTION, &A, &inset, CLIP_NONZERO, out, err);
	clip_paths_free(&A);
	clip_paths_free(&inset);
	return rc;
}

/* A clipped line: its index in the clipped set, its row (v / spacing)
 * and the positions along the direction, u, of its first and last point. */
struct line {
	size_t i;
	long row;
	double u_first, u_last;
};

/* Rows bottom to top, each along the direction. */
static int cmp_line(const void *pa, const void *pb)
{
	const struct line *a = pa, *b = pb;
	double ua = fmin(a->u_first, a->u_last), ub = fmin(b->u_first, b->u_last);

	if (a->row != b->row)
		return a->row < b->row ? -1 : 1;
	return (ua > ub) - (ua < ub);
}

/* Whether the link from p to q stays in the area: at a quarter, half and
 * three quarters of it (its ends are on the area's boundary). */
static bool link_inside(const struct clip_locator *loc, const int64_t *p, const int64_t *q)
{
	for (int s = 1; s <= 3; s++) {
		double t = s / 4.0;
		if (!clip_locator_inside(loc, llround(p[0] + t * (double)(q[0] - p[0])),
					 llround(p[1] + t * (double)(q[1] - p[1]))))
			return false;
	}
	return true;
}

/* Append the points of line l of segs to pts (*n values of *cap), forwards
 * or backwards.  0 or ST_ERR_NOMEM. */
static int take_line(const struct clip_paths *segs, const struct line *l, bool forward,
		     int64_t **pts, size_t *n, size_t *cap)
{
	const int64_t *xy = clip_path_xy(segs, l->i);
	size_t m = clip_path_len(segs, l->i);
	int64_t *grown = st_grow(*pts, cap, *n + 2 * m, sizeof(**pts));

	if (!grown)
		return ST_ERR_NOMEM;
	*pts = grown;
	for (size_t k = 0; k < m; k++) {
		size_t j = forward ? k : m - 1 - k;
		(*pts)[(*n)++] = xy[2 * j];
		(*pts)[(*n)++] = xy[2 * j + 1];
	}
	return 0;
}

/*
 * Join the lines of segs (direction a, rows spacing apart) into zigzags
 * appended to out, as PrusaSlicer's monotonic ironing does: from a line's
 * end to the nearer end of a line of the next row when they are at most
 * IRON_LINK_SPACINGS apart and the link stays inside area.
 */
static int link_lines(const struct clip_paths *segs, const struct clip_paths *area, double a,
		      double spacing, struct clip_paths *out, struct st_error *err)
{
	size_t n = segs->n, npts = 0, cap = 0;
	struct line *ls = calloc(n ? n : 1, sizeof(*ls));
	bool *used = calloc(n ? n : 1, sizeof(*used));
	struct clip_locator *loc = NULL;
	double ca = cos(a), sa = sin(a), reach = IRON_LINK_SPACINGS * spacing;
	int64_t *pts = NULL;
	int rc = 0;

	if (!ls || !used) {
		rc = st_error_set(err, ST_ERR_NOMEM, "ironing: out of memory linking %zu lines", n);
		goto out_free;
	}
	if (n && !(loc = clip_locator_new(area, err))) {
		rc = err ? err->code : ST_ERR_NOMEM;
		goto out_free;
	}
	for (size_t i = 0; i < n; i++) {
		const int64_t *xy = clip_path_xy(segs, i);
		size_t m = clip_path_len(segs, i);
		double v = -(xy[0] + xy[2 * m - 2]) / 2.0 * sa + (xy[1] + xy[2 * m - 1]) / 2.0 * ca;
		ls[i] = (struct line){i, lround(v / spacing), xy[0] * ca + xy[1] * sa,
				      xy[2 * m - 2] * ca + xy[2 * m - 1] * sa};
	}
	qsort(ls, n, sizeof(*ls), cmp_line);
	for (size_t s = 0; s < n && !rc; s++) {
		size_t cur = s;

		if (used[s])
			continue;
		npts = 0;
		used[s] = true;
		rc = take_line(segs, &ls[s], ls[s].u_first <= ls[s].u_last, &pts, &npts, &cap);
		while (!rc) { /* link the nearest free line of the next row */
			const int64_t *end = pts + npts - 2, *xy;
			size_t k = cur + 1, best = n, m;
			bool best_fwd = true;
			double bd = reach;

			while (k < n && ls[k].row <= ls[cur].row)
				k++;
			for (; k < n && ls[k].row == ls[cur].row + 1; k++) {
				xy = clip_path_xy(segs, ls[k].i);
				m = clip_path_len(segs, ls[k].i);
				double d0 = hypot((double)(xy[0] - end[0]), (double)(xy[1] - end[1]));
				double d1 = hypot((double)(xy[2 * m - 2] - end[0]),
						  (double)(xy[2 * m - 1] - end[1]));
				if (used[k] || fmin(d0, d1) > bd)
					continue;
				bd = fmin(d0, d1);
				best = k;
				best_fwd = d0 <= d1;
			}
			if (best == n)
				break;
			xy = clip_path_xy(segs, ls[best].i);
			m = clip_path_len(segs, ls[best].i);
			if (!link_inside(loc, end, best_fwd ? xy : xy + 2 * m - 2))
				break;
			used[best] = true;
			rc = take_line(segs, &ls[best], best_fwd, &pts, &npts, &cap);
			cur = best;
		}
		if (rc)
			rc = st_error_set(err, ST_ERR_NOMEM, "ironing: out of memory linking lines");
		else
			rc = clip_paths_add(out, pts, npts / 2, err);
	}
out_free:
	free(ls);
	free(used);
	free(pts);
	clip_locator_free(loc);
	return rc;
}

int iron_lines(const struct clip_paths *area, double a, double spacing, struct clip_paths *segs,
	       struct st_error *err)
{
	struct clip_paths lines = {0}, cut = {0};
	struct pat_box box;
	int rc = 0;

	clip_paths_clear(segs);
	if (!pat_box_of(area, &box))
		return 0;
	rc = pat_lines(a, spacing, 0.0, &box, &lines, err);
	if (!rc)
		rc = clip_lines(CLIP_INTERSECTION, &lines, area, CLIP_NONZERO, &cut, err);
	if (!rc)
		rc = link_lines(&cut, area, a, spacing, segs, err);
	clip_paths_free(&lines);
	clip_paths_free(&cut);
	return rc;
}
