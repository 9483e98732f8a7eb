/*
 * profile_out.c - a loaded profile written back: as a flat profile file
 * (profile_write, what `stratum printers --show` prints) and as JSON
 * (profile_to_json, `--json`).
 */
#include "profile_int.h"

#include <jansson.h>
#include <stdlib.h>
#include <string.h>


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

	prof_fmt_double(buf, sizeof(buf), v);
	fputs(buf, f);
}

/* Write n points as "XxY,XxY...". */
static void put_points(FILE *f, const struct profile_point *pt, size_t n)
{
	for (size_t i = 0; i < n; i++) {
		if (i)
			fputc(',', f);
		put_double(f, pt[i].x);
		fputc('x', f);
		put_double(f, pt[i].y);
	}
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
	case KT_FIRST_STRING:
		/* per filament in PrusaSlicer: quoted, or it splits the text at ';' */
		fputc('"', f);
		for (const char *c = *(const char *const *)field; *c; c++) {
			if (*c == '"')
				fputc('\\', f);
			put_escaped(f, (char[]){*c, '\0'});
		}
		fputc('"', f);
		break;
	case KT_DOUBLE:
	case KT_FIRST_DOUBLE:
	case KT_FIRST_HEIGHT:
	case KT_WIDTH:
		put_double(f, *(const double *)field);
		break;
	case KT_NUM_PCT:
		put_double(f, ((const struct profile_pct *)field)->value);
		if (((const struct profile_pct *)field)->is_percent)
			fputc('%', f);
		break;
	case KT_DENSITY:
		put_double(f, *(const double *)field);
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
		put_points(f, field, (size_t)ec);
		break;
	case KT_BED:
		put_points(f, p->bed_shape, p->bed_points);
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
	case KT_CHOICE:
		fputs(*(const char *const *)field, f);
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
	size_t ndefs;
	const struct key_def *defs = prof_defs(&ndefs);
	bool other = false;

	if (!p || !f)
		return ST_ERR_ARG;
	fprintf(f, "# %s, resolved by stratum from ", p->id);
	put_escaped(f, p->path);
	fputc('\n', f);
	fprintf(f, "# Every key the loader knows, defaults included.\n");
	for (size_t i = 0; i < ndefs; i++) {
		const struct key_def *d = &defs[i];

		if (prof_decl(d)->group)
			fprintf(f, "\n# %s\n", prof_decl(d)->group);
		if ((prof_decl(d)->flags & SETTING_SAILFISH) && p->protocol != PROFILE_PROTOCOL_SAILFISH &&
		    !prof_find_kv(p->keys, d->key))
			continue; /* unused by Marlin printers, not set: leave out */
		fprintf(f, "%s = ", d->key);
		put_value(f, p, d);
		fputc('\n', f);
	}
	for (size_t i = 0; p->keys && i < p->keys->count; i++) {
		const struct profile_kv *kv = &p->keys->kv[i];

		if (prof_find_def(kv->key))
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


/* A JSON string of s; bytes that are not valid UTF-8 become '?'. */
static json_t *json_text(const char *s)
{
	json_t *j = json_string(s);
	char *copy;

	if (j || !s)
		return j;
	copy = prof_dup(s, strlen(s)); /* invalid UTF-8: keep ASCII, mark the rest */
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
	case KT_FIRST_STRING:
		return json_text(*(const char *const *)field);
	case KT_DOUBLE:
	case KT_FIRST_DOUBLE:
	case KT_FIRST_HEIGHT:
	case KT_WIDTH:
		return json_real(*(const double *)field);
	case KT_NUM_PCT: {
		const struct profile_pct *sp = field;

		if (sp->is_percent) {
			char buf[48];
			prof_fmt_double(buf, sizeof(buf) - 1, sp->value);
			strcat(buf, "%");
			return json_string(buf);
		}
		return json_real(sp->value);
	}
	case KT_DENSITY:
		return json_real(*(const double *)field);
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
	case KT_CHOICE:
		return json_string(*(const char *const *)field);
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
	size_t ndefs;
	const struct key_def *defs = prof_defs(&ndefs);
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
	for (size_t i = 0; i < ndefs; i++) {
		const struct key_def *d = &defs[i];

		if ((prof_decl(d)->flags & SETTING_SAILFISH) && p->protocol != PROFILE_PROTOCOL_SAILFISH &&
		    !prof_find_kv(p->keys, d->key))
			continue;
		if (json_object_set_new(settings, d->key, json_value(p, d)))
			goto out_free;
	}
	for (size_t i = 0; p->keys && i < p->keys->count; i++)
		if (!prof_find_def(p->keys->kv[i].key) &&
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
