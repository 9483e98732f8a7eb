/*
 * support.c - overhang detection, support columns down to the bed or the
 * model, interface and body areas (see support.h).
 */
#include "support_int.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "perimeters.h"
#include "settings.h"

/* A layer top this close to a gap's limit still counts as below it, mm. */
#define SUPPORT_Z_EPS 1e-6
/* The steepest threshold used in the overhang distance, degrees. */
#define SUPPORT_MAX_DEG 89.0

/* The declared default of a support or raft key (settings.c); for a
 * percentage ("50%") the percent. */
static double declared(const char *name)
{
	const struct setting *d = settings_find(name);
	double v = 0.0;

	if (!setting_default_number(name, false, &v) && d && d->dflt)
		v = strtod(d->dflt, NULL);
	return v;
}

void support_settings_init(struct support_settings *s, double nozzle_diameter)
{
	s->support_material = false;
	s->support_material_threshold = declared("support_material_threshold");
	s->support_material_style = SUPPORT_GRID;
	s->support_material_pattern = SUPPORT_RECTILINEAR;
	s->support_material_with_sheath = declared("support_material_with_sheath") != 0;
	s->support_material_buildplate_only = declared("support_material_buildplate_only") != 0;
	s->support_material_contact_distance = declared("support_material_contact_distance");
	s->support_material_bottom_contact_distance =
	    declared("support_material_bottom_contact_distance");
	s->support_material_interface_layers = (int)declared("support_material_interface_layers");
	s->support_material_bottom_interface_layers =
	    (int)declared("support_material_bottom_interface_layers");
	s->support_material_interface_spacing = declared("support_material_interface_spacing");
	s->support_material_spacing = declared("support_material_spacing");
	s->support_material_angle = declared("support_material_angle");
	s->dont_support_bridges = declared("dont_support_bridges") != 0;
	s->extrusion_width = 1.125 * nozzle_diameter;
	s->first_layer_extrusion_width = 0.0;
	/* a percentage of the outer wall's width, automatic: as extrusion_width */
	s->support_material_xy_spacing =
	    declared("support_material_xy_spacing") / 100.0 * s->extrusion_width;
	s->arc_tolerance = 0.002;
	s->raft_layers = (int)declared("raft_layers");
	s->raft_contact_distance = declared("raft_contact_distance");
	s->raft_expansion = declared("raft_expansion");
	s->raft_first_layer_density = declared("raft_first_layer_density");
	s->raft_first_layer_expansion = declared("raft_first_layer_expansion");
}

int support_choice_parse(const char *key, const char *name, int *out, struct st_error *err)
{
	const struct setting *d = settings_find(key);
	char names[128] = "";

	for (size_t i = 0; d && name && i < d->nnames; i++) {
		if (!strcmp(d->names[i], name)) {
			*out = (int)i;
			return 0;
		}
		snprintf(names + strlen(names), sizeof(names) - strlen(names), "%s%s",
			 i ? ", " : "", d->names[i]);
	}
	return st_error_set(err, ST_ERR_ARG, "support: %s \"%.32s\" is unknown; use %s", key,
			    name ? name : "(none)", names);
}

/* The keys support.h checks against their declared ranges (settings.h). */
static int declared_check(const struct support_settings *s, struct st_error *err)
{
	int rc = setting_check("support", "support_material_bottom_contact_distance",
			       s->support_material_bottom_contact_distance, err);

	if (!rc)
		rc = setting_check("support", "support_material_bottom_interface_layers",
				   s->support_material_bottom_interface_layers, err);
	if (!rc)
		rc = setting_check("support", "support_material_interface_spacing",
				   s->support_material_interface_spacing, err);
	if (!rc)
		rc = setting_check("support", "support_material_angle", s->support_material_angle,
				   err);
	return rc;
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
	if ((unsigned)s->support_material_pattern >= SUPPORT_PATTERNS)
		return st_error_set(err, ST_ERR_ARG,
				    "support: support_material_pattern %d is unknown; use rectilinear, "
				    "rectilinear-grid or honeycomb",
				    (int)s->support_material_pattern);
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
	int rc = raft_check(s, err);
	return rc ? rc : declared_check(s, err);
}

/* How far (nm) layer i may reach beyond layer i-1 without support. */
static double overhang_allowance(const struct support_ctx *c, size_t i)
{
	double a = c->s->support_material_threshold;

	if (a <= 0.0)
		return c->w / 2.0;
	a = fmin(a + 1.0, SUPPORT_MAX_DEG) * M_PI / 180.0;
	return c->st->layers[i - 1].height * SLICE_UNITS_PER_MM / tan(a);
}

/* out = the contact area of layer i >= 1 (see support.h); empty if none. */
static int contact(struct support_ctx *c, size_t i, struct clip_paths *out)
{
	struct clip_paths grown = {0}, over = {0};
	double d = overhang_allowance(c, i);
	int rc = clip_offset(support_model(c, i - 1), d, CLIP_JOIN_ROUND, 2.0, c->arc, &grown, c->err);

	clip_paths_clear(out);
	if (!rc)
		rc = clip_boolean(CLIP_DIFFERENCE, support_model(c, i), &grown, CLIP_NONZERO, &over, c->err);
	if (!rc && over.n)
		rc = clip_offset(&over, d + c->w, CLIP_JOIN_ROUND, 2.0, c->arc, &over, c->err);
	if (!rc && over.n)
		rc = clip_boolean(CLIP_DIFFERENCE, support_model(c, i), support_model(c, i - 1), CLIP_NONZERO, out,
				  c->err);
	if (!rc && over.n)
		rc = clip_boolean(CLIP_INTERSECTION, out, &over, CLIP_NONZERO, out, c->err);
	clip_paths_free(&grown);
	clip_paths_free(&over);
	return rc;
}

/* Highest layer under the interface gap of layer i, or -1 if none. */
static long top_layer(const struct support_ctx *c, size_t i)
{
	const struct slice_layer *L = c->st->layers;
	double limit = L[i].z - L[i].height - c->s->support_material_contact_distance +
		       SUPPORT_Z_EPS;

	for (size_t j = i; j-- > 0;)
		if (L[j].z <= limit)
			return (long)j;
	return -1;
}

/* The Z gap kept above the model's top surfaces, mm: none under a soluble
 * (0) top gap, as PrusaSlicer has it. */
static double bottom_gap(const struct support_settings *s)
{
	if (s->support_material_contact_distance <= 0.0)
		return 0.0;
	return s->support_material_bottom_contact_distance > 0.0
		   ? s->support_material_bottom_contact_distance
		   : s->support_material_contact_distance;
}

/* Bottom interface layers: -1 is as many as on top. */
static long bottom_interfaces(const struct support_settings *s)
{
	return s->support_material_bottom_interface_layers < 0
		   ? s->support_material_interface_layers
		   : s->support_material_bottom_interface_layers;
}

/* G[j] = the model on layers 0 .. j (all of it) grown by the xy spacing. */
static int footprints(struct support_ctx *c, struct clip_paths *G)
{
	struct clip_paths F = {0};
	int rc = 0;

	for (size_t j = 0; j < c->st->n && !rc; j++) {
		rc = clip_boolean(CLIP_UNION, &F, support_model(c, j), CLIP_NONZERO, &F, c->err);
		if (!rc)
			rc = clip_offset(&F, c->xy, CLIP_JOIN_ROUND, 2.0, c->arc, &G[j], c->err);
	}
	clip_paths_free(&F);
	return rc;
}

/*
 * B[j] = what support on layer j must not stand in or on: the model on
 * layers k <= j whose top lies less than the bottom gap under layer j's
 * bottom; G[j] = B[j] grown by the xy spacing.
 */
static int blocked(struct support_ctx *c, struct clip_paths *B, struct clip_paths *G)
{
	const struct slice_layer *L = c->st->layers;
	double gap = bottom_gap(c->s);
	int rc = 0;

	for (size_t j = 0; j < c->st->n && !rc; j++) {
		double limit = L[j].z - L[j].height - gap + SUPPORT_Z_EPS;
		for (size_t k = j + 1; k-- > 0 && L[k].z > limit && !rc;)
			rc = clip_paths_append(&B[j], support_model(c, k), c->err);
		if (!rc)
			rc = clip_boolean(CLIP_UNION, &B[j], NULL, CLIP_NONZERO, &B[j], c->err);
		if (!rc)
			rc = clip_offset(&B[j], c->xy, CLIP_JOIN_ROUND, 2.0, c->arc, &G[j], c->err);
	}
	return rc;
}

/*
 * out = the interface area of layer j: the contacts whose top interface
 * layers include j, and with B (support on the model) the area that B
 * cuts off within the bottom interface layers under j.
 */
static int interface_area(struct support_ctx *c, size_t j, const struct clip_paths *C,
			  const long *t, const struct clip_paths *B, struct clip_paths *out)
{
	long L = c->s->support_material_interface_layers, Lb = B ? bottom_interfaces(c->s) : 0;
	int rc = 0;

	clip_paths_clear(out);
	for (size_t i = j + 1; i < c->st->n && !rc; i++)
		if (C[i].n && t[i] >= (long)j && t[i] - L < (long)j)
			rc = clip_paths_append(out, &C[i], c->err);
	for (long m = 1; m <= Lb && m <= (long)j && !rc; m++)
		rc = clip_paths_append(out, &B[j - (size_t)m], c->err);
	if (!rc && out->n)
		rc = clip_boolean(CLIP_UNION, out, NULL, CLIP_NONZERO, out, c->err);
	return rc;
}

/* The axis of the body's lines on layer j: along support_material_angle
 * (axis 0: X at 0 degrees, as PrusaSlicer 2.5 prints them), and with
 * rectilinear-grid turned 90 degrees every other layer. */
static int body_axis(const struct support_settings *s, size_t j)
{
	return s->support_material_pattern == SUPPORT_RECTILINEAR_GRID ? (int)(j & 1) : 0;
}

/* The support of layer j from the column area T (see support.h). */
static int layer_support(struct support_ctx *c, size_t j, const struct clip_paths *T,
			 const struct clip_paths *G, const struct clip_paths *C, const long *t,
			 const struct clip_paths *B, struct layer_paths *l)
{
	struct clip_paths S = {0}, I = {0}, R = {0};
	double sp = perim_spacing(c->w, c->st->layers[j].height * SLICE_UNITS_PER_MM);
	double pitch = c->body + sp; /* PrusaSlicer: the spacing is the gap between beads */
	double face = c->s->support_material_interface_spacing * SLICE_UNITS_PER_MM + sp;
	int rc = 0;

	c->sp = sp;
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
		rc = interface_area(c, j, C, t, B, &I);
	if (!rc && I.n)
		rc = clip_boolean(CLIP_INTERSECTION, &I, &S, CLIP_NONZERO, &I, c->err);
	if (!rc)
		rc = clip_boolean(CLIP_DIFFERENCE, &S, &I, CLIP_NONZERO, &R, c->err);
	if (!rc)
		rc = support_area_paths(c, &I, true, face, (int)(j & 1), l);
	if (!rc)
		rc = support_area_paths(c, &R, false, pitch, body_axis(c->s, j), l);
	clip_paths_free(&S);
	clip_paths_free(&I);
	clip_paths_free(&R);
	return rc;
}

/* Free n path sets and the array holding them. */
static void free_sets(struct clip_paths *v, size_t n)
{
	for (size_t i = 0; v && i < n; i++)
		clip_paths_free(&v[i]);
	free(v);
}

/* Every layer's contact area C[i] and its top support layer t[i]; *any
 * when some contact has a layer to stand on. */
static int contacts(struct support_ctx *c, struct clip_paths *C, long *t, bool *any)
{
	int rc = 0;

	*any = false;
	for (size_t i = 1; i < c->st->n && !rc; i++) {
		rc = contact(c, i, &C[i]);
		if (!rc && C[i].n && c->s->dont_support_bridges)
			rc = support_drop_bridges(c, i, &C[i]);
		t[i] = top_layer(c, i);
		*any = *any || (C[i].n && t[i] >= 0);
	}
	return rc;
}

int support_generate(const struct support_settings *s, const struct slice_stack *st,
		     struct layer_stack *out, struct st_error *err)
{
	struct support_ctx c = {.s = s, .st = st, .err = err};
	struct clip_paths *C = NULL, *G = NULL, *B = NULL, T = {0};
	long *t = NULL;
	bool any = false, on_model;
	int rc = support_settings_check(s, err);

	if (rc)
		return rc;
	if (!st || !out || out->nlayers != st->n)
		return st_error_set(err, ST_ERR_ARG,
				    "support: the output stack must have one layer per sliced layer");
	if (!s->support_material || st->n < 2)
		return 0;
	on_model = !s->support_material_buildplate_only;
	c.w = s->extrusion_width * SLICE_UNITS_PER_MM;
	c.arc = s->arc_tolerance * SLICE_UNITS_PER_MM;
	c.body = s->support_material_spacing * SLICE_UNITS_PER_MM;
	c.xy = s->support_material_xy_spacing * SLICE_UNITS_PER_MM;
	c.angle = s->support_material_angle * M_PI / 180.0;
	for (size_t i = 0; i < st->n; i++)
		if (s->extrusion_width < st->layers[i].height)
			return st_error_set(err, ST_ERR_RANGE,
					    "support: extrusion width %g mm is narrower than the "
					    "%g mm layer %zu; use at least the layer height",
					    s->extrusion_width, st->layers[i].height, i);
	C = calloc(st->n, sizeof(*C));
	G = calloc(st->n, sizeof(*G));
	B = on_model ? calloc(st->n, sizeof(*B)) : NULL;
	t = calloc(st->n, sizeof(*t));
	if (!C || !G || !t || (on_model && !B)) {
		rc = st_error_set(err, ST_ERR_NOMEM, "support: out of memory for %zu layers", st->n);
		goto out_free;
	}
	rc = contacts(&c, C, t, &any);
	if (rc || !any)
		goto out_free;
	rc = on_model ? blocked(&c, B, G) : footprints(&c, G);
	/* Top down: columns start under their contacts and stop where they
	 * meet the model: on the bed only, or on the model below the gap. */
	for (size_t j = st->n; j-- > 0 && !rc;) {
		if (!on_model && j + 1 < st->n && T.n)
			rc = clip_boolean(CLIP_DIFFERENCE, &T, support_model(&c, j + 1), CLIP_NONZERO,
					  &T, err);
		for (size_t i = j + 1; i < st->n && !rc; i++)
			if (t[i] == (long)j && C[i].n)
				rc = clip_boolean(CLIP_UNION, &T, &C[i], CLIP_NONZERO, &T, err);
		if (on_model && !rc && T.n)
			rc = clip_boolean(CLIP_DIFFERENCE, &T, &B[j], CLIP_NONZERO, &T, err);
		/* layer 0 on the bed at the first layer's width (PrusaSlicer's
		 * support_material_1st_layer_flow) */
		c.w = (j == 0 && s->first_layer_extrusion_width > 0 ? s->first_layer_extrusion_width
								     : s->extrusion_width) *
		      SLICE_UNITS_PER_MM;
		if (!rc && T.n)
			rc = layer_support(&c, j, &T, G, C, t, B, &out->layers[j]);
	}
out_free:
	free_sets(C, st->n);
	free_sets(G, st->n);
	free_sets(B, st->n);
	free(t);
	clip_paths_free(&T);
	return rc;
}
