/*
 * profile_check.c - pass 2 of loading in order (extruder count and
 * protocol first, then every key), checks between a profile's keys (layer height against
 * nozzle, protocol against G-code flavor ...) and, last, the slicer's own
 * check of the settings it would slice with, so a profile that loads is one
 * that slices (profile_int.h).
 */
#include "profile_int.h"

#include "ini.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "gcode_writer.h"
#include "profile_slicer.h"
#include "thumbnail.h"

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

/* Where a value came from, for cross-check messages: " (line N)" or " (default)". */
static void origin_of(const struct profile *p, const char *key, char *buf, size_t cap)
{
	const struct profile_kv *kv = prof_find_kv(p->keys, key);

	if (kv && kv->file)
		snprintf(buf, cap, " (%s%s%.0d)", kv->file, kv->line ? " line " : "", kv->line);
	else if (kv)
		snprintf(buf, cap, " (line %d)", kv->line);
	else
		snprintf(buf, cap, " (default)");
}

/* Report a conflict between two keys at the first key's line, or the second's. */
static int conflict(struct loader *L, const char *key, const char *other, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

static int conflict(struct loader *L, const char *key, const char *other, const char *fmt, ...)
{
	const struct profile_kv *kv = prof_find_kv(L->p->keys, key);
	char msg[512];
	va_list ap;

	va_start(ap, fmt);
	vsnprintf(msg, sizeof(msg), fmt, ap);
	va_end(ap);
	if (!kv && other) {
		const struct profile_kv *okv = prof_find_kv(L->p->keys, other);
		if (okv)
			return prof_key_error(L, okv, NULL, ST_ERR_RANGE, "%s", msg);
	}
	return kv ? prof_key_error(L, kv, NULL, ST_ERR_RANGE, "%s", msg)
		  : prof_key_error(L, NULL, key, ST_ERR_RANGE, "%s", msg);
}

/* Checks between keys, once every value is read; resolves the percentages. */
static int keys_agree(struct loader *L, const struct pending *pend)
{
	struct profile *p = L->p;
	char a[32], b[32], o1[200], o2[200];
	double min_nozzle = p->nozzle_diameter[0];
	int ec = p->extruder_count;

	for (int i = 1; i < ec; i++)
		if (p->nozzle_diameter[i] < min_nozzle)
			min_nozzle = p->nozzle_diameter[i];

	struct thumb_size sizes[THUMB_SIZES_MAX];
	size_t nsizes;
	struct st_error terr = {0};
	if (thumb_parse(p->thumbnails, sizes, &nsizes, &terr)) {
		const struct profile_kv *tkv = prof_find_kv(p->keys, "thumbnails");
		return prof_key_error(L, tkv, tkv ? NULL : "thumbnails", ST_ERR_RANGE, "%s",
				      terr.msg);
	}

	if (pend->flh_pct)
		p->first_layer_height = pend->flh / 100 * p->layer_height;
	if (pend->width_pct)
		p->extrusion_width = pend->width / 100 * p->layer_height;
	else if (prof_find_kv(p->keys, "extrusion_width"))
		p->extrusion_width = pend->width;
	if (!pend->flh_pct && prof_find_kv(p->keys, "first_layer_height"))
		p->first_layer_height = pend->flh;

	prof_fmt_double(b, sizeof(b), min_nozzle);
	origin_of(p, "nozzle_diameter", o2, sizeof(o2));
	if (p->layer_height > min_nozzle) {
		prof_fmt_double(a, sizeof(a), p->layer_height);
		origin_of(p, "layer_height", o1, sizeof(o1));
		return conflict(L, "layer_height", "nozzle_diameter",
				"layer_height %s mm%s is larger than the nozzle, %s mm%s", a, o1, b,
				o2);
	}
	if (!(p->first_layer_height > 0) || p->first_layer_height > min_nozzle) {
		prof_fmt_double(a, sizeof(a), p->first_layer_height);
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
		prof_fmt_double(b, sizeof(b), nz);
		if (p->min_layer_height[i] > nz || p->max_layer_height[i] > nz) {
			bool lo = p->min_layer_height[i] > nz;
			prof_fmt_double(a, sizeof(a),
				   lo ? p->min_layer_height[i] : p->max_layer_height[i]);
			return conflict(
			    L, lo ? "min_layer_height" : "max_layer_height", "nozzle_diameter",
			    "extruder %d: %s mm is larger than its nozzle, %s mm", i + 1, a, b);
		}
		if (p->min_layer_height[i] > p->max_layer_height[i]) {
			prof_fmt_double(a, sizeof(a), p->min_layer_height[i]);
			prof_fmt_double(b, sizeof(b), p->max_layer_height[i]);
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
					profile_flavor_name(p->gcode_flavor));
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
				profile_flavor_name(p->gcode_flavor));
	}
	return 0;
}

/* Checks between keys and the slicer's own check, once every value is read. */
static int prof_cross_check(struct loader *L, const struct pending *pend)
{
	struct slicer_config c;
	struct st_error e = {0};
	int rc;

	bed_box(L->p);
	rc = keys_agree(L, pend);
	if (rc)
		return rc;
	/* Derived values (a percentage first-layer speed, half the perimeter
	 * speed ...) meet the same declared ranges in the G-code writer's check:
	 * refused here, in milliseconds, not after repair and slicing. */
	rc = profile_slicer_config(L->p, &c, &e);
	if (!rc)
		rc = gcodew_settings_check(&c.gcodew, &e);
	if (rc)
		return prof_key_error(L, NULL, NULL, rc, "cannot be sliced: %s", e.msg);
	return 0;
}

/* Extruder count: extruder_count, else the length of nozzle_diameter, else 1. */
static int resolve_extruders(struct loader *L, struct pending *pend)
{
	struct profile *p = L->p;
	const struct profile_kv *kv = prof_find_kv(p->keys, "extruder_count");
	struct item items[PROFILE_MAX_EXTRUDERS];
	int n;

	if (kv) {
		L->ec_kv = kv;
		L->ec_key = "extruder_count";
		return prof_apply_key(L, prof_find_def("extruder_count"), kv, pend);
	}
	kv = prof_find_kv(p->keys, "nozzle_diameter");
	if (!kv)
		return 0;
	n = prof_split_list(L, kv, items, PROFILE_MAX_EXTRUDERS);
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
	const struct profile_kv *proto = prof_find_kv(p->keys, "protocol");
	const struct profile_kv *flavor = prof_find_kv(p->keys, "gcode_flavor");
	int rc;

	if (flavor) {
		rc = prof_apply_key(L, prof_find_def("gcode_flavor"), flavor, pend);
		if (rc)
			return rc;
	}
	if (proto) {
		rc = prof_apply_key(L, prof_find_def("protocol"), proto, pend);
		if (rc)
			return rc;
	} else if (flavor && (p->gcode_flavor == PROFILE_FLAVOR_SAILFISH ||
			      p->gcode_flavor == PROFILE_FLAVOR_MAKERWARE)) {
		p->protocol = PROFILE_PROTOCOL_SAILFISH;
	}
	if (p->protocol == PROFILE_PROTOCOL_SAILFISH) {
		enum profile_flavor f = p->gcode_flavor;
		rc = prof_set_defaults(p, true);
		if (rc)
			return prof_key_error(L, NULL, NULL, rc, "the sailfish defaults do not load");
		if (flavor)
			p->gcode_flavor = f;
	}
	return 0;
}

/*
 * Cut the comment after the value of every known key that is not text
 * ("layer_height = 0.2   ; fine", "fill_pattern = gyroid # strong"), in
 * place, before anything reads the values: the typed fields, --show and the
 * placeholder variables all see the value alone.  Text (names, G-code,
 * per-filament "a";"b") keeps its ' ;' and ' #' (ini.h).
 */
static void cut_comments(struct profile *p, const struct key_def *defs, size_t ndefs)
{
	for (size_t i = 0; i < ndefs; i++) {
		const struct profile_kv *kv;
		size_t len;

		if (defs[i].type == KT_STRING || defs[i].type == KT_FIRST_STRING)
			continue;
		kv = prof_find_kv(p->keys, defs[i].key);
		if (!kv)
			continue;
		len = ini_comment_at(kv->value, strlen(kv->value));
		while (len && (kv->value[len - 1] == ' ' || kv->value[len - 1] == '\t'))
			len--;
		kv->value[len] = '\0';
	}
}

/* Pass 2: type every known key, derive defaults that follow other keys, check. */
int prof_apply_all(struct loader *L)
{
	struct profile *p = L->p;
	struct pending pend = {false, false, p->first_layer_height, 0};
	size_t ndefs;
	const struct key_def *defs = prof_defs(&ndefs);
	int rc;

	cut_comments(p, defs, ndefs);
	rc = resolve_extruders(L, &pend);
	if (rc)
		return rc;
	rc = resolve_protocol(L, &pend);
	if (rc)
		return rc;
	for (size_t i = 0; i < ndefs; i++) {
		const struct key_def *d = &defs[i];
		const struct profile_kv *kv;

		if (d->type == KT_EXTRUDERS || d->type == KT_PROTOCOL || d->type == KT_FLAVOR)
			continue;
		kv = prof_find_kv(p->keys, d->key);
		if (!kv)
			continue;
		rc = prof_apply_key(L, d, kv, &pend);
		if (rc)
			return rc;
	}
	if (!prof_find_kv(p->keys, "first_layer_temperature"))
		memcpy(p->first_layer_temperature, p->temperature, sizeof(p->temperature));
	if (!prof_find_kv(p->keys, "first_layer_bed_temperature"))
		p->first_layer_bed_temperature = p->bed_temperature;
	rc = prof_cross_check(L, &pend);
	if (rc)
		return rc;
	return prof_build_vars(p, L->err);
}
