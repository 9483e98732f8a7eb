/*
 * infill_classify.c - the region inside the walls of one layer into
 * bottom skin, bridges, solid, sparse infill and top skin, filled in that
 * order, then ironing (see infill.h for the rules).
 */
#include "infill_int.h"

#include <math.h>

#include "ironing.h"
#include "perimeters.h"

/* Gap between bridge threads beyond their diameter, mm. */
#define INFILL_BRIDGE_GAP_MM 0.05
/* Bridges reach this many solid widths into the supported area. */
#define INFILL_ANCHOR_WIDTHS 3.0

/* z of the bottom of layer i, mm. */
static double z_bottom(const struct slice_stack *st, size_t i)
{
	return st->layers[i].z - st->layers[i].height;
}

/*
 * out = R_i minus the intersection of the solid regions of the k layers
 * next to layer i in direction dir (+1 up, -1 down), k = 1 .. count; a
 * layer beyond the stack is empty.  count 0 gives an empty out: the part
 * of R_i within count layers of a top (dir +1) or bottom surface.
 */
static int shell(struct ctx *c, int dir, size_t count, struct clip_paths *out)
{
	const struct clip_paths *R = c->R;
	struct clip_paths inter = {0};
	int rc = 0;

	clip_paths_clear(out);
	if (!count)
		return 0;
	for (size_t k = 1; k <= count && !rc; k++) {
		if (dir < 0 ? k > c->layer : c->layer + k >= c->st->n) {
			clip_paths_clear(&inter);
			break;
		}
		const struct clip_paths *S = &c->st->layers[c->layer + (size_t)dir * k].regions.paths;
		if (k == 1)
			rc = clip_paths_append(&inter, S, c->err);
		else
			rc = clip_boolean(CLIP_INTERSECTION, &inter, S, CLIP_NONZERO, &inter, c->err);
	}
	if (!rc)
		rc = clip_boolean(CLIP_DIFFERENCE, R, &inter, CLIP_NONZERO, out, c->err);
	clip_paths_free(&inter);
	return rc;
}

/*
 * Split X into the islands smaller than solid_infill_below_area (appended
 * to small) and the rest (appended to big).
 */
static int split_small(struct ctx *c, const struct clip_paths *X, struct clip_paths *small,
		       struct clip_paths *big)
{
	struct clip_expolys ex = {0};
	struct clip_paths P = {0};
	double lim = c->s->solid_infill_below_area * SLICE_UNITS_PER_MM * SLICE_UNITS_PER_MM;
	int rc = clip_boolean_ex(CLIP_UNION, X, NULL, CLIP_NONZERO, &ex, c->err);

	for (size_t i = 0; i < ex.n && !rc; i++) {
		double area = 0;
		rc = clip_expolys_get(&ex, i, &P, c->err);
		if (!rc)
			rc = clip_paths_area(&P, &area, c->err);
		if (!rc)
			rc = clip_paths_append(area < lim ? small : big, &P, c->err);
	}
	clip_expolys_free(&ex);
	clip_paths_free(&P);
	return rc;
}

/* Number of layers of the shell of thickness t (mm) seen from layer i. */
static size_t shell_count(const struct slice_stack *st, size_t i, int dir, double t)
{
	size_t n = 0;

	if (dir > 0)
		for (size_t j = i; j < st->n && st->layers[j].z - st->layers[i].z < t - INFILL_EPS_MM;
		     j++)
			n++;
	else
		for (size_t j = i + 1; j-- > 0 && z_bottom(st, i) - z_bottom(st, j) < t - INFILL_EPS_MM;)
			n++;
	return n;
}

/* Classes of one layer, in printing order (see infill.h). */
enum { CL_BOTTOM, CL_BRIDGE, CL_SOLID, CL_SPARSE, CL_TOP, CL_N };

/*
 * Regions of layer c->layer by class (see infill.h for the rules).
 * cl[CL_BRIDGE] is the bridges grown into their anchors.
 */
static int classify(struct ctx *c, struct clip_paths cl[CL_N])
{
	const struct slice_stack *st = c->st;
	size_t i = c->layer;
	const struct clip_paths *R = c->R;
	double sw = perim_spacing(c->s->solid_infill_extrusion_width, c->h) * SLICE_UNITS_PER_MM;
	struct clip_paths t = {0}, taken = {0}, rest = {0};
	int rc = 0;

	if (i > 0) { /* over air, opened by half a line so slivers do not count */
		rc = clip_boolean(CLIP_DIFFERENCE, R, &st->layers[i - 1].regions.paths,
				  CLIP_NONZERO, &t, c->err);
		if (!rc)
			rc = clip_offset(&t, -sw / 2.0, CLIP_JOIN_ROUND, 0.0, INFILL_ARC_NM, &t,
					 c->err);
		if (!rc)
			rc = clip_offset(&t, sw / 2.0 + INFILL_ANCHOR_WIDTHS * c->s->solid_infill_extrusion_width *
						     SLICE_UNITS_PER_MM,
					 CLIP_JOIN_ROUND, 0.0, INFILL_ARC_NM, &t, c->err);
		if (!rc)
			rc = clip_boolean(CLIP_INTERSECTION, &t, R, CLIP_NONZERO, &cl[CL_BRIDGE],
					  c->err);
	}
	if (!rc)
		rc = clip_paths_append(&taken, &cl[CL_BRIDGE], c->err);
	if (!rc && i == 0)
		rc = clip_boolean(CLIP_DIFFERENCE, R, &taken, CLIP_NONZERO, &cl[CL_BOTTOM], c->err);
	if (!rc && i > 0) {
		rc = shell(c, +1, shell_count(st, i, +1, c->t_top), &t);
		if (!rc)
			rc = clip_boolean(CLIP_DIFFERENCE, &t, &taken, CLIP_NONZERO, &cl[CL_TOP],
					  c->err);
		if (!rc)
			rc = clip_paths_append(&taken, &cl[CL_TOP], c->err);
		/* The bottom shell: skin when it rests on the bed (or on a raft,
		 * which lifts the whole stack), else solid over bridges. */
		bool on_bed = z_bottom(st, i) - z_bottom(st, 0) < c->t_bot - INFILL_EPS_MM;
		if (!rc)
			rc = shell(c, -1, shell_count(st, i, -1, c->t_bot), &t);
		if (!rc)
			rc = clip_boolean(CLIP_DIFFERENCE, &t, &taken, CLIP_NONZERO,
					  &cl[on_bed ? CL_BOTTOM : CL_SOLID], c->err);
	}
	if (!rc)
		rc = clip_paths_append(&taken, &cl[CL_BOTTOM], c->err);
	if (!rc)
		rc = clip_paths_append(&taken, &cl[CL_SOLID], c->err);
	if (!rc)
		rc = clip_boolean(CLIP_DIFFERENCE, R, &taken, CLIP_NONZERO, &rest, c->err);
	if (!rc && c->s->fill_density >= 100.0)
		rc = clip_paths_append(&cl[CL_SOLID], &rest, c->err);
	else if (!rc && c->s->fill_density > 0.0)
		rc = split_small(c, &rest, &cl[CL_SOLID], &cl[CL_SPARSE]);
	clip_paths_free(&t);
	clip_paths_free(&taken);
	clip_paths_free(&rest);
	return rc;
}

/*
 * Ironing of the layer (ironing.h) after its top skin, at the skin's angle
 * a plus 45 degrees; cl are the layer's classes (empty without infill).
 */
static int plan_ironing(struct ctx *c, const struct clip_paths cl[CL_N], double a)
{
	const struct infill_settings *s = c->s;
	double sp = s->ironing_spacing * SLICE_UNITS_PER_MM;
	struct clip_paths solid = {0}, area = {0}, segs = {0};
	int rc = 0;

	/* Sparse infill above 95 % counts as solid, as in PrusaSlicer. */
	if (s->ironing_type == IRON_SOLID)
		for (int k = CL_BOTTOM; k < CL_N && !rc; k++)
			if (k != CL_BRIDGE && (k != CL_SPARSE || s->fill_density > 95.0))
				rc = clip_paths_append(&solid, &cl[k], c->err);
	if (!rc)
		rc = iron_area(s->ironing_type, s->top_solid_layers > 0, c->st, c->layer, c->R,
			       &solid, s->nozzle_diameter, &area, c->err);
	if (!rc)
		rc = iron_lines(&area, a + M_PI / 4.0, sp, &segs, c->err);
	if (!rc && segs.n)
		rc = infill_plan_lines(c, &segs, PATH_IRONING, sp);
	clip_paths_free(&solid);
	clip_paths_free(&area);
	clip_paths_free(&segs);
	return rc;
}

/* Classify and fill one layer. */
int infill_fill_layer(struct ctx *c)
{
	const struct infill_settings *s = c->s;
	struct clip_paths cl[CL_N] = {{0}};
	double a = (s->fill_angle + 90.0 * (double)(c->layer % 2)) * M_PI / 180.0;
	double solid_w = s->solid_infill_extrusion_width, top_w = s->top_infill_extrusion_width;
	/* Bridge flow: a round thread; the bead of equal cross-section. */
	double thread = s->nozzle_diameter * sqrt(s->bridge_flow_ratio);
	double bridge_w = perim_round_bead(thread, c->h);
	const double U = SLICE_UNITS_PER_MM;
	const struct bead solid = {solid_w * U, perim_spacing(solid_w, c->h) * U, PATH_SOLID_INFILL,
				   true};
	const struct bead bottom = {solid_w * U, solid.sp, PATH_BOTTOM_SKIN, true};
	const struct bead top = {top_w * U, perim_spacing(top_w, c->h) * U, PATH_TOP_SKIN, true};
	const struct bead thick = {bridge_w * U, (thread + INFILL_BRIDGE_GAP_MM) * U, PATH_BRIDGE,
				   false};
	/* Flat: the solid bead, its area scaled keeping its spacing
	 * (PrusaSlicer's Flow::with_flow_ratio; a width of equal area change). */
	double flat_w = s->bridge_flow_ratio == 1.0
			    ? solid_w
			    : fmax(c->h, solid_w + (s->bridge_flow_ratio - 1.0) *
						       perim_bead_area(solid_w, c->h) / c->h);
	const struct bead flat = {flat_w * U, solid.sp, PATH_BRIDGE, false};
	const struct bead bridge = s->thick_bridges ? thick : flat;
	int rc = 0;

	if (!clip_paths_points(c->R))
		goto out_iron;
	rc = classify(c, cl);
	if (!rc)
		rc = infill_fill_solid(c, &cl[CL_BOTTOM], a, &bottom, NULL);
	if (!rc && s->bridge_angle != 0.0)
		rc = infill_fill_solid(c, &cl[CL_BRIDGE], s->bridge_angle * M_PI / 180.0, &bridge,
				       NULL);
	else if (!rc)
		rc = infill_fill_solid(c, &cl[CL_BRIDGE], 0.0, &bridge,
				       &c->st->layers[c->layer - (c->layer > 0)].regions.paths);
	if (!rc)
		rc = infill_fill_solid(c, &cl[CL_SOLID], a, &solid, NULL);
	if (!rc)
		rc = infill_fill_sparse(c, &cl[CL_SPARSE], a);
	if (!rc)
		rc = infill_fill_solid(c, &cl[CL_TOP], a, &top, NULL);
out_iron:
	if (!rc && s->ironing)
		rc = plan_ironing(c, cl, a);
	for (int k = 0; k < CL_N; k++)
		clip_paths_free(&cl[k]);
	return rc;
}
