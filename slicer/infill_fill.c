/*
 * infill_fill.c - the lines of the infill classes: solid lines fitted to
 * each island, bridge directions, gap fill, the sparse patterns, and the
 * plan items they become (see infill.h).
 */
#include "infill_int.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "anchors.h"
#include "medial.h"
#include "patterns.h"
#include "perimeters.h"
#include "st_grow.h"

/* Bridge directions tried: every 180 / this many degrees (5, the step of
 * PrusaSlicer's bridge detector; every degree cost a sixth of the infill
 * stage on the scan model and chose the same bridges within a few degrees). */
#define INFILL_BRIDGE_DIRS 36
/* Directions anchoring within this fraction of the best compete on length. */
#define INFILL_BRIDGE_SCORE_SLACK 0.01
/* Solid lines on an island's edge parallel to them stay this far inside, nm. */
#define INFILL_EDGE_MARGIN_NM 10000.0

/* A new empty item at the end of the plan, NULL when out of memory. */
static struct item *plan_item(struct ctx *c)
{
	struct infill_plan *p = c->plan;

	struct item *grown = st_grow(p->v, &p->cap, p->n + 1, sizeof(*grown));

	if (!grown) {
		st_error_set(c->err, ST_ERR_NOMEM, "infill: out of memory planning a layer");
		return NULL;
	}
	p->v = grown;
	p->v[p->n] = (struct item){0};
	return &p->v[p->n++];
}

/* Plan segs as open paths of role and width w (nm), to be ordered nearest
 * first when the layer is emitted. */
int infill_plan_lines(struct ctx *c, const struct clip_paths *segs, enum path_role role, double w)
{
	struct item *it = plan_item(c);

	if (!it)
		return ST_ERR_NOMEM;
	it->role = role;
	it->w = w;
	return clip_paths_append(&it->segs, segs, c->err);
}

/* Plan a path of role to be appended as it is. */
static int emit_path(struct ctx *c, enum path_role role, bool closed,
		     const struct path_point *pts, size_t n)
{
	struct item *it = plan_item(c);

	if (!it)
		return ST_ERR_NOMEM;
	it->fixed = true;
	it->role = role;
	it->closed = closed;
	if (!n)
		return 0;
	it->pts = malloc(n * sizeof(*pts));
	if (!it->pts)
		return st_error_set(c->err, ST_ERR_NOMEM, "infill: out of memory planning a path");
	memcpy(it->pts, pts, n * sizeof(*pts));
	it->n = n;
	return 0;
}

/*
 * One region grown by delta nm (round joins), kept while the same region is
 * clipped against again: the bridge directions all grow their island by
 * the same distance but for the smallest islands.
 */
struct grown {
	bool valid;
	double delta;
	struct clip_paths g;
};

/* Lines clipped to the region grown by delta nm (round joins) into segs;
 * memo (may be NULL) holds the growth of this same region. */
static int clip_to(struct ctx *c, const struct clip_paths *lines, const struct clip_paths *region,
		   double delta, struct grown *memo, struct clip_paths *segs)
{
	struct grown local = {0}, *m = memo ? memo : &local;
	int rc = 0;

	if (!m->valid || m->delta != delta) {
		m->valid = false;
		rc = clip_offset(region, delta, CLIP_JOIN_ROUND, 0.0, INFILL_ARC_NM, &m->g, c->err);
		m->valid = !rc;
		m->delta = delta;
	}
	if (!rc)
		rc = clip_lines(CLIP_INTERSECTION, lines, &m->g, CLIP_NONZERO, segs, c->err);
	clip_paths_free(&local.g);
	return rc;
}

/*
 * Lines of direction a across one island P, a whole number of beads at
 * about spacing sp spanning it, clipped so their ends stop sp/2 inside P
 * grown by the overlap, into segs; *fit is the spacing used.  memo (may be
 * NULL) carries P's growth between calls on the same island.
 */
static int fitted_lines(struct ctx *c, const struct clip_paths *P, double a, double sp,
			struct grown *memo, struct clip_paths *segs, double *fit)
{
	struct clip_paths lines = {0};
	struct pat_box box;
	double vmin, vmax;
	int rc;

	clip_paths_clear(segs);
	*fit = 0;
	if (!pat_box_of(P, &box))
		return 0;
	pat_extent(P, a, &vmin, &vmax);
	double n = fmax(1.0, round((vmax - vmin) / sp));
	*fit = (vmax - vmin) / n;
	if (!(*fit > 0))
		return 0;
	rc = pat_lines(a, *fit, vmin + *fit / 2.0, &box, &lines, c->err);
	if (!rc)
		rc = clip_to(c, &lines, P,
			     fmax(c->overlap - sp / 2.0, INFILL_EDGE_MARGIN_NM - *fit / 2.0), memo,
			     segs);
	clip_paths_free(&lines);
	return rc;
}

/*
 * Gap fill of one solid island P: what beads of width fit along segs leave
 * uncovered, where at least gap_fill_min (and the layer height) wide, as
 * centre-line beads of the local width plus the flow model's overlap
 * h (1 - pi/4): P's edges are the walls' spacing edges, and a bead holds
 * its spacing's worth of filament.
 */
static int gap_fill(struct ctx *c, const struct clip_paths *P, const struct clip_paths *segs,
		    double fit)
{
	double minw = fmax(c->s->gap_fill_min, c->h) * SLICE_UNITS_PER_MM;
	struct clip_paths cover = {0}, piece = {0};
	struct clip_expolys gaps = {0};
	struct medial_lines ml = {0};
	int rc = segs->n ? clip_offset_open(segs, fit / 2.0, CLIP_JOIN_ROUND, CLIP_END_ROUND,
					    2.0, INFILL_ARC_NM, &cover, c->err)
			 : 0;

	if (!rc)
		rc = clip_boolean_ex(CLIP_DIFFERENCE, P, &cover, CLIP_NONZERO, &gaps, c->err);
	for (size_t i = 0; i < gaps.n && !rc; i++) {
		double area = 0;
		rc = clip_expolys_get(&gaps, i, &piece, c->err);
		if (!rc)
			rc = clip_paths_area(&piece, &area, c->err);
		if (rc || area < M_PI / 4.0 * minw * minw)
			continue;
		rc = perim_medial_axis(&piece, minw, fmax(minw / 4.0, 1000.0), INFILL_ARC_NM, &ml,
				       c->err);
		for (size_t k = 0; k < ml.n && !rc; k++) {
			struct medial_line *l = &ml.v[k];
			for (size_t j = 0; j < l->n; j++)
				l->pts[j].width += llround(-perim_spacing(0.0, c->h) * SLICE_UNITS_PER_MM);
			rc = emit_path(c, PATH_GAP_FILL, l->closed, l->pts, l->n);
		}
		perim_medial_free(&ml);
	}
	clip_paths_free(&cover);
	clip_paths_free(&piece);
	clip_expolys_free(&gaps);
	return rc;
}

/*
 * Bridge direction of island P over the anchors A (the layer below): of
 * the directions tried, those whose lines end on A at both ends for the
 * largest share of their length (within INFILL_BRIDGE_SCORE_SLACK) compete
 * on the mean length of those anchored lines; the shortest wins.
 */
static int bridge_direction(struct ctx *c, const struct clip_paths *P,
			    const struct clip_locator *A, double sp, double *angle)
{
	enum { N = INFILL_BRIDGE_DIRS };
	double score[N], mean[N], best = -1.0, fit;
	struct clip_paths segs = {0};
	struct grown memo = {0};
	int rc = 0;

	*angle = 0.0;
	for (int k = 0; k < N && !rc; k++) {
		double a = k * M_PI / N, total = 0, held = 0;
		size_t nheld = 0;
		rc = fitted_lines(c, P, a, sp, &memo, &segs, &fit);
		for (size_t i = 0; i < segs.n && !rc; i++) {
			const int64_t *xy = clip_path_xy(&segs, i);
			size_t m = clip_path_len(&segs, i);
			double dx = (double)(xy[2 * m - 2] - xy[0]), dy = (double)(xy[2 * m - 1] - xy[1]);
			double len = hypot(dx, dy);
			if (len < INFILL_MIN_SEGMENT_NM)
				continue;
			/* Ends nudged 1 um inward, off the boundary they were clipped at. */
			double ux = dx / len * 1000.0, uy = dy / len * 1000.0;
			total += len;
			if (clip_locator_inside(A, xy[0] + llround(ux), xy[1] + llround(uy)) &&
			    clip_locator_inside(A, xy[2 * m - 2] - llround(ux),
						xy[2 * m - 1] - llround(uy))) {
				held += len;
				nheld++;
			}
		}
		score[k] = total > 0 ? held / total : 0;
		mean[k] = nheld ? held / (double)nheld : INFINITY;
		best = fmax(best, score[k]);
	}
	double shortest = INFINITY;
	for (int k = 0; k < N && !rc; k++)
		if (score[k] >= best - INFILL_BRIDGE_SCORE_SLACK && mean[k] < shortest) {
			shortest = mean[k];
			*angle = k * M_PI / N;
		}
	clip_paths_free(&segs);
	clip_paths_free(&memo.g);
	return rc;
}

/*
 * Whether island P is narrower than the line spacing sp everywhere (P
 * shrunk by sp/2 is empty).  Lines of any direction would cross such a
 * strip as short dashes with voids between them (1 % of the section of a
 * 2 mm wall between its walls); its centre line carries it instead.
 */
static int too_narrow(struct ctx *c, const struct clip_paths *P, double sp, bool *narrow)
{
	struct clip_paths core = {0};
	int rc = 0;

	*narrow = false;
	if (clip_erosion_kept(P, sp / 2.0)) /* wide enough by its area alone */
		return 0;
	rc = clip_offset(P, -sp / 2.0, CLIP_JOIN_ROUND, 0.0, INFILL_ARC_NM, &core, c->err);
	*narrow = !rc && core.n == 0;
	clip_paths_free(&core);
	return rc;
}

/*
 * Solid lines over every island of X: direction a, or per island the
 * detected bridge direction over anchors when anchors is not NULL.
 */
int infill_fill_solid(struct ctx *c, const struct clip_paths *X, double a, const struct bead *b,
		      const struct clip_paths *anchors)
{
	struct clip_expolys ex = {0};
	struct clip_paths P = {0}, segs = {0};
	struct clip_locator *A = NULL;
	double fit;
	int rc = clip_boolean_ex(CLIP_UNION, X, NULL, CLIP_NONZERO, &ex, c->err);

	if (!rc && anchors && ex.n && !(A = clip_locator_new(anchors, c->err)))
		rc = c->err ? c->err->code : ST_ERR_NOMEM;

	for (size_t i = 0; i < ex.n && !rc; i++) {
		double ai = a;
		bool narrow = false;
		rc = clip_expolys_get(&ex, i, &P, c->err);
		if (!rc && b->gap_fill)
			rc = too_narrow(c, &P, b->sp, &narrow);
		if (!rc && narrow) { /* one bead along it, as wide as it is */
			clip_paths_clear(&segs);
			rc = gap_fill(c, &P, &segs, 0.0);
			continue;
		}
		if (!rc && anchors)
			rc = bridge_direction(c, &P, A, b->sp, &ai);
		if (!rc)
			rc = fitted_lines(c, &P, ai, b->sp, NULL, &segs, &fit);
		if (!rc)
			rc = infill_plan_lines(c, &segs, b->role, b->w);
		if (!rc && ((b->role == PATH_TOP_SKIN && c->s->top_monotonic) ||
			    (b->role == PATH_BOTTOM_SKIN && c->s->bottom_monotonic)))
			c->plan->v[c->plan->n - 1].monotonic = true;
		if (!rc && b->gap_fill && segs.n)
			rc = gap_fill(c, &P, &segs, fit);
	}
	clip_locator_free(A);
	clip_expolys_free(&ex);
	clip_paths_free(&P);
	clip_paths_free(&segs);
	return rc;
}

/*
 * Triangles, stars and cubic, PrusaSlicer's way (FillRectilinear.cpp): three
 * sets of lines at the fill angle plus 0, 60 and 120 degrees on every layer
 * (no alternation), each 3 S apart so the density is that of lines S apart.
 * Stars shifts the third set by half its period; cubic shifts the sets by
 * +-sqrt(1/2) z, so that the layers stack into tilted cubes.
 */
static int three_line_sets(struct ctx *c, double S, const struct pat_box *box,
			   struct clip_paths *lines)
{
	const struct infill_settings *s = c->s;
	double a = s->fill_angle * M_PI / 180.0;
	double dz = sqrt(0.5) * c->st->layers[c->layer].z * SLICE_UNITS_PER_MM;
	int rc = 0;

	for (int k = 0; k < 3 && !rc; k++) {
		double phase = 0.0;

		if (s->fill_pattern == INFILL_STARS && k == 2)
			phase = 1.5 * S;
		else if (s->fill_pattern == INFILL_CUBIC)
			phase = k == 1 ? -dz : dz;
		rc = pat_lines(a + k * M_PI / 3.0, 3.0 * S, phase, box, lines, c->err);
	}
	return rc;
}

/* Most loops one island's concentric infill may have (a guard). */
#define INFILL_MAX_LOOP_LEVELS 100000

/*
 * Concentric infill of island P, after PrusaSlicer's FillConcentric.cpp:
 * loops S apart, each the one before shrunk by S + sp/2 and grown back by
 * sp/2, so that no loop runs through a strip narrower than a bead.  The
 * outermost loop lies (S - sp)/2 inside where lines would end (sp/2 inside
 * P grown by the overlap): each loop then stands for a band S wide, so
 * the length is the density's (with PrusaSlicer's outermost loop on the
 * edge, the infill test's two 20 mm boxes at 15 % got 30 % more).  One plan item per ring, so
 * rings print outermost first, each nearest first from the nozzle.
 */
static int concentric(struct ctx *c, const struct clip_paths *P, double sp, double S, double w)
{
	struct clip_paths ring = {0}, next = {0};
	int rc = clip_offset(P, c->overlap - sp / 2.0 - (S - sp) / 2.0, CLIP_JOIN_MITER, 3.0,
			     INFILL_ARC_NM, &ring, c->err);

	for (size_t k = 0; !rc && ring.n; k++) {
		struct item *it;
		if (k == INFILL_MAX_LOOP_LEVELS) {
			rc = st_error_set(c->err, ST_ERR_RANGE,
					  "infill: more than %d concentric loops; use a lower density "
					  "or wider lines",
					  INFILL_MAX_LOOP_LEVELS);
			break;
		}
		rc = infill_plan_lines(c, &ring, PATH_SPARSE_INFILL, w);
		if (rc)
			break;
		it = &c->plan->v[c->plan->n - 1];
		it->loops = true;
		rc = clip_offset(&ring, -(S + sp / 2.0), CLIP_JOIN_MITER, 3.0, INFILL_ARC_NM, &next,
				 c->err);
		if (!rc)
			rc = clip_offset(&next, sp / 2.0, CLIP_JOIN_MITER, 3.0, INFILL_ARC_NM, &ring,
					 c->err);
	}
	clip_paths_free(&ring);
	clip_paths_free(&next);
	return rc;
}

/*
 * The patterns PrusaSlicer fills island by island: line (its tilt spans
 * the island) and concentric.  Line lines are planned as the other
 * patterns' are, so each is its own path.
 */
static int sparse_islands(struct ctx *c, const struct clip_paths *X, double a, double sp,
			  double S, double w)
{
	struct clip_expolys ex = {0};
	struct clip_paths P = {0}, lines = {0}, segs = {0};
	int rc = clip_boolean_ex(CLIP_UNION, X, NULL, CLIP_NONZERO, &ex, c->err);

	for (size_t i = 0; i < ex.n && !rc; i++) {
		rc = clip_expolys_get(&ex, i, &P, c->err);
		if (!rc && c->s->fill_pattern == INFILL_CONCENTRIC) {
			rc = concentric(c, &P, sp, S, w);
			continue;
		}
		clip_paths_clear(&lines);
		/* PrusaSlicer's oscillation: the tilted lines' ends come within a
		 * bead spacing of their neighbours */
		if (!rc)
			rc = pat_line_set(&P, a, S, S - sp, &lines, c->err);
		if (!rc)
			rc = clip_to(c, &lines, &P, c->overlap - sp / 2.0, NULL, &segs);
		if (!rc)
			rc = infill_plan_lines(c, &segs, PATH_SPARSE_INFILL, w);
	}
	clip_expolys_free(&ex);
	clip_paths_free(&P);
	clip_paths_free(&lines);
	clip_paths_free(&segs);
	return rc;
}

/* Sparse infill of X at fill_density with the chosen pattern. */
int infill_fill_sparse(struct ctx *c, const struct clip_paths *X, double a)
{
	const struct infill_settings *s = c->s;
	double w = s->infill_extrusion_width * SLICE_UNITS_PER_MM;
	double sp = perim_spacing(s->infill_extrusion_width, c->h) * SLICE_UNITS_PER_MM;
	double d = s->fill_density / 100.0, S = sp / d;
	struct clip_paths lines = {0}, segs = {0};
	struct grown B = {0};
	struct pat_box box;
	int rc = 0;

	if (!pat_box_of(X, &box))
		return 0;
	if (s->fill_pattern == INFILL_LINE || s->fill_pattern == INFILL_CONCENTRIC)
		return sparse_islands(c, X, a, sp, S, w);
	switch (s->fill_pattern) {
	case INFILL_RECTILINEAR:
		rc = pat_lines(a, S, 0.0, &box, &lines, c->err);
		break;
	case INFILL_GRID:
		rc = pat_lines(a, 2.0 * S, 0.0, &box, &lines, c->err);
		if (!rc)
			rc = pat_lines(a + M_PI / 2.0, 2.0 * S, 0.0, &box, &lines, c->err);
		break;
	case INFILL_TRIANGLES:
	case INFILL_STARS:
	case INFILL_CUBIC:
		rc = three_line_sets(c, S, &box, &lines);
		break;
	case INFILL_HONEYCOMB: /* turned 60 degrees a layer, PrusaSlicer's sense */
		rc = pat_honeycomb(pat_honeycomb_cell(sp, S), sp / 2.0,
				   -(s->fill_angle + 60.0 * (double)(c->layer % 3)) * M_PI / 180.0,
				   &box, &lines, c->err);
		break;
	default: { /* INFILL_GYROID, at the layer's mid-height */
		double z = (c->st->layers[c->layer].z - c->h / 2.0) * SLICE_UNITS_PER_MM;
		rc = pat_gyroid(d / (sp * PAT_GYROID_LENGTH), z, &box, &lines, c->err);
		break;
	}
	}
	if (!rc)
		rc = clip_to(c, &lines, X, c->overlap - sp / 2.0, &B, &segs);
	/* joined along B, where the line ends lie (PrusaSlicer's connect_infill) */
	if (!rc && s->infill_anchor_max > 0)
		rc = anchors_connect(&B.g, &segs, s->infill_anchor * SLICE_UNITS_PER_MM,
				     s->infill_anchor_max * SLICE_UNITS_PER_MM, c->err);
	if (!rc)
		rc = infill_plan_lines(c, &segs, PATH_SPARSE_INFILL, w);
	clip_paths_free(&lines);
	clip_paths_free(&segs);
	clip_paths_free(&B.g);
	return rc;
}

