/*
 * stages.c - each stage's settings from the job's config, and the stacks
 * the stages fill (stages.h).
 */
#include "stages.h"

#include <math.h>
#include <stdlib.h>

#include "adaptive.h"
#include "skirt.h"
#include "support.h"

/* The raft's layers, then the sections'. */
struct layer_stack *stage_print_stack(const struct slice_stack *raft, const struct slice_stack *st,
				      struct st_error *err)
{
	size_t nr = raft ? raft->n : 0;
	struct layer_stack *s = layer_stack_new(nr + st->n, err);

	for (size_t i = 0; s && i < nr + st->n; i++) {
		const struct slice_layer *l = i < nr ? &raft->layers[i] : &st->layers[i - nr];
		s->layers[i].z = l->z;
		s->layers[i].height = l->height;
	}
	return s;
}

int stage_slice(const struct mesh *m, const struct slicer_config *c, struct slice_stack **st,
		struct slicer_summary *sum, struct st_error *err)
{
	struct adaptive_settings as;
	struct adaptive_cusp cusp;
	struct layer_span *plan = NULL;
	double lo[3], hi[3];
	size_t n = 0;
	bool profiled = !c->adaptive.enabled && c->adaptive.profile, varying;
	int rc;

	*st = NULL;
	slicer_adaptive_settings(c, &as);
	mesh_bbox(m, lo, hi);
	varying = c->adaptive.enabled || profiled;
	if (c->adaptive.enabled)
		rc = adaptive_plan(m, &as, &plan, &n, err);
	else if (profiled)
		rc = adaptive_plan_profile(hi[2] - lo[2], &as, c->adaptive.profile,
					   c->adaptive.profile_pairs, &plan, &n,
					   &sum->profile_clamped, err);
	else
		rc = slice_plan_uniform(hi[2] - lo[2], as.first_height, c->layer_height, &plan, &n,
					err);
	if (!rc)
		rc = slice_mesh_plan(m, plan, n, &c->slice, st, err);
	if (!rc && varying) /* the first layer's height is fixed */
		rc = adaptive_measure(m, plan + (n > 1), n - (n > 1), NULL, &cusp, err);
	if (!rc) {
		sum->adaptive = c->adaptive.enabled;
		sum->profiled = profiled;
		sum->height_min = n > 1 ? INFINITY : 0.0;
		sum->height_max = 0.0;
		for (size_t i = 1; i < n; i++) {
			sum->height_min = fmin(sum->height_min, plan[i].height);
			sum->height_max = fmax(sum->height_max, plan[i].height);
		}
		sum->cusp_max = varying ? cusp.max : 0.0;
		sum->cusp_mean = varying ? cusp.mean : 0.0;
	}
	free(plan);
	return rc;
}

int stage_report_plan(const struct slicer_config *c, const struct slice_stack *raft,
		      const struct slice_stack *st, struct st_error *err)
{
	size_t nr = raft ? raft->n : 0;
	struct layer_span *all;

	if (!c->planned)
		return 0;
	all = malloc((nr + st->n ? nr + st->n : 1) * sizeof(*all));
	if (!all)
		return st_error_set(err, ST_ERR_NOMEM, "slicer: out of memory for %zu layers",
				    nr + st->n);
	for (size_t i = 0; i < nr + st->n; i++) {
		const struct slice_layer *l = i < nr ? &raft->layers[i] : &st->layers[i - nr];
		all[i] = (struct layer_span){.z = l->z, .height = l->height};
	}
	c->planned(c->planned_ctx, all, nr + st->n);
	free(all);
	return 0;
}

/* The sections' layers alone. */
struct layer_stack *stage_stack(const struct slice_stack *st, struct st_error *err)
{
	return stage_print_stack(NULL, st, err);
}

/* Whether any layer of s holds a path. */
static bool stack_has_paths(const struct layer_stack *s)
{
	for (size_t l = 0; l < s->nlayers; l++)
		if (s->layers[l].n)
			return true;
	return false;
}

/* Support with the job's threshold, and its other keys and the width it
 * shares with the raft (slicer_raft_support). */
int stage_support(const struct slicer_config *c, const struct slice_stack *st,
		  struct layer_stack *out, bool *ran, struct st_error *err)
{
	struct support_settings s;
	int rc;

	*ran = false;
	if (!c->support.enabled)
		return 0;
	slicer_raft_support(c, &s);
	if (c->raft.layers > 0) /* support stands on the raft, not on the bed */
		s.first_layer_extrusion_width = 0;
	s.support_material = true;
	s.support_material_threshold = c->support.threshold;
	rc = support_generate(&s, st, out, err);
	*ran = !rc && stack_has_paths(out);
	return rc;
}

/* The raft's layers; the lifted part must still fit the build height. */
int stage_raft_layers(const struct slicer_config *c, struct slice_stack *st,
		      struct slice_stack **raft, double *lift, struct st_error *err)
{
	struct support_settings ss;
	double top;
	int rc;

	slicer_raft_support(c, &ss);
	rc = support_raft_new(&ss, c->first_layer_height, c->layer_height, c->perim.nozzle_diameter,
			      st, raft, lift, err);
	top = rc ? 0.0 : st->layers[st->n - 1].z;
	if (!rc && top > c->bed.max_height + SLICER_FIT_SLACK)
		rc =
		    st_error_set(err, ST_ERR_RANGE,
				 "on its %.2f mm raft the model reaches %.2f mm but the printer "
				 "builds at most %.2f mm (max_print_height); use fewer raft_layers",
				 *lift, top, c->bed.max_height);
	return rc;
}

/* The raft with the job's raft keys (slicer_raft_support). */
int stage_raft(const struct slicer_config *c, const struct slice_stack *st,
	       const struct layer_stack *support, struct slice_stack *raft, struct layer_stack *out,
	       struct st_error *err)
{
	struct support_settings ss;

	slicer_raft_support(c, &ss);
	return support_raft(&ss, st, support, raft, out, err);
}

/* Skirt and brim with the job's keys, the first layer's width (PrusaSlicer's
 * skirt and brim flow), else the walls'. */
int stage_skirt(const struct slicer_config *c, const struct slice_stack *st,
		const struct layer_stack *support, struct layer_stack *out, bool *ran,
		struct st_error *err)
{
	struct skirt_settings s;
	int rc;

	skirt_settings_init(&s, c->perim.nozzle_diameter);
	/* PrusaSlicer prints no skirt at skirt_height 0. */
	s.skirts = c->skirt.skirt_height > 0 ? c->skirt.skirts : 0;
	s.skirt_distance = c->skirt.skirt_distance;
	s.skirt_height = c->skirt.skirt_height > 0 ? c->skirt.skirt_height : 1;
	s.min_skirt_length = c->skirt.skirt_height > 0 ? c->skirt.min_skirt_length : 0;
	s.brim_width = c->skirt.brim_width;
	s.brim_separation = c->skirt.brim_separation;
	s.extrusion_width = c->first_layer_extrusion_width > 0 ? c->first_layer_extrusion_width
							       : c->perim.extrusion_width;
	s.filament_diameter = c->gcodew.filament_diameter;
	rc = skirt_generate(&s, st, support, out, err);
	*ran = !rc && stack_has_paths(out);
	return rc;
}

/* A role's width w, or the walls' when w is 0. */
static double width_or(double w, const struct slicer_config *c)
{
	return w > 0 ? w : c->perim.extrusion_width;
}

/* The infill job of the settings: the walls' width, the job's flow. */
int stage_infill_job(const struct slicer_config *c, const struct slice_stack *st,
		     struct infill_job **job, struct st_error *err)
{
	struct infill_settings s;
	int rc;

	infill_settings_init(&s, c->perim.nozzle_diameter);
	rc = infill_pattern_parse(c->infill.pattern, &s.fill_pattern, err);
	if (rc)
		return rc;
	s.fill_density = c->infill.density;
	s.top_solid_layers = c->infill.top_solid_layers;
	s.bottom_solid_layers = c->infill.bottom_solid_layers;
	s.solid_infill_below_area = c->infill.solid_infill_below_area;
	s.top_solid_min_thickness = c->infill.top_solid_min_thickness;
	s.bottom_solid_min_thickness = c->infill.bottom_solid_min_thickness;
	s.fill_angle = c->infill.fill_angle;
	s.bridge_angle = c->infill.bridge_angle;
	s.bridge_flow_ratio = c->infill.bridge_flow_ratio;
	s.thick_bridges = c->infill.thick_bridges;
	s.top_monotonic = c->infill.top_monotonic;
	s.infill_anchor = c->infill.anchor;
	s.infill_anchor_max = c->infill.anchor_max;
	s.bottom_monotonic = c->infill.bottom_monotonic;
	s.infill_overlap = c->infill.infill_overlap;
	s.layer_height = c->layer_height;
	s.perimeter_extrusion_width = c->perim.extrusion_width;
	s.infill_extrusion_width = width_or(c->infill.infill_extrusion_width, c);
	s.solid_infill_extrusion_width = width_or(c->infill.solid_infill_extrusion_width, c);
	s.top_infill_extrusion_width = width_or(c->infill.top_infill_extrusion_width, c);
	/* Over a raft the part's first layer is not PrusaSlicer's first layer. */
	s.first_layer_extrusion_width = c->raft.layers == 0 ? c->first_layer_extrusion_width : 0;
	s.ironing = c->gcodew.ironing;
	s.ironing_spacing = c->gcodew.ironing_spacing;
	rc = iron_type_parse(c->gcodew.ironing_type, &s.ironing_type, err);
	return rc ? rc : infill_job_new(&s, st, job, err);
}
