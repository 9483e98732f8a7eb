/*
 * perimeters.c - wall loops by exact erosion, thin walls and gap fill along
 * medial axes (see perimeters.h); where loops start is perimeters_seam.c.
 */
#include "perimeters_int.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "beadwidth.h"
#include "grow.h"
#include "medial.h"

/* Miter limit (multiples of the offset) when restoring trimmed loops. */
#define PERIM_MITER_LIMIT 3.0
/* Thin features this much narrower than epsilon still count (float STL), nm. */
#define PERIM_EPS_SLACK 5000.0
/* Vertices closer than this to their neighbours' line are dropped from loops, nm. */
#define PERIM_CLEAN_NM 10.0
/* Beyond the arc tolerance, slivers this thin between two offsets are noise, nm. */
#define PERIM_HAIRLINE 5.0
/* A thin wall splits into two beads where the second would be at least
 * this share of a spacing wide (where Arachne splits a middle bead: Cura's
 * wall_split_middle_threshold default; PrusaSlicer 2.5 has no key). */
#define PERIM_SPLIT_SHARE 0.5
/* Round joins this share of a spacing fine decide whether infill holds one. */
#define PERIM_CORE_ARC_SHARE 20.0
/* With min_feature_size 0, thin walls down to this width still print, nm. */
#define PERIM_MIN_FEATURE_NM 10000.0

/* Everything one perim_generate call works with, lengths in nm. */
struct ctx {
	const struct perim_settings *s;
	double w, sp;	/* the inner walls' width and spacing */
	double wo, spo; /* the outer wall's */
	double h, arc, eps;
	double min_feature, min_bead; /* nm: the thinnest wall printed, its narrowest bead */
	bool bare;		      /* the island being made has no wall loop */
	struct perim_thin *thin;
	struct perim_seams *sm;
	struct layer_paths *out;
	struct st_error *err;
};

/* The narrowest strip gap fill prints, nm: gap_fill_min, at least the layer. */
static double gap_fill_width(const struct ctx *c)
{
	return fmax(c->s->gap_fill_min * SLICE_UNITS_PER_MM, c->h);
}

/*
 * Append wall loop xy[0..n) of role, its beads widened into the strips too
 * narrow for gap fill inside (may be NULL) and outside it (beadwidth.h),
 * starting at its seam; the last wall (last) takes up the infill pieces
 * inside it whole (narrow_infill).
 */
static int emit_loop(struct ctx *c, const int64_t *xy, size_t n, enum path_role role,
		     const struct clip_paths *inside, const struct clip_paths *outside, bool last)
{
	bool outer = role == PATH_OUTER_PERIMETER, changed = false;
	struct bead_fit f = {.width = outer ? c->wo : c->w,
			     .spacing = outer ? c->spo : c->sp,
			     .gmax = gap_fill_width(c),
			     .gmax_in = last ? (outer ? c->spo : c->sp) : 0.0,
			     .step = c->w / 4.0,
			     .tol = c->arc + PERIM_HAIRLINE + 1000.0};
	struct path_point *fit = NULL, *pts = NULL;
	int64_t *fxy = NULL;
	size_t seam;
	int rc;

	if (n < 3)
		return 0;
	/* The seam is picked on the fitted points, changed or not: even when
	 * nothing is absorbed they may number one more than xy (a sample left on
	 * the closing edge), and xy read that far runs past the loop. */
	rc = bead_fit_loop(xy, n, inside, outside, &f, &fit, &n, &changed, c->err);
	if (!rc && n >= 3 && (fxy = malloc(2 * n * sizeof(*fxy))))
		for (size_t k = 0; k < n; k++) {
			fxy[2 * k] = fit[k].x;
			fxy[2 * k + 1] = fit[k].y;
		}
	if (!rc && n >= 3 && (!fxy || !(pts = malloc(n * sizeof(*pts)))))
		rc = st_error_set(c->err, ST_ERR_NOMEM, "perimeters: out of memory for a loop");
	if (!rc && n >= 3) {
		seam = perim_seam_pick(c->sm, c->s->seam, c->w, fxy, n);
		for (size_t k = 0; k < n; k++)
			pts[k] = fit[(seam + k) % n];
		rc = layer_add_path(c->out, role, true, pts, n, c->err);
		if (!rc)
			rc = perim_seams_record(c->sm, pts[0].x, pts[0].y, c->err);
		c->sm->lx = pts[0].x;
		c->sm->ly = pts[0].y;
		c->sm->have_last = true;
	}
	free(fit);
	free(fxy);
	free(pts);
	return rc;
}

/* Append a medial line; an open one starts at the end nearer the nozzle. */
static int emit_medial(struct ctx *c, struct medial_line *l, enum path_role role)
{
	struct path_point *p = l->pts;
	size_t n = l->n;
	int rc;

	if (!l->closed && c->sm->have_last &&
	    perim_dist2(p[n - 1].x, p[n - 1].y, c->sm->lx, c->sm->ly) <
		    perim_dist2(p[0].x, p[0].y, c->sm->lx, c->sm->ly))
		for (size_t i = 0, j = n - 1; i < j; i++, j--) {
			struct path_point t = p[i];
			p[i] = p[j];
			p[j] = t;
		}
	rc = layer_add_path(c->out, role, l->closed, p, n, c->err);
	c->sm->lx = l->closed ? p[0].x : p[n - 1].x;
	c->sm->ly = l->closed ? p[0].y : p[n - 1].y;
	c->sm->have_last = true;
	return rc;
}

/*
 * A thin wall's centre line: where it is everywhere at least 1 + SPLIT
 * outer spacings wide (PERIM_SPLIT_SHARE; 0.61 mm with 0.45 mm beads),
 * two beads side by side in one loop
 * (bead_split_line), else one bead as wide as the wall.
 */
static int emit_thin(struct ctx *c, struct medial_line *l)
{
	struct medial_line two = {.closed = true};
	int rc = bead_split_line(l, c->w - c->sp, (1.0 + PERIM_SPLIT_SHARE) * c->spo, &two.pts,
				 &two.n, c->err);

	if (!rc)
		rc = emit_medial(c, two.n ? &two : l, PATH_THIN_WALL);
	free(two.pts);
	return rc;
}

/*
 * A gap fill's centre line, its strip measured between the walls' spacing
 * edges: its bead is k = h (1 - pi/4) wider, so its flow fills the strip;
 * where that is at least 1 + SPLIT spacings all along (a 1.5 mm wall's
 * middle), two beads side by side in one loop, as Arachne prints it.
 */
static int emit_gap_fill(struct ctx *c, struct medial_line *l)
{
	double k = c->w - c->sp;
	struct medial_line two = {.closed = true};
	int rc;

	for (size_t j = 0; j < l->n; j++)
		l->pts[j].width += llround(k);
	rc = bead_split_line(l, k, (1.0 + PERIM_SPLIT_SHARE) * c->sp, &two.pts, &two.n, c->err);
	if (!rc)
		rc = emit_medial(c, two.n ? &two : l, PATH_GAP_FILL);
	free(two.pts);
	return rc;
}

/*
 * A piece that holds a disk of diameter min_width but has no centre line (a
 * square or round pillar about as wide as long, whose medial axis is a
 * point): one short bead through the centre of the disk's possible
 * positions, along the piece's longest extent, bead wide (or min_width) and
 * long enough that its flow fills the piece's area (area nm^2).  Adds
 * nothing when no such disk fits.
 */
static int pillar_path(struct ctx *c, const struct clip_paths *piece, double area,
		       double min_width, double bead)
{
	struct clip_paths core = {0};
	const int64_t *o = clip_path_xy(piece, 0);
	size_t n = clip_path_len(piece, 0);
	double w = fmax(fmax(bead, min_width), c->h * 1.01), best = -1, dx = 1, dy = 0, len;
	int64_t x0 = INT64_MAX, y0 = INT64_MAX, x1 = INT64_MIN, y1 = INT64_MIN;
	int rc = clip_offset(piece, -(min_width / 2.0 - PERIM_HAIRLINE), CLIP_JOIN_ROUND, 0.0,
			     c->arc, &core, c->err);

	if (rc || !core.n)
		goto out;
	for (size_t k = 0; k < clip_paths_points(&core); k++) {
		x0 = core.xy[2 * k] < x0 ? core.xy[2 * k] : x0;
		y0 = core.xy[2 * k + 1] < y0 ? core.xy[2 * k + 1] : y0;
		x1 = core.xy[2 * k] > x1 ? core.xy[2 * k] : x1;
		y1 = core.xy[2 * k + 1] > y1 ? core.xy[2 * k + 1] : y1;
	}
	/* The longest extent: the farthest pair of outline vertices (pieces
	 * reaching here are small). */
	for (size_t i = 0; i < n; i++)
		for (size_t j = i + 1; j < n; j++) {
			double ex = (double)(o[2 * j] - o[2 * i]), ey = (double)(o[2 * j + 1] - o[2 * i + 1]);
			if (ex * ex + ey * ey > best) {
				best = ex * ex + ey * ey;
				dx = ex;
				dy = ey;
			}
		}
	best = sqrt(fmax(best, 1.0));
	dx /= best;
	dy /= best;
	/* Bead cross-section h (w - h (1 - pi/4)) times length = area times h. */
	len = area / (w - c->h * (1.0 - M_PI / 4.0));
	if (len > best) { /* widen rather than run past the piece */
		len = best;
		w = area / len + c->h * (1.0 - M_PI / 4.0);
	}
	{
		double cx = ((double)x0 + (double)x1) / 2.0, cy = ((double)y0 + (double)y1) / 2.0;
		struct path_point pts[2] = {
		    {llround(cx - dx * len / 2), llround(cy - dy * len / 2), llround(w)},
		    {llround(cx + dx * len / 2), llround(cy + dy * len / 2), llround(w)},
		};
		struct medial_line l = {.closed = false, .n = 2, .pts = pts};
		rc = emit_medial(c, &l, PATH_THIN_WALL);
	}
out:
	clip_paths_free(&core);
	return rc;
}

/* Length of a medial line, nm. */
static double line_length(const struct medial_line *l)
{
	double len = 0;

	for (size_t j = 0; j + 1 < l->n + (l->closed ? 1 : 0); j++) {
		const struct path_point *p = &l->pts[j], *q = &l->pts[(j + 1) % l->n];
		len += sqrt(perim_dist2(p->x, p->y, q->x, q->y));
	}
	return len;
}

/*
 * A thin-wall piece (area nm^2) the nozzle-wide beads left empty: its
 * centre lines at least min_len nm long where at least min_feature_size
 * wide, each point's bead widened to min_bead_width where the piece is
 * narrower; on an island with no wall, a pillar bead if it has no centre
 * line, else the island is dropped.  Widened beads and dropped islands are
 * counted in c->thin.
 */
static int sub_nozzle(struct ctx *c, const struct clip_paths *piece, double a, double min_len)
{
	struct medial_lines ml = {0};
	double minw = fmax(c->min_feature - PERIM_EPS_SLACK, PERIM_MIN_FEATURE_NM);
	double bead = fmax(c->min_bead, c->h * 1.01);
	size_t before = c->out->n;
	int rc = 0;

	if (a >= M_PI / 4.0 * minw * minw)
		rc = perim_medial_axis(piece, minw, fmax(minw / 4.0, 1000.0), c->arc, &ml, c->err);
	for (size_t k = 0; k < ml.n && !rc; k++) {
		struct medial_line *l = &ml.v[k];
		if (min_len > 0 && line_length(l) < min_len)
			continue;
		for (size_t j = 0; j < l->n; j++) {
			double w = (double)l->pts[j].width;
			if (w >= bead)
				continue;
			if (!c->thin->widened || w / SLICE_UNITS_PER_MM < c->thin->designed)
				c->thin->designed = w / SLICE_UNITS_PER_MM;
			c->thin->printed = bead / SLICE_UNITS_PER_MM;
			c->thin->widened++;
			l->pts[j].width = llround(bead);
		}
		rc = emit_medial(c, l, PATH_THIN_WALL);
	}
	perim_medial_free(&ml);
	if (!rc && c->bare && c->out->n == before && a >= M_PI / 4.0 * minw * minw)
		rc = pillar_path(c, piece, a, minw, bead);
	if (!rc && c->bare && c->out->n == before)
		c->thin->dropped++;
	return rc;
}

/*
 * What the thin-wall lines ml leave of piece where it narrows below the
 * nozzle (a wedge's tip): the piece minus every segment swept at its
 * width, printed by sub_nozzle where a disk of min_feature_size fits and
 * the centre line is at least a nozzle long (a wall's square end leaves
 * corners the round bead end does not reach: too short to print).
 */
static int thin_tips(struct ctx *c, const struct clip_paths *piece,
		     const struct medial_lines *ml)
{
	struct clip_paths segs = {0}, swept = {0}, core = {0}, rest_piece = {0};
	struct clip_expolys rest = {0};
	double minw = fmax(c->min_feature - PERIM_EPS_SLACK, PERIM_MIN_FEATURE_NM), a = 0;
	double *delta = NULL;
	size_t cap = 0;
	bool bare = c->bare;
	int rc = 0;

	for (size_t k = 0; k < ml->n && !rc; k++) {
		const struct medial_line *l = &ml->v[k];
		size_t nseg = l->closed ? l->n : l->n - 1;
		for (size_t j = 0; j < nseg && !rc; j++) {
			const struct path_point *p = &l->pts[j], *q = &l->pts[(j + 1) % l->n];
			int64_t xy[4] = {p->x, p->y, q->x, q->y};
			double *grown = slice_grow(delta, &cap, segs.n + 1, sizeof(*delta));
			if (!grown) {
				rc = st_error_set(c->err, ST_ERR_NOMEM, "perimeters: out of memory");
				break;
			}
			delta = grown;
			delta[segs.n] = p->width / 2.0 + PERIM_HAIRLINE;
			rc = clip_paths_add(&segs, xy, 2, c->err);
		}
	}
	if (!rc && segs.n)
		rc = clip_sweep(&segs, delta, c->arc, &swept, c->err);
	if (!rc)
		rc = clip_boolean_ex(CLIP_DIFFERENCE, piece, &swept, CLIP_NONZERO, &rest, c->err);
	/* Most pieces leave only slivers along the beads: nothing holds the disk. */
	if (!rc)
		rc = clip_offset(&rest.paths, -(minw / 2.0 - PERIM_HAIRLINE), CLIP_JOIN_ROUND, 0.0,
				 c->arc, &core, c->err);
	c->bare = false; /* the piece has its lines: nothing of it is dropped */
	for (size_t i = 0; i < rest.n && core.n && !rc; i++) {
		rc = clip_expolys_get(&rest, i, &rest_piece, c->err);
		if (!rc)
			rc = clip_paths_area(&rest_piece, &a, c->err);
		if (!rc)
			rc = sub_nozzle(c, &rest_piece, a, c->eps);
	}
	c->bare = bare;
	free(delta);
	clip_paths_free(&segs);
	clip_paths_free(&swept);
	clip_paths_free(&core);
	clip_paths_free(&rest_piece);
	clip_expolys_free(&rest);
	return rc;
}

/*
 * Centre lines of every piece of area at least min_width wide, appended as
 * paths of role; a thin-wall piece with none gets pillar_path's bead, and
 * one that still has nothing sub_nozzle's beads; thin_tips prints what
 * narrows below the nozzle beyond the lines.  Pieces whose area cannot
 * hold a disk of that diameter are not sampled for min_width.
 */
static int narrow_paths(struct ctx *c, const struct clip_expolys *area, double min_width,
			enum path_role role)
{
	struct clip_paths piece = {0};
	struct medial_lines ml = {0};
	double step = fmax(min_width / 4.0, 1000.0);
	int rc = 0;

	for (size_t i = 0; i < area->n && !rc; i++) {
		double a = 0.0;
		size_t before = c->out->n;
		rc = clip_expolys_get(area, i, &piece, c->err);
		if (!rc)
			rc = clip_paths_area(&piece, &a, c->err);
		if (rc)
			continue;
		if (a >= M_PI / 4.0 * min_width * min_width) {
			rc = perim_medial_axis(&piece, min_width, step, c->arc, &ml, c->err);
			for (size_t k = 0; k < ml.n && !rc; k++)
				rc = role == PATH_THIN_WALL ? emit_thin(c, &ml.v[k])
							    : emit_gap_fill(c, &ml.v[k]);
			if (!rc && !ml.n && role == PATH_THIN_WALL)
				rc = pillar_path(c, &piece, a, min_width, c->eps);
			if (!rc && ml.n && role == PATH_THIN_WALL)
				rc = thin_tips(c, &piece, &ml);
			perim_medial_free(&ml);
		}
		/* Beside walls, a piece whose centre line is shorter than a
		 * nozzle is what a wide bead's round corner leaves (a 200 %
		 * first layer's square corners), not a feature of the model. */
		if (!rc && role == PATH_THIN_WALL && c->out->n == before)
			rc = sub_nozzle(c, &piece, a, c->bare ? 0 : c->eps);
	}
	clip_paths_free(&piece);
	return rc;
}

/*
 * Centre region of wall k of region R: the erosion of R by d (round joins,
 * so every point is exactly d from R's boundary), cut where two of its
 * sides come closer than its bead spacing sp (an opening by sp/2 whose
 * dilation uses miter joins, so sharp convex corners stay sharp, then
 * intersected with the erosion so no point moves outward).
 */
static int wall_centre(struct ctx *c, const struct clip_paths *R, double d, double sp,
		       struct clip_paths *out)
{
	struct clip_paths e = {0}, t = {0};
	int rc = clip_offset(R, -d, CLIP_JOIN_ROUND, 0.0, c->arc, &e, c->err);

	if (!rc)
		rc = clip_offset(&e, -sp / 2.0, CLIP_JOIN_ROUND, 0.0, c->arc, &t, c->err);
	if (!rc)
		rc = clip_offset(&t, sp / 2.0, CLIP_JOIN_MITER, PERIM_MITER_LIMIT, c->arc, &t,
				 c->err);
	if (!rc)
		rc = clip_boolean(CLIP_INTERSECTION, &e, &t, CLIP_NONZERO, out, c->err);
	/* Where the two boundaries cross, Clipper leaves vertices nm apart. */
	if (!rc)
		rc = clip_clean(out, PERIM_CLEAN_NM, c->err);
	clip_paths_free(&e);
	clip_paths_free(&t);
	return rc;
}

/* area = a minus the dilation of b by d (plus the hairline margin). */
static int minus_grown(struct ctx *c, const struct clip_paths *a, const struct clip_paths *b,
		       double d, struct clip_expolys *area)
{
	struct clip_paths g = {0};
	int rc = clip_offset(b, d + c->arc + PERIM_HAIRLINE, CLIP_JOIN_ROUND, 0.0, c->arc, &g,
			     c->err);

	if (!rc)
		rc = clip_boolean_ex(CLIP_DIFFERENCE, a, &g, CLIP_NONZERO, area, c->err);
	clip_paths_free(&g);
	return rc;
}

/*
 * The pieces of the infill region m (inside the last wall, whose spacing is
 * sp) narrower than sp everywhere, as expolygons: infill lines cannot
 * cross them, and where they are narrower than gap fill too (a wedge's
 * tip inside its inner loop) the last wall's beads take them up.
 */
static int narrow_infill(struct ctx *c, const struct clip_paths *m, double sp,
			 struct clip_expolys *out)
{
	struct clip_expolys all = {0};
	struct clip_paths piece = {0}, core = {0}, keep = {0};
	size_t outers = 0;
	int rc = 0;

	/* One outer contour (the usual island): one piece, no union needed. */
	for (size_t i = 0; i < m->n && outers < 2; i++) {
		const int64_t *xy = clip_path_xy(m, i);
		size_t n = clip_path_len(m, i);
		double a = 0.0;
		for (size_t k = 0; k < n; k++)
			a += (double)xy[2 * k] * (double)xy[2 * ((k + 1) % n) + 1] -
			     (double)xy[2 * ((k + 1) % n)] * (double)xy[2 * k + 1];
		outers += a > 0.0;
	}
	if (outers < 2 && clip_erosion_kept(m, sp / 2.0))
		return 0; /* wide enough by its area alone: nothing narrow */
	if (outers < 2) {
		rc = clip_offset(m, -sp / 2.0, CLIP_JOIN_ROUND, 0.0,
				 fmax(c->arc, sp / PERIM_CORE_ARC_SHARE), &core, c->err);
		if (!rc && !core.n && m->n)
			rc = clip_boolean_ex(CLIP_UNION, m, NULL, CLIP_NONZERO, out, c->err);
		clip_paths_free(&core);
		return rc;
	}
	rc = clip_boolean_ex(CLIP_UNION, m, NULL, CLIP_NONZERO, &all, c->err);
	for (size_t i = 0; i < all.n && !rc; i++) {
		rc = clip_expolys_get(&all, i, &piece, c->err);
		if (!rc && clip_erosion_kept(&piece, sp / 2.0))
			continue;
		if (!rc)
			rc = clip_offset(&piece, -sp / 2.0, CLIP_JOIN_ROUND, 0.0,
					 fmax(c->arc, sp / PERIM_CORE_ARC_SHARE), &core, c->err);
		if (!rc && !core.n)
			rc = clip_paths_append(&keep, &piece, c->err);
	}
	if (!rc && keep.n)
		rc = clip_boolean_ex(CLIP_UNION, &keep, NULL, CLIP_NONZERO, out, c->err);
	clip_expolys_free(&all);
	clip_paths_free(&piece);
	clip_paths_free(&core);
	clip_paths_free(&keep);
	return rc;
}

/* Spacing of wall k, nm. */
static double wall_spacing(const struct ctx *c, int k)
{
	return k == 0 ? c->spo : c->sp;
}

/*
 * How far inside the surface wall k's centre line runs, nm (perimeters.h):
 * w_o/2, then (s_o + s)/2 more, then s more per wall.  Written so that with
 * one width it is w/2 + k s to the last bit.
 */
static double wall_depth(const struct ctx *c, int k)
{
	return k == 0 ? c->wo / 2.0 : c->wo / 2.0 + (c->spo - c->sp) / 2.0 + k * c->sp;
}

/* Walls, gap fill and thin walls of one island R; its infill part into acc. */
static int island(struct ctx *c, const struct clip_paths *R, struct clip_paths *acc)
{
	int N = c->s->perimeters, made = 0, rc = 0;
	size_t first = c->out->n;
	struct clip_paths *loops, *narrow, m = {0};
	struct clip_expolys *strips, area = {0};

	if (N == 0)
		return clip_paths_append(acc, R, c->err);
	loops = calloc((size_t)N, sizeof(*loops));
	strips = calloc((size_t)N, sizeof(*strips));
	narrow = calloc((size_t)N, sizeof(*narrow));
	if (!loops || !strips || !narrow) {
		free(loops);
		free(strips);
		free(narrow);
		return st_error_set(c->err, ST_ERR_NOMEM, "perimeters: out of memory");
	}
	for (; made < N && !rc; made++) {
		rc = wall_centre(c, R, wall_depth(c, made), wall_spacing(c, made), &loops[made]);
		if (!rc && !loops[made].n)
			break;
	}
	/* Strips between walls: what wall k leaves (its inner half-spacing edge)
	 * that wall k+1 cannot cover; after the last wall made short of N, all of
	 * it.  After wall N the rest is infill, whose narrow pieces wall N's beads
	 * may take up (strips[N - 1], never gap filled here). */
	for (int k = 0; k < made && !rc; k++) {
		rc = clip_offset(&loops[k], -wall_spacing(c, k) / 2.0, CLIP_JOIN_ROUND, 0.0, c->arc,
				 &m, c->err);
		if (!rc && k == N - 1)
			rc = narrow_infill(c, &m, wall_spacing(c, k), &strips[k]);
		else if (!rc && k + 1 < made)
			rc = minus_grown(c, &m, &loops[k + 1], wall_spacing(c, k + 1) / 2.0, &strips[k]);
		else if (!rc)
			rc = clip_boolean_ex(CLIP_UNION, &m, NULL, CLIP_NONZERO, &strips[k], c->err);
		if (!rc)
			rc = bead_strips(&strips[k], k == N - 1 ? wall_spacing(c, k) : gap_fill_width(c),
					 c->eps, c->arc, &narrow[k], c->err);
		/* What the last wall does not take up is infill. */
		if (!rc && k == N - 1 && narrow[k].n)
			rc = clip_boolean(CLIP_DIFFERENCE, &m, &narrow[k], CLIP_NONZERO, &m, c->err);
		if (!rc && k == N - 1)
			rc = clip_paths_append(acc, &m, c->err);
	}
	/* Walls in printing order, each widened into the strips beside it. */
	for (int i = 0; i < made && !rc; i++) {
		int k = c->s->outer_first ? i : made - 1 - i;
		enum path_role role = k == 0 ? PATH_OUTER_PERIMETER : PATH_INNER_PERIMETER;
		for (size_t p = 0; p < loops[k].n && !rc; p++)
			rc = emit_loop(c, clip_path_xy(&loops[k], p), clip_path_len(&loops[k], p),
				       role, &narrow[k], k ? &narrow[k - 1] : NULL, k == N - 1);
	}
	/* Gap fill: the strips at least gap_fill_width wide. */
	for (int k = 0; k < made && k < N - 1 && !rc && c->s->gap_fill; k++)
		rc = narrow_paths(c, &strips[k], gap_fill_width(c), PATH_GAP_FILL);
	/* Thin walls: the part of R the outer wall's beads do not reach. */
	c->bare = made == 0;
	if (!rc && c->s->thin_walls) {
		if (made)
			rc = minus_grown(c, R, &loops[0], c->wo / 2.0, &area);
		else
			rc = clip_boolean_ex(CLIP_UNION, R, NULL, CLIP_NONZERO, &area, c->err);
		if (!rc)
			rc = narrow_paths(c, &area, fmax(c->eps - PERIM_EPS_SLACK, c->h),
					  PATH_THIN_WALL);
	}
	/* Each loop's tip carries on into the centre-line bead beyond it. */
	if (!rc && made) {
		struct perim_join jp = {.k = c->w - c->sp,
					.min_width = c->h * 1.01,
					.length = c->s->transition_length * SLICE_UNITS_PER_MM,
					.max_angle = c->s->transition_angle * M_PI / 180.0,
					.reach = c->w / 4.0};
		rc = perim_join_tips(c->out, first, PATH_OUTER_PERIMETER, PATH_THIN_WALL, &jp,
				     c->err);
		if (!rc)
			rc = perim_join_tips(c->out, first, PATH_INNER_PERIMETER, PATH_GAP_FILL, &jp,
					     c->err);
	}
	for (int k = 0; k < N; k++) {
		clip_paths_free(&loops[k]);
		clip_expolys_free(&strips[k]);
		clip_paths_free(&narrow[k]);
	}
	free(loops);
	free(strips);
	free(narrow);
	clip_paths_free(&m);
	clip_expolys_free(&area);
	return rc;
}

int perim_generate(const struct perim_settings *s, const struct clip_expolys *region,
		   double layer_height, struct perim_seams *seams, struct layer_paths *out,
		   struct clip_expolys *infill, struct perim_thin *thin, struct st_error *err)
{
	struct perim_seams local = {.rng = 0x9E3779B97F4A7C15ull};
	struct perim_thin thin_local;
	struct clip_paths R = {0}, acc = {0};
	struct ctx c;
	int rc;

	rc = perim_settings_check(s, layer_height, err);
	if (rc)
		return rc;
	if (!region || !out || !infill || &infill->paths == &region->paths)
		return st_error_set(err, ST_ERR_ARG,
				    "perimeters: perim_generate needs a region, an output layer "
				    "and a distinct infill set");
	c = (struct ctx){.s = s,
			 .w = s->extrusion_width * SLICE_UNITS_PER_MM,
			 .sp = perim_spacing(s->extrusion_width, layer_height) * SLICE_UNITS_PER_MM,
			 .wo = perim_outer_width(s) * SLICE_UNITS_PER_MM,
			 .spo = perim_spacing(perim_outer_width(s), layer_height) * SLICE_UNITS_PER_MM,
			 .h = layer_height * SLICE_UNITS_PER_MM,
			 .arc = s->arc_tolerance * SLICE_UNITS_PER_MM,
			 .eps = s->nozzle_diameter * SLICE_UNITS_PER_MM,
			 .min_feature = s->min_feature_size * SLICE_UNITS_PER_MM,
			 .min_bead = s->min_bead_width * SLICE_UNITS_PER_MM,
			 .thin = thin ? thin : &thin_local,
			 .sm = seams ? seams : &local,
			 .out = out,
			 .err = err};
	*c.thin = (struct perim_thin){0};
	perim_seams_next_layer(c.sm);
	for (size_t i = 0; i < region->n && !rc; i++) {
		rc = clip_expolys_get(region, i, &R, err);
		if (!rc)
			rc = island(&c, &R, &acc);
	}
	if (!rc)
		rc = clip_boolean_ex(CLIP_UNION, &acc, NULL, CLIP_NONZERO, infill, err);
	clip_paths_free(&R);
	clip_paths_free(&acc);
	if (!seams) {
		free(local.prev);
		free(local.cur);
	}
	return rc;
}
