/*
 * profile_bind.c - the binding of each declared setting (slicer/settings.h)
 * to its struct profile field, and the declared defaults applied through
 * it (profile_int.h).  The value parsers are in profile_keys.c.
 */
#include "profile_int.h"

#include <string.h>

#define OFF(field) offsetof(struct profile, field)

/* Every key the loader types, in declaration order (settings.c): the order
 * it applies and writes them. */
static const struct key_def key_defs[] = {
	{"name", KT_STRING, OFF(name)},
	{"description", KT_STRING, OFF(description)},
	{"printer_model", KT_STRING, OFF(printer_model)},
	{"protocol", KT_PROTOCOL, OFF(protocol)},
	{"baudrate", KT_BAUD, OFF(baudrate)},
	{"usb_ids", KT_USB, 0},
	{"rx_buffer_size", KT_INT, OFF(rx_buffer_size)},
	{"bufsize", KT_INT, OFF(bufsize)},
	{"dtr_reset", KT_BOOL, OFF(dtr_reset)},
	{"x3g_buffer_size", KT_INT, OFF(x3g_buffer_size)},
	{"gcode_flavor", KT_FLAVOR, OFF(gcode_flavor)},
	{"bed_shape", KT_BED, 0},
	{"max_print_height", KT_DOUBLE, OFF(max_print_height)},
	{"extruder_count", KT_EXTRUDERS, OFF(extruder_count)},
	{"use_relative_e_distances", KT_BOOL, OFF(use_relative_e_distances)},
	{"nozzle_diameter", KT_EX_DOUBLE, OFF(nozzle_diameter)},
	{"filament_diameter", KT_EX_DOUBLE, OFF(filament_diameter)},
	{"extruder_offset", KT_EX_POINT, OFF(extruder_offset)},
	{"extrusion_multiplier", KT_EX_DOUBLE, OFF(extrusion_multiplier)},
	{"filament_density", KT_FIRST_DOUBLE, OFF(filament_density)},
	{"temperature", KT_EX_INT, OFF(temperature)},
	{"first_layer_temperature", KT_EX_INT, OFF(first_layer_temperature)},
	{"bed_temperature", KT_FIRST_INT, OFF(bed_temperature)},
	{"first_layer_bed_temperature", KT_FIRST_INT, OFF(first_layer_bed_temperature)},
	{"retract_length", KT_EX_DOUBLE, OFF(retract_length)},
	{"retract_speed", KT_EX_DOUBLE, OFF(retract_speed)},
	{"retract_lift", KT_EX_DOUBLE, OFF(retract_lift)},
	{"deretract_speed", KT_EX_DOUBLE, OFF(deretract_speed)},
	{"retract_before_travel", KT_EX_DOUBLE, OFF(retract_before_travel)},
	{"wipe", KT_FIRST_BOOL, OFF(wipe)},
	{"min_layer_height", KT_EX_DOUBLE, OFF(min_layer_height)},
	{"max_layer_height", KT_EX_DOUBLE, OFF(max_layer_height)},
	{"layer_height", KT_DOUBLE, OFF(layer_height)},
	{"first_layer_height", KT_FIRST_HEIGHT, OFF(first_layer_height)},
	{"extrusion_width", KT_WIDTH, OFF(extrusion_width)},
	{"infill_extrusion_width", KT_NUM_PCT, OFF(infill_extrusion_width)},
	{"solid_infill_extrusion_width", KT_NUM_PCT, OFF(solid_infill_extrusion_width)},
	{"top_infill_extrusion_width", KT_NUM_PCT, OFF(top_infill_extrusion_width)},
	{"perimeters", KT_INT, OFF(perimeters)},
	{"elefant_foot_compensation", KT_DOUBLE, OFF(elefant_foot_compensation)},
	{"seam_position", KT_CHOICE, OFF(seam_position)},
	{"external_perimeters_first", KT_BOOL, OFF(external_perimeters_first)},
	{"thin_walls", KT_BOOL, OFF(thin_walls)},
	{"gap_fill_enabled", KT_BOOL, OFF(gap_fill_enabled)},
	{"spiral_vase", KT_BOOL, OFF(spiral_vase)},
	{"top_solid_layers", KT_INT, OFF(top_solid_layers)},
	{"bottom_solid_layers", KT_INT, OFF(bottom_solid_layers)},
	{"top_solid_min_thickness", KT_DOUBLE, OFF(top_solid_min_thickness)},
	{"bottom_solid_min_thickness", KT_DOUBLE, OFF(bottom_solid_min_thickness)},
	{"fill_angle", KT_DOUBLE, OFF(fill_angle)},
	{"bridge_angle", KT_DOUBLE, OFF(bridge_angle)},
	{"bridge_flow_ratio", KT_DOUBLE, OFF(bridge_flow_ratio)},
	{"infill_overlap", KT_NUM_PCT, OFF(infill_overlap)},
	{"fill_density", KT_DENSITY, OFF(fill_density)},
	{"fill_pattern", KT_CHOICE, OFF(fill_pattern)},
	{"solid_infill_below_area", KT_DOUBLE, OFF(solid_infill_below_area)},
	{"ironing", KT_BOOL, OFF(ironing)},
	{"ironing_type", KT_CHOICE, OFF(ironing_type)},
	{"ironing_flowrate", KT_DENSITY, OFF(ironing_flowrate)},
	{"ironing_spacing", KT_DOUBLE, OFF(ironing_spacing)},
	{"ironing_speed", KT_DOUBLE, OFF(ironing_speed)},
	{"skirts", KT_INT, OFF(skirts)},
	{"skirt_distance", KT_DOUBLE, OFF(skirt_distance)},
	{"skirt_height", KT_INT, OFF(skirt_height)},
	{"min_skirt_length", KT_DOUBLE, OFF(min_skirt_length)},
	{"brim_width", KT_DOUBLE, OFF(brim_width)},
	{"brim_separation", KT_DOUBLE, OFF(brim_separation)},
	{"support_material", KT_BOOL, OFF(support_material)},
	{"support_material_threshold", KT_INT, OFF(support_material_threshold)},
	{"raft_layers", KT_INT, OFF(raft_layers)},
	{"raft_contact_distance", KT_DOUBLE, OFF(raft_contact_distance)},
	{"raft_expansion", KT_DOUBLE, OFF(raft_expansion)},
	{"raft_first_layer_density", KT_DENSITY, OFF(raft_first_layer_density)},
	{"raft_first_layer_expansion", KT_DOUBLE, OFF(raft_first_layer_expansion)},
	{"travel_speed", KT_DOUBLE, OFF(travel_speed)},
	{"travel_speed_z", KT_DOUBLE, OFF(travel_speed_z)},
	{"perimeter_speed", KT_DOUBLE, OFF(perimeter_speed)},
	{"external_perimeter_speed", KT_NUM_PCT, OFF(external_perimeter_speed)},
	{"small_perimeter_speed", KT_NUM_PCT, OFF(small_perimeter_speed)},
	{"infill_speed", KT_DOUBLE, OFF(infill_speed)},
	{"solid_infill_speed", KT_NUM_PCT, OFF(solid_infill_speed)},
	{"top_solid_infill_speed", KT_NUM_PCT, OFF(top_solid_infill_speed)},
	{"bridge_speed", KT_DOUBLE, OFF(bridge_speed)},
	{"gap_fill_speed", KT_DOUBLE, OFF(gap_fill_speed)},
	{"support_material_speed", KT_DOUBLE, OFF(support_material_speed)},
	{"support_material_interface_speed", KT_NUM_PCT, OFF(support_material_interface_speed)},
	{"first_layer_speed", KT_NUM_PCT, OFF(first_layer_speed)},
	{"first_layer_speed_over_raft", KT_NUM_PCT, OFF(first_layer_speed_over_raft)},
	{"avoid_crossing_perimeters", KT_BOOL, OFF(avoid_crossing_perimeters)},
	{"only_retract_when_crossing_perimeters", KT_BOOL, OFF(only_retract_when_crossing_perimeters)},
	{"max_unretracted_travel", KT_DOUBLE, OFF(max_unretracted_travel)},
	{"cooling", KT_FIRST_BOOL, OFF(cooling)},
	{"fan_always_on", KT_FIRST_BOOL, OFF(fan_always_on)},
	{"min_fan_speed", KT_FIRST_INT, OFF(min_fan_speed)},
	{"max_fan_speed", KT_FIRST_INT, OFF(max_fan_speed)},
	{"bridge_fan_speed", KT_FIRST_INT, OFF(bridge_fan_speed)},
	{"disable_fan_first_layers", KT_FIRST_INT, OFF(disable_fan_first_layers)},
	{"full_fan_speed_layer", KT_FIRST_INT, OFF(full_fan_speed_layer)},
	{"fan_below_layer_time", KT_FIRST_INT, OFF(fan_below_layer_time)},
	{"slowdown_below_layer_time", KT_FIRST_INT, OFF(slowdown_below_layer_time)},
	{"min_print_speed", KT_FIRST_DOUBLE, OFF(min_print_speed)},
	{"machine_max_feedrate_x", KT_FIRST_DOUBLE, OFF(machine_max_feedrate[PROFILE_AXIS_X])},
	{"machine_max_feedrate_y", KT_FIRST_DOUBLE, OFF(machine_max_feedrate[PROFILE_AXIS_Y])},
	{"machine_max_feedrate_z", KT_FIRST_DOUBLE, OFF(machine_max_feedrate[PROFILE_AXIS_Z])},
	{"machine_max_feedrate_e", KT_FIRST_DOUBLE, OFF(machine_max_feedrate[PROFILE_AXIS_E])},
	{"machine_max_acceleration_x", KT_FIRST_DOUBLE, OFF(machine_max_acceleration[PROFILE_AXIS_X])},
	{"machine_max_acceleration_y", KT_FIRST_DOUBLE, OFF(machine_max_acceleration[PROFILE_AXIS_Y])},
	{"machine_max_acceleration_z", KT_FIRST_DOUBLE, OFF(machine_max_acceleration[PROFILE_AXIS_Z])},
	{"machine_max_acceleration_e", KT_FIRST_DOUBLE, OFF(machine_max_acceleration[PROFILE_AXIS_E])},
	{"machine_max_acceleration_extruding", KT_FIRST_DOUBLE,
	    OFF(machine_max_acceleration_extruding)},
	{"machine_max_acceleration_retracting", KT_FIRST_DOUBLE,
	    OFF(machine_max_acceleration_retracting)},
	{"machine_max_acceleration_travel", KT_FIRST_DOUBLE, OFF(machine_max_acceleration_travel)},
	{"machine_max_jerk_x", KT_FIRST_DOUBLE, OFF(machine_max_jerk[PROFILE_AXIS_X])},
	{"machine_max_jerk_y", KT_FIRST_DOUBLE, OFF(machine_max_jerk[PROFILE_AXIS_Y])},
	{"machine_max_jerk_z", KT_FIRST_DOUBLE, OFF(machine_max_jerk[PROFILE_AXIS_Z])},
	{"machine_max_jerk_e", KT_FIRST_DOUBLE, OFF(machine_max_jerk[PROFILE_AXIS_E])},
	{"steps_per_mm_x", KT_DOUBLE, OFF(steps_per_mm[0])},
	{"steps_per_mm_y", KT_DOUBLE, OFF(steps_per_mm[1])},
	{"steps_per_mm_z", KT_DOUBLE, OFF(steps_per_mm[2])},
	{"steps_per_mm_e", KT_EX_DOUBLE, OFF(steps_per_mm_e)},
	{"home_direction_x", KT_HOME, OFF(home_direction[0])},
	{"home_direction_y", KT_HOME, OFF(home_direction[1])},
	{"home_direction_z", KT_HOME, OFF(home_direction[2])},
	{"home_feedrate_x", KT_DOUBLE, OFF(home_feedrate[0])},
	{"home_feedrate_y", KT_DOUBLE, OFF(home_feedrate[1])},
	{"home_feedrate_z", KT_DOUBLE, OFF(home_feedrate[2])},
	{"home_position_x", KT_DOUBLE, OFF(home_position[0])},
	{"home_position_y", KT_DOUBLE, OFF(home_position[1])},
	{"home_position_z", KT_DOUBLE, OFF(home_position[2])},
	{"x3g_toolhead_offset_x", KT_DOUBLE, OFF(x3g_toolhead_offset[0])},
	{"x3g_toolhead_offset_y", KT_DOUBLE, OFF(x3g_toolhead_offset[1])},
	{"x3g_toolhead_offset_z", KT_DOUBLE, OFF(x3g_toolhead_offset[2])},
	{"x3g_heated_platform", KT_BOOL, OFF(x3g_heated_platform)},
	{"x3g_home_timeout", KT_INT, OFF(x3g_home_timeout)},
	{"start_gcode", KT_STRING, OFF(start_gcode)},
	{"end_gcode", KT_STRING, OFF(end_gcode)},
	{"before_layer_gcode", KT_STRING, OFF(before_layer_gcode)},
	{"layer_gcode", KT_STRING, OFF(layer_gcode)},
	{"start_filament_gcode", KT_FIRST_STRING, OFF(start_filament_gcode)},
	{"end_filament_gcode", KT_FIRST_STRING, OFF(end_filament_gcode)},
	{"toolchange_gcode", KT_STRING, OFF(toolchange_gcode)},
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
