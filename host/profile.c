/*
 * profile.c - printer profiles: loading, freeing and raw key access
 * (profile.h).  Loading is two passes over memory: first the shared ini
 * reader (ini.h) splits the file into (key, decoded value, line number) with
 * duplicate checks; then every declared key is typed and range-checked
 * (profile_keys.c) and keys are checked against each other and against the
 * slicer's own check (profile_check.c).  Nothing is returned unless the
 * whole file passed.
 */
#include "profile_int.h"

#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include <sys/stat.h>

#include "ini.h"
#include "placeholder.h"
#include "st_grow.h"

/* ---------------------------------------------------------------------------
 * Helpers shared by the profile modules (profile_int.h)
 */

char *prof_dup(const char *s, size_t len)
{
	char *d = malloc(len + 1);

	if (!d)
		return NULL;
	memcpy(d, s, len);
	d[len] = '\0';
	return d;
}

void prof_trim(const char **s, size_t *len)
{
	while (*len && (**s == ' ' || **s == '\t')) {
		(*s)++;
		(*len)--;
	}
	while (*len && ((*s)[*len - 1] == ' ' || (*s)[*len - 1] == '\t'))
		(*len)--;
}

/* Shortest %g form of v that reads back exactly. */
void prof_fmt_double(char *buf, size_t cap, double v)
{
	snprintf(buf, cap, "%.15g", v);
	if (strtod(buf, NULL) != v)
		snprintf(buf, cap, "%.17g", v);
}

int prof_key_error(struct loader *L, const struct profile_kv *kv, const char *key, int code,
		   const char *fmt, ...)
{
	char msg[256];
	va_list ap;

	va_start(ap, fmt);
	vsnprintf(msg, sizeof(msg), fmt, ap);
	va_end(ap);
	if (kv && kv->line)
		return st_error_set(L->err, code, "%s: line %d: %s: %s",
				    kv->file ? kv->file : L->origin, kv->line, kv->key, msg);
	if (kv || key)
		return st_error_set(L->err, code, "%s: %s: %s",
				    kv && kv->file ? kv->file : L->origin, kv ? kv->key : key, msg);
	return st_error_set(L->err, code, "%s: %s", L->origin, msg);
}

/* ---------------------------------------------------------------------------
 * Pass 1: lines into key = value pairs
 */

/* Decode PrusaSlicer's C-style escapes: \n \r \\ \" ; any other \X is kept as is. */
static char *prof_decode_value(const char *s, size_t len)
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
struct profile_kv *prof_find_kv(const struct profile_keys *keys, const char *key)
{
	for (size_t i = 0; keys && i < keys->count; i++)
		if (!strcmp(keys->kv[i].key, key))
			return &keys->kv[i];
	return NULL;
}

/* Append one pair; takes ownership of key and value (frees them on failure). */
int prof_keys_add(struct profile_keys *keys, char *key, char *value, int line)
{
	struct profile_kv *kv = st_grow(keys->kv, &keys->cap, keys->count + 1, sizeof(*kv));

	if (!kv)
		goto out_free;
	keys->kv = kv;
	keys->kv[keys->count].key = key;
	keys->kv[keys->count].value = value;
	keys->kv[keys->count].line = line;
	keys->kv[keys->count].file = NULL;
	keys->count++;
	return 0;

out_free:
	free(key);
	free(value);
	return ST_ERR_NOMEM;
}

/* A section line: PrusaSlicer's bundles have them, a profile does not. */
static int on_section(void *ctx, int line, const char *s, size_t len, struct st_error *err)
{
	const struct loader *L = ctx;
	char tok[INI_SHOW_MAX];

	ini_show(tok, sizeof(tok), s, len);
	return st_error_set(err, ST_ERR_PARSE,
			    "%s: line %d: sections such as '%s' are not supported; a profile is "
			    "one flat key = value file (PrusaSlicer: File > Export > Export Config)",
			    L->origin, line, tok);
}

int prof_add_entry(struct profile_keys *keys, const struct ini_entry *e, const char *origin,
		   struct st_error *err)
{
	struct profile_kv *prev;
	char *k, *v;

	k = prof_dup(e->key, e->key_len);
	if (!k)
		return st_error_set(err, ST_ERR_NOMEM, "%s: line %d: out of memory", origin, e->line);
	prev = prof_find_kv(keys, k);
	if (prev) {
		int first = prev->line;
		free(k);
		return st_error_set(err, ST_ERR_PARSE,
				    "%s: line %d: duplicate key '%.*s' (first set on line %d)", origin,
				    e->line, (int)(e->key_len > 64 ? 64 : e->key_len), e->key, first);
	}
	v = prof_decode_value(e->value, e->value_len);
	if (!v) {
		free(k);
		return st_error_set(err, ST_ERR_NOMEM, "%s: line %d: out of memory", origin, e->line);
	}
	if (prof_keys_add(keys, k, v, e->line))
		return st_error_set(err, ST_ERR_NOMEM, "%s: line %d: out of memory", origin, e->line);
	return 0;
}

/* A key = value line of a profile file. */
static int on_entry(void *ctx, const struct ini_entry *e, struct st_error *err)
{
	struct loader *L = ctx;

	return prof_add_entry(L->p->keys, e, L->origin, err);
}

/* ---------------------------------------------------------------------------
 * Loading
 */

/*
 * The placeholder variables: PrusaSlicer gives the custom G-code every key
 * of its config, so every key of the file is one, typed from its text;
 * declared keys the file leaves out give their default, and the preset
 * names PrusaSlicer always sets are empty unless the file names them.
 * The G-code writer puts the values it prints with above these.
 */
int prof_build_vars(struct profile *p, struct st_error *err)
{
	static const char *const ids[] = {"print_settings_id", "filament_settings_id",
					  "printer_settings_id"};
	int rc = 0;

	ph_vars_free(p->vars);
	p->vars = ph_vars_new(NULL);
	if (!p->vars)
		return st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", p->path);
	for (size_t i = 0; rc == 0 && i < p->keys->count; i++)
		rc = ph_vars_set_config(p->vars, p->keys->kv[i].key, p->keys->kv[i].value, err);
	for (size_t i = 0; rc == 0 && i < settings_count(); i++) {
		const struct setting *s = settings_at(i);
		const char *d = s->dflt;

		if (!ph_vars_has(p->vars, s->name) && d && *d)
			rc = ph_vars_set_config(p->vars, s->name, d, err);
	}
	for (size_t i = 0; rc == 0 && i < sizeof(ids) / sizeof(ids[0]); i++) {
		const char *empty = "";

		if (!ph_vars_has(p->vars, ids[i]))
			rc = ph_vars_set_strings(p->vars, ids[i], &empty, 1, i == 1, err);
	}
	if (rc == 0 && !ph_vars_has(p->vars, "printer_model"))
		rc = ph_vars_set_strings(p->vars, "printer_model", &p->printer_model, 1, false, err);
	if (rc == 0) { /* PrusaSlicer's bed box variables, from bed_shape */
		double lo[2] = {p->bed_min_x, p->bed_min_y}, hi[2] = {p->bed_max_x, p->bed_max_y};
		double size[2] = {hi[0] - lo[0], hi[1] - lo[1]};

		rc = ph_vars_set_numbers(p->vars, "print_bed_min", PH_REAL, lo, 2, true, err);
		if (rc == 0)
			rc = ph_vars_set_numbers(p->vars, "print_bed_max", PH_REAL, hi, 2, true, err);
		if (rc == 0)
			rc = ph_vars_set_numbers(p->vars, "print_bed_size", PH_REAL, size, 2, true, err);
	}
	return rc;
}

/* The id: base name of origin without a trailing ".ini" (or the ".3mf" of a
 * PrusaSlicer project whose settings are loaded). */
static char *id_of(const char *origin)
{
	const char *base = strrchr(origin, '/');
	size_t len;

	base = base ? base + 1 : origin;
	len = strlen(base);
	if (len > 4 && (!strcmp(base + len - 4, ".ini") || !strcmp(base + len - 4, ".3mf")))
		len -= 4;
	return prof_dup(base, len);
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
		for (size_t i = 0; i < p->keys->nfiles; i++)
			free(p->keys->files[i]);
		free(p->keys->files);
		free(p->keys->kv);
		free(p->keys);
	}
	ph_vars_free(p->vars);
	free(p->bed_shape);
	free((char *)p->id);
	free((char *)p->path);
	free(p);
}

struct profile *prof_new(const char *origin, struct st_error *err)
{
	struct profile *p = calloc(1, sizeof(*p));

	if (!p) {
		st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", origin);
		return NULL;
	}
	p->keys = calloc(1, sizeof(*p->keys));
	p->id = id_of(origin);
	p->path = prof_dup(origin, strlen(origin));
	p->extruder_count = 1;
	if (!p->keys || !p->id || !p->path) {
		st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", origin);
		profile_free(p);
		return NULL;
	}
	p->name = p->id;
	if (prof_set_defaults(p, false)) {
		st_error_set(err, ST_ERR_INTERNAL, "%s: the declared defaults do not load", origin);
		profile_free(p);
		return NULL;
	}
	return p;
}

int prof_finish(struct profile *p, const char *origin, struct profile **out,
		struct st_error *err)
{
	struct loader L = {.p = p, .origin = origin, .err = err};
	int rc = prof_apply_all(&L);

	if (rc) {
		profile_free(p);
		return rc;
	}
	*out = p;
	return 0;
}

int profile_load_buffer(const char *text, size_t len, const char *origin, struct profile **out,
			struct st_error *err)
{
	static const struct ini_handler handler = {on_section, on_entry, false, false};
	struct loader L = {0};
	struct profile *p;
	int rc;

	if (!out || (!text && len) || !origin)
		return st_error_set(err, ST_ERR_ARG, "profile_load_buffer: bad arguments");
	*out = NULL;
	p = prof_new(origin, err);
	if (!p)
		return err && err->code ? err->code : ST_ERR_NOMEM;
	L.p = p;
	L.origin = origin;
	L.err = err;
	rc = ini_parse(text, len, origin, &handler, &L, err);
	if (rc) {
		profile_free(p);
		return rc;
	}
	return prof_finish(p, origin, out, err);
}

int profile_load_file(const char *path, struct profile **out, struct st_error *err)
{
	struct stat st;
	char *buf;
	size_t len;
	int rc;

	if (!out || !path)
		return st_error_set(err, ST_ERR_ARG, "profile_load_file: bad arguments");
	*out = NULL;
	if (stat(path, &st) == 0 && S_ISDIR(st.st_mode))
		return st_error_set(err, ST_ERR_IO, "%s: is a directory, not a printer profile",
				    path);
	rc = ini_read_file(path, &buf, &len, err);
	if (rc)
		return rc;
	rc = profile_load_buffer(buf, len, path, out, err);
	free(buf);
	return rc;
}

/* ---------------------------------------------------------------------------
 * Raw access
 */

const char *profile_printer_name(const struct profile *p)
{
	const char *preset = profile_get(p, "printer_settings_id");

	return preset && *preset ? preset : p->id;
}

const char *profile_get(const struct profile *p, const char *key)
{
	const struct profile_kv *kv = p && key ? prof_find_kv(p->keys, key) : NULL;

	return kv ? kv->value : NULL;
}

/* The declared name of an enum value, "?" when out of range. */
static const char *name_of(const char *key, size_t i)
{
	const struct setting *s = settings_find(key);

	return i < s->nnames ? s->names[i] : "?";
}

const char *profile_protocol_name(enum profile_protocol protocol)
{
	return name_of("protocol", (size_t)protocol);
}

const char *profile_flavor_name(enum profile_flavor flavor)
{
	return name_of("gcode_flavor", (size_t)flavor);
}

const char *profile_home_name(enum profile_home dir)
{
	return name_of("home_direction_x", (size_t)dir);
}

