/*
 * support_raft.c - the raft under the part and its support (support.h).
 */
#include "support_int.h"

#include <math.h>
#include <stdlib.h>

#include "perimeters.h"

/* How much more the raft grows below its contact layer, mm (PrusaSlicer's
 * inflate_factor_fine). */
#define RAFT_FINE_MM 0.5

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
static int raft_footprint(struct support_ctx *c, const struct layer_stack *support,
			  struct clip_paths *out)
{
	struct clip_paths beads = {0};
	int rc = clip_paths_append(out, support_model(c, 0), c->err);

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
	struct support_ctx c = {.s = s, .st = st, .err = err};
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
			rc = support_fill_lines(&c, &R, pitch, i & 1, role, &out->layers[i]);
	}
	clip_paths_free(&F);
	clip_paths_free(&R);
	return rc;
}
