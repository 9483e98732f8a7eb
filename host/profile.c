/*
 * profile.c - printer profiles: read a flat PrusaSlicer-style key = value
 * file, check every line and every typed value, fill struct profile.
 *
 * Loading is two passes over memory: first every line is split into
 * (key, decoded value, line number) with syntax and duplicate checks; then a
 * table of known keys (key_defs below) types and range-checks the values in
 * a fixed order, and a last step checks keys against each other (layer
 * height against nozzle, protocol against G-code flavor ...).  Nothing is
 * returned unless the whole file passed.
 *
 * Numbers are read with our own grammar, [+-]digits[.digits] (no exponent,
 * no hexadecimal, no decimal comma), and only a validated copy is handed to
 * strtod; the program never calls setlocale, so the C locale's '.' applies.
 */
#include "profile.h"
#include "st_number.h"

#include <dirent.h>
#include <errno.h>
#include <jansson.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define FILE_MAX (16u * 1024 * 1024) /* a profile is a few KiB; refuse absurd files */
#define TOKEN_SHOW 40		     /* bytes of an offending value quoted in messages */

/* One key = value line of the file. */
struct profile_kv {
	char *key;
	char *value; /* escapes decoded */
	int line;
};

struct profile_keys {
	struct profile_kv *kv;
	size_t count, cap;
};

/* ---------------------------------------------------------------------------
 * Key table
 */

enum key_type {
	KT_STRING,	 /* const char * */
	KT_DOUBLE,	 /* double */
	KT_INT,		 /* int */
	KT_BOOL,	 /* bool, 0/1 */
	KT_EX_DOUBLE,	 /* double[PROFILE_MAX_EXTRUDERS], one per extruder */
	KT_EX_INT,	 /* int[PROFILE_MAX_EXTRUDERS] */
	KT_EX_POINT,	 /* struct profile_point[PROFILE_MAX_EXTRUDERS], "XxY" */
	KT_FIRST_DOUBLE, /* double; a list is accepted, its first value used */
	KT_FIRST_INT,	 /* int; likewise */
	KT_FIRST_BOOL,	 /* bool; likewise */
	KT_FIRST_HEIGHT, /* first_layer_height: mm or % of layer_height */
	KT_WIDTH,	 /* extrusion_width: mm or % of layer_height, 0 = auto */
	KT_SPEED_PCT,	 /* first_layer_speed: mm/s or % */
	KT_DENSITY,	 /* fill_density: N% or a fraction 0-1 */
	KT_PROTOCOL,	 /* enum profile_protocol */
	KT_FLAVOR,	 /* enum profile_flavor */
	KT_BAUD,	 /* long, a standard rate */
	KT_USB,		 /* usb_ids */
	KT_BED,		 /* bed_shape */
	KT_PATTERN,	 /* fill_pattern */
	KT_HOME,	 /* enum profile_home */
	KT_EXTRUDERS,	 /* extruder_count */
};

#define KF_GT_MIN 1u   /* the minimum itself is not allowed */
#define KF_LIMITS 2u   /* machine limit: 1 or 2 values (normal, stealth) */
#define KF_SAILFISH 4u /* matters for sailfish printers only */

struct key_def {
	const char *key;
	enum key_type type;
	size_t off; /* offsetof(struct profile, field) */
	double min, max;
	unsigned flags;
	const char *unit;  /* for range messages */
	const char *group; /* starts a group in profile_write */
};

#define OFF(field) offsetof(struct profile, field)

/* Every key the loader types, in the order it applies and writes them. */
static const struct key_def key_defs[] = {
    {"name", KT_STRING, OFF(name), 0, 0, 0, "", "Identity"},
    {"description", KT_STRING, OFF(description), 0, 0, 0, "", NULL},
    {"printer_model", KT_STRING, OFF(printer_model), 0, 0, 0, "", NULL},

    {"protocol", KT_PROTOCOL, OFF(protocol), 0, 0, 0, "", "Connection"},
    {"baudrate", KT_BAUD, OFF(baudrate), 0, 0, 0, "", NULL},
    {"usb_ids", KT_USB, 0, 0, 0, 0, "", NULL},
    {"rx_buffer_size", KT_INT, OFF(rx_buffer_size), 16, 65536, 0, "bytes", NULL},
    {"dtr_reset", KT_BOOL, OFF(dtr_reset), 0, 0, 0, "", NULL},
    {"x3g_buffer_size", KT_INT, OFF(x3g_buffer_size), 0, 65536, KF_SAILFISH, "bytes", NULL},

    {"gcode_flavor", KT_FLAVOR, OFF(gcode_flavor), 0, 0, 0, "", "Machine"},
    {"bed_shape", KT_BED, 0, -10000, 10000, 0, "mm", NULL},
    {"max_print_height", KT_DOUBLE, OFF(max_print_height), 0, 10000, KF_GT_MIN, "mm", NULL},
    {"extruder_count", KT_EXTRUDERS, OFF(extruder_count), 1, PROFILE_MAX_EXTRUDERS, 0, "", NULL},
    {"use_relative_e_distances", KT_BOOL, OFF(use_relative_e_distances), 0, 0, 0, "", NULL},

    {"nozzle_diameter", KT_EX_DOUBLE, OFF(nozzle_diameter), 0.05, 3, 0, "mm", "Extruders"},
    {"filament_diameter", KT_EX_DOUBLE, OFF(filament_diameter), 1, 3.5, 0, "mm", NULL},
    {"extruder_offset", KT_EX_POINT, OFF(extruder_offset), -1000, 1000, 0, "mm", NULL},
    {"extrusion_multiplier", KT_EX_DOUBLE, OFF(extrusion_multiplier), 0, 5, KF_GT_MIN, "", NULL},
    {"temperature", KT_EX_INT, OFF(temperature), 0, 450, 0, "C", NULL},
    {"first_layer_temperature", KT_EX_INT, OFF(first_layer_temperature), 0, 450, 0, "C", NULL},
    {"bed_temperature", KT_FIRST_INT, OFF(bed_temperature), 0, 150, 0, "C", NULL},
    {"first_layer_bed_temperature", KT_FIRST_INT, OFF(first_layer_bed_temperature), 0, 150, 0, "C",
     NULL},
    {"retract_length", KT_EX_DOUBLE, OFF(retract_length), 0, 50, 0, "mm", NULL},
    {"retract_speed", KT_EX_DOUBLE, OFF(retract_speed), 0, 1000, KF_GT_MIN, "mm/s", NULL},
    {"retract_lift", KT_EX_DOUBLE, OFF(retract_lift), 0, 50, 0, "mm", NULL},
    {"min_layer_height", KT_EX_DOUBLE, OFF(min_layer_height), 0, 3, 0, "mm", NULL},
    {"max_layer_height", KT_EX_DOUBLE, OFF(max_layer_height), 0, 3, 0, "mm", NULL},

    {"layer_height", KT_DOUBLE, OFF(layer_height), 0, 3, KF_GT_MIN, "mm", "Print"},
    {"first_layer_height", KT_FIRST_HEIGHT, OFF(first_layer_height), 0, 3, KF_GT_MIN, "mm", NULL},
    {"extrusion_width", KT_WIDTH, OFF(extrusion_width), 0, 10, 0, "mm", NULL},
    {"perimeters", KT_INT, OFF(perimeters), 0, 100, 0, "", NULL},
    {"top_solid_layers", KT_INT, OFF(top_solid_layers), 0, 1000, 0, "", NULL},
    {"bottom_solid_layers", KT_INT, OFF(bottom_solid_layers), 0, 1000, 0, "", NULL},
    {"fill_density", KT_DENSITY, OFF(fill_density), 0, 100, 0, "%", NULL},
    {"fill_pattern", KT_PATTERN, OFF(fill_pattern), 0, 0, 0, "", NULL},
    {"skirts", KT_INT, OFF(skirts), 0, 100, 0, "", NULL},
    {"brim_width", KT_DOUBLE, OFF(brim_width), 0, 200, 0, "mm", NULL},
    {"support_material", KT_BOOL, OFF(support_material), 0, 0, 0, "", NULL},
    {"support_material_threshold", KT_INT, OFF(support_material_threshold), 0, 90, 0, "degrees",
     NULL},

    {"travel_speed", KT_DOUBLE, OFF(travel_speed), 0, 1000, KF_GT_MIN, "mm/s", "Speed"},
    {"perimeter_speed", KT_DOUBLE, OFF(perimeter_speed), 0, 1000, KF_GT_MIN, "mm/s", NULL},
    {"infill_speed", KT_DOUBLE, OFF(infill_speed), 0, 1000, KF_GT_MIN, "mm/s", NULL},
    {"first_layer_speed", KT_SPEED_PCT, OFF(first_layer_speed), 0, 1000, KF_GT_MIN, "mm/s", NULL},

    {"cooling", KT_FIRST_BOOL, OFF(cooling), 0, 0, 0, "", "Cooling"},
    {"min_fan_speed", KT_FIRST_INT, OFF(min_fan_speed), 0, 100, 0, "%", NULL},
    {"max_fan_speed", KT_FIRST_INT, OFF(max_fan_speed), 0, 100, 0, "%", NULL},
    {"bridge_fan_speed", KT_FIRST_INT, OFF(bridge_fan_speed), 0, 100, 0, "%", NULL},
    {"fan_below_layer_time", KT_FIRST_INT, OFF(fan_below_layer_time), 0, 3600, 0, "s", NULL},
    {"slowdown_below_layer_time", KT_FIRST_INT, OFF(slowdown_below_layer_time), 0, 3600, 0, "s",
     NULL},
    {"min_print_speed", KT_FIRST_DOUBLE, OFF(min_print_speed), 0, 1000, 0, "mm/s", NULL},

    {"machine_max_feedrate_x", KT_FIRST_DOUBLE, OFF(machine_max_feedrate[PROFILE_AXIS_X]), 0, 10000,
     KF_GT_MIN | KF_LIMITS, "mm/s", "Machine limits"},
    {"machine_max_feedrate_y", KT_FIRST_DOUBLE, OFF(machine_max_feedrate[PROFILE_AXIS_Y]), 0, 10000,
     KF_GT_MIN | KF_LIMITS, "mm/s", NULL},
    {"machine_max_feedrate_z", KT_FIRST_DOUBLE, OFF(machine_max_feedrate[PROFILE_AXIS_Z]), 0, 10000,
     KF_GT_MIN | KF_LIMITS, "mm/s", NULL},
    {"machine_max_feedrate_e", KT_FIRST_DOUBLE, OFF(machine_max_feedrate[PROFILE_AXIS_E]), 0, 10000,
     KF_GT_MIN | KF_LIMITS, "mm/s", NULL},
    {"machine_max_acceleration_x", KT_FIRST_DOUBLE, OFF(machine_max_acceleration[PROFILE_AXIS_X]),
     0, 100000, KF_GT_MIN | KF_LIMITS, "mm/s^2", NULL},
    {"machine_max_acceleration_y", KT_FIRST_DOUBLE, OFF(machine_max_acceleration[PROFILE_AXIS_Y]),
     0, 100000, KF_GT_MIN | KF_LIMITS, "mm/s^2", NULL},
    {"machine_max_acceleration_z", KT_FIRST_DOUBLE, OFF(machine_max_acceleration[PROFILE_AXIS_Z]),
     0, 100000, KF_GT_MIN | KF_LIMITS, "mm/s^2", NULL},
    {"machine_max_acceleration_e", KT_FIRST_DOUBLE, OFF(machine_max_acceleration[PROFILE_AXIS_E]),
     0, 100000, KF_GT_MIN | KF_LIMITS, "mm/s^2", NULL},
    {"machine_max_acceleration_extruding", KT_FIRST_DOUBLE, OFF(machine_max_acceleration_extruding),
     0, 100000, KF_LIMITS, "mm/s^2", NULL},
    {"machine_max_acceleration_retracting", KT_FIRST_DOUBLE,
     OFF(machine_max_acceleration_retracting), 0, 100000, KF_LIMITS, "mm/s^2", NULL},
    {"machine_max_acceleration_travel", KT_FIRST_DOUBLE, OFF(machine_max_acceleration_travel), 0,
     100000, KF_LIMITS, "mm/s^2", NULL},
    {"machine_max_jerk_x", KT_FIRST_DOUBLE, OFF(machine_max_jerk[PROFILE_AXIS_X]), 0, 1000,
     KF_LIMITS, "mm/s", NULL},
    {"machine_max_jerk_y", KT_FIRST_DOUBLE, OFF(machine_max_jerk[PROFILE_AXIS_Y]), 0, 1000,
     KF_LIMITS, "mm/s", NULL},
    {"machine_max_jerk_z", KT_FIRST_DOUBLE, OFF(machine_max_jerk[PROFILE_AXIS_Z]), 0, 1000,
     KF_LIMITS, "mm/s", NULL},
    {"machine_max_jerk_e", KT_FIRST_DOUBLE, OFF(machine_max_jerk[PROFILE_AXIS_E]), 0, 1000,
     KF_LIMITS, "mm/s", NULL},

    {"steps_per_mm_x", KT_DOUBLE, OFF(steps_per_mm[0]), 0, 100000, KF_SAILFISH, "steps/mm",
     "Sailfish machine (X3G)"},
    {"steps_per_mm_y", KT_DOUBLE, OFF(steps_per_mm[1]), 0, 100000, KF_SAILFISH, "steps/mm", NULL},
    {"steps_per_mm_z", KT_DOUBLE, OFF(steps_per_mm[2]), 0, 100000, KF_SAILFISH, "steps/mm", NULL},
    {"steps_per_mm_e", KT_EX_DOUBLE, OFF(steps_per_mm_e), 0, 100000, KF_SAILFISH, "steps/mm", NULL},
    {"home_direction_x", KT_HOME, OFF(home_direction[0]), 0, 0, KF_SAILFISH, "", NULL},
    {"home_direction_y", KT_HOME, OFF(home_direction[1]), 0, 0, KF_SAILFISH, "", NULL},
    {"home_direction_z", KT_HOME, OFF(home_direction[2]), 0, 0, KF_SAILFISH, "", NULL},
    {"home_feedrate_x", KT_DOUBLE, OFF(home_feedrate[0]), 0, 100000, KF_SAILFISH, "mm/min", NULL},
    {"home_feedrate_y", KT_DOUBLE, OFF(home_feedrate[1]), 0, 100000, KF_SAILFISH, "mm/min", NULL},
    {"home_feedrate_z", KT_DOUBLE, OFF(home_feedrate[2]), 0, 100000, KF_SAILFISH, "mm/min", NULL},
    {"home_position_x", KT_DOUBLE, OFF(home_position[0]), -10000, 10000, KF_SAILFISH, "mm", NULL},
    {"home_position_y", KT_DOUBLE, OFF(home_position[1]), -10000, 10000, KF_SAILFISH, "mm", NULL},
    {"home_position_z", KT_DOUBLE, OFF(home_position[2]), -10000, 10000, KF_SAILFISH, "mm", NULL},
    {"x3g_toolhead_offset_x", KT_DOUBLE, OFF(x3g_toolhead_offset[0]), -1000, 1000, KF_SAILFISH,
     "mm", NULL},
    {"x3g_toolhead_offset_y", KT_DOUBLE, OFF(x3g_toolhead_offset[1]), -1000, 1000, KF_SAILFISH,
     "mm", NULL},
    {"x3g_toolhead_offset_z", KT_DOUBLE, OFF(x3g_toolhead_offset[2]), -1000, 1000, KF_SAILFISH,
     "mm", NULL},

    {"start_gcode", KT_STRING, OFF(start_gcode), 0, 0, 0, "", "Custom G-code"},
    {"end_gcode", KT_STRING, OFF(end_gcode), 0, 0, 0, "", NULL},
};

#define KEY_DEFS (sizeof(key_defs) / sizeof(key_defs[0]))

static const char *const protocol_names[] = {"marlin", "sailfish"};

/* PrusaSlicer's gcode_flavor names (PrintConfig.cpp), in enum order. */
static const char *const flavor_names[] = {
    "reprap",  "reprapfirmware", "repetier", "teacup",	   "makerware", "marlin",	"marlin2",
    "klipper", "sailfish",	 "mach3",    "machinekit", "smoothie",	"no-extrusion",
};

/* PrusaSlicer's InfillPattern names (PrintConfig.cpp s_keys_map_InfillPattern). */
static const char *const pattern_names[] = {
    "rectilinear",
    "monotonic",
    "monotoniclines",
    "alignedrectilinear",
    "grid",
    "triangles",
    "stars",
    "cubic",
    "line",
    "concentric",
    "honeycomb",
    "3dhoneycomb",
    "gyroid",
    "hilbertcurve",
    "archimedeanchords",
    "octagramspiral",
    "adaptivecubic",
    "supportcubic",
    "lightning",
    "zigzag",
};

static const long baud_rates[] = {2400,	  4800,	  9600,	  19200,  38400,  57600,   115200,
				  230400, 250000, 460800, 500000, 921600, 1000000, 2000000};

#define COUNT(a) (sizeof(a) / sizeof((a)[0]))

/* Loading state: the profile being filled and where errors go. */
struct loader {
	struct profile *p;
	const char *origin;
	struct st_error *err;
	const struct profile_kv *ec_kv; /* what set extruder_count, NULL = default */
	const char *ec_key;
};

/* ---------------------------------------------------------------------------
 * Small helpers
 */

/* Duplicate len bytes as a NUL-terminated string, or NULL. */
static char *dup_n(const char *s, size_t len)
{
	char *d = malloc(len + 1);

	if (!d)
		return NULL;
	memcpy(d, s, len);
	d[len] = '\0';
	return d;
}

/* Locale-independent character classes. */
static bool is_digit(char c)
{
	return c >= '0' && c <= '9';
}

static bool is_blank(char c)
{
	return c == ' ' || c == '\t';
}

/* Value of a hex digit, or -1. */
static int hex_value(char c)
{
	if (c >= '0' && c <= '9')
		return c - '0';
	if (c >= 'a' && c <= 'f')
		return c - 'a' + 10;
	if (c >= 'A' && c <= 'F')
		return c - 'A' + 10;
	return -1;
}

/* Trim blanks from both ends of [*s, *s + *len). */
static void trim(const char **s, size_t *len)
{
	while (*len && is_blank(**s)) {
		(*s)++;
		(*len)--;
	}
	while (*len && is_blank((*s)[*len - 1]))
		(*len)--;
}

/* Copy at most TOKEN_SHOW bytes of a value for a message, marking a cut with "...". */
static void show_token(char *buf, size_t cap, const char *s, size_t len)
{
	size_t n = len < TOKEN_SHOW ? len : TOKEN_SHOW;
	size_t i, o = 0;

	for (i = 0; i < n && o + 1 < cap; i++)
		buf[o++] = (s[i] == '\n' || s[i] == '\r' || s[i] == '\0') ? ' ' : s[i];
	if (len > n)
		for (i = 0; i < 3 && o + 1 < cap; i++)
			buf[o++] = '.';
	buf[o] = '\0';
}

/* Shortest %g form of v that reads back exactly. */
static void fmt_double(char *buf, size_t cap, double v)
{
	snprintf(buf, cap, "%.15g", v);
	if (strtod(buf, NULL) != v)
		snprintf(buf, cap, "%.17g", v);
}

/* s[0..len) as a decimal number without exponent; false if it is not one. */
static bool parse_number(const char *s, size_t len, double *out)
{
	return st_parse_double(s, len, 0, out) == ST_NUMBER_OK;
}

/* [+-]digits, at most 18 digits, into *out. */
static bool parse_integer(const char *s, size_t len, long long *out)
{
	size_t i = 0;
	long long v = 0;
	bool neg = false;

	if (len && (s[0] == '+' || s[0] == '-')) {
		neg = s[0] == '-';
		i++;
	}
	if (i == len || len - i > 18)
		return false;
	for (; i < len; i++) {
		if (!is_digit(s[i]))
			return false;
		v = v * 10 + (s[i] - '0');
	}
	*out = neg ? -v : v;
	return true;
}

/* 0, 1, false, true. */
static bool parse_bool(const char *s, size_t len, bool *out)
{
	if ((len == 1 && s[0] == '1') || (len == 4 && !memcmp(s, "true", 4))) {
		*out = true;
		return true;
	}
	if ((len == 1 && s[0] == '0') || (len == 5 && !memcmp(s, "false", 5))) {
		*out = false;
		return true;
	}
	return false;
}

/* ---------------------------------------------------------------------------
 * Errors
 */

/*
 * Fill the error as "ORIGIN: line N: KEY: message" (line and key left out
 * when kv is NULL and key is NULL).  Returns code.
 */
static int key_error(struct loader *L, const struct profile_kv *kv, const char *key, int code,
		     const char *fmt, ...) __attribute__((format(printf, 5, 6)));

static int key_error(struct loader *L, const struct profile_kv *kv, const char *key, int code,
		     const char *fmt, ...)
{
	char msg[256];
	va_list ap;

	va_start(ap, fmt);
	vsnprintf(msg, sizeof(msg), fmt, ap);
	va_end(ap);
	if (kv)
		return st_error_set(L->err, code, "%s: line %d: %s: %s", L->origin, kv->line,
				    kv->key, msg);
	if (key)
		return st_error_set(L->err, code, "%s: %s: %s", L->origin, key, msg);
	return st_error_set(L->err, code, "%s: %s", L->origin, msg);
}

/* Describe the allowed range of d for a message. */
static void range_text(const struct key_def *d, char *buf, size_t cap)
{
	char lo[32], hi[32];

	fmt_double(lo, sizeof(lo), d->min);
	fmt_double(hi, sizeof(hi), d->max);
	if (d->flags & KF_GT_MIN)
		snprintf(buf, cap, "more than %s and at most %s%s%s", lo, hi, *d->unit ? " " : "",
			 d->unit);
	else
		snprintf(buf, cap, "between %s and %s%s%s", lo, hi, *d->unit ? " " : "", d->unit);
}

/* Is v inside d's range (minimum excluded with KF_GT_MIN)? */
static bool in_range(const struct key_def *d, double v)
{
	if (d->flags & KF_GT_MIN)
		return v > d->min && v <= d->max;
	return v >= d->min && v <= d->max;
}

/* ---------------------------------------------------------------------------
 * Pass 1: lines into key = value pairs
 */

/* Decode PrusaSlicer's C-style escapes: \n \r \\ \" ; any other \X is kept as is. */
static char *decode_value(const char *s, size_t len)
{
	char *d = malloc(len + 1);
	size_t i, o = 0;

	if (!d)
		return NULL;
	for (i = 0; i < len; i++) {
		if (s[i] == '\\' && i + 1 < len) {
			char c = s[i + 1];
			if (c == 'n' || c == 'r' || c == '\\' || c == '"') {
				d[o++] = c == 'n' ? '\n' : c == 'r' ? '\r' : c;
				i++;
				continue;
			}
		}
		d[o++] = s[i];
	}
	d[o] = '\0';
	return d;
}

/* The file's line for key, or NULL. */
static struct profile_kv *find_kv(const struct profile_keys *keys, const char *key)
{
	for (size_t i = 0; keys && i < keys->count; i++)
		if (!strcmp(keys->kv[i].key, key))
			return &keys->kv[i];
	return NULL;
}

/* Append one pair; takes ownership of key and value (frees them on failure). */
static int keys_add(struct profile_keys *keys, char *key, char *value, int line)
{
	if (keys->count == keys->cap) {
		size_t cap = keys->cap ? keys->cap * 2 : 64;
		struct profile_kv *kv;

		if (cap > SIZE_MAX / sizeof(*kv))
			goto out_free;
		kv = realloc(keys->kv, cap * sizeof(*kv));
		if (!kv)
			goto out_free;
		keys->kv = kv;
		keys->cap = cap;
	}
	keys->kv[keys->count].key = key;
	keys->kv[keys->count].value = value;
	keys->kv[keys->count].line = line;
	keys->count++;
	return 0;

out_free:
	free(key);
	free(value);
	return ST_ERR_NOMEM;
}

/* Check one line and add its key = value; blank and comment lines are skipped. */
static int parse_line(struct loader *L, const char *s, size_t len, int line)
{
	struct profile_keys *keys = L->p->keys;
	const char *eq, *key, *val;
	size_t klen, vlen, i;
	struct profile_kv *prev;
	char tok[TOKEN_SHOW + 4];
	char *k, *v;

	if (memchr(s, '\0', len))
		return st_error_set(L->err, ST_ERR_PARSE,
				    "%s: line %d: unexpected NUL byte (binary data in a text file)",
				    L->origin, line);
	trim(&s, &len);
	if (len == 0 || s[0] == '#' || s[0] == ';')
		return 0;
	if (s[0] == '[') {
		show_token(tok, sizeof(tok), s, len);
		return st_error_set(L->err, ST_ERR_PARSE,
				    "%s: line %d: sections such as '%s' are not supported; a "
				    "profile is one flat key = value file (PrusaSlicer: File > "
				    "Export > Export Config)",
				    L->origin, line, tok);
	}
	eq = memchr(s, '=', len);
	if (!eq) {
		show_token(tok, sizeof(tok), s, len);
		return st_error_set(L->err, ST_ERR_PARSE,
				    "%s: line %d: expected 'key = value', found '%s'", L->origin,
				    line, tok);
	}
	key = s;
	klen = (size_t)(eq - s);
	trim(&key, &klen);
	for (i = 0; i < klen; i++)
		if (!is_digit(key[i]) && !(key[i] >= 'a' && key[i] <= 'z') &&
		    !(key[i] >= 'A' && key[i] <= 'Z') && key[i] != '_')
			break;
	if (klen == 0 || i < klen) {
		show_token(tok, sizeof(tok), key, klen);
		return st_error_set(
		    L->err, ST_ERR_PARSE,
		    "%s: line %d: '%s' is not a valid key (letters, digits and '_')", L->origin,
		    line, tok);
	}
	val = eq + 1;
	vlen = (size_t)(s + len - val);
	trim(&val, &vlen);

	k = dup_n(key, klen);
	if (!k)
		return st_error_set(L->err, ST_ERR_NOMEM, "%s: line %d: out of memory", L->origin,
				    line);
	prev = find_kv(keys, k);
	if (prev) {
		int first = prev->line;
		free(k);
		return st_error_set(L->err, ST_ERR_PARSE,
				    "%s: line %d: duplicate key '%.*s' (first set on line %d)",
				    L->origin, line, (int)(klen > 64 ? 64 : klen), key, first);
	}
	v = decode_value(val, vlen);
	if (!v) {
		free(k);
		return st_error_set(L->err, ST_ERR_NOMEM, "%s: line %d: out of memory", L->origin,
				    line);
	}
	if (keys_add(keys, k, v, line))
		return st_error_set(L->err, ST_ERR_NOMEM, "%s: line %d: out of memory", L->origin,
				    line);
	return 0;
}

/* Split the buffer into lines (LF or CRLF), bounded, and parse each. */
static int parse_lines(struct loader *L, const char *text, size_t len)
{
	size_t pos = 0;
	int line = 0, rc;

	if (len >= 3 && !memcmp(text, "\xEF\xBB\xBF", 3))
		pos = 3; /* UTF-8 byte order mark */
	while (pos < len) {
		const char *start = text + pos;
		const char *nl = memchr(start, '\n', len - pos);
		size_t n = nl ? (size_t)(nl - start) : len - pos;

		line++;
		pos += n + (nl ? 1 : 0);
		if (n && start[n - 1] == '\r')
			n--;
		if (n > PROFILE_LINE_MAX)
			return st_error_set(L->err, ST_ERR_PARSE,
					    "%s: line %d is longer than %d bytes; the line is "
					    "rejected, not cut",
					    L->origin, line, PROFILE_LINE_MAX);
		rc = parse_line(L, start, n, line);
		if (rc)
			return rc;
	}
	return 0;
}

/* ---------------------------------------------------------------------------
 * Pass 2: typed values
 */

/* One comma-separated item of a list value. */
struct item {
	const char *s;
	size_t len;
};

/*
 * Split value on ',' into at most cap trimmed items.  Returns the count, or
 * ST_ERR_PARSE (error set) when there are more than cap or one is empty.
 */
static int split_list(struct loader *L, const struct profile_kv *kv, struct item *items, size_t cap)
{
	const char *s = kv->value;
	size_t n = 0;

	for (;;) {
		const char *comma = strchr(s, ',');
		size_t len = comma ? (size_t)(comma - s) : strlen(s);
		const char *t = s;

		trim(&t, &len);
		if (len == 0) {
			return key_error(L, kv, NULL, ST_ERR_PARSE, "%s",
					 n == 0 && !comma
					     ? "no value given"
					     : "empty value in the comma-separated list");
		}
		if (n == cap) {
			return key_error(L, kv, NULL, ST_ERR_PARSE,
					 "too many values in the list (at most %zu)", cap);
		}
		items[n].s = t;
		items[n].len = len;
		n++;
		if (!comma)
			break;
		s = comma + 1;
	}
	return (int)n;
}

/* Name the n-th item in a message when the list has more than one. */
static void item_where(char *buf, size_t cap, int i, int n)
{
	if (n > 1)
		snprintf(buf, cap, "value %d of %d, ", i + 1, n);
	else
		buf[0] = '\0';
}

/* Read a number item and check it against d's range. */
static int number_item(struct loader *L, const struct profile_kv *kv, const struct key_def *d,
		       const struct item *it, int i, int n, double *out)
{
	char tok[TOKEN_SHOW + 4], where[48], range[96];

	item_where(where, sizeof(where), i, n);
	if (!parse_number(it->s, it->len, out)) {
		show_token(tok, sizeof(tok), it->s, it->len);
		return key_error(L, kv, NULL, ST_ERR_PARSE,
				 "%s'%s' is not a number (write digits with an optional sign and "
				 "'.', e.g. 0.4)",
				 where, tok);
	}
	if (!in_range(d, *out)) {
		range_text(d, range, sizeof(range));
		show_token(tok, sizeof(tok), it->s, it->len);
		return key_error(L, kv, NULL, ST_ERR_RANGE, "%s%s is out of range (must be %s)",
				 where, tok, range);
	}
	return 0;
}

/* Read a whole-number item and check it against d's range. */
static int int_item(struct loader *L, const struct profile_kv *kv, const struct key_def *d,
		    const struct item *it, int i, int n, int *out)
{
	char tok[TOKEN_SHOW + 4], where[48], range[96];
	long long v;

	item_where(where, sizeof(where), i, n);
	if (!parse_integer(it->s, it->len, &v)) {
		show_token(tok, sizeof(tok), it->s, it->len);
		return key_error(L, kv, NULL, ST_ERR_PARSE, "%s'%s' is not a whole number", where,
				 tok);
	}
	if (!in_range(d, (double)v)) {
		range_text(d, range, sizeof(range));
		return key_error(L, kv, NULL, ST_ERR_RANGE, "%s%lld is out of range (must be %s)",
				 where, v, range);
	}
	*out = (int)v;
	return 0;
}

/* Read a bool item. */
static int bool_item(struct loader *L, const struct profile_kv *kv, const struct item *it, int i,
		     int n, bool *out)
{
	char tok[TOKEN_SHOW + 4], where[48];

	item_where(where, sizeof(where), i, n);
	if (!parse_bool(it->s, it->len, out)) {
		show_token(tok, sizeof(tok), it->s, it->len);
		return key_error(L, kv, NULL, ST_ERR_PARSE, "%sexpected 0 or 1, found '%s'", where,
				 tok);
	}
	return 0;
}

/* Read "XxY" into a point, both coordinates within d's range. */
static int point_item(struct loader *L, const struct profile_kv *kv, const struct key_def *d,
		      const struct item *it, int i, int n, struct profile_point *out)
{
	char tok[TOKEN_SHOW + 4], where[48], range[96];
	const char *x = memchr(it->s, 'x', it->len);
	struct item a, b;

	item_where(where, sizeof(where), i, n);
	show_token(tok, sizeof(tok), it->s, it->len);
	if (!x)
		return key_error(L, kv, NULL, ST_ERR_PARSE,
				 "%s'%s' is not a point XxY (e.g. 227x148)", where, tok);
	a.s = it->s;
	a.len = (size_t)(x - it->s);
	b.s = x + 1;
	b.len = it->len - a.len - 1;
	trim(&a.s, &a.len);
	trim(&b.s, &b.len);
	if (!parse_number(a.s, a.len, &out->x) || !parse_number(b.s, b.len, &out->y))
		return key_error(L, kv, NULL, ST_ERR_PARSE,
				 "%s'%s' is not a point XxY of two numbers (e.g. 227x148)", where,
				 tok);
	if (!in_range(d, out->x) || !in_range(d, out->y)) {
		range_text(d, range, sizeof(range));
		return key_error(L, kv, NULL, ST_ERR_RANGE,
				 "%spoint %s is out of range (coordinates must be %s)", where, tok,
				 range);
	}
	return 0;
}

/* Where the extruder count came from, for messages. */
static void ec_source(const struct loader *L, char *buf, size_t cap)
{
	if (L->ec_kv)
		snprintf(buf, cap, "%s on line %d", L->ec_key, L->ec_kv->line);
	else
		snprintf(buf, cap, "the default");
}

/*
 * A per-extruder list (or a list whose first value is used) must hold one
 * value or one per extruder.
 */
static int check_count(struct loader *L, const struct profile_kv *kv, const struct key_def *d,
		       int n)
{
	char src[96];
	int ec = L->p->extruder_count;

	if (d->flags & KF_LIMITS) {
		if (n > 2)
			return key_error(L, kv, NULL, ST_ERR_RANGE,
					 "has %d values; machine limits take 1 or 2 "
					 "(normal, stealth)",
					 n);
		return 0;
	}
	if (n == 1 || n == ec)
		return 0;
	ec_source(L, src, sizeof(src));
	return key_error(L, kv, NULL, ST_ERR_RANGE,
			 "has %d values but the printer has %d extruder%s (%s); give one value "
			 "for all or one per extruder",
			 n, ec, ec == 1 ? "" : "s", src);
}

/* Match s against a table of names; index or -1. */
static int name_index(const char *const *names, size_t count, const char *s)
{
	for (size_t i = 0; i < count; i++)
		if (!strcmp(names[i], s))
			return (int)i;
	return -1;
}

/* Join names with ", " for a message. */
static void join_names(char *buf, size_t cap, const char *const *names, size_t count)
{
	size_t o = 0;

	buf[0] = '\0';
	for (size_t i = 0; i < count && o < cap; i++) {
		int w = snprintf(buf + o, cap - o, "%s%s", i ? ", " : "", names[i]);
		if (w < 0)
			break;
		o += (size_t)w;
	}
}

/* usb_ids: a list of VVVV:PPPP, 4 hex digits each; empty = none. */
static int apply_usb(struct loader *L, const struct profile_kv *kv)
{
	struct item items[PROFILE_MAX_USB_IDS];
	struct profile *p = L->p;
	char tok[TOKEN_SHOW + 4];
	int n;

	p->usb_id_count = 0;
	if (kv->value[0] == '\0')
		return 0;
	n = split_list(L, kv, items, PROFILE_MAX_USB_IDS);
	if (n < 0)
		return n;
	for (int i = 0; i < n; i++) {
		const char *s = items[i].s;
		unsigned vid = 0, pid = 0;
		bool ok = items[i].len == 9 && s[4] == ':';

		for (int j = 0; ok && j < 9; j++) {
			int h = j == 4 ? 0 : hex_value(s[j]);
			if (h < 0)
				ok = false;
			else if (j < 4)
				vid = vid * 16 + (unsigned)h;
			else if (j > 4)
				pid = pid * 16 + (unsigned)h;
		}
		if (!ok) {
			show_token(tok, sizeof(tok), s, items[i].len);
			return key_error(L, kv, NULL, ST_ERR_PARSE,
					 "'%s' is not a USB id VVVV:PPPP (4 hex digits each, e.g. "
					 "2c99:0002)",
					 tok);
		}
		p->usb_ids[i].vid = (uint16_t)vid;
		p->usb_ids[i].pid = (uint16_t)pid;
	}
	p->usb_id_count = (size_t)n;
	return 0;
}

/* bed_shape: at least 3 points XxY enclosing some area. */
static int apply_bed(struct loader *L, const struct profile_kv *kv, const struct key_def *d)
{
	struct profile *p = L->p;
	struct item *items = NULL;
	struct profile_point *pts = NULL;
	double area = 0;
	int n, i, rc;

	items = calloc(PROFILE_MAX_BED_POINTS, sizeof(*items));
	if (!items)
		return key_error(L, kv, NULL, ST_ERR_NOMEM, "out of memory");
	n = split_list(L, kv, items, PROFILE_MAX_BED_POINTS);
	if (n < 0) {
		rc = n;
		goto out_free_items;
	}
	if (n < 3) {
		rc = key_error(L, kv, NULL, ST_ERR_PARSE,
			       "a bed polygon needs at least 3 points XxY, found %d (e.g. "
			       "0x0,227x0,227x148,0x148)",
			       n);
		goto out_free_items;
	}
	pts = calloc((size_t)n, sizeof(*pts));
	if (!pts) {
		rc = key_error(L, kv, NULL, ST_ERR_NOMEM, "out of memory");
		goto out_free_items;
	}
	for (i = 0; i < n; i++) {
		rc = point_item(L, kv, d, &items[i], i, n, &pts[i]);
		if (rc)
			goto out_free_pts;
	}
	for (i = 0; i < n; i++) {
		const struct profile_point *a = &pts[i], *b = &pts[(i + 1) % n];
		area += a->x * b->y - b->x * a->y;
	}
	if (fabs(area) / 2 < 1.0) {
		rc = key_error(L, kv, NULL, ST_ERR_RANGE,
			       "the bed polygon encloses no area (its points are on a line)");
		goto out_free_pts;
	}
	free(p->bed_shape);
	p->bed_shape = pts;
	p->bed_points = (size_t)n;
	free(items);
	return 0;

out_free_pts:
	free(pts);
out_free_items:
	free(items);
	return rc;
}

/* The sign-and-number part of "N%" or "N", with *pct telling which. */
static int pct_or_number(struct loader *L, const struct profile_kv *kv, double *v, bool *pct)
{
	const char *s = kv->value;
	size_t len = strlen(s);
	char tok[TOKEN_SHOW + 4];

	*pct = len && s[len - 1] == '%';
	if (*pct)
		len--;
	if (!parse_number(s, len, v)) {
		show_token(tok, sizeof(tok), kv->value, strlen(kv->value));
		return key_error(L, kv, NULL, ST_ERR_PARSE,
				 "'%s' is not a number or a percentage (e.g. 0.2 or 150%%)", tok);
	}
	return 0;
}

/* State pass 2 keeps for percentages resolved once layer_height is known. */
struct pending {
	bool flh_pct, width_pct;
	double flh, width;
};

/* Apply one known key that the file sets. */
static int apply_key(struct loader *L, const struct key_def *d, const struct profile_kv *kv,
		     struct pending *pend)
{
	struct profile *p = L->p;
	void *field = (char *)p + d->off;
	struct item items[PROFILE_MAX_EXTRUDERS];
	struct item one = {kv->value, strlen(kv->value)};
	char tok[TOKEN_SHOW + 4], names[256], range[96];
	int n, i, rc, idx;
	double v;
	bool pct;

	if (!*kv->value && d->type != KT_STRING && d->type != KT_USB)
		return key_error(L, kv, NULL, ST_ERR_PARSE,
				 "no value given (write one or remove the line)");
	switch (d->type) {
	case KT_STRING:
		*(const char **)field = kv->value;
		return 0;
	case KT_DOUBLE:
		trim(&one.s, &one.len);
		return number_item(L, kv, d, &one, 0, 1, (double *)field);
	case KT_INT:
	case KT_EXTRUDERS:
		trim(&one.s, &one.len);
		return int_item(L, kv, d, &one, 0, 1, (int *)field);
	case KT_BOOL:
		trim(&one.s, &one.len);
		return bool_item(L, kv, &one, 0, 1, (bool *)field);
	case KT_EX_DOUBLE:
	case KT_EX_INT:
	case KT_EX_POINT:
	case KT_FIRST_DOUBLE:
	case KT_FIRST_INT:
	case KT_FIRST_BOOL:
		n = split_list(L, kv, items, PROFILE_MAX_EXTRUDERS);
		if (n < 0)
			return n;
		for (i = 0; i < n; i++) {
			double dv;
			int iv;
			bool bv;
			struct profile_point pv;

			switch (d->type) {
			case KT_EX_DOUBLE:
			case KT_FIRST_DOUBLE:
				rc = number_item(L, kv, d, &items[i], i, n, &dv);
				if (rc)
					return rc;
				if (d->type == KT_FIRST_DOUBLE) {
					if (i == 0)
						*(double *)field = dv;
				} else {
					((double *)field)[i] = dv;
				}
				break;
			case KT_EX_INT:
			case KT_FIRST_INT:
				rc = int_item(L, kv, d, &items[i], i, n, &iv);
				if (rc)
					return rc;
				if (d->type == KT_FIRST_INT) {
					if (i == 0)
						*(int *)field = iv;
				} else {
					((int *)field)[i] = iv;
				}
				break;
			case KT_EX_POINT:
				rc = point_item(L, kv, d, &items[i], i, n, &pv);
				if (rc)
					return rc;
				((struct profile_point *)field)[i] = pv;
				break;
			default: /* KT_FIRST_BOOL */
				rc = bool_item(L, kv, &items[i], i, n, &bv);
				if (rc)
					return rc;
				if (i == 0)
					*(bool *)field = bv;
				break;
			}
		}
		rc = check_count(L, kv, d, n);
		if (rc)
			return rc;
		/* One value applies to every extruder. */
		for (i = n; n == 1 && i < p->extruder_count; i++) {
			if (d->type == KT_EX_DOUBLE)
				((double *)field)[i] = ((double *)field)[0];
			else if (d->type == KT_EX_INT)
				((int *)field)[i] = ((int *)field)[0];
			else if (d->type == KT_EX_POINT)
				((struct profile_point *)field)[i] =
				    ((struct profile_point *)field)[0];
		}
		return 0;
	case KT_FIRST_HEIGHT:
	case KT_WIDTH:
	case KT_SPEED_PCT:
		rc = pct_or_number(L, kv, &v, &pct);
		if (rc)
			return rc;
		if (pct) {
			if (!(v >= 0 && v <= 1000) || (v == 0 && d->type != KT_WIDTH))
				return key_error(
				    L, kv, NULL, ST_ERR_RANGE,
				    "%s is out of range (a percentage must be %s)", kv->value,
				    d->type == KT_WIDTH ? "between 0% and 1000%"
							: "more than 0% and at most 1000%");
		} else if (!in_range(d, v)) {
			range_text(d, range, sizeof(range));
			return key_error(L, kv, NULL, ST_ERR_RANGE,
					 "%s is out of range (must be %s, or a percentage)",
					 kv->value, range);
		}
		if (d->type == KT_FIRST_HEIGHT) {
			pend->flh_pct = pct;
			pend->flh = v;
		} else if (d->type == KT_WIDTH) {
			pend->width_pct = pct;
			pend->width = v;
		} else {
			p->first_layer_speed = v;
			p->first_layer_speed_is_percent = pct;
		}
		return 0;
	case KT_DENSITY:
		rc = pct_or_number(L, kv, &v, &pct);
		if (rc)
			return rc;
		if (!pct)
			v *= 100; /* a bare number is a fraction, as in Slic3r */
		if (!(v >= 0 && v <= 100))
			return key_error(L, kv, NULL, ST_ERR_RANGE,
					 "%s is out of range (must be 0%% to 100%%, or a fraction "
					 "0 to 1)",
					 kv->value);
		p->fill_density = v;
		return 0;
	case KT_PROTOCOL:
		idx = name_index(protocol_names, COUNT(protocol_names), kv->value);
		if (idx < 0) {
			show_token(tok, sizeof(tok), kv->value, strlen(kv->value));
			return key_error(L, kv, NULL, ST_ERR_PARSE,
					 "expected marlin or sailfish, found '%s'", tok);
		}
		p->protocol = (enum profile_protocol)idx;
		return 0;
	case KT_FLAVOR:
		idx = name_index(flavor_names, COUNT(flavor_names), kv->value);
		if (idx < 0 && !strcmp(kv->value, "marlinfirmware"))
			idx = PROFILE_FLAVOR_MARLIN2; /* PrusaSlicer 2.4 alpha's name */
		if (idx < 0) {
			show_token(tok, sizeof(tok), kv->value, strlen(kv->value));
			join_names(names, sizeof(names), flavor_names, COUNT(flavor_names));
			return key_error(L, kv, NULL, ST_ERR_PARSE, "'%s' is not one of %s", tok,
					 names);
		}
		p->gcode_flavor = (enum profile_flavor)idx;
		return 0;
	case KT_PATTERN:
		idx = name_index(pattern_names, COUNT(pattern_names), kv->value);
		if (idx < 0 && !strcmp(kv->value, "monotonous"))
			idx = 1; /* PrusaSlicer's old name of monotonic */
		if (idx < 0) {
			show_token(tok, sizeof(tok), kv->value, strlen(kv->value));
			join_names(names, sizeof(names), pattern_names, COUNT(pattern_names));
			return key_error(L, kv, NULL, ST_ERR_PARSE, "'%s' is not one of %s", tok,
					 names);
		}
		p->fill_pattern = pattern_names[idx];
		return 0;
	case KT_HOME:
		if (!strcmp(kv->value, "min") || !strcmp(kv->value, "max")) {
			*(enum profile_home *)field =
			    kv->value[1] == 'i' ? PROFILE_HOME_MIN : PROFILE_HOME_MAX;
			return 0;
		}
		show_token(tok, sizeof(tok), kv->value, strlen(kv->value));
		return key_error(L, kv, NULL, ST_ERR_PARSE, "expected min or max, found '%s'", tok);
	case KT_BAUD: {
		long long b;

		if (!parse_integer(kv->value, strlen(kv->value), &b)) {
			show_token(tok, sizeof(tok), kv->value, strlen(kv->value));
			return key_error(L, kv, NULL, ST_ERR_PARSE, "'%s' is not a whole number",
					 tok);
		}
		for (size_t k = 0; k < COUNT(baud_rates); k++)
			if (baud_rates[k] == b) {
				p->baudrate = (long)b;
				return 0;
			}
		return key_error(L, kv, NULL, ST_ERR_RANGE,
				 "%lld is not a standard baud rate (use 9600, 19200, 38400, 57600, "
				 "115200, 230400, 250000, 460800, 500000, 921600 or 1000000)",
				 b);
	}
	case KT_USB:
		return apply_usb(L, kv);
	case KT_BED:
		return apply_bed(L, kv, d);
	}
	return key_error(L, kv, NULL, ST_ERR_INTERNAL, "no parser for this key");
}

/* ---------------------------------------------------------------------------
 * Defaults and cross-checks
 */

/* Fill every field with its documented default (protocol-specific ones later). */
static int set_defaults(struct profile *p)
{
	static const struct profile_point bed[4] = {{0, 0}, {200, 0}, {200, 200}, {0, 200}};
	static const double feed[PROFILE_AXES] = {500, 500, 12, 120};
	static const double accel[PROFILE_AXES] = {9000, 9000, 500, 10000};
	static const double jerk[PROFILE_AXES] = {10, 10, 0.2, 2.5};

	p->name = p->id;
	p->description = "";
	p->printer_model = "";
	p->protocol = PROFILE_PROTOCOL_MARLIN;
	p->baudrate = 115200;
	p->rx_buffer_size = 128;
	p->dtr_reset = true;
	p->x3g_buffer_size = 0;
	p->gcode_flavor = PROFILE_FLAVOR_MARLIN2;
	p->bed_shape = malloc(sizeof(bed));
	if (!p->bed_shape)
		return ST_ERR_NOMEM;
	memcpy(p->bed_shape, bed, sizeof(bed));
	p->bed_points = 4;
	p->max_print_height = 200;
	p->use_relative_e_distances = false;
	p->extruder_count = 1;
	for (int i = 0; i < PROFILE_MAX_EXTRUDERS; i++) {
		p->nozzle_diameter[i] = 0.4;
		p->filament_diameter[i] = 1.75;
		p->extrusion_multiplier[i] = 1;
		p->extruder_offset[i].x = p->extruder_offset[i].y = 0;
		p->temperature[i] = 200;
		p->first_layer_temperature[i] = 200;
		p->retract_length[i] = 2;
		p->retract_speed[i] = 40;
		p->retract_lift[i] = 0;
		p->min_layer_height[i] = 0.07;
		p->max_layer_height[i] = 0;
		p->steps_per_mm_e[i] = 0;
	}
	p->bed_temperature = 0;
	p->first_layer_bed_temperature = 0;
	p->layer_height = 0.2;
	p->first_layer_height = 0.2;
	p->extrusion_width = 0;
	p->perimeters = 3;
	p->top_solid_layers = 3;
	p->bottom_solid_layers = 3;
	p->fill_density = 20;
	/* the slicer's own default (infill_settings_init, slicer/infill.c): one
	 * it prints; PrusaSlicer's "stars" is refused (docs/printers.md) */
	p->fill_pattern = "grid";
	p->skirts = 1;
	p->brim_width = 0;
	p->support_material = false;
	p->support_material_threshold = 0;
	p->travel_speed = 130;
	p->perimeter_speed = 60;
	p->infill_speed = 80;
	p->first_layer_speed = 30;
	p->first_layer_speed_is_percent = false;
	p->cooling = true;
	p->min_fan_speed = 35;
	p->max_fan_speed = 100;
	p->bridge_fan_speed = 100;
	p->fan_below_layer_time = 60;
	p->slowdown_below_layer_time = 5;
	p->min_print_speed = 10;
	for (int a = 0; a < PROFILE_AXES; a++) {
		p->machine_max_feedrate[a] = feed[a];
		p->machine_max_acceleration[a] = accel[a];
		p->machine_max_jerk[a] = jerk[a];
	}
	p->machine_max_acceleration_extruding = 1500;
	p->machine_max_acceleration_retracting = 1500;
	p->machine_max_acceleration_travel = 1500;
	for (int a = 0; a < 3; a++) {
		p->steps_per_mm[a] = 0;
		p->home_direction[a] = PROFILE_HOME_MIN;
		p->home_feedrate[a] = 0;
		p->home_position[a] = 0;
		p->x3g_toolhead_offset[a] = 0;
	}
	/* PrusaSlicer's own defaults (PrintConfig.cpp). */
	p->start_gcode = "G28 ; home all axes\nG1 Z5 F5000 ; lift nozzle\n";
	p->end_gcode = "M104 S0 ; turn off temperature\nG28 X0  ; home X axis\nM84     ; disable "
		       "motors\n";
	return 0;
}

/*
 * Defaults of a sailfish printer: the Replicator 1 machine of GPX
 * (markwal/GPX src/shared/std_machines.h, replicator_1), the family the
 * FlashForge Creator Pro belongs to.
 */
static void set_sailfish_defaults(struct profile *p)
{
	p->gcode_flavor = PROFILE_FLAVOR_SAILFISH;
	p->steps_per_mm[0] = 94.117647;
	p->steps_per_mm[1] = 94.117647;
	p->steps_per_mm[2] = 400;
	for (int i = 0; i < PROFILE_MAX_EXTRUDERS; i++)
		p->steps_per_mm_e[i] = 96.275201870333662;
	p->home_direction[0] = PROFILE_HOME_MAX;
	p->home_direction[1] = PROFILE_HOME_MAX;
	p->home_direction[2] = PROFILE_HOME_MIN;
	p->home_feedrate[0] = 2500;
	p->home_feedrate[1] = 2500;
	p->home_feedrate[2] = 1100;
	/* No G-code is safe on every Sailfish machine: the profile must give it. */
	p->start_gcode = "";
	p->end_gcode = "";
}

/* The table entry of a known key, or NULL. */
static const struct key_def *find_def(const char *key)
{
	for (size_t i = 0; i < KEY_DEFS; i++)
		if (!strcmp(key_defs[i].key, key))
			return &key_defs[i];
	return NULL;
}

/* Where a value came from, for cross-check messages: " (line N)" or " (default)". */
static void origin_of(const struct profile *p, const char *key, char *buf, size_t cap)
{
	const struct profile_kv *kv = find_kv(p->keys, key);

	if (kv)
		snprintf(buf, cap, " (line %d)", kv->line);
	else
		snprintf(buf, cap, " (default)");
}

/* Report a conflict between two keys at the first key's line, or the second's. */
static int conflict(struct loader *L, const char *key, const char *other, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

static int conflict(struct loader *L, const char *key, const char *other, const char *fmt, ...)
{
	const struct profile_kv *kv = find_kv(L->p->keys, key);
	char msg[200];
	va_list ap;

	va_start(ap, fmt);
	vsnprintf(msg, sizeof(msg), fmt, ap);
	va_end(ap);
	if (!kv && other) {
		const struct profile_kv *okv = find_kv(L->p->keys, other);
		if (okv)
			return key_error(L, okv, NULL, ST_ERR_RANGE, "%s", msg);
	}
	return kv ? key_error(L, kv, NULL, ST_ERR_RANGE, "%s", msg)
		  : key_error(L, NULL, key, ST_ERR_RANGE, "%s", msg);
}

/* Checks between keys, once every value is read. */
static int cross_check(struct loader *L, const struct pending *pend)
{
	struct profile *p = L->p;
	char a[32], b[32], o1[32], o2[32];
	double min_nozzle = p->nozzle_diameter[0];
	int ec = p->extruder_count;

	for (int i = 1; i < ec; i++)
		if (p->nozzle_diameter[i] < min_nozzle)
			min_nozzle = p->nozzle_diameter[i];

	if (pend->flh_pct)
		p->first_layer_height = pend->flh / 100 * p->layer_height;
	if (pend->width_pct)
		p->extrusion_width = pend->width / 100 * p->layer_height;
	else if (find_kv(p->keys, "extrusion_width"))
		p->extrusion_width = pend->width;
	if (!pend->flh_pct && find_kv(p->keys, "first_layer_height"))
		p->first_layer_height = pend->flh;

	fmt_double(b, sizeof(b), min_nozzle);
	origin_of(p, "nozzle_diameter", o2, sizeof(o2));
	if (p->layer_height > min_nozzle) {
		fmt_double(a, sizeof(a), p->layer_height);
		origin_of(p, "layer_height", o1, sizeof(o1));
		return conflict(L, "layer_height", "nozzle_diameter",
				"layer_height %s mm%s is larger than the nozzle, %s mm%s", a, o1, b,
				o2);
	}
	if (!(p->first_layer_height > 0) || p->first_layer_height > min_nozzle) {
		fmt_double(a, sizeof(a), p->first_layer_height);
		origin_of(p, "first_layer_height", o1, sizeof(o1));
		return conflict(L, "first_layer_height", "nozzle_diameter",
				"first_layer_height %s mm%s must be more than 0 and at most the "
				"nozzle, %s mm%s",
				a, o1, b, o2);
	}
	for (int i = 0; i < ec; i++) {
		double nz = p->nozzle_diameter[i];

		if (p->max_layer_height[i] == 0)
			p->max_layer_height[i] = 0.75 * nz; /* PrusaSlicer's meaning of 0 */
		fmt_double(b, sizeof(b), nz);
		if (p->min_layer_height[i] > nz || p->max_layer_height[i] > nz) {
			bool lo = p->min_layer_height[i] > nz;
			fmt_double(a, sizeof(a),
				   lo ? p->min_layer_height[i] : p->max_layer_height[i]);
			return conflict(
			    L, lo ? "min_layer_height" : "max_layer_height", "nozzle_diameter",
			    "extruder %d: %s mm is larger than its nozzle, %s mm", i + 1, a, b);
		}
		if (p->min_layer_height[i] > p->max_layer_height[i]) {
			fmt_double(a, sizeof(a), p->min_layer_height[i]);
			fmt_double(b, sizeof(b), p->max_layer_height[i]);
			return conflict(L, "min_layer_height", "max_layer_height",
					"extruder %d: min_layer_height %s mm is larger than "
					"max_layer_height %s mm",
					i + 1, a, b);
		}
	}
	if (p->protocol == PROFILE_PROTOCOL_SAILFISH) {
		if (p->gcode_flavor != PROFILE_FLAVOR_SAILFISH &&
		    p->gcode_flavor != PROFILE_FLAVOR_MAKERWARE)
			return conflict(L, "gcode_flavor", "protocol",
					"gcode_flavor %s does not fit protocol sailfish (use "
					"sailfish or makerware)",
					flavor_names[p->gcode_flavor]);
		if (ec > 2)
			return conflict(L, "extruder_count", "nozzle_diameter",
					"a sailfish printer drives at most 2 extruders (A and B), "
					"not %d",
					ec);
		for (int a3 = 0; a3 < 3; a3++)
			if (!(p->steps_per_mm[a3] > 0)) {
				char key[32];
				snprintf(key, sizeof(key), "steps_per_mm_%c", "xyz"[a3]);
				return conflict(L, key, NULL,
						"a sailfish printer needs steps per mm for X3G; "
						"set it above 0");
			}
		for (int i = 0; i < ec; i++)
			if (!(p->steps_per_mm_e[i] > 0))
				return conflict(L, "steps_per_mm_e", NULL,
						"a sailfish printer needs steps per mm for X3G; "
						"set it above 0");
	} else if (p->gcode_flavor == PROFILE_FLAVOR_SAILFISH ||
		   p->gcode_flavor == PROFILE_FLAVOR_MAKERWARE) {
		return conflict(L, "gcode_flavor", "protocol",
				"gcode_flavor %s needs protocol = sailfish (X3G), not marlin",
				flavor_names[p->gcode_flavor]);
	}
	return 0;
}

/* Bounding box of the bed polygon. */
static void bed_box(struct profile *p)
{
	p->bed_min_x = p->bed_max_x = p->bed_shape[0].x;
	p->bed_min_y = p->bed_max_y = p->bed_shape[0].y;
	for (size_t i = 1; i < p->bed_points; i++) {
		p->bed_min_x = fmin(p->bed_min_x, p->bed_shape[i].x);
		p->bed_max_x = fmax(p->bed_max_x, p->bed_shape[i].x);
		p->bed_min_y = fmin(p->bed_min_y, p->bed_shape[i].y);
		p->bed_max_y = fmax(p->bed_max_y, p->bed_shape[i].y);
	}
}

/* Extruder count: extruder_count, else the length of nozzle_diameter, else 1. */
static int resolve_extruders(struct loader *L, struct pending *pend)
{
	struct profile *p = L->p;
	const struct profile_kv *kv = find_kv(p->keys, "extruder_count");
	struct item items[PROFILE_MAX_EXTRUDERS];
	int n;

	if (kv) {
		L->ec_kv = kv;
		L->ec_key = "extruder_count";
		return apply_key(L, find_def("extruder_count"), kv, pend);
	}
	kv = find_kv(p->keys, "nozzle_diameter");
	if (!kv)
		return 0;
	n = split_list(L, kv, items, PROFILE_MAX_EXTRUDERS);
	if (n < 0)
		return n;
	p->extruder_count = n;
	L->ec_kv = kv;
	L->ec_key = "nozzle_diameter";
	return 0;
}

/* Protocol and flavor, each defaulting from the other. */
static int resolve_protocol(struct loader *L, struct pending *pend)
{
	struct profile *p = L->p;
	const struct profile_kv *proto = find_kv(p->keys, "protocol");
	const struct profile_kv *flavor = find_kv(p->keys, "gcode_flavor");
	int rc;

	if (flavor) {
		rc = apply_key(L, find_def("gcode_flavor"), flavor, pend);
		if (rc)
			return rc;
	}
	if (proto) {
		rc = apply_key(L, find_def("protocol"), proto, pend);
		if (rc)
			return rc;
	} else if (flavor && (p->gcode_flavor == PROFILE_FLAVOR_SAILFISH ||
			      p->gcode_flavor == PROFILE_FLAVOR_MAKERWARE)) {
		p->protocol = PROFILE_PROTOCOL_SAILFISH;
	}
	if (p->protocol == PROFILE_PROTOCOL_SAILFISH) {
		enum profile_flavor f = p->gcode_flavor;
		set_sailfish_defaults(p);
		if (flavor)
			p->gcode_flavor = f;
	}
	return 0;
}

/* Pass 2: type every known key, derive defaults that follow other keys, check. */
static int apply_all(struct loader *L)
{
	struct profile *p = L->p;
	struct pending pend = {false, false, p->first_layer_height, 0};
	int rc;

	rc = resolve_extruders(L, &pend);
	if (rc)
		return rc;
	rc = resolve_protocol(L, &pend);
	if (rc)
		return rc;
	for (size_t i = 0; i < KEY_DEFS; i++) {
		const struct key_def *d = &key_defs[i];
		const struct profile_kv *kv;

		if (d->type == KT_EXTRUDERS || d->type == KT_PROTOCOL || d->type == KT_FLAVOR)
			continue;
		kv = find_kv(p->keys, d->key);
		if (!kv)
			continue;
		rc = apply_key(L, d, kv, &pend);
		if (rc)
			return rc;
	}
	if (!find_kv(p->keys, "first_layer_temperature"))
		memcpy(p->first_layer_temperature, p->temperature, sizeof(p->temperature));
	if (!find_kv(p->keys, "first_layer_bed_temperature"))
		p->first_layer_bed_temperature = p->bed_temperature;
	bed_box(p);
	return cross_check(L, &pend);
}

/* ---------------------------------------------------------------------------
 * Loading
 */

/* The id: base name of origin without a trailing ".ini". */
static char *id_of(const char *origin)
{
	const char *base = strrchr(origin, '/');
	size_t len;

	base = base ? base + 1 : origin;
	len = strlen(base);
	if (len > 4 && !strcmp(base + len - 4, ".ini"))
		len -= 4;
	return dup_n(base, len);
}

void profile_free(struct profile *p)
{
	if (!p)
		return;
	if (p->keys) {
		for (size_t i = 0; i < p->keys->count; i++) {
			free(p->keys->kv[i].key);
			free(p->keys->kv[i].value);
		}
		free(p->keys->kv);
		free(p->keys);
	}
	free(p->bed_shape);
	free((char *)p->id);
	free((char *)p->path);
	free(p);
}

int profile_load_buffer(const char *text, size_t len, const char *origin, struct profile **out,
			struct st_error *err)
{
	struct loader L = {0};
	struct profile *p;
	int rc;

	if (!out || (!text && len) || !origin)
		return st_error_set(err, ST_ERR_ARG, "profile_load_buffer: bad arguments");
	*out = NULL;
	p = calloc(1, sizeof(*p));
	if (!p)
		return st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", origin);
	p->keys = calloc(1, sizeof(*p->keys));
	p->id = id_of(origin);
	p->path = dup_n(origin, strlen(origin));
	if (!p->keys || !p->id || !p->path || set_defaults(p)) {
		rc = st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", origin);
		goto out_free;
	}
	L.p = p;
	L.origin = origin;
	L.err = err;
	rc = parse_lines(&L, text, len);
	if (rc)
		goto out_free;
	rc = apply_all(&L);
	if (rc)
		goto out_free;
	*out = p;
	return 0;

out_free:
	profile_free(p);
	return rc;
}

int profile_load_file(const char *path, struct profile **out, struct st_error *err)
{
	struct stat st;
	FILE *f;
	char *buf = NULL;
	size_t len = 0, cap = 0;
	int rc;

	if (!out || !path)
		return st_error_set(err, ST_ERR_ARG, "profile_load_file: bad arguments");
	*out = NULL;
	if (stat(path, &st) == 0 && S_ISDIR(st.st_mode))
		return st_error_set(err, ST_ERR_IO, "%s: is a directory, not a printer profile",
				    path);
	f = fopen(path, "rb");
	if (!f)
		return st_error_set(err, ST_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
	for (;;) {
		size_t got;

		if (len == cap) {
			size_t ncap = cap ? cap * 2 : 16384;
			char *nbuf;

			if (cap >= FILE_MAX + 1) {
				rc = st_error_set(err, ST_ERR_PARSE,
						  "%s: larger than %u MiB; a printer profile is a "
						  "few kilobytes of text",
						  path, FILE_MAX >> 20);
				goto out_close;
			}
			if (ncap > FILE_MAX + 1)
				ncap = FILE_MAX + 1;
			nbuf = realloc(buf, ncap);
			if (!nbuf) {
				rc = st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", path);
				goto out_close;
			}
			buf = nbuf;
			cap = ncap;
		}
		got = fread(buf + len, 1, cap - len, f);
		len += got;
		if (got == 0) {
			if (ferror(f)) {
				rc = st_error_set(err, ST_ERR_IO, "%s: read error: %s", path,
						  strerror(errno));
				goto out_close;
			}
			break;
		}
		if (len > FILE_MAX) {
			rc = st_error_set(err, ST_ERR_PARSE,
					  "%s: larger than %u MiB; a printer profile is a few "
					  "kilobytes of text",
					  path, FILE_MAX >> 20);
			goto out_close;
		}
	}
	fclose(f);
	rc = profile_load_buffer(buf, len, path, out, err);
	free(buf);
	return rc;

out_close:
	fclose(f);
	free(buf);
	return rc;
}

/* ---------------------------------------------------------------------------
 * Finding profiles
 */

/* Add dir to dirs unless it is empty, too long or already there. */
static void dirs_add(struct profile_dirs *dirs, const char *dir)
{
	if (!dir || !*dir || strlen(dir) >= PROFILE_PATH_MAX || dirs->count == PROFILE_MAX_DIRS)
		return;
	for (size_t i = 0; i < dirs->count; i++)
		if (!strcmp(dirs->path[i], dir))
			return;
	strcpy(dirs->path[dirs->count++], dir);
}

void profile_search_dirs(struct profile_dirs *dirs)
{
	char exe[PROFILE_PATH_MAX], cand[PROFILE_PATH_MAX + 32], real[PATH_MAX];
	ssize_t n;

	dirs->count = 0;
	dirs_add(dirs, getenv("STRATUM_PRINTERS_DIR"));
	n = readlink("/proc/self/exe", exe, sizeof(exe) - 1);
	if (n > 0) {
		char *slash;

		exe[n] = '\0';
		slash = strrchr(exe, '/');
		if (slash) {
			*slash = '\0'; /* the executable's directory */
			/* <exe dir>/../printers, else <exe dir>/../../printers */
			for (int up = 1; up <= 2; up++) {
				snprintf(cand, sizeof(cand), "%s/%s", exe,
					 up == 1 ? "../printers" : "../../printers");
				if (realpath(cand, real)) {
					struct stat st;
					if (stat(real, &st) == 0 && S_ISDIR(st.st_mode)) {
						dirs_add(dirs, real);
						break;
					}
				}
			}
		}
	}
	dirs_add(dirs, STRATUM_DATADIR);
}

/* A NAME is letters, digits, '.', '_', '-', not starting with '.'. */
static bool valid_name(const char *s)
{
	if (!*s || *s == '.')
		return false;
	for (; *s; s++)
		if (!is_digit(*s) && !(*s >= 'a' && *s <= 'z') && !(*s >= 'A' && *s <= 'Z') &&
		    *s != '.' && *s != '_' && *s != '-')
			return false;
	return true;
}

/* Does path name an existing regular file? */
static bool is_regular_file(const char *path)
{
	struct stat st;

	return stat(path, &st) == 0 && S_ISREG(st.st_mode);
}

int profile_find(const char *name_or_path, struct profile **out, struct st_error *err)
{
	struct profile_dirs dirs;
	char path[PROFILE_PATH_MAX + 300], looked[200];
	size_t len, o = 0;

	if (!out)
		return st_error_set(err, ST_ERR_ARG, "profile_find: bad arguments");
	*out = NULL;
	if (!name_or_path || !*name_or_path)
		return st_error_set(err, ST_ERR_ARG,
				    "no printer given; name a profile ('stratum printers' lists "
				    "them) or a .ini file");
	len = strlen(name_or_path);
	if (strchr(name_or_path, '/') || (len >= 4 && !strcmp(name_or_path + len - 4, ".ini")))
		return profile_load_file(name_or_path, out, err);
	if (!valid_name(name_or_path))
		return st_error_set(err, ST_ERR_ARG,
				    "'%.64s' is not a printer name (letters, digits, '.', '_' and "
				    "'-'); give a file as a path ending in .ini",
				    name_or_path);
	profile_search_dirs(&dirs);
	for (size_t i = 0; i < dirs.count; i++) {
		snprintf(path, sizeof(path), "%s/%s.ini", dirs.path[i], name_or_path);
		if (is_regular_file(path))
			return profile_load_file(path, out, err);
	}
	looked[0] = '\0';
	for (size_t i = 0; i < dirs.count && o < sizeof(looked); i++) {
		int w =
		    snprintf(looked + o, sizeof(looked) - o, "%s%s", i ? ", " : "", dirs.path[i]);
		if (w < 0)
			break;
		o += (size_t)w;
	}
	return st_error_set(err, ST_ERR_ARG,
			    "no printer profile named '%.64s' (looked in %s); 'stratum printers' "
			    "lists them",
			    name_or_path, looked);
}

/* qsort order of profile_list: by id. */
static int entry_cmp(const void *a, const void *b)
{
	return strcmp(((const struct profile_entry *)a)->id, ((const struct profile_entry *)b)->id);
}

void profile_list_free(struct profile_entry *list, size_t count)
{
	if (!list)
		return;
	for (size_t i = 0; i < count; i++) {
		free(list[i].id);
		free(list[i].path);
	}
	free(list);
}

int profile_list(struct profile_entry **out, size_t *count, struct st_error *err)
{
	struct profile_dirs dirs;
	struct profile_entry *list = NULL;
	size_t n = 0, cap = 0;

	if (!out || !count)
		return st_error_set(err, ST_ERR_ARG, "profile_list: bad arguments");
	*out = NULL;
	*count = 0;
	profile_search_dirs(&dirs);
	for (size_t d = 0; d < dirs.count; d++) {
		DIR *dir = opendir(dirs.path[d]);
		struct dirent *de;

		if (!dir)
			continue;
		while ((de = readdir(dir))) {
			size_t len = strlen(de->d_name);
			char path[PROFILE_PATH_MAX + 300];
			char *id;
			bool seen = false;

			if (len <= 4 || strcmp(de->d_name + len - 4, ".ini"))
				continue;
			id = dup_n(de->d_name, len - 4);
			if (!id)
				goto out_nomem;
			for (size_t k = 0; k < n && !seen; k++)
				seen = !strcmp(list[k].id, id);
			snprintf(path, sizeof(path), "%s/%s", dirs.path[d], de->d_name);
			if (seen || !valid_name(id) || !is_regular_file(path)) {
				free(id);
				continue;
			}
			if (n == cap) {
				size_t ncap = cap ? cap * 2 : 16;
				struct profile_entry *nl;

				if (ncap > SIZE_MAX / sizeof(*nl))
					nl = NULL;
				else
					nl = realloc(list, ncap * sizeof(*nl));
				if (!nl) {
					free(id);
					closedir(dir);
					goto out_nomem;
				}
				list = nl;
				cap = ncap;
			}
			list[n].id = id;
			list[n].path = dup_n(path, strlen(path));
			n++;
			if (!list[n - 1].path) {
				closedir(dir);
				goto out_nomem;
			}
		}
		closedir(dir);
	}
	if (n)
		qsort(list, n, sizeof(*list), entry_cmp);
	*out = list;
	*count = n;
	return 0;

out_nomem:
	profile_list_free(list, n);
	return st_error_set(err, ST_ERR_NOMEM, "out of memory listing printer profiles");
}

/* ---------------------------------------------------------------------------
 * Raw access
 */

const char *profile_get(const struct profile *p, const char *key)
{
	const struct profile_kv *kv = p && key ? find_kv(p->keys, key) : NULL;

	return kv ? kv->value : NULL;
}

int profile_key_line(const struct profile *p, const char *key)
{
	const struct profile_kv *kv = p && key ? find_kv(p->keys, key) : NULL;

	return kv ? kv->line : 0;
}

int profile_get_number(const struct profile *p, const char *key, double min, double max,
		       double dflt, double *out, struct st_error *err)
{
	const struct profile_kv *kv;
	struct key_def d = {key, KT_DOUBLE, 0, min, max, 0, "", NULL};
	struct loader L = {0};
	struct item it;

	if (!p || !key || !out)
		return st_error_set(err, ST_ERR_ARG, "profile_get_number: bad arguments");
	kv = find_kv(p->keys, key);
	if (!kv) {
		*out = dflt;
		return 0;
	}
	L.p = (struct profile *)p;
	L.origin = p->path;
	L.err = err;
	it.s = kv->value;
	it.len = strlen(kv->value);
	trim(&it.s, &it.len);
	return number_item(&L, kv, &d, &it, 0, 1, out);
}

size_t profile_key_count(const struct profile *p)
{
	return p && p->keys ? p->keys->count : 0;
}

const char *profile_key_at(const struct profile *p, size_t i, const char **value, int *line)
{
	if (!p || !p->keys || i >= p->keys->count)
		return NULL;
	if (value)
		*value = p->keys->kv[i].value;
	if (line)
		*line = p->keys->kv[i].line;
	return p->keys->kv[i].key;
}

bool profile_key_known(const char *key)
{
	return key && find_def(key) != NULL;
}

const char *profile_protocol_name(enum profile_protocol protocol)
{
	return (unsigned)protocol < COUNT(protocol_names) ? protocol_names[protocol] : "?";
}

const char *profile_flavor_name(enum profile_flavor flavor)
{
	return (unsigned)flavor < COUNT(flavor_names) ? flavor_names[flavor] : "?";
}

const char *profile_home_name(enum profile_home dir)
{
	return dir == PROFILE_HOME_MAX ? "max" : "min";
}

/* ---------------------------------------------------------------------------
 * Writing
 */

/* Write s with PrusaSlicer's escapes (\n, \r, \\). */
static void put_escaped(FILE *f, const char *s)
{
	for (; *s; s++) {
		if (*s == '\n')
			fputs("\\n", f);
		else if (*s == '\r')
			fputs("\\r", f);
		else if (*s == '\\')
			fputs("\\\\", f);
		else
			fputc(*s, f);
	}
}

/* Write v in its shortest exact form. */
static void put_double(FILE *f, double v)
{
	char buf[40];

	fmt_double(buf, sizeof(buf), v);
	fputs(buf, f);
}

/* Write d's resolved value in file syntax. */
static void put_value(FILE *f, const struct profile *p, const struct key_def *d)
{
	const void *field = (const char *)p + d->off;
	int ec = p->extruder_count;

	switch (d->type) {
	case KT_STRING:
		put_escaped(f, *(const char *const *)field);
		break;
	case KT_DOUBLE:
	case KT_FIRST_DOUBLE:
	case KT_FIRST_HEIGHT:
	case KT_WIDTH:
		put_double(f, *(const double *)field);
		break;
	case KT_SPEED_PCT:
		put_double(f, p->first_layer_speed);
		if (p->first_layer_speed_is_percent)
			fputc('%', f);
		break;
	case KT_DENSITY:
		put_double(f, p->fill_density);
		fputc('%', f);
		break;
	case KT_INT:
	case KT_FIRST_INT:
	case KT_EXTRUDERS:
		fprintf(f, "%d", *(const int *)field);
		break;
	case KT_BOOL:
	case KT_FIRST_BOOL:
		fputc(*(const bool *)field ? '1' : '0', f);
		break;
	case KT_EX_DOUBLE:
		for (int i = 0; i < ec; i++) {
			if (i)
				fputc(',', f);
			put_double(f, ((const double *)field)[i]);
		}
		break;
	case KT_EX_INT:
		for (int i = 0; i < ec; i++)
			fprintf(f, "%s%d", i ? "," : "", ((const int *)field)[i]);
		break;
	case KT_EX_POINT:
		for (int i = 0; i < ec; i++) {
			const struct profile_point *pt = &((const struct profile_point *)field)[i];
			if (i)
				fputc(',', f);
			put_double(f, pt->x);
			fputc('x', f);
			put_double(f, pt->y);
		}
		break;
	case KT_BED:
		for (size_t i = 0; i < p->bed_points; i++) {
			if (i)
				fputc(',', f);
			put_double(f, p->bed_shape[i].x);
			fputc('x', f);
			put_double(f, p->bed_shape[i].y);
		}
		break;
	case KT_USB:
		for (size_t i = 0; i < p->usb_id_count; i++)
			fprintf(f, "%s%04x:%04x", i ? "," : "", p->usb_ids[i].vid,
				p->usb_ids[i].pid);
		break;
	case KT_PROTOCOL:
		fputs(profile_protocol_name(p->protocol), f);
		break;
	case KT_FLAVOR:
		fputs(profile_flavor_name(p->gcode_flavor), f);
		break;
	case KT_PATTERN:
		fputs(p->fill_pattern, f);
		break;
	case KT_HOME:
		fputs(profile_home_name(*(const enum profile_home *)field), f);
		break;
	case KT_BAUD:
		fprintf(f, "%ld", p->baudrate);
		break;
	}
}

int profile_write(const struct profile *p, FILE *f)
{
	bool other = false;

	if (!p || !f)
		return ST_ERR_ARG;
	fprintf(f, "# %s, resolved by stratum from ", p->id);
	put_escaped(f, p->path);
	fputc('\n', f);
	fprintf(f, "# Every key the loader knows, defaults included.\n");
	for (size_t i = 0; i < KEY_DEFS; i++) {
		const struct key_def *d = &key_defs[i];

		if (d->group)
			fprintf(f, "\n# %s\n", d->group);
		if ((d->flags & KF_SAILFISH) && p->protocol != PROFILE_PROTOCOL_SAILFISH &&
		    !find_kv(p->keys, d->key))
			continue; /* unused by Marlin printers, not set: leave out */
		fprintf(f, "%s = ", d->key);
		put_value(f, p, d);
		fputc('\n', f);
	}
	for (size_t i = 0; p->keys && i < p->keys->count; i++) {
		const struct profile_kv *kv = &p->keys->kv[i];

		if (find_def(kv->key))
			continue;
		if (!other)
			fprintf(f, "\n# Other keys of the file (not used by stratum yet)\n");
		other = true;
		fprintf(f, "%s = ", kv->key);
		put_escaped(f, kv->value);
		fputc('\n', f);
	}
	if (ferror(f))
		return ST_ERR_IO;
	return 0;
}

/* ---------------------------------------------------------------------------
 * JSON
 */

/* A JSON string of s; bytes that are not valid UTF-8 become '?'. */
static json_t *json_text(const char *s)
{
	json_t *j = json_string(s);
	char *copy;

	if (j || !s)
		return j;
	copy = dup_n(s, strlen(s)); /* invalid UTF-8: keep ASCII, mark the rest */
	if (!copy)
		return NULL;
	for (char *c = copy; *c; c++)
		if ((unsigned char)*c >= 0x80)
			*c = '?';
	j = json_string(copy);
	free(copy);
	return j;
}

/* A point as [x, y]. */
static json_t *json_point(const struct profile_point *pt)
{
	return json_pack("[ff]", pt->x, pt->y);
}

/* d's resolved value as a typed JSON value (new reference, NULL on OOM). */
static json_t *json_value(const struct profile *p, const struct key_def *d)
{
	const void *field = (const char *)p + d->off;
	int ec = p->extruder_count;
	json_t *a;

	switch (d->type) {
	case KT_STRING:
		return json_text(*(const char *const *)field);
	case KT_DOUBLE:
	case KT_FIRST_DOUBLE:
	case KT_FIRST_HEIGHT:
	case KT_WIDTH:
		return json_real(*(const double *)field);
	case KT_SPEED_PCT:
		if (p->first_layer_speed_is_percent) {
			char buf[48];
			fmt_double(buf, sizeof(buf) - 1, p->first_layer_speed);
			strcat(buf, "%");
			return json_string(buf);
		}
		return json_real(p->first_layer_speed);
	case KT_DENSITY:
		return json_real(p->fill_density);
	case KT_INT:
	case KT_FIRST_INT:
	case KT_EXTRUDERS:
		return json_integer(*(const int *)field);
	case KT_BOOL:
	case KT_FIRST_BOOL:
		return json_boolean(*(const bool *)field);
	case KT_BAUD:
		return json_integer(p->baudrate);
	case KT_PROTOCOL:
		return json_string(profile_protocol_name(p->protocol));
	case KT_FLAVOR:
		return json_string(profile_flavor_name(p->gcode_flavor));
	case KT_PATTERN:
		return json_string(p->fill_pattern);
	case KT_HOME:
		return json_string(profile_home_name(*(const enum profile_home *)field));
	case KT_EX_DOUBLE:
	case KT_EX_INT:
	case KT_EX_POINT:
	case KT_BED:
	case KT_USB:
		break;
	}
	a = json_array();
	if (!a)
		return NULL;
	if (d->type == KT_BED) {
		for (size_t i = 0; i < p->bed_points; i++)
			if (json_array_append_new(a, json_point(&p->bed_shape[i])))
				goto out_free;
	} else if (d->type == KT_USB) {
		for (size_t i = 0; i < p->usb_id_count; i++) {
			char buf[16];
			snprintf(buf, sizeof(buf), "%04x:%04x", p->usb_ids[i].vid,
				 p->usb_ids[i].pid);
			if (json_array_append_new(a, json_string(buf)))
				goto out_free;
		}
	} else {
		for (int i = 0; i < ec; i++) {
			json_t *v = d->type == KT_EX_DOUBLE ? json_real(((const double *)field)[i])
				    : d->type == KT_EX_INT
					? json_integer(((const int *)field)[i])
					: json_point(&((const struct profile_point *)field)[i]);
			if (json_array_append_new(a, v))
				goto out_free;
		}
	}
	return a;

out_free:
	json_decref(a);
	return NULL;
}

json_t *profile_to_json(const struct profile *p)
{
	json_t *o, *settings, *other;

	if (!p)
		return NULL;
	o = json_object();
	settings = json_object();
	other = json_object();
	if (!o || !settings || !other)
		goto out_free;
	if (json_object_set_new(o, "id", json_text(p->id)) ||
	    json_object_set_new(o, "path", json_text(p->path)))
		goto out_free;
	for (size_t i = 0; i < KEY_DEFS; i++) {
		const struct key_def *d = &key_defs[i];

		if ((d->flags & KF_SAILFISH) && p->protocol != PROFILE_PROTOCOL_SAILFISH &&
		    !find_kv(p->keys, d->key))
			continue;
		if (json_object_set_new(settings, d->key, json_value(p, d)))
			goto out_free;
	}
	for (size_t i = 0; p->keys && i < p->keys->count; i++)
		if (!find_def(p->keys->kv[i].key) &&
		    json_object_set_new(other, p->keys->kv[i].key, json_text(p->keys->kv[i].value)))
			goto out_free;
	if (json_object_set_new(o, "settings", settings)) {
		settings = NULL;
		goto out_free;
	}
	settings = NULL;
	if (json_object_set_new(o, "other", other)) {
		other = NULL;
		goto out_free;
	}
	return o;

out_free:
	json_decref(other);
	json_decref(settings);
	json_decref(o);
	return NULL;
}
