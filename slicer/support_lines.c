/*
 * support_lines.c - support's straight lines on the global grid, turned by
 * support_material_angle, and the beads they cover (support_int.h).
 */
#include "support_int.h"

#include <math.h>
#include <stdlib.h>

#include "anchors.h"
#include "emit.h"
#include "grow.h"
#include "patterns.h"

/* Support, interface and raft lines are joined along their boundary where
 * the link is at most this many line pitches long (PrusaSlicer's
 * link_max_length_factor for support, over the fill's density). */
#define SUPPORT_LINK_PITCHES 3.0

/* One clipped line piece, for ordering the pieces of a layer. */
struct piece {
	size_t path;	 /* index in the clipped set */
	int64_t line;	 /* which grid line */
	int64_t along;	 /* smallest coordinate along the line */
};

/*
 * The unit vectors along (t) and across (n) lines at angle a, turned 90
 * degrees for axis 1.  At a = 0 they are exactly the X and Y axes, so the
 * projections below are the coordinates themselves.
 */
static void line_frame(double a, int axis, double t[2], double n[2])
{
	double c = cos(a), s = sin(a);

	if (axis == 0) {
		t[0] = c, t[1] = s, n[0] = -s, n[1] = c;
	} else {
		t[0] = -s, t[1] = c, n[0] = c, n[1] = s;
	}
}

static double dot(const double u[2], const int64_t *xy)
{
	return (double)xy[0] * u[0] + (double)xy[1] * u[1];
}

int support_line_pieces(struct support_ctx *c, const struct clip_paths *R, double gap, double a,
			int axis, struct clip_paths *cut)
{
	struct clip_paths lines = {0};
	double t[2], n[2], lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
	int rc = 0;

	clip_paths_clear(cut);
	if (!R->n)
		return 0;
	line_frame(a, axis, t, n);
	for (size_t k = 0; k < clip_paths_points(R); k++) {
		double p[2] = {dot(t, &R->xy[2 * k]), dot(n, &R->xy[2 * k])};
		for (int d = 0; d < 2; d++) {
			lo[d] = fmin(lo[d], p[d]);
			hi[d] = fmax(hi[d], p[d]);
		}
	}
	for (double k = ceil(lo[1] / gap); !rc && k * gap <= hi[1]; k++) {
		double across = (double)llround(k * gap), along[2] = {lo[0] - 1, hi[0] + 1};
		int64_t seg[4];
		for (int e = 0; e < 2; e++) {
			seg[2 * e] = llround(along[e] * t[0] + across * n[0]);
			seg[2 * e + 1] = llround(along[e] * t[1] + across * n[1]);
		}
		rc = clip_paths_add(&lines, seg, 2, c->err);
	}
	if (!rc && lines.n)
		rc = clip_lines(CLIP_INTERSECTION, &lines, R, CLIP_NONZERO, cut, c->err);
	clip_paths_free(&lines);
	return rc;
}

/* Order pieces by line, then along the line. */
static int piece_cmp(const void *a, const void *b)
{
	const struct piece *p = a, *q = b;

	if (p->line != q->line)
		return p->line < q->line ? -1 : 1;
	return (p->along > q->along) - (p->along < q->along);
}

/* Append the polylines of cut to l as role, ordered by the grid line their
 * first point is on and then along it, every other line reversed. */
static int emit_ordered(struct support_ctx *c, const struct clip_paths *cut, double gap,
			int axis, enum path_role role, struct layer_paths *l)
{
	struct piece *pc = NULL;
	double t[2], n[2];
	int rc = 0;

	line_frame(c->angle, axis, t, n);
	if (cut->n && !(pc = calloc(cut->n, sizeof(*pc))))
		rc = st_error_set(c->err, ST_ERR_NOMEM, "support: out of memory for lines");
	for (size_t i = 0; !rc && i < cut->n; i++) {
		const int64_t *xy = clip_path_xy(cut, i);
		size_t m = clip_path_len(cut, i);
		double a0 = dot(t, xy), a1 = dot(t, &xy[2 * (m - 1)]);
		pc[i] = (struct piece){.path = i,
				       .line = llround(dot(n, xy) / gap),
				       .along = llround(fmin(a0, a1))};
	}
	if (!rc && cut->n)
		qsort(pc, cut->n, sizeof(*pc), piece_cmp);
	/* Zigzag: every other line runs backwards; pieces shorter than half a
	 * bead are not worth a start and a stop. */
	size_t line_no = 0;
	for (size_t i = 0; !rc && i < cut->n; i++) {
		const int64_t *xy = clip_path_xy(cut, pc[i].path);
		size_t m = clip_path_len(cut, pc[i].path);
		double a0 = dot(t, xy), a1 = dot(t, &xy[2 * (m - 1)]);

		if (i > 0 && pc[i].line != pc[i - 1].line)
			line_no++;
		if (m == 2 && fabs(a1 - a0) < c->w / 2.0)
			continue;
		rc = slice_emit_xy(l, role, false, xy, m, llround(c->w), 0, (a1 >= a0) == (line_no & 1),
				   c->err);
	}
	free(pc);
	return rc;
}

/* The pieces cut (lines every gap nm, clipped to F) joined along F's
 * boundary where the link is at most SUPPORT_LINK_PITCHES lines long, as
 * PrusaSlicer links every support and raft fill (link_max_length), then
 * appended to l as role. */
static int emit_linked(struct support_ctx *c, const struct clip_paths *F, struct clip_paths *cut,
		       double gap, int axis, enum path_role role, struct layer_paths *l)
{
	int rc = 0;

	if (cut->n)
		rc = anchors_connect(F, cut, 0.0, SUPPORT_LINK_PITCHES * gap, c->err);
	if (!rc)
		rc = emit_ordered(c, cut, gap, axis, role, l);
	return rc;
}

int support_fill_lines(struct support_ctx *c, const struct clip_paths *R, double gap, int axis,
		       enum path_role role, struct layer_paths *l)
{
	struct clip_paths cut = {0};
	int rc = support_line_pieces(c, R, gap, c->angle, axis, &cut);

	if (!rc)
		rc = emit_linked(c, R, &cut, gap, axis, role, l);
	clip_paths_free(&cut);
	return rc;
}

/*
 * The body in the centre region R (support_int.h, support_area_paths): the
 * sheath, then the pattern in F (R, or a spacing inside the sheath), its
 * lines joined along F's boundary.
 */
static int body_paths(struct support_ctx *c, const struct clip_paths *R, double gap, int axis,
		      struct layer_paths *l)
{
	struct clip_paths in = {0}, cut = {0}, comb = {0};
	const struct clip_paths *F = R;
	struct pat_box box;
	int rc = 0;

	if (c->s->support_material_with_sheath) {
		for (size_t i = 0; i < R->n && !rc; i++)
			rc = slice_emit_xy(l, PATH_SUPPORT, true, clip_path_xy(R, i),
					   clip_path_len(R, i), llround(c->w), 0, false, c->err);
		if (!rc)
			rc = clip_offset(R, -c->sp, CLIP_JOIN_ROUND, 2.0, c->arc, &in, c->err);
		F = &in;
	}
	if (!rc && c->s->support_material_pattern == SUPPORT_HONEYCOMB && pat_box_of(F, &box)) {
		rc = pat_honeycomb(pat_honeycomb_cell(c->sp, gap), c->sp / 2.0, -c->angle, &box,
				   &comb, c->err);
		if (!rc && comb.n)
			rc = clip_lines(CLIP_INTERSECTION, &comb, F, CLIP_NONZERO, &cut, c->err);
	} else if (!rc && c->s->support_material_pattern != SUPPORT_HONEYCOMB) {
		rc = support_line_pieces(c, F, gap, c->angle, axis, &cut);
	}
	if (!rc)
		rc = emit_linked(c, F, &cut, gap, axis, PATH_SUPPORT, l);
	clip_paths_free(&in);
	clip_paths_free(&cut);
	clip_paths_free(&comb);
	return rc;
}

int support_area_paths(struct support_ctx *c, const struct clip_paths *A, bool interface,
		       double gap, int axis, struct layer_paths *l)
{
	struct clip_paths R = {0};
	int rc = 0;

	if (!A->n)
		return 0;
	rc = clip_offset(A, -c->w / 2.0, CLIP_JOIN_ROUND, 2.0, c->arc, &R, c->err);
	if (!rc && interface)
		rc = support_fill_lines(c, &R, gap, axis, PATH_SUPPORT_INTERFACE, l);
	else if (!rc)
		rc = body_paths(c, &R, gap, axis, l);
	clip_paths_free(&R);
	return rc;
}

int support_beads(const struct layer_paths *l, double arc, struct clip_paths *out,
		  struct st_error *err)
{
	struct clip_paths line = {0}, band = {0};
	int64_t *xy = NULL;
	size_t cap = 0;
	int rc = 0;

	clip_paths_clear(out);
	for (size_t i = 0; i < l->n && !rc; i++) {
		const struct toolpath *p = &l->paths[i];
		size_t n = p->n + (p->closed ? 1 : 0);
		int64_t wmax = 0;
		int64_t *grown;

		if (p->role != PATH_SUPPORT && p->role != PATH_SUPPORT_INTERFACE)
			continue;
		if (!(grown = slice_grow(xy, &cap, n, 2 * sizeof(*xy)))) {
			rc = st_error_set(err, ST_ERR_NOMEM, "support: out of memory for its beads");
			break;
		}
		xy = grown;
		for (size_t k = 0; k < n; k++) {
			const struct path_point *q = &p->pts[k % p->n];
			xy[2 * k] = q->x;
			xy[2 * k + 1] = q->y;
			wmax = q->width > wmax ? q->width : wmax;
		}
		clip_paths_clear(&line);
		rc = clip_paths_add(&line, xy, n, err);
		if (!rc)
			rc = clip_offset_open(&line, wmax / 2.0, CLIP_JOIN_ROUND, CLIP_END_ROUND, 2.0,
					      arc, &band, err);
		if (!rc)
			rc = clip_paths_append(out, &band, err);
	}
	if (!rc)
		rc = clip_boolean(CLIP_UNION, out, NULL, CLIP_NONZERO, out, err);
	free(xy);
	clip_paths_free(&line);
	clip_paths_free(&band);
	return rc;
}

