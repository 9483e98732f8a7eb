/*
 * support.c - overhang detection, support columns down to the bed,
 * interface and body lines (see support.h).
 */
#include "support.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "emit.h"
#include "grow.h"
#include "perimeters.h"
#include "settings.h"

/* A layer top this close to the contact limit still counts as below it, mm. */
#define SUPPORT_Z_EPS 1e-6
/* How much more the raft grows below its contact layer, mm (PrusaSlicer's
 * inflate_factor_fine). */
#define RAFT_FINE_MM 0.5
/* The steepest threshold used in the overhang distance, degrees. */
#define SUPPORT_MAX_DEG 89.0

/* Everything one support_generate call works with, lengths in nm. */
struct ctx {
	const struct support_settings *s;
	const struct slice_stack *st;
	double w, arc, body, xy;
	struct st_error *err;
};

/* One clipped line piece, for ordering the pieces of a layer. */
struct piece {
	size_t path;	 /* index in the clipped set */
	int64_t line;	 /* coordinate across the lines */
	int64_t along;	 /* smallest coordinate along the line */
};

/* The declared default of a raft key (settings.c). */
static double declared(const char *name)
{
	double v = 0.0;

	setting_default_number(name, false, &v);
	return v;
}

void support_settings_init(struct support_settings *s, double nozzle_diameter)
{
	s->support_material = false;
	s->support_material_threshold = 0.0;
	s->support_material_style = SUPPORT_GRID;
	s->support_material_contact_distance = 0.2;
	s->support_material_interface_layers = 3;
	s->support_material_spacing = 2.5;
	s->extrusion_width = 1.125 * nozzle_diameter;
	s->first_layer_extrusion_width = 0.0;
	s->support_material_xy_spacing = 0.6 * s->extrusion_width;
	s->arc_tolerance = 0.002;
	s->raft_layers = (int)declared("raft_layers");
	s->raft_contact_distance = declared("raft_contact_distance");
	s->raft_expansion = declared("raft_expansion");
	s->raft_first_layer_density = declared("raft_first_layer_density");
	s->raft_first_layer_expansion = declared("raft_first_layer_expansion");
}

/* The raft's keys inside their declared ranges (settings.h). */
static int raft_check(const struct support_settings *s, struct st_error *err)
{
	int rc = setting_check("support", "raft_layers", s->raft_layers, err);

	if (!rc)
		rc = setting_check("support", "raft_contact_distance", s->raft_contact_distance,
				   err);
	if (!rc)
		rc = setting_check("support", "raft_expansion", s->raft_expansion, err);
	if (!rc)
		rc = setting_check("support", "raft_first_layer_density",
				   s->raft_first_layer_density, err);
	if (!rc)
		rc = setting_check("support", "raft_first_layer_expansion",
				   s->raft_first_layer_expansion, err);
	return rc;
}

int support_settings_check(const struct support_settings *s, struct st_error *err)
{
	if (!s)
		return st_error_set(err, ST_ERR_ARG, "support: no settings given");
	if (!(s->support_material_threshold >= 0.0 && s->support_material_threshold <= 90.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "support: support_material_threshold = %g degrees is out of "
				    "range; use 0 (automatic) to 90 degrees from horizontal",
				    s->support_material_threshold);
	if ((unsigned)s->support_material_style >= SUPPORT_STYLES)
		return st_error_set(err, ST_ERR_ARG,
				    "support: support_material_style %d is unknown; use grid or snug",
				    (int)s->support_material_style);
	if (!(s->support_material_contact_distance >= 0.0 &&
	      s->support_material_contact_distance <= 10.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "support: support_material_contact_distance = %g mm is out of "
				    "range; use 0 to 10 mm",
				    s->support_material_contact_distance);
	if (s->support_material_interface_layers < 0 ||
	    s->support_material_interface_layers > 1000)
		return st_error_set(err, ST_ERR_RANGE,
				    "support: support_material_interface_layers = %d is out of range; "
				    "use 0 to 1000",
				    s->support_material_interface_layers);
	if (!(s->extrusion_width > 0.0 && s->extrusion_width <= 20.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "support: extrusion width %g mm is out of range; use (0, 20] mm",
				    s->extrusion_width);
	if (!(s->first_layer_extrusion_width >= 0.0 && s->first_layer_extrusion_width <= 20.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "support: first layer extrusion width %g mm is out of range; use "
				    "0 (support's width) to 20 mm",
				    s->first_layer_extrusion_width);
	if (!(s->support_material_spacing > 0.0 && s->support_material_spacing <= 1000.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "support: support_material_spacing = %g mm is out of range; use "
				    "(0, 1000] mm",
				    s->support_material_spacing);
	if (!(s->support_material_xy_spacing >= 0.0 && s->support_material_xy_spacing <= 100.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "support: support_material_xy_spacing = %g mm is out of range; "
				    "use 0 to 100 mm",
				    s->support_material_xy_spacing);
	if (!(s->arc_tolerance > 0.0 && s->arc_tolerance <= s->extrusion_width / 4.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "support: arc tolerance %g mm is out of range; use (0, %g] mm (a "
				    "quarter of the extrusion width)",
				    s->arc_tolerance, s->extrusion_width / 4.0);
	return raft_check(s, err);
}

/* Regions of layer i as one polygon set (outer CCW, holes CW). */
static const struct clip_paths *model(const struct ctx *c, size_t i)
{
	return &c->st->layers[i].regions.paths;
}

/* How far (nm) layer i may reach beyond layer i-1 without support. */
static double overhang_allowance(const struct ctx *c, size_t i)
{
	double a = c->s->support_material_threshold;

	if (a <= 0.0)
		return c->w / 2.0;
	a = fmin(a + 1.0, SUPPORT_MAX_DEG) * M_PI / 180.0;
	return c->st->layers[i - 1].height * SLICE_UNITS_PER_MM / tan(a);
}

/* out = the contact area of layer i >= 1 (see support.h); empty if none. */
static int contact(struct ctx *c, size_t i, struct clip_paths *out)
{
	struct clip_paths grown = {0}, over = {0};
	double d = overhang_allowance(c, i);
	int rc = clip_offset(model(c, i - 1), d, CLIP_JOIN_ROUND, 2.0, c->arc, &grown, c->err);

	clip_paths_clear(out);
	if (!rc)
		rc = clip_boolean(CLIP_DIFFERENCE, model(c, i), &grown, CLIP_NONZERO, &over, c->err);
	if (!rc && over.n)
		rc = clip_offset(&over, d + c->w, CLIP_JOIN_ROUND, 2.0, c->arc, &over, c->err);
	if (!rc && over.n)
		rc = clip_boolean(CLIP_DIFFERENCE, model(c, i), model(c, i - 1), CLIP_NONZERO, out,
				  c->err);
	if (!rc && over.n)
		rc = clip_boolean(CLIP_INTERSECTION, out, &over, CLIP_NONZERO, out, c->err);
	clip_paths_free(&grown);
	clip_paths_free(&over);
	return rc;
}

/* Highest layer under the interface gap of layer i, or -1 if none. */
static long top_layer(const struct ctx *c, size_t i)
{
	const struct slice_layer *L = c->st->layers;
	double limit = L[i].z - L[i].height - c->s->support_material_contact_distance +
		       SUPPORT_Z_EPS;

	for (size_t j = i; j-- > 0;)
		if (L[j].z <= limit)
			return (long)j;
	return -1;
}

/* Order pieces by line, then along the line. */
static int piece_cmp(const void *a, const void *b)
{
	const struct piece *p = a, *q = b;

	if (p->line != q->line)
		return p->line < q->line ? -1 : 1;
	return (p->along > q->along) - (p->along < q->along);
}

/*
 * Lines across the centre region R (nm) every gap nm on the global grid,
 * along X (axis 0: y constant) or Y (axis 1), clipped to R and appended to
 * l as role in a zigzag order (every other line reversed).
 */
static int fill_lines(struct ctx *c, const struct clip_paths *R, double gap, int axis,
		      enum path_role role, struct layer_paths *l)
{
	struct clip_paths lines = {0}, cut = {0};
	struct piece *pc = NULL;
	int64_t lo[2] = {INT64_MAX, INT64_MAX}, hi[2] = {INT64_MIN, INT64_MIN};
	int rc = 0;

	for (size_t k = 0; k < clip_paths_points(R); k++)
		for (int a = 0; a < 2; a++) {
			lo[a] = R->xy[2 * k + a] < lo[a] ? R->xy[2 * k + a] : lo[a];
			hi[a] = R->xy[2 * k + a] > hi[a] ? R->xy[2 * k + a] : hi[a];
		}
	if (!R->n)
		return 0;
	int across = axis == 0 ? 1 : 0, alongx = axis == 0 ? 0 : 1;
	for (double k = ceil(lo[across] / gap); !rc && k * gap <= hi[across]; k++) {
		int64_t seg[4];
		seg[2 * 0 + across] = seg[2 * 1 + across] = llround(k * gap);
		seg[alongx] = lo[alongx] - 1;
		seg[2 + alongx] = hi[alongx] + 1;
		rc = clip_paths_add(&lines, seg, 2, c->err);
	}
	if (!rc && lines.n)
		rc = clip_lines(CLIP_INTERSECTION, &lines, R, CLIP_NONZERO, &cut, c->err);
	if (!rc && cut.n && !(pc = calloc(cut.n, sizeof(*pc))))
		rc = st_error_set(c->err, ST_ERR_NOMEM, "support: out of memory for lines");
	for (size_t i = 0; !rc && i < cut.n; i++) {
		const int64_t *xy = clip_path_xy(&cut, i);
		size_t n = clip_path_len(&cut, i);
		pc[i] = (struct piece){.path = i, .line = xy[across], .along = xy[alongx]};
		if (xy[2 * (n - 1) + alongx] < pc[i].along)
			pc[i].along = xy[2 * (n - 1) + alongx];
	}
	if (!rc && cut.n)
		qsort(pc, cut.n, sizeof(*pc), piece_cmp);
	/* Zigzag: every other line runs backwards; pieces shorter than half a
	 * bead are not worth a start and a stop. */
	size_t line_no = 0;
	for (size_t i = 0; !rc && i < cut.n; i++) {
		const int64_t *xy = clip_path_xy(&cut, pc[i].path);
		size_t n = clip_path_len(&cut, pc[i].path);
		bool fwd = xy[2 * (n - 1) + alongx] >= xy[alongx];
		double len = fabs((double)(xy[2 * (n - 1) + alongx] - xy[alongx]));

		if (i > 0 && pc[i].line != pc[i - 1].line)
			line_no++;
		if (len < c->w / 2.0)
			continue;
		rc = slice_emit_xy(l, role, false, xy, n, llround(c->w), 0, fwd == (line_no & 1),
				   c->err);
	}
	free(pc);
	clip_paths_free(&lines);
	clip_paths_free(&cut);
	return rc;
}

/*
 * Paths of one support area A (nm) on layer l: its centre region is A
 * shrunk by w/2; interface lines along axis, or the body of the chosen
 * style, every gap nm.
 */
static int area_paths(struct ctx *c, const struct clip_paths *A, bool interface, double gap,
		      int axis, struct layer_paths *l)
{
	struct clip_paths R = {0};
	int rc = 0;

	if (!A->n)
		return 0;
	rc = clip_offset(A, -c->w / 2.0, CLIP_JOIN_ROUND, 2.0, c->arc, &R, c->err);
	if (!rc && interface)
		rc = fill_lines(c, &R, gap, axis, PATH_SUPPORT_INTERFACE, l);
	else if (!rc && c->s->support_material_style == SUPPORT_SNUG) {
		for (size_t i = 0; i < R.n && !rc; i++)
			rc = slice_emit_xy(l, PATH_SUPPORT, true, clip_path_xy(&R, i),
					   clip_path_len(&R, i), llround(c->w), 0, false, c->err);
		if (!rc)
			rc = fill_lines(c, &R, gap, 1, PATH_SUPPORT, l);
	} else if (!rc) {
		rc = fill_lines(c, &R, gap, 0, PATH_SUPPORT, l);
		if (!rc)
			rc = fill_lines(c, &R, gap, 1, PATH_SUPPORT, l);
	}
	clip_paths_free(&R);
	return rc;
}

/* G[j] = the model on layers 0 .. j (all of it) grown by the xy spacing. */
static int footprints(struct ctx *c, struct clip_paths *G)
{
	struct clip_paths F = {0};
	int rc = 0;

	for (size_t j = 0; j < c->st->n && !rc; j++) {
		rc = clip_boolean(CLIP_UNION, &F, model(c, j), CLIP_NONZERO, &F, c->err);
		if (!rc)
			rc = clip_offset(&F, c->xy, CLIP_JOIN_ROUND, 2.0, c->arc, &G[j], c->err);
	}
	clip_paths_free(&F);
	return rc;
}

/* out = the union of the contacts whose interface layers include layer j. */
static int interface_area(struct ctx *c, size_t j, const struct clip_paths *C, const long *t,
			  struct clip_paths *out)
{
	long L = c->s->support_material_interface_layers;
	int rc = 0;

	clip_paths_clear(out);
	for (size_t i = j + 1; i < c->st->n && !rc; i++)
		if (C[i].n && t[i] >= (long)j && t[i] - L < (long)j)
			rc = clip_paths_append(out, &C[i], c->err);
	if (!rc && out->n)
		rc = clip_boolean(CLIP_UNION, out, NULL, CLIP_NONZERO, out, c->err);
	return rc;
}

/* The support of layer j from the column area T (see support.h). */
static int layer_support(struct ctx *c, size_t j, const struct clip_paths *T,
			 const struct clip_paths *G, const struct clip_paths *C, const long *t,
			 struct layer_paths *l)
{
	struct clip_paths S = {0}, I = {0}, B = {0};
	double sp = perim_spacing(c->w, c->st->layers[j].height * SLICE_UNITS_PER_MM);
	double pitch = c->body + sp; /* PrusaSlicer: the spacing is the gap between beads */
	int rc = 0;

	if (c->s->support_material_style == SUPPORT_GRID) {
		rc = clip_offset(T, pitch / 2.0, CLIP_JOIN_SQUARE, 2.0, c->arc, &S, c->err);
		if (!rc)
			rc = clip_offset(&S, -pitch / 2.0, CLIP_JOIN_SQUARE, 2.0, c->arc, &S,
					 c->err);
		if (!rc)
			rc = clip_boolean(CLIP_UNION, &S, T, CLIP_NONZERO, &S, c->err);
	} else {
		rc = clip_paths_append(&S, T, c->err);
	}
	if (!rc)
		rc = clip_boolean(CLIP_DIFFERENCE, &S, &G[j], CLIP_NONZERO, &S, c->err);
	if (!rc)
		rc = interface_area(c, j, C, t, &I);
	if (!rc && I.n)
		rc = clip_boolean(CLIP_INTERSECTION, &I, &S, CLIP_NONZERO, &I, c->err);
	if (!rc)
		rc = clip_boolean(CLIP_DIFFERENCE, &S, &I, CLIP_NONZERO, &B, c->err);
	if (!rc)
		rc = area_paths(c, &I, true, sp, (int)(j & 1), l);
	if (!rc)
		rc = area_paths(c, &B, false, pitch, 0, l);
	clip_paths_free(&S);
	clip_paths_free(&I);
	clip_paths_free(&B);
	return rc;
}

/* Free n path sets and the array holding them. */
static void free_sets(struct clip_paths *v, size_t n)
{
	for (size_t i = 0; v && i < n; i++)
		clip_paths_free(&v[i]);
	free(v);
}

int support_generate(const struct support_settings *s, const struct slice_stack *st,
		     struct layer_stack *out, struct st_error *err)
{
	struct ctx c = {.s = s, .st = st, .err = err};
	struct clip_paths *C = NULL, *G = NULL, T = {0};
	long *t = NULL;
	bool any = false;
	int rc = support_settings_check(s, err);

	if (rc)
		return rc;
	if (!st || !out || out->nlayers != st->n)
		return st_error_set(err, ST_ERR_ARG,
				    "support: the output stack must have one layer per sliced layer");
	if (!s->support_material || st->n < 2)
		return 0;
	c.w = s->extrusion_width * SLICE_UNITS_PER_MM;
	c.arc = s->arc_tolerance * SLICE_UNITS_PER_MM;
	c.body = s->support_material_spacing * SLICE_UNITS_PER_MM;
	c.xy = s->support_material_xy_spacing * SLICE_UNITS_PER_MM;
	for (size_t i = 0; i < st->n; i++)
		if (s->extrusion_width < st->layers[i].height)
			return st_error_set(err, ST_ERR_RANGE,
					    "support: extrusion width %g mm is narrower than the "
					    "%g mm layer %zu; use at least the layer height",
					    s->extrusion_width, st->layers[i].height, i);
	C = calloc(st->n, sizeof(*C));
	G = calloc(st->n, sizeof(*G));
	t = calloc(st->n, sizeof(*t));
	if (!C || !G || !t) {
		rc = st_error_set(err, ST_ERR_NOMEM, "support: out of memory for %zu layers", st->n);
		goto out_free;
	}
	for (size_t i = 1; i < st->n && !rc; i++) {
		rc = contact(&c, i, &C[i]);
		t[i] = top_layer(&c, i);
		any = any || (C[i].n && t[i] >= 0);
	}
	if (rc || !any)
		goto out_free;
	rc = footprints(&c, G);
	/* Top down: columns start under their contacts and stop at the model. */
	for (size_t j = st->n; j-- > 0 && !rc;) {
		if (j + 1 < st->n && T.n)
			rc = clip_boolean(CLIP_DIFFERENCE, &T, model(&c, j + 1), CLIP_NONZERO, &T,
					  err);
		for (size_t i = j + 1; i < st->n && !rc; i++)
			if (t[i] == (long)j && C[i].n)
				rc = clip_boolean(CLIP_UNION, &T, &C[i], CLIP_NONZERO, &T, err);
		/* layer 0 on the bed at the first layer's width (PrusaSlicer's
		 * support_material_1st_layer_flow) */
		c.w = (j == 0 && s->first_layer_extrusion_width > 0 ? s->first_layer_extrusion_width
								     : s->extrusion_width) *
		      SLICE_UNITS_PER_MM;
		if (!rc && T.n)
			rc = layer_support(&c, j, &T, G, C, t, &out->layers[j]);
	}
out_free:
	free_sets(C, st->n);
	free_sets(G, st->n);
	free(t);
	clip_paths_free(&T);
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

/* ---------------------------------------------------------------------------
 * The raft (support.h)
 */

/* Interface layers of a raft of n layers, PrusaSlicer's split: the upper half. */
static int raft_interface_layers(int n)
{
	return (n + 1) / 2;
}

int support_raft_new(const struct support_settings *s, double first_layer_height,
		     double layer_height, double nozzle_diameter, struct slice_stack *st,
		     struct slice_stack **raft, double *lift, struct st_error *err)
{
	/* PrusaSlicer: the raft's upper layers as thick as the nozzle allows,
	 * so the raft is quick and stiff. */
	double upper = fmax(layer_height, 0.75 * nozzle_diameter), top = 0.0;
	size_t n = s && s->raft_layers > 0 ? (size_t)s->raft_layers : 0;
	struct slice_stack *r;

	*raft = NULL;
	if (!n || !st || !st->n)
		return st_error_set(err, ST_ERR_ARG, "support: no raft layers or no part to lift");
	r = calloc(1, sizeof(*r));
	if (r)
		r->layers = calloc(n, sizeof(*r->layers));
	if (!r || !r->layers) {
		slice_stack_free(r);
		return st_error_set(err, ST_ERR_NOMEM, "support: out of memory for the raft");
	}
	r->n = n;
	for (size_t i = 0; i < n; i++) {
		r->layers[i].height = i == 0 ? first_layer_height : upper;
		top += r->layers[i].height;
		r->layers[i].z = top;
	}
	*lift = top + s->raft_contact_distance;
	for (size_t i = 0; i < st->n; i++)
		st->layers[i].z += *lift;
	*raft = r;
	return 0;
}

/*
 * How far (mm) raft layer i reaches beyond the footprint, PrusaSlicer's
 * rule: the contact layer (the top) raft_expansion; under it, the raft
 * grows 0.5 mm more for stability, and layer 0 reaches
 * raft_first_layer_expansion beyond the footprint's raft_expansion, at
 * least those 0.5 mm.  A one-layer raft is its contact layer.
 */
static double raft_growth(const struct support_settings *s, int i)
{
	if (s->raft_layers == 1 || i == s->raft_layers - 1)
		return s->raft_expansion;
	if (i > 0)
		return s->raft_expansion + RAFT_FINE_MM;
	return s->raft_expansion + fmax(s->raft_first_layer_expansion, RAFT_FINE_MM);
}

/* out = the part's first layer and the support's beads on it (support may be NULL). */
static int raft_footprint(struct ctx *c, const struct layer_stack *support,
			  struct clip_paths *out)
{
	struct clip_paths beads = {0};
	int rc = clip_paths_append(out, model(c, 0), c->err);

	if (!rc && support && support->nlayers)
		rc = support_beads(&support->layers[0], c->arc, &beads, c->err);
	if (!rc && beads.n)
		rc = clip_boolean(CLIP_UNION, out, &beads, CLIP_NONZERO, out, c->err);
	clip_paths_free(&beads);
	return rc;
}

int support_raft(const struct support_settings *s, const struct slice_stack *st,
		 const struct layer_stack *support, struct slice_stack *raft,
		 struct layer_stack *out, struct st_error *err)
{
	struct ctx c = {.s = s, .st = st, .err = err};
	struct clip_paths F = {0}, R = {0};
	int n = s ? s->raft_layers : 0, base, rc = support_settings_check(s, err);

	if (rc)
		return rc;
	if (!st || !st->n || !raft || !out || raft->n != (size_t)n || out->nlayers != raft->n)
		return st_error_set(err, ST_ERR_ARG,
				    "support: the raft stacks must have raft_layers = %d layers", n);
	c.w = s->extrusion_width * SLICE_UNITS_PER_MM;
	c.arc = s->arc_tolerance * SLICE_UNITS_PER_MM;
	c.body = s->support_material_spacing * SLICE_UNITS_PER_MM;
	base = n - raft_interface_layers(n);
	rc = raft_footprint(&c, support, &F);
	for (int i = 0; i < n && !rc; i++) {
		struct slice_layer *L = &raft->layers[i];
		double grow = raft_growth(s, i);
		c.w = (i == 0 && s->first_layer_extrusion_width > 0 ? s->first_layer_extrusion_width
								     : s->extrusion_width) *
		      SLICE_UNITS_PER_MM;
		double sp = perim_spacing(c.w, L->height * SLICE_UNITS_PER_MM), pitch = sp;
		enum path_role role = i < base ? PATH_SUPPORT : PATH_SUPPORT_INTERFACE;

		if (s->extrusion_width < L->height) {
			rc = st_error_set(err, ST_ERR_RANGE,
					  "support: extrusion width %g mm is narrower than the "
					  "%g mm raft layer %d; use at least the layer height",
					  s->extrusion_width, L->height, i + 1);
			break;
		}
		if (i == 0)
			pitch = sp * 100.0 / s->raft_first_layer_density;
		else if (i < base)
			pitch = c.body + sp; /* the spacing is the gap between beads */
		if (i == 0 && base == 0)
			role = PATH_SUPPORT_INTERFACE; /* a one-layer raft is its contact layer */
		rc = clip_offset_ex(&F, grow * SLICE_UNITS_PER_MM, CLIP_JOIN_ROUND, 2.0, c.arc,
				    &L->regions, err);
		if (!rc)
			rc = clip_offset(&L->regions.paths, -c.w / 2.0, CLIP_JOIN_ROUND, 2.0, c.arc,
					 &R, err);
		if (!rc)
			rc = fill_lines(&c, &R, pitch, i & 1, role, &out->layers[i]);
	}
	clip_paths_free(&F);
	clip_paths_free(&R);
	return rc;
}
