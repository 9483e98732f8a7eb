/*
 * profile_slicer.c - printer profile to slicer settings (profile_slicer.h).
 */
#include "profile_slicer.h"

#include <string.h>

#include "infill.h"
#include "profile_int.h"

/* Whether and how the G-code carries the limits: PrusaSlicer writes them
 * for Marlin only (X3G has no such commands). */
static enum gcodew_limits_form limits_form(const struct profile *p)
{
	const char *usage = p->machine_limits_usage;

	if (!usage || strcmp(usage, "emit_to_gcode") != 0)
		return GCODEW_LIMITS_NONE;
	if (p->gcode_flavor == PROFILE_FLAVOR_MARLIN)
		return GCODEW_LIMITS_MARLIN_LEGACY;
	if (p->gcode_flavor == PROFILE_FLAVOR_MARLIN2)
		return GCODEW_LIMITS_MARLIN2;
	return GCODEW_LIMITS_NONE;
}

bool prof_flavor_arcs(enum profile_flavor f)
{
	return f == PROFILE_FLAVOR_MARLIN || f == PROFILE_FLAVOR_MARLIN2 ||
	       f == PROFILE_FLAVOR_REPRAPFIRMWARE;
}

/* Machine limits of the profile where it sets them (> 0), else the defaults. */
static void limits_from_profile(const struct profile *p, struct est_limits *lim)
{
	static const enum profile_axis pa[EST_AXES] = {PROFILE_AXIS_X, PROFILE_AXIS_Y,
						       PROFILE_AXIS_Z, PROFILE_AXIS_E};

	est_limits_init(lim);
	for (int k = 0; k < EST_AXES; k++) {
		if (p->machine_max_feedrate[pa[k]] > 0)
			lim->max_feedrate[k] = p->machine_max_feedrate[pa[k]];
		if (p->machine_max_acceleration[pa[k]] > 0)
			lim->max_acceleration[k] = p->machine_max_acceleration[pa[k]];
		lim->max_jerk[k] = p->machine_max_jerk[pa[k]];
	}
	if (p->machine_max_acceleration_extruding > 0)
		lim->accel_extruding = p->machine_max_acceleration_extruding;
	if (p->machine_max_acceleration_retracting > 0)
		lim->accel_retracting = p->machine_max_acceleration_retracting;
	lim->accel_travel = p->machine_max_acceleration_travel;
}

/* A speed in mm/s, or its percentage of base. */
static double speed_of(const struct profile_pct *sp, double base)
{
	return sp->is_percent ? sp->value / 100 * base : sp->value;
}

/* A width in mm, or its percentage of the layer height h; 0 means dflt. */
static double width_of(const struct profile_pct *w, double h, double dflt)
{
	double v = w->is_percent ? w->value / 100 * h : w->value;

	return v > 0 ? v : dflt;
}

/*
 * Copy every key bound to a slicer field as the profile holds it
 * (profile_bind.c, which refuses at compile time a pair that does not fit).
 */
static void copy_bound(const struct profile *p, struct slicer_config *c)
{
	static const size_t size[] = {[CT_DOUBLE] = sizeof(double), [CT_INT] = sizeof(int),
				      [CT_BOOL] = sizeof(bool), [CT_STRING] = sizeof(const char *)};
	size_t n;
	const struct key_def *defs = prof_defs(&n);

	for (size_t i = 0; i < n; i++) {
		const struct key_def *d = &defs[i];
		const char *src = (const char *)p + d->off;
		char *dst = (char *)c + d->cfg;

		if (d->cfg_type == CT_NONE)
			continue;
		if (d->held == CT_INT && d->cfg_type == CT_DOUBLE)
			*(double *)dst = *(const int *)src;
		else
			memcpy(dst, src, size[d->cfg_type]);
	}
}

/*
 * The slicer's settings from p (profile_slicer.h): the keys bound to a
 * slicer field are copied by copy_bound, those the slicer takes computed
 * are set here.
 */
int profile_slicer_config(const struct profile *p, struct slicer_config *c,
			  struct st_error *err)
{
	struct gcodew_settings *g = &c->gcodew;
	enum infill_pattern pat;
	int rc;

	slicer_config_init(c, p->nozzle_diameter[0]);
	/* Each role's key, else extrusion_width, else the automatic width of
	 * PrusaSlicer 2.5's Flow: the nozzle's for the top skin and support,
	 * 1.125 x the nozzle's (the walls' default) for the others. */
	double base = p->extrusion_width > 0 ? p->extrusion_width : c->perim.extrusion_width;
	double thin = p->extrusion_width > 0 ? p->extrusion_width : p->nozzle_diameter[0];
	c->perim.extrusion_width = width_of(&p->perimeter_extrusion_width, p->layer_height, base);
	c->perim.external_extrusion_width =
	    width_of(&p->external_perimeter_extrusion_width, p->layer_height, base);
	/* Percentages of the nozzle, as PrusaSlicer's Arachne takes them. */
	c->perim.min_feature_size = width_of(&p->min_feature_size, p->nozzle_diameter[0], 0);
	c->perim.min_bead_width =
	    width_of(&p->min_bead_width, p->nozzle_diameter[0], c->perim.min_bead_width);
	c->perim.transition_length = p->wall_transition_length.is_percent
					 ? p->wall_transition_length.value / 100 * p->nozzle_diameter[0]
					 : p->wall_transition_length.value;
	c->first_layer_extrusion_width =
	    width_of(&p->first_layer_extrusion_width, p->first_layer_height, 0);
	rc = perim_seam_parse(p->seam_position, &c->perim.seam, err);
	if (rc)
		return rc; /* not reached: the loader accepts the declared names only */

	/* A pattern Stratum does not print is rectilinear, and named in the
	 * profile's unsupported keys (profile_unsupported). */
	c->infill.pattern = infill_pattern_parse(p->fill_pattern, &pat, NULL) ? "rectilinear"
									     : p->fill_pattern;
	/* The infill stage takes a percentage of the walls' width. */
	c->infill.infill_overlap = p->infill_overlap.is_percent
				       ? p->infill_overlap.value
				       : p->infill_overlap.value / c->perim.extrusion_width * 100;
	c->infill.infill_extrusion_width = width_of(&p->infill_extrusion_width, p->layer_height, base);
	c->infill.solid_infill_extrusion_width =
	    width_of(&p->solid_infill_extrusion_width, p->layer_height, base);
	c->infill.top_infill_extrusion_width =
	    width_of(&p->top_infill_extrusion_width, p->layer_height, thin);
	c->support.extrusion_width =
	    width_of(&p->support_material_extrusion_width, p->layer_height, thin);
	/* PrusaSlicer: a percentage of the outer wall's width; 0 is no gap */
	c->support.xy_spacing =
	    width_of(&p->support_material_xy_spacing, c->perim.external_extrusion_width, 0);
	c->infill.anchor = width_of(&p->infill_anchor, c->infill.infill_extrusion_width, 0);
	c->infill.anchor_max = width_of(&p->infill_anchor_max, c->infill.infill_extrusion_width, 0);
	c->infill.top_monotonic = !strcmp(p->top_fill_pattern, "monotonic");
	c->infill.bottom_monotonic = !strcmp(p->bottom_fill_pattern, "monotonic");
	c->max_detour = p->avoid_crossing_perimeters_max_detour.value;
	c->max_detour_is_percent = p->avoid_crossing_perimeters_max_detour.is_percent;
	c->bed = (struct slicer_bed){.min_x = p->bed_min_x, .min_y = p->bed_min_y,
				     .max_x = p->bed_max_x, .max_y = p->bed_max_y};

	/* Percentages resolved against the key each is of (settings.h pct_of),
	 * so the G-code header lists the speeds printed with. */
	g->external_perimeter_speed = speed_of(&p->external_perimeter_speed, p->perimeter_speed);
	g->small_perimeter_speed = speed_of(&p->small_perimeter_speed, p->perimeter_speed);
	g->solid_infill_speed = speed_of(&p->solid_infill_speed, p->infill_speed);
	g->top_solid_infill_speed = speed_of(&p->top_solid_infill_speed, g->solid_infill_speed);
	g->support_material_interface_speed =
	    speed_of(&p->support_material_interface_speed, p->support_material_speed);
	/* A percentage scales each role's own speed (PrusaSlicer 2.5). */
	g->first_layer_speed = p->first_layer_speed.value;
	g->first_layer_speed_is_percent = p->first_layer_speed.is_percent;
	g->first_layer_speed_over_raft = p->first_layer_speed_over_raft.value;
	g->first_layer_speed_over_raft_is_percent = p->first_layer_speed_over_raft.is_percent;
	g->fan_on_off = p->gcode_flavor == PROFILE_FLAVOR_MAKERWARE ||
			p->gcode_flavor == PROFILE_FLAVOR_SAILFISH;
	/* PrusaSlicer times a stealth mode for these flavours only. */
	g->remaining_times_silent = p->silent_mode && (p->gcode_flavor == PROFILE_FLAVOR_MARLIN ||
						       p->gcode_flavor == PROFILE_FLAVOR_MARLIN2);
	g->accel_form = p->gcode_flavor == PROFILE_FLAVOR_REPRAPFIRMWARE ? GCODEW_ACCEL_M204_P
			: p->gcode_flavor == PROFILE_FLAVOR_REPETIER	   ? GCODEW_ACCEL_M201_M202
									   : GCODEW_ACCEL_M204_S;
	/* Lines where the firmware has no arcs (profile_unsupported says so). */
	g->arc_fitting =
	    !strcmp(p->arc_fitting, "emit_center") && prof_flavor_arcs(p->gcode_flavor);
	limits_from_profile(p, &g->limits);
	g->limits_form = limits_form(p);
	g->min_extruding_rate = p->machine_min_extruding_rate;
	g->min_travel_rate = p->machine_min_travel_rate;
	g->vars = p->vars;
	g->printer_settings_id = profile_printer_name(p);
	if (profile_get(p, "bed_shape"))
		g->bed_shape = profile_get(p, "bed_shape");
	copy_bound(p, c);
	return 0;
}
