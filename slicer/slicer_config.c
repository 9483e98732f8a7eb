/*
 * slicer_config.c - the slicing job's settings: the defaults and the checks
 * made before any work (slicer.h).
 */
#include "slicer.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "adaptive.h"
#include "infill.h"
#include "settings.h"
#include "support.h"
#include "travel.h"

/* Support's keys as support.h defaults them (the declared defaults). */
static void support_defaults(struct slicer_support_settings *c, double nozzle_diameter)
{
	struct support_settings s;

	support_settings_init(&s, nozzle_diameter);
	*c = (struct slicer_support_settings){
	    .enabled = s.support_material,
	    .style = settings_find("support_material_style")->names[s.support_material_style],
	    .pattern = settings_find("support_material_pattern")->names[s.support_material_pattern],
	    .with_sheath = s.support_material_with_sheath,
	    .threshold = (int)s.support_material_threshold,
	    .buildplate_only = s.support_material_buildplate_only,
	    .dont_support_bridges = s.dont_support_bridges,
	    .contact_distance = s.support_material_contact_distance,
	    .bottom_contact_distance = s.support_material_bottom_contact_distance,
	    .interface_layers = s.support_material_interface_layers,
	    .bottom_interface_layers = s.support_material_bottom_interface_layers,
	    .interface_spacing = s.support_material_interface_spacing,
	    .spacing = s.support_material_spacing,
	    .angle = s.support_material_angle,
	    .xy_spacing = s.support_material_xy_spacing};
}

void slicer_config_init(struct slicer_config *c, double nozzle_diameter)
{
	memset(c, 0, sizeof(*c));
	c->layer_height = 0.2;
	c->first_layer_height = 0.2;
	slice_settings_init(&c->slice);
	c->slice.nozzle_diameter = nozzle_diameter;
	perim_settings_init(&c->perim, nozzle_diameter);
	gcodew_settings_init(&c->gcodew);
	c->gcodew.nozzle_diameter = nozzle_diameter;
	c->infill = (struct slicer_infill_settings){
	    .density = 20, .pattern = "rectilinear", .top_solid_layers = 3, .bottom_solid_layers = 3,
	    .solid_infill_below_area = 70, .fill_angle = 45, .bridge_flow_ratio = 1,
	    .thick_bridges = true,
	    .infill_overlap = 25};
	support_defaults(&c->support, nozzle_diameter);
	/* The declared defaults, as the writer has them. */
	c->raft = (struct slicer_raft_settings){
	    .layers = c->gcodew.raft_layers,
	    .contact_distance = c->gcodew.raft_contact_distance,
	    .expansion = c->gcodew.raft_expansion,
	    .first_layer_density = c->gcodew.raft_first_layer_density,
	    .first_layer_expansion = c->gcodew.raft_first_layer_expansion};
	c->skirt = (struct slicer_skirt_settings){.skirts = 1, .skirt_distance = 6, .skirt_height = 1};
	c->adaptive.allowed = true;
	setting_default_number("adaptive_max_cusp", false, &c->adaptive.max_cusp);
	setting_default_number("min_layer_height", false, &c->adaptive.min_height);
	setting_default_number("max_layer_height", false, &c->adaptive.max_height);
	c->max_detour = TRAVEL_DETOUR_DEFAULT_PCT;
	c->max_detour_is_percent = true;
	c->bed = (struct slicer_bed){.max_x = 200, .max_y = 200, .max_height = 200,
				     .object_distance = 6};
}

void slicer_config_modes(struct slicer_config *c)
{
	if (!c->gcodew.spiral_vase)
		return;
	c->perim.perimeters = 1;
	c->infill.top_solid_layers = 0;
	c->infill.top_solid_min_thickness = 0;
	c->infill.density = 0;
}

static int adaptive_check(const struct slicer_config *c, struct st_error *err);

int slicer_config_check(const struct slicer_config *c, struct st_error *err)
{
	int rc;

	if (!c)
		return st_error_set(err, ST_ERR_ARG, "slicer: no settings given");
	if (c->slice.nozzle_diameter != c->perim.nozzle_diameter)
		return st_error_set(err, ST_ERR_ARG,
				    "slicer: the slicing nozzle %g mm and the walls' nozzle %g mm "
				    "differ; set both from nozzle_diameter",
				    c->slice.nozzle_diameter, c->perim.nozzle_diameter);
	rc = slice_settings_check(&c->slice, c->first_layer_height, c->layer_height, err);
	if (!rc)
		rc = perim_settings_check(&c->perim, c->first_layer_height, err);
	if (!rc)
		rc = perim_settings_check(&c->perim, c->layer_height, err);
	if (!rc && c->first_layer_extrusion_width != 0.0) {
		struct perim_settings first;
		slicer_first_layer_walls(c, &first);
		if (!(c->first_layer_extrusion_width > 0.0))
			return st_error_set(err, ST_ERR_RANGE,
					    "first_layer_extrusion_width = %g mm is out of range; "
					    "use 0 (each role's width) or more",
					    c->first_layer_extrusion_width);
		rc = perim_settings_check(&first, c->first_layer_height, err);
	}
	if (!rc)
		rc = gcodew_settings_check(&c->gcodew, err);
	if (rc)
		return rc;
	if (!(c->infill.density >= 0.0 && c->infill.density <= 100.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "fill_density = %g%% is out of range; use 0 to 100%%",
				    c->infill.density);
	if (!c->infill.pattern)
		return st_error_set(err, ST_ERR_ARG, "slicer: no fill_pattern given");
	enum infill_pattern pattern;
	rc = infill_pattern_parse(c->infill.pattern, &pattern, err);
	if (rc)
		return rc; /* before any slicing: a pattern we cannot print */
	if (c->infill.top_solid_layers < 0 || c->infill.bottom_solid_layers < 0)
		return st_error_set(err, ST_ERR_RANGE,
				    "top_solid_layers = %d, bottom_solid_layers = %d: layer counts "
				    "cannot be negative; use 0 or more",
				    c->infill.top_solid_layers, c->infill.bottom_solid_layers);
	if (c->gcodew.spiral_vase && c->support.enabled)
		return st_error_set(err, ST_ERR_RANGE,
				    "spiral_vase = 1 cannot print support material "
				    "(support_material = 1), as in PrusaSlicer; turn one of them off");
	if (c->support.threshold < 0 || c->support.threshold > 90)
		return st_error_set(err, ST_ERR_RANGE,
				    "support_material_threshold = %d is out of range; use 0 "
				    "(automatic) to 90 degrees",
				    c->support.threshold);
	int style, body;
	rc = support_choice_parse("support_material_style", c->support.style, &style, err);
	if (!rc)
		rc = support_choice_parse("support_material_pattern", c->support.pattern, &body, err);
	if (rc)
		return rc;
	struct support_settings raft;
	slicer_raft_support(c, &raft);
	rc = support_settings_check(&raft, err);
	if (rc)
		return rc;
	if (c->skirt.skirts < 0)
		return st_error_set(err, ST_ERR_RANGE,
				    "skirts = %d: the loop count cannot be negative; use 0 or more",
				    c->skirt.skirts);
	if (!(c->skirt.brim_width >= 0.0 && c->skirt.brim_width <= 1000.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "brim_width = %g mm is out of range; use 0 to 1000 mm",
				    c->skirt.brim_width);
	if (!(c->bed.max_x > c->bed.min_x && c->bed.max_y > c->bed.min_y &&
	      c->bed.max_height > 0.0 && isfinite(c->bed.max_x - c->bed.min_x) &&
	      isfinite(c->bed.max_y - c->bed.min_y) && isfinite(c->bed.max_height)))
		return st_error_set(err, ST_ERR_RANGE,
				    "the bed (%g to %g mm in X, %g to %g mm in Y, %g mm high) is "
				    "empty; check bed_shape and max_print_height",
				    c->bed.min_x, c->bed.max_x, c->bed.min_y, c->bed.max_y,
				    c->bed.max_height);
	rc = setting_check("slicer", "elefant_foot_compensation", c->elefant_foot_compensation,
			   err);
	if (rc)
		return rc;
	if (c->bed.has_center && !(isfinite(c->bed.center_x) && isfinite(c->bed.center_y)))
		return st_error_set(err, ST_ERR_RANGE, "the placement centre is not a finite point");
	if (c->threads < 0 || c->threads > SLICER_MAX_THREADS)
		return st_error_set(err, ST_ERR_RANGE,
				    "threads = %d is out of range; use 0 (all cores) to %d",
				    c->threads, SLICER_MAX_THREADS);
	return c->adaptive.enabled || c->adaptive.profile ? adaptive_check(c, err) : 0;
}

void slicer_adaptive_settings(const struct slicer_config *c, struct adaptive_settings *out)
{
	double top = 0.75 * c->perim.nozzle_diameter; /* PrusaSlicer's largest height */

	out->first_height = c->raft.layers > 0 ? c->layer_height : c->first_layer_height;
	out->min_height = c->adaptive.min_height;
	out->max_height = c->adaptive.max_height > 0 ? fmin(c->adaptive.max_height, top) : top;
	out->max_cusp = c->adaptive.max_cusp;
}

/* Adaptive layers: allowed by the printer, heights every stage can print. */
static int adaptive_check(const struct slicer_config *c, struct st_error *err)
{
	struct adaptive_settings a;
	int rc;

	if (!c->adaptive.allowed)
		return st_error_set(err, ST_ERR_RANGE,
				    "adaptive layer heights: the printer does not allow variable "
				    "layer heights (variable_layer_height = 0); slice with uniform "
				    "layers or set variable_layer_height = 1");
	rc = setting_check("slicer", "adaptive_max_cusp", c->adaptive.max_cusp, err);
	if (rc)
		return rc;
	slicer_adaptive_settings(c, &a);
	if (!(a.min_height >= ADAPTIVE_STEP_MM && a.min_height <= a.max_height))
		return st_error_set(err, ST_ERR_RANGE,
				    "adaptive layer heights: min_layer_height = %g mm must be at "
				    "least %g mm and at most the largest layer height %g mm "
				    "(max_layer_height, at most 75%% of the %g mm nozzle)",
				    a.min_height, ADAPTIVE_STEP_MM, a.max_height,
				    c->perim.nozzle_diameter);
	rc = perim_settings_check(&c->perim, a.min_height, err);
	return rc ? rc : perim_settings_check(&c->perim, a.max_height, err);
}

void slicer_first_layer_walls(const struct slicer_config *c, struct perim_settings *out)
{
	*out = c->perim;
	/* Over a raft the part's first layer is not PrusaSlicer's first layer. */
	if (c->first_layer_extrusion_width > 0.0 && c->raft.layers == 0) {
		out->extrusion_width = c->first_layer_extrusion_width;
		out->external_extrusion_width = c->first_layer_extrusion_width;
	}
}

void slicer_raft_support(const struct slicer_config *c, struct support_settings *s)
{
	support_settings_init(s, c->perim.nozzle_diameter);
	/* PrusaSlicer prints the raft with support's width */
	s->extrusion_width =
	    c->support.extrusion_width > 0 ? c->support.extrusion_width : c->perim.extrusion_width;
	/* the stack's layer 0 is on the bed: the raft's, or support's without one */
	s->first_layer_extrusion_width = c->first_layer_extrusion_width;
	int style = SUPPORT_STYLES, pattern = SUPPORT_PATTERNS; /* unknown: refused by the check */
	support_choice_parse("support_material_style", c->support.style, &style, NULL);
	support_choice_parse("support_material_pattern", c->support.pattern, &pattern, NULL);
	s->support_material_style = (enum support_style)style;
	s->support_material_pattern = (enum support_pattern)pattern;
	s->support_material_with_sheath = c->support.with_sheath;
	s->support_material_buildplate_only = c->support.buildplate_only;
	s->support_material_contact_distance = c->support.contact_distance;
	s->support_material_bottom_contact_distance = c->support.bottom_contact_distance;
	s->support_material_interface_layers = c->support.interface_layers;
	s->support_material_bottom_interface_layers = c->support.bottom_interface_layers;
	s->support_material_interface_spacing = c->support.interface_spacing;
	s->support_material_spacing = c->support.spacing;
	s->support_material_angle = c->support.angle;
	s->support_material_xy_spacing = c->support.xy_spacing;
	s->dont_support_bridges = c->support.dont_support_bridges;
	s->raft_layers = c->raft.layers;
	s->raft_contact_distance = c->raft.contact_distance;
	s->raft_expansion = c->raft.expansion;
	s->raft_first_layer_density = c->raft.first_layer_density;
	s->raft_first_layer_expansion = c->raft.first_layer_expansion;
}

size_t slicer_settings_text(const struct slicer_config *c, char *buf, size_t cap)
{
	struct slicer_config m = *c;
	const struct setting *seam = settings_find("seam_position");
	int n;

	slicer_config_modes(&m);
	n = snprintf(buf, cap,
		     "; perimeters = %d\n; top_solid_layers = %d\n; bottom_solid_layers = %d\n"
		     "; fill_density = %g%%\n; fill_pattern = %s\n; top_fill_pattern = %s\n"
		     "; bottom_fill_pattern = %s\n; fill_angle = %g\n"
		     "; solid_infill_below_area = %g\n; external_perimeters_first = %d\n"
		     "; seam_position = %s\n; skirts = %d\n; skirt_distance = %g\n"
		     "; skirt_height = %d\n; brim_width = %g\n; support_material = %d\n"
		     "; support_material_threshold = %d\n; elefant_foot_compensation = %g\n",
		     m.perim.perimeters, m.infill.top_solid_layers, m.infill.bottom_solid_layers,
		     m.infill.density, m.infill.pattern,
		     m.infill.top_monotonic ? "monotonic" : "rectilinear",
		     m.infill.bottom_monotonic ? "monotonic" : "rectilinear", m.infill.fill_angle,
		     m.infill.solid_infill_below_area, m.perim.outer_first,
		     seam && (size_t)m.perim.seam < seam->nnames ? seam->names[m.perim.seam] : "?",
		     m.skirt.skirts, m.skirt.skirt_distance, m.skirt.skirt_height,
		     m.skirt.brim_width, m.support.enabled, m.support.threshold,
		     m.elefant_foot_compensation);
	return n < 0 ? 0 : (size_t)n;
}
