/*
 * profile_bind.c - the binding of each declared setting (slicer/settings.h)
 * to its struct profile field and, where the slicer takes the value as it
 * is, to its struct slicer_config field (profile_slicer.c copies those);
 * and the declared defaults applied through it (profile_int.h).  The value
 * parsers are in profile_keys.c.
 */
#include "profile_int.h"

#include <string.h>

#include "slicer.h"

/* What a field holds, for the copy into the slicer's (an array: its first value). */
#define CT_OF(x)                                                                                   \
	_Generic((x), double: CT_DOUBLE, double *: CT_DOUBLE, int: CT_INT, int *: CT_INT,          \
		 bool: CT_BOOL, const char *: CT_STRING)
#define PROF(f) (((struct profile *)0)->f)
#define CFG(f) (((struct slicer_config *)0)->f)
/* 1, or a compile error (an array of size -1) when field f cannot be copied into cf. */
#define FITS(f, cf)                                                                                \
	sizeof(char[CT_OF(PROF(f)) == CT_OF(CFG(cf)) ||                                            \
			    (CT_OF(PROF(f)) == CT_INT && CT_OF(CFG(cf)) == CT_DOUBLE)               \
			? 1                                                                        \
			: -1])

/* Key bound to profile field f only (P), or also to the slicer's field cf (S),
 * the G-code writer's field of the same name (G). */
#define P(f) offsetof(struct profile, f), 0, CT_NONE, CT_NONE
#define S(f, cf)                                                                                   \
	offsetof(struct profile, f), offsetof(struct slicer_config, cf) * FITS(f, cf),             \
	    CT_OF(PROF(f)), CT_OF(CFG(cf))
#define G(f) S(f, gcodew.f)
#define NOFIELD 0, 0, CT_NONE, CT_NONE /* typed into other fields (prof_apply_key) */

/* Every key the loader types, in declaration order (settings.c): the order
 * it applies and writes them. */
static const struct key_def key_defs[] = {
	{"name", KT_STRING, P(name)},
	{"description", KT_STRING, P(description)},
	{"printer_model", KT_STRING, G(printer_model)},
	{"protocol", KT_PROTOCOL, P(protocol)},
	{"baudrate", KT_BAUD, P(baudrate)},
	{"usb_ids", KT_USB, NOFIELD},
	{"rx_buffer_size", KT_INT, P(rx_buffer_size)},
	{"bufsize", KT_INT, P(bufsize)},
	{"dtr_reset", KT_BOOL, P(dtr_reset)},
	{"x3g_buffer_size", KT_INT, P(x3g_buffer_size)},
	{"gcode_flavor", KT_FLAVOR, P(gcode_flavor)},
	{"bed_shape", KT_BED, NOFIELD},
	{"max_print_height", KT_DOUBLE, S(max_print_height, bed.max_height)},
	{"extruder_count", KT_EXTRUDERS, P(extruder_count)},
	{"use_relative_e_distances", KT_BOOL, G(use_relative_e_distances)},
	{"remaining_times", KT_BOOL, G(remaining_times)},
	{"silent_mode", KT_BOOL, P(silent_mode)},
	{"nozzle_diameter", KT_EX_DOUBLE, P(nozzle_diameter)},
	{"filament_diameter", KT_EX_DOUBLE, G(filament_diameter)},
	{"extruder_offset", KT_EX_POINT, P(extruder_offset)},
	{"extrusion_multiplier", KT_EX_DOUBLE, G(extrusion_multiplier)},
	{"filament_density", KT_FIRST_DOUBLE, G(filament_density)},
	{"temperature", KT_EX_INT, G(temperature)},
	{"first_layer_temperature", KT_EX_INT, G(first_layer_temperature)},
	{"bed_temperature", KT_FIRST_INT, G(bed_temperature)},
	{"first_layer_bed_temperature", KT_FIRST_INT, G(first_layer_bed_temperature)},
	{"retract_length", KT_EX_DOUBLE, G(retract_length)},
	{"retract_speed", KT_EX_DOUBLE, G(retract_speed)},
	{"retract_lift", KT_EX_DOUBLE, G(retract_lift)},
	{"retract_lift_above", KT_EX_DOUBLE, G(retract_lift_above)},
	{"retract_lift_below", KT_EX_DOUBLE, G(retract_lift_below)},
	{"deretract_speed", KT_EX_DOUBLE, G(deretract_speed)},
	{"retract_before_travel", KT_EX_DOUBLE, G(retract_before_travel)},
	{"wipe", KT_FIRST_BOOL, G(wipe)},
	{"retract_before_wipe", KT_DENSITY, G(retract_before_wipe)},
	{"retract_layer_change", KT_FIRST_BOOL, G(retract_layer_change)},
	{"variable_layer_height", KT_BOOL, S(variable_layer_height, adaptive.allowed)},
	{"min_layer_height", KT_EX_DOUBLE, S(min_layer_height, adaptive.min_height)},
	{"max_layer_height", KT_EX_DOUBLE, S(max_layer_height, adaptive.max_height)},
	{"layer_height", KT_DOUBLE, S(layer_height, layer_height)},
	{"first_layer_height", KT_FIRST_HEIGHT, S(first_layer_height, first_layer_height)},
	{"adaptive_layer_height", KT_BOOL, S(adaptive_layer_height, adaptive.enabled)},
	{"adaptive_max_cusp", KT_DOUBLE, S(adaptive_max_cusp, adaptive.max_cusp)},
	{"extrusion_width", KT_WIDTH, P(extrusion_width)},
	{"first_layer_extrusion_width", KT_NUM_PCT, P(first_layer_extrusion_width)},
	{"perimeter_extrusion_width", KT_NUM_PCT, P(perimeter_extrusion_width)},
	{"external_perimeter_extrusion_width", KT_NUM_PCT, P(external_perimeter_extrusion_width)},
	{"infill_extrusion_width", KT_NUM_PCT, P(infill_extrusion_width)},
	{"solid_infill_extrusion_width", KT_NUM_PCT, P(solid_infill_extrusion_width)},
	{"top_infill_extrusion_width", KT_NUM_PCT, P(top_infill_extrusion_width)},
	{"support_material_extrusion_width", KT_NUM_PCT, P(support_material_extrusion_width)},
	{"perimeters", KT_INT, S(perimeters, perim.perimeters)},
	{"elefant_foot_compensation", KT_DOUBLE, S(elefant_foot_compensation, elefant_foot_compensation)},
	{"seam_position", KT_CHOICE, P(seam_position)},
	{"external_perimeters_first", KT_BOOL, S(external_perimeters_first, perim.outer_first)},
	{"thin_walls", KT_BOOL, S(thin_walls, perim.thin_walls)},
	{"gap_fill_enabled", KT_BOOL, S(gap_fill_enabled, perim.gap_fill)},
	{"overhangs", KT_BOOL, S(overhangs, overhangs)},
	{"spiral_vase", KT_BOOL, G(spiral_vase)},
	{"top_solid_layers", KT_INT, S(top_solid_layers, infill.top_solid_layers)},
	{"bottom_solid_layers", KT_INT, S(bottom_solid_layers, infill.bottom_solid_layers)},
	{"top_solid_min_thickness", KT_DOUBLE, S(top_solid_min_thickness, infill.top_solid_min_thickness)},
	{"bottom_solid_min_thickness", KT_DOUBLE, S(bottom_solid_min_thickness, infill.bottom_solid_min_thickness)},
	{"fill_angle", KT_DOUBLE, S(fill_angle, infill.fill_angle)},
	{"bridge_angle", KT_DOUBLE, S(bridge_angle, infill.bridge_angle)},
	{"bridge_flow_ratio", KT_DOUBLE, S(bridge_flow_ratio, infill.bridge_flow_ratio)},
	{"thick_bridges", KT_BOOL, S(thick_bridges, infill.thick_bridges)},
	{"infill_overlap", KT_NUM_PCT, P(infill_overlap)},
	{"min_feature_size", KT_NUM_PCT, P(min_feature_size)},
	{"min_bead_width", KT_NUM_PCT, P(min_bead_width)},
	{"wall_transition_length", KT_NUM_PCT, P(wall_transition_length)},
	{"wall_transition_angle", KT_DOUBLE, S(wall_transition_angle, perim.transition_angle)},
	{"fill_density", KT_DENSITY, S(fill_density, infill.density)},
	{"fill_pattern", KT_CHOICE, P(fill_pattern)},
	{"infill_anchor", KT_NUM_PCT, P(infill_anchor)},
	{"infill_anchor_max", KT_NUM_PCT, P(infill_anchor_max)},
	{"top_fill_pattern", KT_CHOICE, P(top_fill_pattern)},
	{"bottom_fill_pattern", KT_CHOICE, P(bottom_fill_pattern)},
	{"solid_infill_below_area", KT_DOUBLE, S(solid_infill_below_area, infill.solid_infill_below_area)},
	{"ironing", KT_BOOL, G(ironing)},
	{"ironing_type", KT_CHOICE, G(ironing_type)},
	{"ironing_flowrate", KT_DENSITY, G(ironing_flowrate)},
	{"ironing_spacing", KT_DOUBLE, G(ironing_spacing)},
	{"ironing_speed", KT_DOUBLE, G(ironing_speed)},
	{"skirts", KT_INT, S(skirts, skirt.skirts)},
	{"skirt_distance", KT_DOUBLE, S(skirt_distance, skirt.skirt_distance)},
	{"skirt_height", KT_INT, S(skirt_height, skirt.skirt_height)},
	{"min_skirt_length", KT_DOUBLE, S(min_skirt_length, skirt.min_skirt_length)},
	{"brim_width", KT_DOUBLE, S(brim_width, skirt.brim_width)},
	{"brim_separation", KT_DOUBLE, S(brim_separation, skirt.brim_separation)},
	{"duplicate_distance", KT_DOUBLE, S(duplicate_distance, bed.object_distance)},
	{"support_material", KT_BOOL, S(support_material, support.enabled)},
	{"support_material_threshold", KT_INT, S(support_material_threshold, support.threshold)},
	{"support_material_style", KT_CHOICE, S(support_material_style, support.style)},
	{"support_material_pattern", KT_CHOICE, S(support_material_pattern, support.pattern)},
	{"support_material_with_sheath", KT_BOOL, S(support_material_with_sheath, support.with_sheath)},
	{"support_material_buildplate_only", KT_BOOL, S(support_material_buildplate_only, support.buildplate_only)},
	{"support_material_contact_distance", KT_DOUBLE, S(support_material_contact_distance, support.contact_distance)},
	{"support_material_bottom_contact_distance", KT_DOUBLE, S(support_material_bottom_contact_distance, support.bottom_contact_distance)},
	{"support_material_interface_layers", KT_INT, S(support_material_interface_layers, support.interface_layers)},
	{"support_material_bottom_interface_layers", KT_INT, S(support_material_bottom_interface_layers, support.bottom_interface_layers)},
	{"support_material_interface_spacing", KT_DOUBLE, S(support_material_interface_spacing, support.interface_spacing)},
	{"support_material_spacing", KT_DOUBLE, S(support_material_spacing, support.spacing)},
	{"support_material_angle", KT_DOUBLE, S(support_material_angle, support.angle)},
	{"support_material_xy_spacing", KT_NUM_PCT, P(support_material_xy_spacing)},
	{"dont_support_bridges", KT_BOOL, S(dont_support_bridges, support.dont_support_bridges)},
	{"raft_layers", KT_INT, S(raft_layers, raft.layers)},
	{"raft_contact_distance", KT_DOUBLE, S(raft_contact_distance, raft.contact_distance)},
	{"raft_expansion", KT_DOUBLE, S(raft_expansion, raft.expansion)},
	{"raft_first_layer_density", KT_DENSITY, S(raft_first_layer_density, raft.first_layer_density)},
	{"raft_first_layer_expansion", KT_DOUBLE, S(raft_first_layer_expansion, raft.first_layer_expansion)},
	{"gcode_resolution", KT_DOUBLE, G(gcode_resolution)},
	{"arc_fitting", KT_CHOICE, P(arc_fitting)},
	{"travel_speed", KT_DOUBLE, G(travel_speed)},
	{"travel_speed_z", KT_DOUBLE, G(travel_speed_z)},
	{"perimeter_speed", KT_DOUBLE, G(perimeter_speed)},
	{"external_perimeter_speed", KT_NUM_PCT, P(external_perimeter_speed)},
	{"small_perimeter_speed", KT_NUM_PCT, P(small_perimeter_speed)},
	{"infill_speed", KT_DOUBLE, G(infill_speed)},
	{"solid_infill_speed", KT_NUM_PCT, P(solid_infill_speed)},
	{"top_solid_infill_speed", KT_NUM_PCT, P(top_solid_infill_speed)},
	{"bridge_speed", KT_DOUBLE, G(bridge_speed)},
	{"gap_fill_speed", KT_DOUBLE, G(gap_fill_speed)},
	{"support_material_speed", KT_DOUBLE, G(support_material_speed)},
	{"support_material_interface_speed", KT_NUM_PCT, P(support_material_interface_speed)},
	{"first_layer_speed", KT_NUM_PCT, P(first_layer_speed)},
	{"first_layer_speed_over_raft", KT_NUM_PCT, P(first_layer_speed_over_raft)},
	{"max_volumetric_speed", KT_DOUBLE, G(max_volumetric_speed)},
	{"filament_max_volumetric_speed", KT_FIRST_DOUBLE, G(filament_max_volumetric_speed)},
	{"default_acceleration", KT_DOUBLE, G(default_acceleration)},
	{"perimeter_acceleration", KT_DOUBLE, G(perimeter_acceleration)},
	{"infill_acceleration", KT_DOUBLE, G(infill_acceleration)},
	{"bridge_acceleration", KT_DOUBLE, G(bridge_acceleration)},
	{"first_layer_acceleration", KT_DOUBLE, G(first_layer_acceleration)},
	{"avoid_crossing_perimeters", KT_BOOL, G(avoid_crossing_perimeters)},
	{"avoid_crossing_perimeters_max_detour", KT_NUM_PCT, P(avoid_crossing_perimeters_max_detour)},
	{"only_retract_when_crossing_perimeters", KT_BOOL, G(only_retract_when_crossing_perimeters)},
	{"max_unretracted_travel", KT_DOUBLE, G(max_unretracted_travel)},
	{"cooling", KT_FIRST_BOOL, G(cooling)},
	{"fan_always_on", KT_FIRST_BOOL, G(fan_always_on)},
	{"min_fan_speed", KT_FIRST_INT, G(min_fan_speed)},
	{"max_fan_speed", KT_FIRST_INT, G(max_fan_speed)},
	{"bridge_fan_speed", KT_FIRST_INT, G(bridge_fan_speed)},
	{"disable_fan_first_layers", KT_FIRST_INT, G(disable_fan_first_layers)},
	{"full_fan_speed_layer", KT_FIRST_INT, G(full_fan_speed_layer)},
	{"fan_below_layer_time", KT_FIRST_INT, G(fan_below_layer_time)},
	{"slowdown_below_layer_time", KT_FIRST_INT, G(slowdown_below_layer_time)},
	{"min_print_speed", KT_FIRST_DOUBLE, G(min_print_speed)},
	{"machine_max_feedrate_x", KT_FIRST_DOUBLE, P(machine_max_feedrate[PROFILE_AXIS_X])},
	{"machine_max_feedrate_y", KT_FIRST_DOUBLE, P(machine_max_feedrate[PROFILE_AXIS_Y])},
	{"machine_max_feedrate_z", KT_FIRST_DOUBLE, P(machine_max_feedrate[PROFILE_AXIS_Z])},
	{"machine_max_feedrate_e", KT_FIRST_DOUBLE, P(machine_max_feedrate[PROFILE_AXIS_E])},
	{"machine_max_acceleration_x", KT_FIRST_DOUBLE, P(machine_max_acceleration[PROFILE_AXIS_X])},
	{"machine_max_acceleration_y", KT_FIRST_DOUBLE, P(machine_max_acceleration[PROFILE_AXIS_Y])},
	{"machine_max_acceleration_z", KT_FIRST_DOUBLE, P(machine_max_acceleration[PROFILE_AXIS_Z])},
	{"machine_max_acceleration_e", KT_FIRST_DOUBLE, P(machine_max_acceleration[PROFILE_AXIS_E])},
	{"machine_max_acceleration_extruding", KT_FIRST_DOUBLE, P(machine_max_acceleration_extruding)},
	{"machine_max_acceleration_retracting", KT_FIRST_DOUBLE, P(machine_max_acceleration_retracting)},
	{"machine_max_acceleration_travel", KT_FIRST_DOUBLE, P(machine_max_acceleration_travel)},
	{"machine_max_jerk_x", KT_FIRST_DOUBLE, P(machine_max_jerk[PROFILE_AXIS_X])},
	{"machine_max_jerk_y", KT_FIRST_DOUBLE, P(machine_max_jerk[PROFILE_AXIS_Y])},
	{"machine_max_jerk_z", KT_FIRST_DOUBLE, P(machine_max_jerk[PROFILE_AXIS_Z])},
	{"machine_max_jerk_e", KT_FIRST_DOUBLE, P(machine_max_jerk[PROFILE_AXIS_E])},
	{"machine_min_extruding_rate", KT_FIRST_DOUBLE, P(machine_min_extruding_rate)},
	{"machine_min_travel_rate", KT_FIRST_DOUBLE, P(machine_min_travel_rate)},
	{"machine_limits_usage", KT_CHOICE, P(machine_limits_usage)},
	{"steps_per_mm_x", KT_DOUBLE, P(steps_per_mm[0])},
	{"steps_per_mm_y", KT_DOUBLE, P(steps_per_mm[1])},
	{"steps_per_mm_z", KT_DOUBLE, P(steps_per_mm[2])},
	{"steps_per_mm_e", KT_EX_DOUBLE, P(steps_per_mm_e)},
	{"home_direction_x", KT_HOME, P(home_direction[0])},
	{"home_direction_y", KT_HOME, P(home_direction[1])},
	{"home_direction_z", KT_HOME, P(home_direction[2])},
	{"home_feedrate_x", KT_DOUBLE, P(home_feedrate[0])},
	{"home_feedrate_y", KT_DOUBLE, P(home_feedrate[1])},
	{"home_feedrate_z", KT_DOUBLE, P(home_feedrate[2])},
	{"home_position_x", KT_DOUBLE, P(home_position[0])},
	{"home_position_y", KT_DOUBLE, P(home_position[1])},
	{"home_position_z", KT_DOUBLE, P(home_position[2])},
	{"x3g_toolhead_offset_x", KT_DOUBLE, P(x3g_toolhead_offset[0])},
	{"x3g_toolhead_offset_y", KT_DOUBLE, P(x3g_toolhead_offset[1])},
	{"x3g_toolhead_offset_z", KT_DOUBLE, P(x3g_toolhead_offset[2])},
	{"x3g_heated_platform", KT_BOOL, P(x3g_heated_platform)},
	{"x3g_home_timeout", KT_INT, P(x3g_home_timeout)},
	{"start_gcode", KT_STRING, G(start_gcode)},
	{"end_gcode", KT_STRING, G(end_gcode)},
	{"before_layer_gcode", KT_STRING, G(before_layer_gcode)},
	{"layer_gcode", KT_STRING, G(layer_gcode)},
	{"start_filament_gcode", KT_FIRST_STRING, G(start_filament_gcode)},
	{"end_filament_gcode", KT_FIRST_STRING, G(end_filament_gcode)},
	{"toolchange_gcode", KT_STRING, P(toolchange_gcode)},
	{"thumbnails", KT_STRING, G(thumbnails)},
};

#define KEY_DEFS (sizeof(key_defs) / sizeof(key_defs[0]))

const struct key_def *prof_defs(size_t *count)
{
	*count = KEY_DEFS;
	return key_defs;
}

const struct key_def *prof_find_def(const char *key)
{
	for (size_t i = 0; i < KEY_DEFS; i++)
		if (!strcmp(key_defs[i].key, key))
			return &key_defs[i];
	return NULL;
}

/* Every bound key is declared (tests/check_profile.c checks the tables agree). */
const struct setting *prof_decl(const struct key_def *d)
{
	return settings_find(d->key);
}

/*
 * The declared defaults, read with the same parsers as a file's values so a
 * default is always a value the loader accepts.  sailfish: only the keys
 * whose default differs on a sailfish printer.  Defaults derived from other
 * keys (declared NULL) are filled by prof_apply_all.
 */
int prof_set_defaults(struct profile *p, bool sailfish)
{
	struct st_error err = {0};
	struct loader L = {.p = p, .origin = "the declared defaults", .err = &err};
	struct pending pend = {0};
	int ec = p->extruder_count, rc = 0;

	p->extruder_count = PROFILE_MAX_EXTRUDERS; /* one value fills every extruder */
	for (size_t i = 0; i < KEY_DEFS && !rc; i++) {
		const struct key_def *d = &key_defs[i];
		const struct setting *s = prof_decl(d);
		const char *text = sailfish ? s->sailfish_dflt : s->dflt;
		struct profile_kv kv = {(char *)d->key, (char *)text, 0, NULL};

		if (!text || d->type == KT_EXTRUDERS)
			continue;
		rc = prof_apply_key(&L, d, &kv, &pend);
		if (d->type == KT_FIRST_HEIGHT)
			p->first_layer_height = pend.flh;
		else if (d->type == KT_WIDTH)
			p->extrusion_width = pend.width;
	}
	p->extruder_count = ec;
	return rc ? ST_ERR_INTERNAL : 0;
}
