/*
 * profile_unsupported.c - which keys of a loaded profile Stratum does not
 * honour (profile.h, profile_unsupported).  A key is honoured when the
 * loader types it (slicer/settings.h), when it cannot change what Stratum prints (names, notes,
 * the GUI's and the print host's keys, multi-material and wipe tower
 * settings of a single-extruder print ...), or when its value asks for
 * what Stratum does anyway (complete_objects = 0, fuzzy_skin = none).
 * Every other key the profile sets is listed, with its value.
 */
#include "profile_int.h"
#include "st_grow.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "infill.h"
#include "st_number.h"

/*
 * PrusaSlicer keys (2.5's PrintConfig.cpp names) that are honoured by what
 * Stratum does.  ok NULL: no effect on the printed G-code at any value.
 * Otherwise honoured when the value equals ok (numbers compared as
 * numbers, every item of a list); when_key set: no effect at all while
 * when_key has the value when_off (an ironing setting with ironing = 0).
 * A name ending in '*' covers every key it starts.
 */
struct known {
	const char *key, *ok, *when_key, *when_off;
};

static const struct known known[] = {
    /* Names, notes, links between presets, the GUI, the print host */
    {"inherits", NULL, NULL, NULL}, {"renamed_from", NULL, NULL, NULL},
    {"compatible_printers", NULL, NULL, NULL}, {"compatible_printers_condition", NULL, NULL, NULL},
    {"compatible_prints", NULL, NULL, NULL}, {"compatible_prints_condition", NULL, NULL, NULL},
    {"default_print_profile", NULL, NULL, NULL}, {"default_filament_profile", NULL, NULL, NULL},
    {"default_sla_print_profile", NULL, NULL, NULL}, {"default_sla_material_profile", NULL, NULL, NULL},
    {"print_settings_id", NULL, NULL, NULL}, {"filament_settings_id", NULL, NULL, NULL},
    {"printer_settings_id", NULL, NULL, NULL}, {"printer_variant", NULL, NULL, NULL},
    {"printer_vendor", NULL, NULL, NULL}, {"printer_technology", "FFF", NULL, NULL},
    {"notes", NULL, NULL, NULL}, {"printer_notes", NULL, NULL, NULL},
    {"filament_notes", NULL, NULL, NULL}, {"filament_vendor", NULL, NULL, NULL},
    {"filament_type", NULL, NULL, NULL}, {"filament_colour", NULL, NULL, NULL},
    {"extruder_colour", NULL, NULL, NULL}, {"filament_cost", NULL, NULL, NULL},
    {"filament_spool_weight", NULL, NULL, NULL}, {"filament_soluble", NULL, NULL, NULL},
    {"output_filename_format", NULL, NULL, NULL}, {"host_type", NULL, NULL, NULL},
    {"print_host", NULL, NULL, NULL}, {"printhost_*", NULL, NULL, NULL},
    {"octoprint_*", NULL, NULL, NULL}, {"serial_port", NULL, NULL, NULL},
    {"serial_speed", NULL, NULL, NULL}, {"bed_custom_texture", NULL, NULL, NULL},
    {"bed_custom_model", NULL, NULL, NULL}, {"bed_model", NULL, NULL, NULL},
    {"bed_texture", NULL, NULL, NULL}, {"thumbnails_format", "PNG", NULL, NULL},
    {"threads", NULL, NULL, NULL},
    {"color_change_gcode", NULL, NULL, NULL}, {"pause_print_gcode", NULL, NULL, NULL},
    {"template_custom_gcode", NULL, NULL, NULL}, {"between_objects_gcode", NULL, NULL, NULL},
    {"gcode_comments", NULL, NULL, NULL},
    {"extruder_clearance_height", NULL, NULL, NULL}, {"extruder_clearance_radius", NULL, NULL, NULL},
    {"perimeter_generator", NULL, NULL, NULL}, /* Stratum's own wall generator */
    {"wall_*", NULL, NULL, NULL}, {"slice_closing_radius", NULL, NULL, NULL},
    {"resolution", "0", NULL, NULL},
    {"clip_multipart_objects", NULL, NULL, NULL}, {"slicing_mode", "regular", NULL, NULL},
    {"max_print_speed", NULL, NULL, NULL}, /* PrusaSlicer's auto speed only */
    /* One extruder, no tool changes */
    {"perimeter_extruder", "1", NULL, NULL}, {"infill_extruder", "1", NULL, NULL},
    {"solid_infill_extruder", "1", NULL, NULL}, {"support_material_extruder", NULL, "support_material", "0"},
    {"support_material_interface_extruder", NULL, "support_material", "0"},
    {"wipe_tower", NULL, NULL, NULL}, /* PrusaSlicer builds none for one extruder */
    {"wipe_tower_*", NULL, NULL, NULL},
    {"wiping_volumes_*", NULL, NULL, NULL}, {"single_extruder_multi_material", "0", NULL, NULL},
    {"single_extruder_multi_material_priming", NULL, NULL, NULL},
    {"cooling_tube_*", NULL, NULL, NULL}, {"parking_pos_retraction", NULL, NULL, NULL},
    {"extra_loading_move", NULL, NULL, NULL}, {"high_current_on_filament_swap", NULL, NULL, NULL},
    {"filament_cooling_*", NULL, NULL, NULL}, {"filament_loading_speed*", NULL, NULL, NULL},
    {"filament_unloading_speed*", NULL, NULL, NULL}, {"filament_load_time", NULL, NULL, NULL},
    {"filament_unload_time", NULL, NULL, NULL}, {"filament_ramming_parameters", NULL, NULL, NULL},
    {"filament_minimal_purge_on_wipe_tower", NULL, NULL, NULL},
    {"filament_toolchange_delay", NULL, NULL, NULL}, {"filament_multitool_ramming*", NULL, NULL, NULL},
    {"retract_length_toolchange", NULL, NULL, NULL}, {"retract_restart_extra_toolchange", NULL, NULL, NULL},
    {"wipe_into_infill", NULL, NULL, NULL}, {"wipe_into_objects", NULL, NULL, NULL},
    {"ooze_prevention", "0", NULL, NULL}, {"standby_temperature_delta", NULL, "ooze_prevention", "0"},
    {"mmu_segmented_region_max_width", NULL, NULL, NULL},
    /* Filament overrides: applied by the loader (profile_load_layers) */
    {"filament_retract_*", NULL, NULL, NULL}, {"filament_deretract_speed", NULL, NULL, NULL},
    {"filament_wipe", NULL, NULL, NULL},
    /* Features Stratum does not have, honoured while they are off */
    {"raft_*", NULL, "raft_layers", "0"}, /* beyond the raft keys settings.c declares */
    {"first_layer_acceleration_over_raft", NULL, "raft_layers", "0"},
    {"complete_objects", "0", NULL, NULL},
    {"fuzzy_skin", "none", NULL, NULL}, {"fuzzy_skin_*", NULL, "fuzzy_skin", "none"},
    {"draft_shield", "disabled", NULL, NULL}, {"xy_size_compensation", "0", NULL, NULL},
    {"z_offset", "0", NULL, NULL},
    {"use_firmware_retraction", "0", NULL, NULL}, {"use_volumetric_e", "0", NULL, NULL},
    {"extrusion_axis", "E", NULL, NULL}, {"infill_every_layers", "1", NULL, NULL},
    {"solid_infill_every_layers", "0", NULL, NULL}, {"interface_shells", "0", NULL, NULL},
    {"infill_only_where_needed", "0", NULL, NULL}, {"colorprint_heights", "", NULL, NULL},
    {"post_process", "", NULL, NULL}, {"gcode_substitutions", "", NULL, NULL},
    {"gcode_label_objects", NULL, NULL, NULL}, /* comments for host plugins */
    /* Solid skins are lines alternating 90 degrees a layer (infill_fill.c) */
    {"external_fill_pattern", "rectilinear", NULL, NULL},
    /* The shells are counted through every layer's whole region (infill.h),
     * so slopes keep their vertical shell thickness: PrusaSlicer's 1 */
    {"ensure_vertical_shell_thickness", "1", NULL, NULL},
    {"extra_perimeters", "0", NULL, NULL}, /* no walls added for the layer above */
    {"retract_restart_extra", "0", NULL, NULL},
    {"max_volumetric_extrusion_rate_slope_*", "0", NULL, NULL},
    {"infill_first", "0", NULL, NULL}, {"brim_*", NULL, "brim_width", "0"},
    {"support_material_*", NULL, "support_material", "0"},
    {"dont_support_bridges", NULL, "support_material", "0"},
    {"travel_acceleration", "0", NULL, NULL},
    {"external_perimeter_acceleration", "0", NULL, NULL}, {"top_solid_infill_acceleration", "0", NULL, NULL},
    {"solid_infill_acceleration", "0", NULL, NULL},
};

/* Numbers compared as numbers ("0" = "0.0" = "0%"), other text as text;
 * every item of a comma list must match. */
static bool same_value(const char *v, const char *ok)
{
	double a, b;
	size_t ol = strlen(ok);

	if (st_parse_double(ok, ol, 0, &b) != ST_NUMBER_OK)
		return !strcmp(v, ok);
	for (;;) {
		const char *comma = strchr(v, ',');
		size_t n = comma ? (size_t)(comma - v) : strlen(v);

		while (n && (*v == ' ' || *v == '"'))
			v++, n--;
		while (n && (v[n - 1] == ' ' || v[n - 1] == '%' || v[n - 1] == '"'))
			n--;
		if (st_parse_double(v, n, 0, &a) != ST_NUMBER_OK || a != b)
			return false;
		if (!comma)
			return true;
		v = comma + 1;
	}
}

static const struct known *find_known(const char *key)
{
	for (size_t i = 0; i < sizeof(known) / sizeof(known[0]); i++) {
		size_t n = strlen(known[i].key);
		if (known[i].key[n - 1] == '*' ? !strncmp(key, known[i].key, n - 1)
					       : !strcmp(key, known[i].key))
			return &known[i];
	}
	return NULL;
}

/* True when p honours kv (see the top of the file). */
static bool honoured(const struct profile *p, const struct profile_kv *kv)
{
	const struct setting *s = settings_find(kv->key);
	const struct known *k;

	k = find_known(kv->key);
	if (s)
		return true;
	if (!k)
		return false;
	if (k->when_key) {
		const char *w = profile_get(p, k->when_key);
		const struct setting *ws = settings_find(k->when_key);

		if (!w && ws)
			w = ws->dflt;
		if (!w || same_value(w, k->when_off))
			return true;
	}
	return k->ok ? same_value(kv->value, k->ok) : k->when_key == NULL;
}

/* Append "KEY=VALUE" (value cut at 24 bytes and at a line end). */
static int add_item(char **buf, size_t *len, size_t *cap, const char *key, const char *value,
		    const char *note)
{
	size_t vl = strcspn(value, "\n");
	size_t need = strlen(key) + 40 + (note ? strlen(note) : 0);
	char *grown = st_grow(*buf, cap, *len + need + 1, 1);

	if (!grown)
		return ST_ERR_NOMEM;
	*buf = grown;
	*len += (size_t)snprintf(grown + *len, need + 1, "%s%s=%.*s%s%s%s", *len ? ", " : "", key,
				 (int)(vl > 24 ? 24 : vl), value, vl > 24 ? "..." : "",
				 note ? " " : "", note ? note : "");
	return 0;
}

/* A top or bottom skin pattern Stratum prints. */
static bool skin_pattern_printed(const char *name)
{
	return !strcmp(name, "rectilinear") || !strcmp(name, "monotonic");
}

int profile_unsupported(const struct profile *p, char **out)
{
	char *buf = NULL;
	size_t len = 0, cap = 0;
	enum infill_pattern pat;
	int rc = 0;

	*out = NULL;
	if (!p)
		return ST_ERR_ARG;
	if (infill_pattern_parse(p->fill_pattern, &pat, NULL))
		rc = add_item(&buf, &len, &cap, "fill_pattern", p->fill_pattern,
			      "(rectilinear used)");
	/* the skins print rectilinear or monotonic lines (profile_slicer.c) */
	if (!rc && !skin_pattern_printed(p->top_fill_pattern))
		rc = add_item(&buf, &len, &cap, "top_fill_pattern", p->top_fill_pattern,
			      "(rectilinear used)");
	if (!rc && !skin_pattern_printed(p->bottom_fill_pattern))
		rc = add_item(&buf, &len, &cap, "bottom_fill_pattern", p->bottom_fill_pattern,
			      "(rectilinear used)");
	/* arcs only where the firmware takes them (profile_slicer.c) */
	if (!rc && strcmp(p->arc_fitting, "disabled") && !prof_flavor_arcs(p->gcode_flavor)) {
		char note[80];
		snprintf(note, sizeof(note), "(gcode_flavor = %s has no G2/G3: lines written)",
			 profile_flavor_name(p->gcode_flavor));
		rc = add_item(&buf, &len, &cap, "arc_fitting", p->arc_fitting, note);
	}
	for (size_t i = 0; rc == 0 && i < p->keys->count; i++)
		if (!honoured(p, &p->keys->kv[i]))
			rc = add_item(&buf, &len, &cap, p->keys->kv[i].key, p->keys->kv[i].value, NULL);
	if (rc) {
		free(buf);
		return rc;
	}
	*out = buf;
	return 0;
}
