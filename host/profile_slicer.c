/*
 * profile_slicer.c - printer profile to slicer settings (profile_slicer.h).
 */
#include "profile_slicer.h"

#include "infill.h"

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

/* A width in mm, or its percentage of the layer height; 0 means dflt. */
static double width_of(const struct profile_pct *w, const struct profile *p, double dflt)
{
	double v = w->is_percent ? w->value / 100 * p->layer_height : w->value;

	return v > 0 ? v : dflt;
}

/* The slicer's settings from p (profile_slicer.h). */
int profile_slicer_config(const struct profile *p, struct slicer_config *c,
			  struct st_error *err)
{
	struct gcodew_settings *g = &c->gcodew;
	double nozzle = p->nozzle_diameter[0];
	enum infill_pattern pat;
	int rc;

	slicer_config_init(c, nozzle);
	c->layer_height = p->layer_height;
	c->first_layer_height = p->first_layer_height;
	if (p->extrusion_width > 0)
		c->perim.extrusion_width = p->extrusion_width;
	c->perim.perimeters = p->perimeters;
	c->elefant_foot_compensation = p->elefant_foot_compensation;
	c->perim.outer_first = p->external_perimeters_first;
	c->perim.thin_walls = p->thin_walls;
	c->perim.gap_fill = p->gap_fill_enabled;
	c->gcodew.spiral_vase = p->spiral_vase;
	c->gcodew.ironing = p->ironing;
	c->gcodew.ironing_type = p->ironing_type;
	c->gcodew.ironing_flowrate = p->ironing_flowrate;
	c->gcodew.ironing_spacing = p->ironing_spacing;
	c->gcodew.ironing_speed = p->ironing_speed;
	rc = perim_seam_parse(p->seam_position, &c->perim.seam, err);
	if (rc)
		return rc; /* not reached: the loader accepts the declared names only */

	c->infill.density = p->fill_density;
	/* A pattern Stratum does not print is rectilinear, and named in the
	 * profile's unsupported keys (profile_unsupported). */
	c->infill.pattern = infill_pattern_parse(p->fill_pattern, &pat, NULL) ? "rectilinear"
									     : p->fill_pattern;
	c->infill.top_solid_layers = p->top_solid_layers;
	c->infill.bottom_solid_layers = p->bottom_solid_layers;
	c->support.enabled = p->support_material;
	c->support.threshold = p->support_material_threshold;
	c->infill.solid_infill_below_area = p->solid_infill_below_area;
	c->infill.top_solid_min_thickness = p->top_solid_min_thickness;
	c->infill.bottom_solid_min_thickness = p->bottom_solid_min_thickness;
	c->infill.fill_angle = p->fill_angle;
	c->infill.bridge_flow_ratio = p->bridge_flow_ratio;
	/* The infill stage takes a percentage of the walls' width. */
	c->infill.infill_overlap = p->infill_overlap.is_percent
				       ? p->infill_overlap.value
				       : p->infill_overlap.value / c->perim.extrusion_width * 100;
	c->infill.infill_extrusion_width =
	    width_of(&p->infill_extrusion_width, p, c->perim.extrusion_width);
	c->infill.solid_infill_extrusion_width =
	    width_of(&p->solid_infill_extrusion_width, p, c->perim.extrusion_width);
	c->infill.top_infill_extrusion_width =
	    width_of(&p->top_infill_extrusion_width, p, c->perim.extrusion_width);
	c->infill.bridge_angle = p->bridge_angle;
	c->raft = (struct slicer_raft_settings){
	    .layers = p->raft_layers,
	    .contact_distance = p->raft_contact_distance,
	    .expansion = p->raft_expansion,
	    .first_layer_density = p->raft_first_layer_density,
	    .first_layer_expansion = p->raft_first_layer_expansion};
	c->skirt = (struct slicer_skirt_settings){.skirts = p->skirts,
						  .skirt_distance = p->skirt_distance,
						  .skirt_height = p->skirt_height,
						  .min_skirt_length = p->min_skirt_length,
						  .brim_width = p->brim_width,
						  .brim_separation = p->brim_separation};

	c->bed = (struct slicer_bed){.min_x = p->bed_min_x, .min_y = p->bed_min_y,
				     .max_x = p->bed_max_x, .max_y = p->bed_max_y,
				     .max_height = p->max_print_height};

	g->filament_diameter = p->filament_diameter[0];
	g->extrusion_multiplier = p->extrusion_multiplier[0];
	g->filament_density = p->filament_density;
	g->use_relative_e_distances = p->use_relative_e_distances;
	g->temperature = p->temperature[0];
	g->first_layer_temperature = p->first_layer_temperature[0];
	g->bed_temperature = p->bed_temperature;
	g->first_layer_bed_temperature = p->first_layer_bed_temperature;
	g->retract_length = p->retract_length[0];
	g->retract_speed = p->retract_speed[0];
	g->retract_lift = p->retract_lift[0];
	g->deretract_speed = p->deretract_speed[0];
	g->retract_before_travel = p->retract_before_travel[0];
	g->wipe = p->wipe;
	/* Travel routing. */
	g->avoid_crossing_perimeters = p->avoid_crossing_perimeters;
	g->only_retract_when_crossing_perimeters = p->only_retract_when_crossing_perimeters;
	g->max_unretracted_travel = p->max_unretracted_travel;
	/* Percentages resolved against the key each is of (settings.h pct_of),
	 * so the G-code header lists the speeds printed with. */
	g->travel_speed = p->travel_speed;
	g->travel_speed_z = p->travel_speed_z;
	g->perimeter_speed = p->perimeter_speed;
	g->external_perimeter_speed = speed_of(&p->external_perimeter_speed, p->perimeter_speed);
	g->small_perimeter_speed = speed_of(&p->small_perimeter_speed, p->perimeter_speed);
	g->infill_speed = p->infill_speed;
	g->solid_infill_speed = speed_of(&p->solid_infill_speed, p->infill_speed);
	g->top_solid_infill_speed = speed_of(&p->top_solid_infill_speed, g->solid_infill_speed);
	g->bridge_speed = p->bridge_speed;
	g->gap_fill_speed = p->gap_fill_speed;
	g->support_material_speed = p->support_material_speed;
	g->support_material_interface_speed =
	    speed_of(&p->support_material_interface_speed, p->support_material_speed);
	/* A percentage scales each role's own speed (PrusaSlicer 2.5). */
	g->first_layer_speed = p->first_layer_speed.value;
	g->first_layer_speed_is_percent = p->first_layer_speed.is_percent;
	g->first_layer_speed_over_raft = p->first_layer_speed_over_raft.value;
	g->first_layer_speed_over_raft_is_percent = p->first_layer_speed_over_raft.is_percent;
	g->cooling = p->cooling;
	g->fan_always_on = p->fan_always_on;
	g->fan_on_off = p->gcode_flavor == PROFILE_FLAVOR_MAKERWARE ||
			p->gcode_flavor == PROFILE_FLAVOR_SAILFISH;
	g->min_fan_speed = p->min_fan_speed;
	g->max_fan_speed = p->max_fan_speed;
	g->bridge_fan_speed = p->bridge_fan_speed;
	g->disable_fan_first_layers = p->disable_fan_first_layers;
	g->full_fan_speed_layer = p->full_fan_speed_layer;
	g->fan_below_layer_time = p->fan_below_layer_time;
	g->slowdown_below_layer_time = p->slowdown_below_layer_time;
	g->min_print_speed = p->min_print_speed;
	limits_from_profile(p, &g->limits);
	g->start_gcode = p->start_gcode;
	g->end_gcode = p->end_gcode;
	g->before_layer_gcode = p->before_layer_gcode;
	g->layer_gcode = p->layer_gcode;
	g->start_filament_gcode = p->start_filament_gcode;
	g->end_filament_gcode = p->end_filament_gcode;
	g->vars = p->vars;
	g->printer_settings_id = profile_printer_name(p);
	g->printer_model = p->printer_model;
	if (profile_get(p, "bed_shape"))
		g->bed_shape = profile_get(p, "bed_shape");
	return 0;
}

