/*
 * gcode_writer.c - layer stack to Marlin G-code (see gcode_writer.h).
 *
 * Each layer is first planned into a list of operations (moves with their
 * kind, and role changes), so the layer's time can be estimated and its
 * speeds lowered before anything is written; then the operations are
 * emitted.  The print is generated once, into an anonymous temporary file
 * while the estimator runs beside it; the header with the estimates is
 * then written and the body copied after it.
 *
 * E is kept in integer units of 1e-5 mm (the written precision): the
 * position written is extruded - retracted, both rounded from exact
 * running sums, so per-layer amounts do not drift and every unretraction
 * restores exactly what its retraction took.
 */
#include "gcode_writer.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "ironing.h"
#include "placeholder.h"
#include "settings.h"
#include "st_file.h"
#include "travel.h"
#include "st_grow.h"

#define E_UNITS 100000.0 /* E written in 1e-5 mm */
#define E_DIGITS 5
#define XYZ_UNITS 1000.0 /* X, Y, Z written in um */
#define XYZ_DIGITS 3
#define NUM_MAX 48	    /* longest formatted number */
#define MOVE_EPS 1e-7	    /* mm: shorter travels are no travel */
#define SLOWDOWN_STEPS 40   /* bisection steps for the slow-down factor */
#define WIPE_SPEED_SHARE 0.8 /* wipe at 80% of the travel speed, as PrusaSlicer */

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
};

#define KD(n, vec) {#n, KEY_DOUBLE, offsetof(struct gcodew_settings, n), vec, false}
#define KI(n, vec) {#n, KEY_INT, offsetof(struct gcodew_settings, n), vec, false}
#define KB(n, vec) {#n, KEY_BOOL, offsetof(struct gcodew_settings, n), vec, false}
#define KRD(n) {#n, KEY_DOUBLE, offsetof(struct gcodew_settings, n), false, true}
#define KRI(n) {#n, KEY_INT, offsetof(struct gcodew_settings, n), false, true}

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
    KD(retract_before_travel, true),
    KB(wipe, true),
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
	s->printer_settings_id = s->printer_model = "";
	s->bed_shape = settings_find("bed_shape")->dflt;
	s->spiral_vase = setting_default_number("spiral_vase", false, &v) && v != 0;
	s->ironing = setting_default_number("ironing", false, &v) && v != 0;
	s->ironing_type = settings_find("ironing_type")->dflt;
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
static size_t fmt_units(char *buf, int64_t u, int digits)
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
static void fmt_num(char *buf, double v, int digits)
{
	double scale = pow(10, digits);

	if (!(fabs(v) * scale < 9e18)) {
		snprintf(buf, NUM_MAX, "%.0f", isfinite(v) ? v : 0.0);
		return;
	}
	fmt_units(buf, llround(v * scale), digits);
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
static struct ph_vars *writer_vars(const struct gcodew_settings *s, size_t nlayers,
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
static int set_layer_vars(struct ph_vars *v, size_t li, double z, double max_z,
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
	v = writer_vars(s, nlayers, err);
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
static bool gcode_sets(const char *text, int m1, int m2)
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
 * Planning a layer
 */

enum op_kind { OP_MOVE, OP_ROLE };

enum move_kind {
	MV_TRAVEL,    /* no extrusion */
	MV_EXTRUDE,   /* e mm of filament extruded; slowed down for cooling */
	MV_RETRACT,   /* e mm pulled back (standing, or wiping when xy) */
	MV_UNRETRACT, /* everything retracted pushed back */
};

struct op {
	enum op_kind kind;
	enum move_kind mv;
	enum path_role role; /* OP_ROLE */
	bool xy;	     /* the move has an XY target */
	double x, y, z;	     /* mm, target */
	double e;	     /* mm of filament, see enum move_kind */
	double f;	     /* mm/s */
};

struct gcodew {
	const struct gcodew_settings *s;
	size_t nlayers;		 /* layers announced to gcodew_begin */
	size_t next;		 /* index of the next layer to write */
	char *start, *start_filament; /* custom G-code, placeholders expanded */
	struct ph_vars *vars;	 /* placeholders: the print's variables */
	double max_z;		 /* mm, highest layer written so far */
	FILE *body;		 /* the body, generated before the header */
	struct st_file_out out;	 /* gcodew_begin_file: the file being written */
	double len[PATH_ROLES], area[PATH_ROLES]; /* per role: nm and nm^2 of
						     * beads, for the mean widths */
	struct st_error *err;
	FILE *fp;		 /* where put() writes: the body, then the output */
	struct est_planner *est; /* times the body's moves as they are written */

	/* Planning state, in mm */
	bool pos_known;
	double px, py, pz;
	double layer_z;
	int plan_role; /* role of the last path planned in this layer, -1 none */
	double fil_area;
	struct op *ops;
	size_t nops, opcap;
	double *wipe; /* x, y pairs: the last path backwards from the nozzle */
	size_t nwipe, wipecap;
	bool *done; /* per path of the layer: already planned */
	size_t donecap;
	struct travel_map *map;	  /* this layer's, NULL: straight travels */
	bool spiral_below;	  /* the layer below was a spiral (layer_paths.spiral) */
	struct travel_route route; /* the travel being planned */

	/* Emission state */
	double ext_exact, r_exact; /* mm extruded since the last reset / retracted now */
	int64_t ext_units, r_units, epos_units; /* the same in E units; position written */
	double e_machine;			/* mm, absolute E for the estimator */
	bool xy_known, z_known;
	int64_t wx, wy, wz; /* um, last written */
	long long wf;	    /* mm/min, last written, 0 none */
	int fan;	    /* percent written, -1 unknown */
	int layer_fan;	    /* percent for this layer's non-bridge paths */
	int bridge_fan;	    /* percent for bridges on this layer; -1: layer_fan */
	size_t moves;
	double filament_mm;
};

/* Append an operation. */
static int push(struct gcodew *w, struct op o)
{
	struct op *grown = st_grow(w->ops, &w->opcap, w->nops + 1, sizeof(*grown));

	if (!grown)
		return st_error_set(w->err, ST_ERR_NOMEM, "G-code: out of memory planning a layer");
	w->ops = grown;
	w->ops[w->nops++] = o;
	return 0;
}

/* A move op to (x, y, z); xy false leaves X and Y alone. */
static int push_move(struct gcodew *w, enum move_kind mv, bool xy, double x, double y, double z,
		     double e, double f)
{
	int rc = push(w, (struct op){.kind = OP_MOVE, .mv = mv, .xy = xy, .x = x, .y = y, .z = z,
				     .e = e, .f = f});
	if (rc == 0) {
		if (xy) {
			w->px = x;
			w->py = y;
		}
		w->pz = z;
	}
	return rc;
}

/* Z speed: travel_speed_z, else the machine's Z limit. */
static double z_speed(const struct gcodew_settings *s)
{
	return s->travel_speed_z > 0 ? s->travel_speed_z : s->limits.max_feedrate[EST_Z];
}

/* Retract, wiping back over the last path when asked. */
static int plan_retract(struct gcodew *w)
{
	const struct gcodew_settings *s = w->s;
	double len = s->retract_length, taken = 0;
	int rc = 0;

	if (s->wipe && w->nwipe >= 2) {
		double speed = WIPE_SPEED_SHARE * s->travel_speed;
		double dist = len / s->retract_speed * speed, walked = 0;
		for (size_t k = 0; k + 1 < w->nwipe && walked < dist && rc == 0; k++) {
			double x0 = w->wipe[2 * k], y0 = w->wipe[2 * k + 1];
			double x1 = w->wipe[2 * k + 2], y1 = w->wipe[2 * k + 3];
			double seg = hypot(x1 - x0, y1 - y0), step = fmin(seg, dist - walked);
			if (seg <= 0)
				continue;
			double t = step / seg, r = len * step / dist;
			rc = push_move(w, MV_RETRACT, true, x0 + t * (x1 - x0), y0 + t * (y1 - y0),
				       w->pz, r, speed);
			walked += step;
			taken += r;
		}
	}
	w->nwipe = 0;
	if (rc == 0 && len - taken > 1e-9)
		rc = push_move(w, MV_RETRACT, false, w->px, w->py, w->pz, len - taken,
			       s->retract_speed);
	return rc;
}

/*
 * Travel to (x, y) on the current layer, routed inside the part when the
 * layer has a travel map: retract (and lift) when longer than
 * retract_before_travel unless the route stays inside one island and is
 * short enough to skip it, reach the layer's Z before moving in XY when not
 * lifted, unretract on arrival.
 */
static int plan_travel(struct gcodew *w, double x, double y)
{
	const struct gcodew_settings *s = w->s;
	struct travel_route *r = &w->route;
	double lz = w->layer_z, tz = lz, d, len;
	bool retract;
	int rc = 0;

	if (!w->pos_known) {
		w->pos_known = true;
		rc = push_move(w, MV_TRAVEL, false, 0, 0, lz, 0, z_speed(s));
		return rc ? rc : push_move(w, MV_TRAVEL, true, x, y, lz, 0, s->travel_speed);
	}
	d = hypot(x - w->px, y - w->py);
	if (d < MOVE_EPS && fabs(w->pz - lz) < 1e-9)
		return 0;
	rc = travel_plan(w->map, llround(w->px * SLICE_UNITS_PER_MM),
			 llround(w->py * SLICE_UNITS_PER_MM), llround(x * SLICE_UNITS_PER_MM),
			 llround(y * SLICE_UNITS_PER_MM), r, w->err);
	if (rc)
		return rc;
	len = r->length / SLICE_UNITS_PER_MM;
	retract = s->retract_length > 0 && len > s->retract_before_travel;
	if (retract && r->inside && s->only_retract_when_crossing_perimeters &&
	    (s->max_unretracted_travel == 0 || len <= s->max_unretracted_travel))
		retract = false; /* any ooze falls inside the part */
	if (retract) {
		rc = plan_retract(w);
		if (s->retract_lift > 0)
			tz = lz + s->retract_lift;
	}
	if (rc == 0 && fabs(w->pz - tz) > 1e-9)
		rc = push_move(w, MV_TRAVEL, false, 0, 0, tz, 0, z_speed(s));
	for (size_t k = 0; k + 1 < r->n && rc == 0; k++) /* the route's turns */
		rc = push_move(w, MV_TRAVEL, true, r->xy[2 * k] / SLICE_UNITS_PER_MM,
			       r->xy[2 * k + 1] / SLICE_UNITS_PER_MM, tz, 0, s->travel_speed);
	if (rc == 0)
		rc = push_move(w, MV_TRAVEL, true, x, y, tz, 0, s->travel_speed);
	if (rc == 0 && tz != lz)
		rc = push_move(w, MV_TRAVEL, false, 0, 0, lz, 0, z_speed(s));
	if (rc == 0 && retract)
		rc = push_move(w, MV_UNRETRACT, false, 0, 0, lz, s->retract_length,
			       s->deretract_speed > 0 ? s->deretract_speed : s->retract_speed);
	return rc;
}

/* Print speed of a role, PrusaSlicer's choice of key. */
static double role_base_speed(const struct gcodew_settings *s, enum path_role role)
{
	switch (role) {
	case PATH_OUTER_PERIMETER:
	case PATH_THIN_WALL:
		return s->external_perimeter_speed;
	case PATH_GAP_FILL:
		return s->gap_fill_speed;
	case PATH_SOLID_INFILL:
	case PATH_BOTTOM_SKIN:
		return s->solid_infill_speed;
	case PATH_TOP_SKIN:
		return s->top_solid_infill_speed;
	case PATH_SPARSE_INFILL:
		return s->infill_speed;
	case PATH_BRIDGE:
		return s->bridge_speed;
	case PATH_SUPPORT:
	case PATH_SKIRT:
	case PATH_BRIM:
		return s->support_material_speed;
	case PATH_SUPPORT_INTERFACE:
		return s->support_material_interface_speed;
	case PATH_IRONING:
		return s->ironing_speed;
	default: /* inner perimeters */
		return s->perimeter_speed;
	}
}

/* A closed wall this long or shorter prints at small_perimeter_speed
 * (PrusaSlicer's SMALL_PERIMETER_LENGTH: a circle of radius 6.5 mm), mm. */
#define SMALL_PERIMETER_MM (2 * M_PI * 6.5)

/* Whether p is a small perimeter: a closed wall loop at most SMALL_PERIMETER_MM long. */
static bool small_perimeter(const struct toolpath *p)
{
	double len = 0;

	if (!p->closed || (p->role != PATH_OUTER_PERIMETER && p->role != PATH_INNER_PERIMETER))
		return false;
	for (size_t k = 0; k < p->n && len <= SMALL_PERIMETER_MM; k++) {
		const struct path_point *a = &p->pts[k], *b = &p->pts[(k + 1) % p->n];
		len += hypot((double)(b->x - a->x), (double)(b->y - a->y)) / SLICE_UNITS_PER_MM;
	}
	return len <= SMALL_PERIMETER_MM;
}

/* Print speed of path p on layer li (0-based): its role's, or
 * small_perimeter_speed for a small wall loop; the first layer's replaces
 * it, or scales it when a percentage, and so does the part's first layer
 * on a raft (PrusaSlicer's first_layer_speed_over_raft). */
static double path_speed(const struct gcodew_settings *s, const struct toolpath *p, size_t li)
{
	double v = small_perimeter(p) ? s->small_perimeter_speed : role_base_speed(s, p->role);
	double f = s->first_layer_speed;
	bool pct = s->first_layer_speed_is_percent;

	if (li > 0 && s->raft_layers > 0 && li == (size_t)s->raft_layers) {
		f = s->first_layer_speed_over_raft;
		pct = s->first_layer_speed_over_raft_is_percent;
	} else if (li > 0) {
		return v;
	}
	if (f <= 0)
		return v;
	return pct ? v * f / 100 : f;
}

/* Whether key k of s is written as a percentage. */
static bool key_is_pct(const struct gcodew_settings *s, const struct key *k)
{
	if (k->off == offsetof(struct gcodew_settings, first_layer_speed))
		return s->first_layer_speed_is_percent;
	if (k->off == offsetof(struct gcodew_settings, first_layer_speed_over_raft))
		return s->first_layer_speed_over_raft_is_percent;
	return k->off == offsetof(struct gcodew_settings, raft_first_layer_density);
}

/* Point index of step k (0 .. n or n-1) of a path printed forwards or
 * reversed; a closed loop ends back at its seam. */
static size_t trav(const struct toolpath *p, bool rev, size_t k)
{
	if (rev)
		return p->n - 1 - k;
	return k == p->n ? 0 : k;
}

/* Remember the printed path backwards from its end, for a wipe; a closed
 * path printed from point first (a spiral loop) is rotated by first. */
static int record_wipe(struct gcodew *w, const struct toolpath *p, bool rev, size_t steps,
		       size_t first)
{
	const struct gcodew_settings *s = w->s;
	double dist = s->retract_length / s->retract_speed * WIPE_SPEED_SHARE * s->travel_speed;
	double walked = 0;

	w->nwipe = 0;
	for (size_t k = steps; k-- > 0;) {
		const struct path_point *q = &p->pts[(trav(p, rev, k) + first) % p->n];
		double x = q->x / SLICE_UNITS_PER_MM, y = q->y / SLICE_UNITS_PER_MM;
		double *grown = st_grow(w->wipe, &w->wipecap, w->nwipe + 1, 2 * sizeof(*grown));
		if (!grown)
			return st_error_set(w->err, ST_ERR_NOMEM, "G-code: out of memory for a wipe");
		w->wipe = grown;
		if (w->nwipe)
			walked += hypot(x - w->wipe[2 * w->nwipe - 2], y - w->wipe[2 * w->nwipe - 1]);
		w->wipe[2 * w->nwipe] = x;
		w->wipe[2 * w->nwipe + 1] = y;
		w->nwipe++;
		if (walked >= dist)
			break;
	}
	return 0;
}

/*
 * Extrude from pa to pb (path pi of layer li; pb is its point at, for
 * messages), ending at height z: a bead width nm wide, its filament from
 * the flow model at the top of gcode_writer.h times share.  A bead
 * narrower than the layer is refused; a segment of no length adds nothing.
 */
static int plan_segment(struct gcodew *w, const struct layer_paths *l, size_t li, size_t pi,
			size_t at, const struct path_point *pa, const struct path_point *pb,
			int64_t width, double z, double speed, double share)
{
	double h = l->height, bead = width / SLICE_UNITS_PER_MM;
	double len = hypot((double)(pb->x - pa->x), (double)(pb->y - pa->y)) / SLICE_UNITS_PER_MM;
	bool iron = l->paths[pi].role == PATH_IRONING;
	double area = iron ? bead * w->s->layer_height * w->s->ironing_flowrate / 100
			   : (bead - h) * h + M_PI * h * h / 4;

	if (bead < h && !iron)
		return st_error_set(w->err, ST_ERR_RANGE,
				    "G-code: layer %zu, path %zu (%s), point %zu: bead width %.4f mm "
				    "is below the layer height %.4f mm",
				    li + 1, pi, path_role_name(l->paths[pi].role), at, bead, h);
	if (len <= 0)
		return 0;
	return push_move(w, MV_EXTRUDE, true, pb->x / SLICE_UNITS_PER_MM,
			 pb->y / SLICE_UNITS_PER_MM, z,
			 share * area * len / w->fil_area * w->s->extrusion_multiplier, speed);
}

/* Plan path pi of layer li: travel to its start, then its segments. */
static int plan_path(struct gcodew *w, const struct layer_paths *l, size_t li, size_t pi, bool rev)
{
	const struct gcodew_settings *s = w->s;
	const struct toolpath *p = &l->paths[pi];
	size_t steps = p->closed ? p->n + 1 : p->n;
	double speed = path_speed(s, p, li);
	const struct path_point *q0 = &p->pts[trav(p, rev, 0)];
	int rc;

	rc = plan_travel(w, q0->x / SLICE_UNITS_PER_MM, q0->y / SLICE_UNITS_PER_MM);
	if (rc == 0 && w->plan_role != (int)p->role) {
		rc = push(w, (struct op){.kind = OP_ROLE, .role = p->role});
		w->plan_role = (int)p->role;
	}
	for (size_t k = 0; k + 1 < steps && rc == 0; k++) {
		size_t a = trav(p, rev, k), b = trav(p, rev, k + 1);
		const struct path_point *pa = &p->pts[a], *pb = &p->pts[b];
		rc = plan_segment(w, l, li, pi, rev ? b : a, pa, pb, (rev ? pb : pa)->width,
				  w->layer_z, speed, 1);
	}
	if (rc == 0 && s->wipe)
		rc = record_wipe(w, p, rev, steps, 0);
	return rc;
}

/* Squared distance (mm^2) from the nozzle to (x, y) in nm. */
static double dist2(const struct gcodew *w, int64_t x, int64_t y)
{
	double dx = x / SLICE_UNITS_PER_MM - w->px, dy = y / SLICE_UNITS_PER_MM - w->py;
	return dx * dx + dy * dy;
}

/* Perimeter runs keep their order; other runs go nearest first. */
static bool keep_order(enum path_role role)
{
	return role == PATH_OUTER_PERIMETER || role == PATH_INNER_PERIMETER;
}

/* Plan the paths [i, j) of one role run, nearest neighbour first. */
static int plan_run(struct gcodew *w, const struct layer_paths *l, size_t li, size_t i, size_t j)
{
	for (size_t left = j - i; left > 0; left--) {
		size_t best = j;
		bool best_rev = false;
		double best_d = INFINITY;
		for (size_t k = i; k < j; k++) {
			const struct toolpath *p = &l->paths[k];
			if (w->done[k])
				continue;
			if (!w->pos_known || keep_order(p->role)) {
				best = k;
				break;
			}
			double d0 = dist2(w, p->pts[0].x, p->pts[0].y);
			double d1 = p->closed ? INFINITY : dist2(w, p->pts[p->n - 1].x, p->pts[p->n - 1].y);
			if (d0 < best_d || d1 < best_d) {
				best = k;
				best_rev = d1 < d0;
				best_d = fmin(d0, d1);
			}
		}
		w->done[best] = true;
		int rc = plan_path(w, l, li, best, best_rev);
		if (rc)
			return rc;
	}
	return 0;
}

/*
 * Plan spiral layer li (layer_paths.spiral): its one loop from the vertex
 * nearest the nozzle, Z rising with the length printed from the top of the
 * layer below to l->z.  Reached from a spiral below by a plain move (no
 * retraction: it is the loop's own continuation), else by a travel; then,
 * as PrusaSlicer's transition layer, the flow rises with Z from nothing,
 * since the gap under the nozzle starts at nothing.
 */
static int plan_spiral(struct gcodew *w, const struct layer_paths *l, size_t li)
{
	const struct toolpath *p = &l->paths[0];
	double h = l->height, z0 = l->z - h, speed = path_speed(w->s, p, li);
	double total = 0, done = 0, best = INFINITY;
	size_t first = 0;
	int rc;

	for (size_t k = 0; k < p->n; k++) {
		const struct path_point *a = &p->pts[k], *b = &p->pts[(k + 1) % p->n];
		double d = w->pos_known ? dist2(w, a->x, a->y) : 0;
		total += hypot((double)(b->x - a->x), (double)(b->y - a->y)) / SLICE_UNITS_PER_MM;
		if (d < best) {
			best = d;
			first = k;
		}
	}
	w->layer_z = z0;
	if (w->spiral_below && w->pos_known)
		rc = push_move(w, MV_TRAVEL, true, p->pts[first].x / SLICE_UNITS_PER_MM,
			       p->pts[first].y / SLICE_UNITS_PER_MM, z0, 0, w->s->travel_speed);
	else
		rc = plan_travel(w, p->pts[first].x / SLICE_UNITS_PER_MM,
				 p->pts[first].y / SLICE_UNITS_PER_MM);
	if (rc == 0)
		rc = push(w, (struct op){.kind = OP_ROLE, .role = p->role});
	for (size_t k = 0; k < p->n && rc == 0; k++) {
		const struct path_point *pa = &p->pts[(first + k) % p->n];
		const struct path_point *pb = &p->pts[(first + k + 1) % p->n];
		double t;
		done += hypot((double)(pb->x - pa->x), (double)(pb->y - pa->y)) / SLICE_UNITS_PER_MM;
		t = fmin(1, done / total);
		rc = plan_segment(w, l, li, 0, (first + k) % p->n, pa, pb, pa->width, z0 + h * t,
				  speed, w->spiral_below ? 1 : t);
	}
	w->layer_z = l->z;
	if (rc == 0 && w->s->wipe)
		rc = record_wipe(w, p, false, p->n + 1, first);
	return rc;
}

/* Plan every path of layer li into w->ops. */
static int plan_layer(struct gcodew *w, const struct layer_paths *l, size_t li)
{
	int rc = 0;

	w->nops = 0;
	w->layer_z = l->z;
	w->plan_role = -1;
	w->map = w->s->avoid_crossing_perimeters ? l->travel : NULL;
	if (l->n > w->donecap) {
		bool *grown = st_grow(w->done, &w->donecap, l->n, sizeof(*grown));
		if (!grown)
			return st_error_set(w->err, ST_ERR_NOMEM, "G-code: out of memory planning a layer");
		w->done = grown;
	}
	if (l->n)
		memset(w->done, 0, l->n * sizeof(*w->done));
	if (l->spiral && l->n == 1 && l->paths[0].closed) {
		rc = plan_spiral(w, l, li);
		w->spiral_below = true;
		return rc;
	}
	w->spiral_below = false;
	for (size_t i = 0, j; i < l->n && rc == 0; i = j) {
		for (j = i + 1; j < l->n && l->paths[j].role == l->paths[i].role; j++)
			;
		rc = plan_run(w, l, li, i, j);
	}
	return rc;
}

/* ---------------------------------------------------------------------------
 * Cooling
 */

/* Speed of an extrusion slowed by factor f, never below min_print_speed
 * unless it was slower already. */
static double slowed(double v, double f, double min_speed)
{
	return fmax(v * f, fmin(v, min_speed));
}

/* Planner time of the layer's ops with extrusions slowed by f. */
static int layer_time(struct gcodew *w, const double start[EST_AXES], double f, double *t)
{
	struct est_planner *p = est_planner_new(&w->s->limits, start, w->err);
	struct est_result r;
	double x = start[EST_X], y = start[EST_Y], e = 0;
	int rc = 0;

	if (!p)
		return w->err ? w->err->code : ST_ERR_NOMEM;
	for (size_t i = 0; i < w->nops && rc == 0; i++) {
		const struct op *o = &w->ops[i];
		double v = o->f;
		if (o->kind != OP_MOVE)
			continue;
		if (o->xy) {
			x = o->x;
			y = o->y;
		}
		if (o->mv == MV_EXTRUDE) {
			e += o->e;
			v = slowed(v, f, w->s->min_print_speed);
		} else if (o->mv == MV_RETRACT) {
			e -= o->e;
		} else if (o->mv == MV_UNRETRACT) {
			e += o->e;
		}
		rc = est_planner_add(p, &(struct est_move){x, y, o->z, e, v}, w->err);
	}
	est_planner_result(p, &r);
	est_planner_free(p);
	*t = r.time_s;
	return rc;
}

/* The first layer (0-based) the fan may run on: a ramp starts on layer 2
 * at the earliest (PrusaSlicer). */
static size_t first_fan_layer(const struct gcodew_settings *s)
{
	return s->disable_fan_first_layers <= 0 && s->full_fan_speed_layer > 0
		   ? 1
		   : (size_t)s->disable_fan_first_layers;
}

/* fan percent on layer li, ramped up to full at full_fan_speed_layer (1-based). */
static int fan_ramp(const struct gcodew_settings *s, size_t li, int fan)
{
	double d = (double)first_fan_layer(s);

	if ((int)li + 1 >= s->full_fan_speed_layer)
		return fan;
	return (int)lround(fan * ((double)li + 1 - d) / (s->full_fan_speed_layer - d));
}

/* Fan percent of layer li taking t seconds (PrusaSlicer's rule). */
static int fan_for(const struct gcodew_settings *s, size_t li, double t)
{
	int fan;

	if (li < first_fan_layer(s))
		return 0;
	fan = s->fan_always_on ? s->min_fan_speed : 0;
	if (!s->cooling)
		return fan;
	if (t < s->slowdown_below_layer_time) {
		fan = s->max_fan_speed;
	} else if (t < s->fan_below_layer_time) {
		double k = (t - s->slowdown_below_layer_time) /
			   (s->fan_below_layer_time - s->slowdown_below_layer_time);
		fan = (int)lround(k * s->min_fan_speed + (1 - k) * s->max_fan_speed);
	}
	return fan_ramp(s, li, fan);
}

/* Decide the layer's fan and slow its extrusions down if it is too fast. */
static int cool_layer(struct gcodew *w, size_t li, const double start[EST_AXES])
{
	const struct gcodew_settings *s = w->s;
	double t, target = s->slowdown_below_layer_time, lo = 0, hi = 1;
	int rc = layer_time(w, start, 1, &t);

	if (rc)
		return rc;
	w->layer_fan = fan_for(s, li, t);
	w->bridge_fan = s->cooling && li >= first_fan_layer(s)
			    ? fan_ramp(s, li, s->bridge_fan_speed)
			    : -1;
	if (!s->cooling || t >= target || w->nops == 0)
		return 0;
	rc = layer_time(w, start, 0, &t);
	if (rc)
		return rc;
	if (t <= target) { /* even at min_print_speed it is too fast */
		hi = 0;
	} else {
		for (int i = 0; i < SLOWDOWN_STEPS && rc == 0; i++) {
			double mid = 0.5 * (lo + hi);
			rc = layer_time(w, start, mid, &t);
			if (t > target)
				lo = mid;
			else
				hi = mid;
		}
	}
	for (size_t i = 0; i < w->nops; i++)
		if (w->ops[i].kind == OP_MOVE && w->ops[i].mv == MV_EXTRUDE)
			w->ops[i].f = slowed(w->ops[i].f, hi, s->min_print_speed);
	return rc;
}

/* ---------------------------------------------------------------------------
 * Emission
 */

/* printf to the current output. */
static void put(struct gcodew *w, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

static void put(struct gcodew *w, const char *fmt, ...)
{
	va_list ap;

	va_start(ap, fmt);
	vfprintf(w->fp, fmt, ap);
	va_end(ap);
}

/* Set the fan to percent when it differs from what was written. */
static void set_fan(struct gcodew *w, int percent)
{
	if (percent == w->fan)
		return;
	if (w->s->fan_on_off)
		put(w, "%s", percent ? "M126\n" : "M127\n");
	else if (percent == 0)
		put(w, "M107\n");
	else
		put(w, "M106 S%ld\n", lround(percent * 255.0 / 100));
	w->fan = percent;
}

/* Write one move op and feed it to the estimator. */
static int emit_move(struct gcodew *w, const struct op *o)
{
	int64_t x = o->xy ? llround(o->x * XYZ_UNITS) : w->wx;
	int64_t y = o->xy ? llround(o->y * XYZ_UNITS) : w->wy;
	int64_t z = llround(o->z * XYZ_UNITS), epos, de;
	long long f = llround(o->f * 60);
	bool mx, my, mz;
	char line[6 * NUM_MAX];
	size_t len;

	switch (o->mv) {
	case MV_EXTRUDE:
		w->ext_exact += o->e;
		w->ext_units = llround(w->ext_exact * E_UNITS);
		w->filament_mm += o->e;
		break;
	case MV_RETRACT:
		w->r_exact += o->e;
		w->r_units = llround(w->r_exact * E_UNITS);
		break;
	case MV_UNRETRACT:
		w->r_exact = 0;
		w->r_units = 0;
		break;
	case MV_TRAVEL:
		break;
	}
	epos = w->ext_units - w->r_units;
	de = epos - w->epos_units;
	mx = o->xy && (!w->xy_known || x != w->wx);
	my = o->xy && (!w->xy_known || y != w->wy);
	mz = !w->z_known || z != w->wz;
	if (!mx && !my && !mz && de == 0)
		return 0;
	if (f < 1)
		f = 1;
	/* The line is assembled here and written at once (see fmt_units). */
	len = 2;
	memcpy(line, "G1", 2);
	if (mx) {
		memcpy(line + len, " X", 2);
		len += 2 + fmt_units(line + len + 2, x, XYZ_DIGITS);
	}
	if (my) {
		memcpy(line + len, " Y", 2);
		len += 2 + fmt_units(line + len + 2, y, XYZ_DIGITS);
	}
	if (mz) {
		memcpy(line + len, " Z", 2);
		len += 2 + fmt_units(line + len + 2, z, XYZ_DIGITS);
	}
	if (de) {
		memcpy(line + len, " E", 2);
		len += 2 + fmt_units(line + len + 2,
				     w->s->use_relative_e_distances ? de : epos, E_DIGITS);
	}
	if (f != w->wf) {
		memcpy(line + len, " F", 2);
		len += 2 + fmt_units(line + len + 2, f, 0);
	}
	line[len++] = '\n';
	fwrite(line, 1, len, w->fp);
	w->moves++;
	if (o->xy) {
		w->wx = x;
		w->wy = y;
		w->xy_known = true;
	}
	w->wz = z;
	w->z_known = true;
	w->wf = f;
	w->epos_units = epos;
	w->e_machine += de / E_UNITS;
	return est_planner_add(w->est,
			       &(struct est_move){x / XYZ_UNITS, y / XYZ_UNITS, z / XYZ_UNITS,
						  w->e_machine, f / 60.0},
			       w->err);
}

/* Write the planned ops of the current layer. */
static int emit_ops(struct gcodew *w)
{
	int rc = 0;

	for (size_t i = 0; i < w->nops && rc == 0; i++) {
		const struct op *o = &w->ops[i];
		if (o->kind == OP_ROLE) {
			put(w, ";TYPE:%s\n", path_role_name(o->role));
			set_fan(w, o->role == PATH_BRIDGE && w->bridge_fan >= 0 ? w->bridge_fan
									       : w->layer_fan);
		} else {
			rc = emit_move(w, o);
		}
	}
	return rc;
}

/* G92 E0: the written E position becomes 0, retraction state kept. */
static void reset_e(struct gcodew *w)
{
	put(w, "G92 E0\n");
	w->ext_exact -= w->epos_units / E_UNITS;
	w->ext_units -= w->epos_units;
	w->epos_units = 0;
}

static int put_expanded(struct gcodew *w, const char *text, const char *what, size_t li,
			double z);

/* Plan, cool and write layer li. */
static int do_layer(struct gcodew *w, const struct layer_paths *l, size_t li)
{
	const struct gcodew_settings *s = w->s;
	double start[EST_AXES] = {w->wx / XYZ_UNITS, w->wy / XYZ_UNITS, w->wz / XYZ_UNITS, 0};
	char nz[NUM_MAX], nh[NUM_MAX];
	int rc;

	if (!isfinite(l->z) || !isfinite(l->height) || l->z <= 0 || l->height <= 0 ||
	    l->height > l->z + 1e-9)
		return st_error_set(w->err, ST_ERR_RANGE,
				    "G-code: layer %zu has Z %g mm and height %g mm; both must be "
				    "> 0 with the height at most Z",
				    li + 1, l->z, l->height);
	rc = plan_layer(w, l, li);
	if (rc == 0)
		rc = cool_layer(w, li, start);
	if (rc)
		return rc;
	fmt_num(nz, l->z, XYZ_DIGITS);
	fmt_num(nh, l->height, XYZ_DIGITS);
	/* PrusaSlicer 2.5's order: the layer change comments, before_layer_gcode
	 * (the new layer's number and Z, the old maximum), layer_gcode (the new
	 * maximum). */
	put(w, ";LAYER_CHANGE\n;Z:%s\n;HEIGHT:%s\n", nz, nh);
	rc = put_expanded(w, s->before_layer_gcode, "before_layer_gcode", li, l->z);
	if (rc)
		return rc;
	w->max_z = fmax(w->max_z, l->z);
	rc = put_expanded(w, s->layer_gcode, "layer_gcode", li, l->z);
	if (rc)
		return rc;
	if (!s->use_relative_e_distances && li > 0)
		reset_e(w);
	if (li == 1 && s->temperature > 0 && s->temperature != s->first_layer_temperature)
		put(w, "M104 S%d ; set temperature\n", s->temperature);
	if (li == 1 && s->bed_temperature > 0 &&
	    s->bed_temperature != s->first_layer_bed_temperature)
		put(w, "M140 S%d ; set bed temperature\n", s->bed_temperature);
	set_fan(w, w->layer_fan);
	return emit_ops(w);
}

/* Write "; estimated printing time = 1h 2m 3s". */
static void put_time(struct gcodew *w, double seconds)
{
	long long t = llround(seconds), d = t / 86400, h = t / 3600 % 24, m = t / 60 % 60;

	put(w, "; estimated printing time =");
	if (d)
		put(w, " %lldd", d);
	if (d || h)
		put(w, " %lldh", h);
	if (d || h || m)
		put(w, " %lldm", m);
	put(w, " %llds\n", t % 60);
}

/* "; KEY = TEXT" with control characters as blanks: one comment line. */
static void put_header_text(struct gcodew *w, const char *key, const char *text)
{
	put(w, "; %s = ", key);
	for (const char *c = text; *c; c++)
		fputc((unsigned char)*c < ' ' ? ' ' : *c, w->fp);
	put(w, "\n");
}

/* The header: printer, estimates, settings, machine limits, bead widths used. */
static void put_header(struct gcodew *w, const struct gcodew_summary *sum)
{
	static const char axis[EST_AXES] = {'x', 'y', 'z', 'e'};
	const struct est_limits *lim = &w->s->limits;
	const double *len = w->len, *area = w->area;
	char n[NUM_MAX];

	put(w, "; generated by Stratum\n");
	put_header_text(w, "printer_settings_id", w->s->printer_settings_id);
	put_header_text(w, "printer_model", w->s->printer_model);
	put_header_text(w, "bed_shape", w->s->bed_shape);
	put_time(w, sum->time_s);
	fmt_num(n, sum->filament_mm, 2);
	put(w, "; filament used [mm] = %s\n", n);
	fmt_num(n, sum->filament_cm3, 2);
	put(w, "; filament used [cm3] = %s\n", n);
	fmt_num(n, sum->filament_g, 2);
	put(w, "; filament used [g] = %s\n", n);
	put(w, "; total layers count = %zu\n", sum->layers);
	put(w, "; total moves = %zu\n", sum->moves);
	for (size_t i = 0; i < NKEYS; i++) {
		bool pct = key_is_pct(w->s, &keys[i]);

		if (keys[i].raft && w->s->raft_layers == 0)
			continue; /* as before rafts were printed */
		fmt_num(n, key_value(w->s, &keys[i]), 6);
		put(w, "; %s = %s%s\n", keys[i].name, n, pct ? "%" : "");
	}
	if (w->s->spiral_vase)
		put(w, "; spiral_vase = 1\n");
	if (w->s->ironing) {
		fmt_num(n, w->s->ironing_flowrate, 6);
		put(w, "; ironing = 1\n; ironing_type = %s\n; ironing_flowrate = %s%%\n",
		    w->s->ironing_type, n);
		fmt_num(n, w->s->ironing_spacing, 6);
		put(w, "; ironing_spacing = %s\n", n);
		fmt_num(n, w->s->ironing_speed, 6);
		put(w, "; ironing_speed = %s\n", n);
	}
	for (int a = 0; a < EST_AXES; a++) {
		char f[NUM_MAX], acc[NUM_MAX], j[NUM_MAX];
		fmt_num(f, lim->max_feedrate[a], 3);
		fmt_num(acc, lim->max_acceleration[a], 3);
		fmt_num(j, lim->max_jerk[a], 3);
		put(w, "; machine_max_feedrate_%c = %s\n; machine_max_acceleration_%c = %s\n"
		       "; machine_max_jerk_%c = %s\n",
		    axis[a], f, axis[a], acc, axis[a], j);
	}
	fmt_num(n, lim->accel_extruding, 3);
	put(w, "; machine_max_acceleration_extruding = %s\n", n);
	fmt_num(n, lim->accel_retracting, 3);
	put(w, "; machine_max_acceleration_retracting = %s\n", n);
	fmt_num(n, lim->accel_travel, 3);
	put(w, "; machine_max_acceleration_travel = %s\n", n);

	for (int r = 0; r < PATH_ROLES; r++)
		if (len[r] > 0) {
			fmt_num(n, area[r] / len[r] / SLICE_UNITS_PER_MM, 3);
			put(w, "; extrusion width (%s) = %s mm\n", path_role_name((enum path_role)r), n);
		}
	put(w, "\n");
}

/* Write custom G-code text, ending it with a newline. */
static void put_custom(struct gcodew *w, const char *text)
{
	size_t n = strlen(text);

	if (n)
		put(w, "%s%s", text, text[n - 1] == '\n' ? "" : "\n");
}

/* Expand text for layer li at z and write it; nothing for an empty text. */
static int put_expanded(struct gcodew *w, const char *text, const char *what, size_t li, double z)
{
	char *out = NULL;
	int rc;

	if (!*text)
		return 0;
	rc = set_layer_vars(w->vars, li, z, w->max_z, w->err);
	if (rc == 0)
		rc = ph_expand(text, what, w->vars, 0, &out, w->err);
	if (rc == 0)
		put_custom(w, out);
	free(out);
	return rc;
}

/* The part before the first layer: temperatures, start G-code, modes. */
static void put_start(struct gcodew *w)
{
	const struct gcodew_settings *s = w->s;
	const char *start = w->start;
	bool bed_set = gcode_sets(start, 140, 190), nozzle_set = gcode_sets(start, 104, 109);

	if (!bed_set && s->first_layer_bed_temperature > 0)
		put(w, "M190 S%d ; set bed temperature and wait for it to be reached\n",
		    s->first_layer_bed_temperature);
	if (!nozzle_set && s->first_layer_temperature > 0)
		put(w, "M104 S%d ; set temperature\n", s->first_layer_temperature);
	put_custom(w, start);
	put_custom(w, w->start_filament); /* PrusaSlicer: the first tool's filament */
	if (!nozzle_set && s->first_layer_temperature > 0)
		put(w, "M109 S%d ; set temperature and wait for it to be reached\n",
		    s->first_layer_temperature);
	put(w, "G21 ; set units to millimeters\nG90 ; use absolute coordinates\n");
	put(w, "%s\n", s->use_relative_e_distances ? "M83 ; use relative distances for extrusion"
						   : "M82 ; use absolute distances for extrusion");
	put(w, "G92 E0\n");
	w->fan = -1;
	set_fan(w, 0);
}

/* The part after the last layer: final retraction, fan off, end G-code. */
static int put_end(struct gcodew *w)
{
	int rc = 0;

	/* Final retraction, left for the end G-code to undo. */
	w->nops = 0;
	if (w->pos_known && w->s->retract_length > 0) {
		rc = plan_retract(w);
		if (rc == 0)
			rc = emit_ops(w);
	}
	set_fan(w, 0);
	if (rc == 0)
		rc = put_expanded(w, w->s->end_filament_gcode, "end_filament_gcode",
				  w->nlayers ? w->nlayers - 1 : 0, w->layer_z);
	if (rc == 0)
		rc = put_expanded(w, w->s->end_gcode, "end_gcode", w->nlayers ? w->nlayers - 1 : 0,
				  w->layer_z);
	return rc;
}

/* Add the beads of layer l to the per-role sums of the header's widths
 * (in the order of the layers, so the sums do not depend on batching). */
static void add_widths(struct gcodew *w, const struct layer_paths *l)
{
	for (size_t pi = 0; pi < l->n; pi++) {
		const struct toolpath *p = &l->paths[pi];
		for (size_t k = 0; k + 1 < (p->closed ? p->n + 1 : p->n); k++) {
			const struct path_point *a = &p->pts[k], *b = &p->pts[trav(p, false, k + 1)];
			double d = hypot((double)(b->x - a->x), (double)(b->y - a->y));
			w->len[p->role] += d;
			w->area[p->role] += d * a->width;
		}
	}
}

/* The machine state before the first line: nothing known, fan unset. */
static void writer_start(struct gcodew *w)
{
	w->pos_known = false;
	w->spiral_below = false;
	w->px = w->py = w->pz = 0;
	w->nwipe = 0;
	w->ext_exact = w->r_exact = w->e_machine = 0;
	w->ext_units = w->r_units = w->epos_units = 0;
	w->xy_known = w->z_known = false;
	w->wx = w->wy = w->wz = 0;
	w->wf = 0;
	w->fan = -1;
	w->moves = 0;
	w->filament_mm = 0;
}

/* Append everything of body (rewound here) to fp. */
static int copy_body(FILE *body, FILE *fp, struct st_error *err)
{
	char buf[65536];
	size_t n;

	rewind(body);
	while ((n = fread(buf, 1, sizeof(buf), body)) > 0)
		if (fwrite(buf, 1, n, fp) != n)
			return st_error_set(err, ST_ERR_IO, "G-code: write failed: %s",
					    strerror(errno));
	if (ferror(body))
		return st_error_set(err, ST_ERR_IO, "G-code: cannot read back the temporary "
				    "file: %s", strerror(errno));
	return 0;
}

void gcodew_free(struct gcodew *w)
{
	if (!w)
		return;
	if (w->body)
		fclose(w->body);
	st_file_abort(&w->out); /* a file begun and never finished */
	est_planner_free(w->est);
	free(w->ops);
	free(w->wipe);
	free(w->done);
	travel_route_free(&w->route);
	free(w->start);
	free(w->start_filament);
	ph_vars_free(w->vars);
	free(w);
}

/*
 * The variables, the start texts expanded, and every other text expanded
 * once as it would be on its first use, so a mistake in any of them is
 * refused before the first layer rather than after the last.
 */
static int begin_texts(struct gcodew *w, struct st_error *err)
{
	const struct gcodew_settings *s = w->s;
	const char *const later[][2] = {{s->before_layer_gcode, "before_layer_gcode"},
					{s->layer_gcode, "layer_gcode"},
					{s->end_filament_gcode, "end_filament_gcode"},
					{s->end_gcode, "end_gcode"}};
	int rc;

	w->vars = writer_vars(s, w->nlayers, err);
	if (!w->vars)
		return err && err->code ? err->code : ST_ERR_NOMEM;
	rc = ph_expand(s->start_gcode, "start_gcode", w->vars, 0, &w->start, err);
	if (rc == 0)
		rc = ph_expand(s->start_filament_gcode, "start_filament_gcode", w->vars, 0,
			       &w->start_filament, err);
	for (size_t i = 0; rc == 0 && i < sizeof(later) / sizeof(later[0]); i++) {
		char *out = NULL;

		rc = set_layer_vars(w->vars, 0, s->first_layer_height, s->first_layer_height, err);
		if (rc == 0)
			rc = ph_expand(later[i][0], later[i][1], w->vars, 0, &out, err);
		free(out);
	}
	return rc;
}

int gcodew_begin(const struct gcodew_settings *s, size_t nlayers, struct gcodew **out,
		 struct st_error *err)
{
	struct gcodew *w;
	int rc;

	if (!out)
		return st_error_set(err, ST_ERR_ARG, "G-code: gcodew_begin needs an out pointer");
	*out = NULL;
	if (!s)
		return st_error_set(err, ST_ERR_ARG, "G-code: no layers, settings or output given");
	rc = gcodew_settings_check(s, err);
	if (rc)
		return rc;
	w = calloc(1, sizeof(*w));
	if (!w)
		return st_error_set(err, ST_ERR_NOMEM, "G-code: out of memory");
	w->s = s;
	w->nlayers = nlayers;
	w->err = err;
	rc = begin_texts(w, err);
	if (rc)
		goto out_free;
	w->fil_area = M_PI * s->filament_diameter * s->filament_diameter / 4;

	/* One pass: the body into a temporary file, the estimator beside it. */
	w->body = tmpfile();
	if (!w->body) {
		rc = st_error_set(err, ST_ERR_IO, "G-code: cannot create a temporary file: %s",
				  strerror(errno));
		goto out_free;
	}
	w->est = est_planner_new(&s->limits, NULL, err);
	if (!w->est) {
		rc = err && err->code ? err->code : ST_ERR_NOMEM;
		goto out_free;
	}
	w->fp = w->body;
	writer_start(w);
	put_start(w);
	*out = w;
	return 0;
out_free:
	gcodew_free(w);
	return rc;
}

int gcodew_layer(struct gcodew *w, const struct layer_paths *l, struct st_error *err)
{
	if (!w || !l)
		return st_error_set(err, ST_ERR_ARG, "G-code: no writer or layer given");
	if (w->next >= w->nlayers)
		return st_error_set(err, ST_ERR_ARG, "G-code: layer %zu is one more than the %zu "
				    "announced", w->next + 1, w->nlayers);
	w->err = err;
	add_widths(w, l);
	return do_layer(w, l, w->next++);
}

int gcodew_finish(struct gcodew *w, FILE *fp, struct gcodew_summary *sum, struct st_error *err)
{
	struct gcodew_summary res = {0};
	struct est_result er;
	int rc;

	if (!w || !fp)
		return st_error_set(err, ST_ERR_ARG, "G-code: no writer or output given");
	if (w->next != w->nlayers)
		return st_error_set(err, ST_ERR_ARG, "G-code: %zu of the %zu layers announced were "
				    "written", w->next, w->nlayers);
	w->err = err;
	rc = put_end(w);
	est_planner_result(w->est, &er);
	if (rc == 0 && (fflush(w->body) != 0 || ferror(w->body)))
		rc = st_error_set(err, ST_ERR_IO, "G-code: write failed: %s", strerror(errno));
	if (rc)
		return rc;
	res.time_s = er.time_s;
	res.filament_mm = w->filament_mm;
	res.filament_cm3 = w->filament_mm * w->fil_area / 1000;
	res.filament_g = res.filament_cm3 * w->s->filament_density;
	res.layers = w->nlayers;
	res.moves = w->moves;

	/* The header first, then the body as generated. */
	w->fp = fp;
	put_header(w, &res);
	rc = copy_body(w->body, fp, err);
	if (rc == 0 && (fflush(fp) != 0 || ferror(fp)))
		rc = st_error_set(err, ST_ERR_IO, "G-code: write failed: %s", strerror(errno));
	if (rc == 0 && sum)
		*sum = res;
	return rc;
}

int gcodew_write_stream(const struct layer_stack *stack, const struct gcodew_settings *s,
			FILE *fp, struct gcodew_summary *sum, struct st_error *err)
{
	struct st_error local;
	struct gcodew *w = NULL;
	int rc;

	if (!err)
		err = &local;
	if (!stack || !s || !fp || (stack->nlayers && !stack->layers))
		return st_error_set(err, ST_ERR_ARG, "G-code: no layers, settings or output given");
	rc = gcodew_begin(s, stack->nlayers, &w, err);
	for (size_t li = 0; rc == 0 && li < stack->nlayers; li++)
		rc = gcodew_layer(w, &stack->layers[li], err);
	if (rc == 0)
		rc = gcodew_finish(w, fp, sum, err);
	gcodew_free(w);
	return rc;
}

int gcodew_begin_file(const struct gcodew_settings *s, size_t nlayers, const char *path,
		      struct gcodew **out, struct st_error *err)
{
	struct st_file_out o;
	int rc;

	if (!out)
		return st_error_set(err, ST_ERR_ARG, "G-code: gcodew_begin_file needs an out pointer");
	*out = NULL;
	if (!path || !*path)
		return st_error_set(err, ST_ERR_ARG, "G-code: no output file name given");
	if ((rc = st_file_begin(&o, path, err)))
		return rc;
	if ((rc = gcodew_begin(s, nlayers, out, err))) {
		st_file_abort(&o);
		return rc;
	}
	(*out)->out = o;
	return 0;
}

int gcodew_finish_file(struct gcodew *w, struct gcodew_summary *sum, struct st_error *err)
{
	int rc;

	if (!w || !w->out.f)
		return st_error_set(err, ST_ERR_ARG, "G-code: no writer of a file given");
	if ((rc = gcodew_finish(w, w->out.f, sum, err))) {
		st_file_abort(&w->out);
		return rc;
	}
	return st_file_commit(&w->out, err);
}

int gcodew_write_file(const struct layer_stack *stack, const struct gcodew_settings *s,
		      const char *path, struct gcodew_summary *sum, struct st_error *err)
{
	struct st_error local;
	struct gcodew *w = NULL;
	int rc;

	if (!err)
		err = &local;
	if (!path || !*path)
		return st_error_set(err, ST_ERR_ARG, "G-code: no output file name given");
	if (!stack || !s || (stack->nlayers && !stack->layers))
		return st_error_set(err, ST_ERR_ARG, "G-code: no layers, settings or output given");
	rc = gcodew_begin_file(s, stack->nlayers, path, &w, err);
	for (size_t li = 0; rc == 0 && li < stack->nlayers; li++)
		rc = gcodew_layer(w, &stack->layers[li], err);
	if (rc == 0)
		rc = gcodew_finish_file(w, sum, err);
	gcodew_free(w);
	return rc;
}
