/*
 * gcode_writer_config.c - the G-code writer's settings table and what
 * reads it: defaults and checks, the placeholder variables, the number
 * format and the header of settings and estimates (see gcode_writer.h).
 */
#include "gcode_writer_int.h"

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "ironing.h"
#include "placeholder.h"
#include "settings.h"

/* ---------------------------------------------------------------------------
 * Settings: the writer's fields bound to their declarations (settings.h),
 * which give every range and default; the table also drives the header and
 * the placeholders.
 */

enum key_type { KEY_DOUBLE, KEY_INT, KEY_BOOL };

struct key {
	const char *name; /* the declared setting */
	enum key_type type;
	size_t off;	  /* in struct gcodew_settings */
	bool vector;	  /* per extruder/filament in PrusaSlicer: {name[0]} allowed */
	bool raft;	  /* in the header only when there is a raft */
	bool nonzero;	  /* in the header only when not 0 (as before the key was) */
};

#define KD(n, vec) {#n, KEY_DOUBLE, offsetof(struct gcodew_settings, n), vec, false, false}
#define KI(n, vec) {#n, KEY_INT, offsetof(struct gcodew_settings, n), vec, false, false}
#define KB(n, vec) {#n, KEY_BOOL, offsetof(struct gcodew_settings, n), vec, false, false}
#define KRD(n) {#n, KEY_DOUBLE, offsetof(struct gcodew_settings, n), false, true, false}
#define KRI(n) {#n, KEY_INT, offsetof(struct gcodew_settings, n), false, true, false}
#define KZD(n) {#n, KEY_DOUBLE, offsetof(struct gcodew_settings, n), false, false, true}
#define KZB(n) {#n, KEY_BOOL, offsetof(struct gcodew_settings, n), false, false, true}
#define KZDV(n) {#n, KEY_DOUBLE, offsetof(struct gcodew_settings, n), true, false, true}
#define KZBV(n) {#n, KEY_BOOL, offsetof(struct gcodew_settings, n), true, false, true}

static const struct key keys[] = {
    KD(nozzle_diameter, true),
    KD(filament_diameter, true),
    KD(extrusion_multiplier, true),
    KD(filament_density, true),
    KB(use_relative_e_distances, false),
    KD(layer_height, false),
    KD(first_layer_height, false),
    KI(temperature, true),
    KI(first_layer_temperature, true),
    KI(bed_temperature, true),
    KI(first_layer_bed_temperature, true),
    KD(retract_length, true),
    KD(retract_speed, true),
    KD(deretract_speed, true),
    KD(retract_lift, true),
    KZDV(retract_lift_above),
    KZDV(retract_lift_below),
    KD(retract_before_travel, true),
    KB(wipe, true),
    KZDV(retract_before_wipe),
    KZBV(retract_layer_change),
    KB(avoid_crossing_perimeters, false),
    KB(only_retract_when_crossing_perimeters, false),
    KD(max_unretracted_travel, false),
    KD(perimeter_speed, false),
    KD(external_perimeter_speed, false),
    KD(small_perimeter_speed, false),
    KD(infill_speed, false),
    KD(solid_infill_speed, false),
    KD(top_solid_infill_speed, false),
    KD(bridge_speed, false),
    KD(gap_fill_speed, false),
    KD(support_material_speed, false),
    KD(support_material_interface_speed, false),
    KD(travel_speed, false),
    KD(travel_speed_z, false),
    KD(first_layer_speed, false),
    KB(cooling, true),
    KB(fan_always_on, true),
    KI(min_fan_speed, true),
    KI(max_fan_speed, true),
    KI(bridge_fan_speed, true),
    KI(disable_fan_first_layers, true),
    KI(full_fan_speed_layer, true),
    KD(fan_below_layer_time, true),
    KD(slowdown_below_layer_time, true),
    KD(min_print_speed, true),
    KRI(raft_layers),
    KRD(raft_contact_distance),
    KRD(raft_expansion),
    KRD(raft_first_layer_density),
    KRD(raft_first_layer_expansion),
    KRD(first_layer_speed_over_raft),
    KZD(max_volumetric_speed),
    KZDV(filament_max_volumetric_speed),
    KZD(default_acceleration),
    KZD(perimeter_acceleration),
    KZD(infill_acceleration),
    KZD(bridge_acceleration),
    KZD(first_layer_acceleration),
    KZD(gcode_resolution),
    KZB(remaining_times),
};

#define NKEYS (sizeof(keys) / sizeof(keys[0]))

/* The value of key k in s, as a double. */
static double key_value(const struct gcodew_settings *s, const struct key *k)
{
	const char *base = (const char *)s + k->off;

	switch (k->type) {
	case KEY_INT:
		return *(const int *)(const void *)base;
	case KEY_BOOL:
		return *(const bool *)(const void *)base ? 1 : 0;
	default:
		return *(const double *)(const void *)base;
	}
}

/* Store v as key k's field of s. */
static void key_set(struct gcodew_settings *s, const struct key *k, double v)
{
	char *base = (char *)s + k->off;

	switch (k->type) {
	case KEY_INT:
		*(int *)(void *)base = (int)v;
		break;
	case KEY_BOOL:
		*(bool *)(void *)base = v != 0;
		break;
	default:
		*(double *)(void *)base = v;
		break;
	}
}

void gcodew_settings_init(struct gcodew_settings *s)
{
	double v;

	memset(s, 0, sizeof(*s));
	for (size_t i = 0; i < NKEYS; i++)
		if (setting_default_number(keys[i].name, false, &v))
			key_set(s, &keys[i], v);
	/* Declared as following another key (settings.c). */
	s->first_layer_temperature = s->temperature;
	s->first_layer_bed_temperature = s->bed_temperature;
	s->start_gcode = settings_find("start_gcode")->dflt;
	s->end_gcode = settings_find("end_gcode")->dflt;
	s->before_layer_gcode = s->layer_gcode = "";
	s->start_filament_gcode = s->end_filament_gcode = "";
	s->thumbnails = "";
	s->printer_settings_id = s->printer_model = "";
	s->bed_shape = settings_find("bed_shape")->dflt;
	s->spiral_vase = setting_default_number("spiral_vase", false, &v) && v != 0;
	s->ironing = setting_default_number("ironing", false, &v) && v != 0;
	s->ironing_type = settings_find("ironing_type")->dflt;
	s->arc_fitting = !strcmp(settings_find("arc_fitting")->dflt, "emit_center");
	setting_default_number("ironing_flowrate", false, &s->ironing_flowrate);
	setting_default_number("ironing_spacing", false, &s->ironing_spacing);
	setting_default_number("ironing_speed", false, &s->ironing_speed);
	est_limits_init(&s->limits);
}

int gcodew_settings_check(const struct gcodew_settings *s, struct st_error *err)
{
	if (!s)
		return st_error_set(err, ST_ERR_ARG, "G-code settings: none given");
	for (size_t i = 0; i < NKEYS; i++) {
		int rc = setting_check("G-code settings", keys[i].name, key_value(s, &keys[i]), err);
		if (rc)
			return rc;
	}
	static const char *const ironing_keys[] = {"ironing_flowrate", "ironing_spacing",
						   "ironing_speed"};
	const double ironing_values[] = {s->ironing_flowrate, s->ironing_spacing, s->ironing_speed};
	for (size_t i = 0; i < sizeof(ironing_keys) / sizeof(ironing_keys[0]); i++) {
		int rc = setting_check("G-code settings", ironing_keys[i], ironing_values[i], err);
		if (rc)
			return rc;
	}
	enum iron_type type;
	int rc = iron_type_parse(s->ironing_type, &type, err);
	if (rc)
		return rc;
	if (s->min_fan_speed > s->max_fan_speed)
		return st_error_set(err, ST_ERR_RANGE,
				    "G-code settings: min_fan_speed %d is above max_fan_speed %d",
				    s->min_fan_speed, s->max_fan_speed);
	if (!s->start_gcode || !s->end_gcode || !s->before_layer_gcode || !s->layer_gcode ||
	    !s->start_filament_gcode || !s->end_filament_gcode || !s->printer_settings_id ||
	    !s->printer_model || !s->bed_shape)
		return st_error_set(err, ST_ERR_ARG,
				    "G-code settings: the custom G-code and printer texts must not "
				    "be NULL");
	return 0;
}

/* ---------------------------------------------------------------------------
 * Numbers: fixed decimals, trailing zeros dropped, never an exponent or "-0".
 */

/*
 * Write u / 10^digits into buf (NUM_MAX bytes, digits < NUM_MAX - 3) and
 * return its length.  By hand rather than through snprintf: a print has
 * millions of coordinates and this was a tenth of the writer's time.
 */
size_t gcodew_fmt_units(char *buf, int64_t u, int digits)
{
	uint64_t mag = u < 0 ? (uint64_t)0 - (uint64_t)u : (uint64_t)u;
	char rev[NUM_MAX]; /* decimal digits, least significant first */
	int n = 0, lo = 0;
	size_t len = 0;

	do {
		rev[n++] = (char)('0' + mag % 10);
		mag /= 10;
	} while (mag || n <= digits);
	if (u < 0)
		buf[len++] = '-';
	for (int i = n - 1; i >= digits; i--)
		buf[len++] = rev[i];
	while (lo < digits && rev[lo] == '0') /* trailing zeros dropped */
		lo++;
	if (lo < digits) {
		buf[len++] = '.';
		for (int i = digits - 1; i >= lo; i--)
			buf[len++] = rev[i];
	}
	buf[len] = '\0';
	return len;
}

/* Write v rounded to digits decimals into buf (NUM_MAX bytes). */
void gcodew_fmt_num(char *buf, double v, int digits)
{
	double scale = pow(10, digits);

	if (!(fabs(v) * scale < 9e18)) {
		snprintf(buf, NUM_MAX, "%.0f", isfinite(v) ? v : 0.0);
		return;
	}
	gcodew_fmt_units(buf, llround(v * scale), digits);
}

/* ---------------------------------------------------------------------------
 * Placeholders (slicer/placeholder.h): the writer's own variables - the
 * settings it prints with and PrusaSlicer's standard variables - over the
 * printer's config (s->vars).
 */

static const enum ph_type ph_types[] = {[KEY_DOUBLE] = PH_REAL, [KEY_INT] = PH_INT,
					[KEY_BOOL] = PH_BOOL};

/* Skip blanks in [*i, end). */
static void skip_blanks(const char *t, size_t *i, size_t end)
{
	while (*i < end && (t[*i] == ' ' || t[*i] == '\t'))
		(*i)++;
}

/* The variables of a print of nlayers layers, before its first layer. */
struct ph_vars *gcodew_vars_new(const struct gcodew_settings *s, size_t nlayers,
				struct st_error *err)
{
	static const char *const zero_ints[] = {"initial_extruder", "initial_tool",
						"current_extruder", "next_extruder",
						"filament_extruder_id", "layer_num"};
	static const char *const no_bools[] = {"has_wipe_tower",
					       "has_single_extruder_multi_material_priming"};
	struct ph_vars *v = ph_vars_new(s->vars);
	int rc = v ? 0 : st_error_set(err, ST_ERR_NOMEM, "G-code: out of memory");

	for (size_t i = 0; rc == 0 && i < NKEYS; i++) {
		double x = key_value(s, &keys[i]);
		rc = ph_vars_set_numbers(v, keys[i].name, ph_types[keys[i].type], &x, 1,
					 keys[i].vector, err);
	}
	for (size_t i = 0; rc == 0 && i < sizeof(zero_ints) / sizeof(zero_ints[0]); i++)
		rc = ph_vars_set_number(v, zero_ints[i], PH_INT, 0, err);
	for (size_t i = 0; rc == 0 && i < sizeof(no_bools) / sizeof(no_bools[0]); i++)
		rc = ph_vars_set_number(v, no_bools[i], PH_BOOL, 0, err);
	if (rc == 0)
		rc = ph_vars_set_number(v, "total_layer_count", PH_INT, (double)nlayers, err);
	if (rc == 0)
		rc = ph_vars_set_number(v, "layer_z", PH_REAL, s->first_layer_height, err);
	if (rc == 0)
		rc = ph_vars_set_number(v, "max_layer_z", PH_REAL, 0, err);
	if (rc) {
		ph_vars_free(v);
		return NULL;
	}
	return v;
}

/* layer_num (from 0), layer_z and max_layer_z for the next text. */
int gcodew_set_layer_vars(struct ph_vars *v, size_t li, double z, double max_z,
			  struct st_error *err)
{
	int rc = ph_vars_set_number(v, "layer_num", PH_INT, (double)li, err);

	if (rc == 0)
		rc = ph_vars_set_number(v, "layer_z", PH_REAL, z, err);
	if (rc == 0)
		rc = ph_vars_set_number(v, "max_layer_z", PH_REAL, max_z, err);
	return rc;
}

int gcodew_expand(const char *text, const char *what, const struct gcodew_settings *s,
		  size_t nlayers, char **out, struct st_error *err)
{
	struct ph_vars *v;
	int rc;

	if (out)
		*out = NULL;
	if (!text || !s || !out)
		return st_error_set(err, ST_ERR_ARG, "placeholders: no text, settings or output");
	v = gcodew_vars_new(s, nlayers, err);
	if (!v)
		return err && err->code ? err->code : ST_ERR_NOMEM;
	rc = ph_expand(text, what, v, 0, out, err);
	ph_vars_free(v);
	return rc;
}

/*
 * True when a line of text starts with the command M<m1> or M<m2> (an
 * optional N<n> line number before it, comments ignored): PrusaSlicer's
 * test for "the start G-code sets this temperature itself".
 */
bool gcodew_text_sets(const char *text, int m1, int m2)
{
	const char *p = text;

	while (*p) {
		const char *end = strchr(p, '\n');
		size_t n = end ? (size_t)(end - p) : strlen(p), i = 0;
		skip_blanks(p, &i, n);
		if (i < n && (p[i] == 'N' || p[i] == 'n')) {
			for (i++; i < n && p[i] >= '0' && p[i] <= '9'; i++)
				;
			skip_blanks(p, &i, n);
		}
		if (i < n && (p[i] == 'M' || p[i] == 'm')) {
			int num = 0, digits = 0;
			for (i++; i < n && p[i] >= '0' && p[i] <= '9' && digits < 6; i++, digits++)
				num = num * 10 + (p[i] - '0');
			if (digits && (i == n || !(p[i] == '.' || (p[i] >= '0' && p[i] <= '9'))) &&
			    (num == m1 || num == m2))
				return true;
		}
		p += n;
		if (*p == '\n')
			p++;
	}
	return false;
}

/* ---------------------------------------------------------------------------
 * The header
 */

/* Whether key k of s is written as a percentage. */
static bool key_is_pct(const struct gcodew_settings *s, const struct key *k)
{
	if (k->off == offsetof(struct gcodew_settings, first_layer_speed))
		return s->first_layer_speed_is_percent;
	if (k->off == offsetof(struct gcodew_settings, first_layer_speed_over_raft))
		return s->first_layer_speed_over_raft_is_percent;
	return k->off == offsetof(struct gcodew_settings, raft_first_layer_density) ||
	       k->off == offsetof(struct gcodew_settings, retract_before_wipe);
}

/* Write "; estimated printing time = 1h 2m 3s". */
static void put_time(struct gcodew *w, double seconds)
{
	long long t = llround(seconds), d = t / 86400, h = t / 3600 % 24, m = t / 60 % 60;

	gcodew_put(w, "; estimated printing time =");
	if (d)
		gcodew_put(w, " %lldd", d);
	if (d || h)
		gcodew_put(w, " %lldh", h);
	if (d || h || m)
		gcodew_put(w, " %lldm", m);
	gcodew_put(w, " %llds\n", t % 60);
}

/* "; KEY = TEXT" with control characters as blanks: one comment line. */
static void put_header_text(struct gcodew *w, const char *key, const char *text)
{
	gcodew_put(w, "; %s = ", key);
	for (const char *c = text; *c; c++)
		fputc((unsigned char)*c < ' ' ? ' ' : *c, w->fp);
	gcodew_put(w, "\n");
}

/* The header: printer, estimates, settings, machine limits, bead widths used. */
void gcodew_put_header(struct gcodew *w, const struct gcodew_summary *sum)
{
	static const char axis[EST_AXES] = {'x', 'y', 'z', 'e'};
	const struct est_limits *lim = &w->s->limits;
	const double *len = w->len, *area = w->area;
	char n[NUM_MAX];

	gcodew_put(w, "; generated by Stratum\n");
	if (w->s->thumbnail_block)
		gcodew_put(w, "%s", w->s->thumbnail_block);
	put_header_text(w, "printer_settings_id", w->s->printer_settings_id);
	put_header_text(w, "printer_model", w->s->printer_model);
	put_header_text(w, "bed_shape", w->s->bed_shape);
	for (size_t i = 0; w->s->input_file_count >= 2 && i < w->s->input_file_count; i++)
		put_header_text(w, "input file", w->s->input_files[i]);
	put_time(w, sum->time_s);
	gcodew_fmt_num(n, sum->filament_mm, 2);
	gcodew_put(w, "; filament used [mm] = %s\n", n);
	gcodew_fmt_num(n, sum->filament_cm3, 2);
	gcodew_put(w, "; filament used [cm3] = %s\n", n);
	gcodew_fmt_num(n, sum->filament_g, 2);
	gcodew_put(w, "; filament used [g] = %s\n", n);
	gcodew_put(w, "; total layers count = %zu\n", sum->layers);
	gcodew_put(w, "; total moves = %zu\n", sum->moves);
	for (size_t i = 0; i < NKEYS; i++) {
		bool pct = key_is_pct(w->s, &keys[i]);

		if (keys[i].raft && w->s->raft_layers == 0)
			continue; /* as before rafts were printed */
		if (keys[i].nonzero && key_value(w->s, &keys[i]) == 0)
			continue;
		gcodew_fmt_num(n, key_value(w->s, &keys[i]), 6);
		gcodew_put(w, "; %s = %s%s\n", keys[i].name, n, pct ? "%" : "");
	}
	if (w->s->spiral_vase)
		gcodew_put(w, "; spiral_vase = 1\n");
	if (w->s->arc_fitting)
		gcodew_put(w, "; arc_fitting = emit_center\n");
	if (w->s->ironing) {
		gcodew_fmt_num(n, w->s->ironing_flowrate, 6);
		gcodew_put(w, "; ironing = 1\n; ironing_type = %s\n; ironing_flowrate = %s%%\n",
			   w->s->ironing_type, n);
		gcodew_fmt_num(n, w->s->ironing_spacing, 6);
		gcodew_put(w, "; ironing_spacing = %s\n", n);
		gcodew_fmt_num(n, w->s->ironing_speed, 6);
		gcodew_put(w, "; ironing_speed = %s\n", n);
	}
	if (w->s->slicer_block)
		gcodew_put(w, "%s", w->s->slicer_block);
	for (int a = 0; a < EST_AXES; a++) {
		char f[NUM_MAX], acc[NUM_MAX], j[NUM_MAX];
		gcodew_fmt_num(f, lim->max_feedrate[a], 3);
		gcodew_fmt_num(acc, lim->max_acceleration[a], 3);
		gcodew_fmt_num(j, lim->max_jerk[a], 3);
		gcodew_put(w,
			   "; machine_max_feedrate_%c = %s\n; machine_max_acceleration_%c = %s\n"
			   "; machine_max_jerk_%c = %s\n",
			   axis[a], f, axis[a], acc, axis[a], j);
	}
	gcodew_fmt_num(n, lim->accel_extruding, 3);
	gcodew_put(w, "; machine_max_acceleration_extruding = %s\n", n);
	gcodew_fmt_num(n, lim->accel_retracting, 3);
	gcodew_put(w, "; machine_max_acceleration_retracting = %s\n", n);
	gcodew_fmt_num(n, lim->accel_travel, 3);
	gcodew_put(w, "; machine_max_acceleration_travel = %s\n", n);

	for (int r = 0; r < PATH_ROLES; r++)
		if (len[r] > 0) {
			gcodew_fmt_num(n, area[r] / len[r] / SLICE_UNITS_PER_MM, 3);
			gcodew_put(w, "; extrusion width (%s) = %s mm\n",
				   path_role_name((enum path_role)r), n);
		}
	gcodew_put(w, "\n");
}
