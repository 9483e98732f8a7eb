/*
 * overhang.c - walls cut where they overhang the layer below (overhang.h).
 */
#include "overhang.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "perimeters.h"
#include "section.h"
#include "st_grow.h"

/* Chord error of the grown layer below, nm. */
#define OVERHANG_ARC_NM 2000.0

/* Where a piece being built stands. */
struct piece {
	struct path_point *pts;
	size_t n, cap;
};

static int piece_add(struct piece *pc, int64_t x, int64_t y, int64_t width)
{
	struct path_point *grown = st_grow(pc->pts, &pc->cap, pc->n + 1, sizeof(*grown));

	if (!grown)
		return ST_ERR_NOMEM;
	pc->pts = grown;
	pc->pts[pc->n++] = (struct path_point){x, y, width};
	return 0;
}

/* The bead of an overhanging piece of a wall w nm wide at height h mm, nm. */
static int64_t overhang_bead(const struct overhang_settings *s, int64_t w, double h)
{
	double wm = (double)w / SLICE_UNITS_PER_MM;

	if (s->thick_bridges)
		return llround(perim_round_bead(s->nozzle_diameter * sqrt(s->bridge_flow_ratio), h) *
			       SLICE_UNITS_PER_MM);
	if (s->bridge_flow_ratio == 1.0)
		return w;
	return llround(fmax(h, wm + (s->bridge_flow_ratio - 1.0) * perim_bead_area(wm, h) / h) *
		       SLICE_UNITS_PER_MM);
}

/* Emit piece pc (its points, the last one included) of role into out and
 * start the next at its last point; every point width wide, or with
 * width 0 as wide as it was added (each point's width is its segment's). */
static int piece_flush(struct piece *pc, struct layer_paths *out, enum path_role role,
		       int64_t width, struct st_error *err)
{
	size_t keep = 0;
	int rc = 0;

	/* drop repeated points: a piece needs two distinct ones */
	for (size_t k = 0; k < pc->n; k++)
		if (!keep || pc->pts[k].x != pc->pts[keep - 1].x || pc->pts[k].y != pc->pts[keep - 1].y)
			pc->pts[keep++] = pc->pts[k];
		else
			pc->pts[keep - 1].width = pc->pts[k].width;
	int64_t carried = keep ? pc->pts[keep - 1].width : 0; /* the next piece's */
	for (size_t k = 0; k < keep && width; k++)
		pc->pts[k].width = width;
	if (keep >= 2)
		rc = layer_add_path(out, role, false, pc->pts, keep, err);
	if (keep) {
		pc->pts[0] = pc->pts[keep - 1];
		pc->pts[0].width = carried;
		pc->n = 1;
	}
	return rc;
}

/* Wall p (a closed loop, or an open run a loop's tip joined to its
 * centre-line bead: perimeters_join.c) cut into its pieces from its start,
 * appended to out, the supported ones keeping each segment's width; *cut
 * false (nothing appended) when it lies wholly on one side. */
static int split_wall(const struct toolpath *p, const struct clip_locator *lower, double h,
		      const struct overhang_settings *s, struct layer_paths *out, bool *cut,
		      struct st_error *err)
{
	int64_t bead = overhang_bead(s, p->pts[0].width, h);
	struct piece pc = {0};
	bool first = clip_locator_inside(lower, p->pts[0].x, p->pts[0].y), in = first;
	bool mixed = false;
	size_t segs = p->closed ? p->n : p->n - 1;
	int rc = 0;

	/* a first pass only asks whether the wall is cut at all */
	for (int pass = 0; pass < 2 && !rc; pass++) {
		if (pass == 1 && !mixed)
			break;
		in = first;
		if (pass == 1)
			rc = piece_add(&pc, p->pts[0].x, p->pts[0].y, p->pts[0].width);
		for (size_t i = 0; i < segs && !rc; i++) {
			const struct path_point *a = &p->pts[i], *b = &p->pts[(i + 1) % p->n];
			double len = hypot((double)(b->x - a->x), (double)(b->y - a->y));
			size_t steps = (size_t)ceil(len / OVERHANG_STEP_NM);
			double px = (double)a->x, py = (double)a->y;

			for (size_t k = 1; k <= steps && !rc; k++) {
				double t = (double)k / (double)steps;
				double qx = (double)a->x + t * (double)(b->x - a->x);
				double qy = (double)a->y + t * (double)(b->y - a->y);
				bool q_in = clip_locator_inside(lower, llround(qx), llround(qy));

				if (q_in != in) {
					mixed = true;
					if (pass == 1) {
						rc = piece_add(&pc, llround((px + qx) / 2),
							       llround((py + qy) / 2), a->width);
						if (!rc)
							rc = piece_flush(&pc, out,
									 in ? p->role
									    : PATH_OVERHANG_PERIMETER,
									 in ? 0 : bead, err);
					}
					in = q_in;
				}
				px = qx;
				py = qy;
			}
			if (pass == 1 && !rc)
				rc = piece_add(&pc, b->x, b->y, b->width);
		}
		if (pass == 1 && !rc)
			rc = piece_flush(&pc, out, in ? p->role : PATH_OVERHANG_PERIMETER,
					 in ? 0 : bead, err);
	}
	free(pc.pts);
	*cut = mixed;
	if (rc == ST_ERR_NOMEM && !err->code)
		st_error_set(err, ST_ERR_NOMEM, "overhangs: out of memory cutting a wall");
	if (!rc && !mixed && !first) { /* wholly over air: the loop as it is, overhanging */
		struct path_point *q = malloc(p->n * sizeof(*q));
		if (!q)
			return st_error_set(err, ST_ERR_NOMEM, "overhangs: out of memory");
		for (size_t k = 0; k < p->n; k++)
			q[k] = (struct path_point){p->pts[k].x, p->pts[k].y, bead};
		rc = layer_add_path(out, PATH_OVERHANG_PERIMETER, p->closed, q, p->n, err);
		free(q);
		*cut = true;
	}
	return rc;
}

int overhang_split(struct layer_paths *l, const struct clip_paths *here,
		   const struct clip_paths *below, const struct overhang_settings *s,
		   struct st_error *err)
{
	struct clip_paths grown = {0}, over = {0};
	struct clip_locator *lower = NULL;
	struct layer_paths out = {.z = l->z, .height = l->height};
	bool any = false;
	int rc = clip_offset(below, s->nozzle_diameter / 2.0 * SLICE_UNITS_PER_MM, CLIP_JOIN_ROUND,
			     0.0, OVERHANG_ARC_NM, &grown, err);

	/* The walls lie inside the layer's own region: none leaves the grown
	 * layer below unless the region does (most layers stop here). */
	if (!rc)
		rc = clip_boolean(CLIP_DIFFERENCE, here, &grown, CLIP_NONZERO, &over, err);
	if (!rc && !over.n)
		goto out;
	if (!rc && !(lower = clip_locator_new(&grown, err)))
		rc = err->code ? err->code : ST_ERR_NOMEM;
	for (size_t i = 0; i < l->n && !rc; i++) {
		const struct toolpath *p = &l->paths[i];
		bool cut = false;

		if (p->role == PATH_OUTER_PERIMETER || p->role == PATH_INNER_PERIMETER)
			rc = split_wall(p, lower, l->height, s, &out, &cut, err);
		if (!rc && !cut)
			rc = layer_add_path(&out, p->role, p->closed, p->pts, p->n, err);
		any = any || cut;
	}
	if (!rc && any) { /* l takes out's paths; its own are freed */
		struct layer_paths old = *l;
		l->paths = out.paths;
		l->n = out.n;
		l->cap = out.cap;
		out = old;
		out.travel = NULL; /* stays with l */
	}
	out.travel = NULL;
	layer_paths_clear(&out);
out:
	clip_locator_free(lower);
	clip_paths_free(&grown);
	clip_paths_free(&over);
	return rc;
}
