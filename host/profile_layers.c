/*
 * profile_layers.c - a profile made of layers (profile.h,
 * profile_load_layers): a printer profile, then config files in order, each
 * a flat PrusaSlicer config or a vendor bundle with presets, then single
 * KEY=VALUE overrides.  A later layer's key replaces an earlier one's, as
 * PrusaSlicer's repeated --load does; every key remembers the file and line
 * that set it, for messages.
 *
 * Bundles (PrusaSlicer's profiles/VENDOR.ini): [printer:NAME], [print:NAME]
 * and [filament:NAME] sections, resolved through `inherits` (parents
 * separated by ';', applied left to right, then the preset's own keys;
 * names in *stars* are abstract presets).  [vendor] and [printer_model:...]
 * sections describe the bundle and set no print setting.  The printer
 * preset's default_print_profile and default_filament_profile pick the
 * others unless named; when the bundle has no preset of that name (or the
 * printer names none), the first non-abstract one compatible with the
 * printer (its compatible_printers list, else its
 * compatible_printers_condition on the printer's keys), as PrusaSlicer
 * picks one.
 */
#include "profile_int.h"

#include <stdlib.h>
#include <string.h>

#include "ini.h"
#include "meshio.h"
#include "placeholder.h"
#include "st_append.h"
#include "st_grow.h"

#define BUNDLE_DEPTH_MAX 16 /* inherits chains longer than this are a loop */

/* One section of a file: its name ("" before the first) and its keys. */
struct section {
	char *name;
	struct profile_keys keys;
};

struct file_read {
	const char *path;
	struct section *sec;
	size_t n, cap;
};

static void sections_free(struct file_read *f)
{
	for (size_t i = 0; i < f->n; i++) {
		for (size_t k = 0; k < f->sec[i].keys.count; k++) {
			free(f->sec[i].keys.kv[k].key);
			free(f->sec[i].keys.kv[k].value);
		}
		free(f->sec[i].keys.kv);
		free(f->sec[i].name);
	}
	free(f->sec);
}

static int add_section(struct file_read *f, const char *name, size_t len, struct st_error *err)
{
	struct section *grown = st_grow(f->sec, &f->cap, f->n + 1, sizeof(*grown));

	if (!grown)
		return st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", f->path);
	f->sec = grown;
	memset(&f->sec[f->n], 0, sizeof(f->sec[0]));
	f->sec[f->n].name = prof_dup(name, len);
	if (!f->sec[f->n].name)
		return st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", f->path);
	f->n++;
	return 0;
}

static int on_section(void *ctx, int line, const char *s, size_t len, struct st_error *err)
{
	struct file_read *f = ctx;

	if (len < 2 || s[len - 1] != ']')
		return st_error_set(err, ST_ERR_PARSE, "%s: line %d: a section line ends in ']'",
				    f->path, line);
	return add_section(f, s + 1, len - 2, err);
}

/* A key = value line of the current section; a duplicate in one section is refused. */
static int on_entry(void *ctx, const struct ini_entry *e, struct st_error *err)
{
	struct file_read *f = ctx;

	return prof_add_entry(&f->sec[f->n - 1].keys, e, f->path, err);
}

/* An origin string owned by the profile's key list. */
static const char *own_file(struct profile_keys *keys, const char *file)
{
	char **grown;

	for (size_t i = 0; i < keys->nfiles; i++)
		if (!strcmp(keys->files[i], file))
			return keys->files[i];
	grown = st_grow(keys->files, &keys->files_cap, keys->nfiles + 1, sizeof(*grown));
	if (!grown)
		return NULL;
	keys->files = grown;
	grown[keys->nfiles] = strdup(file);
	return grown[keys->nfiles] ? grown[keys->nfiles++] : NULL;
}

/* Set key to value from file:line, replacing an earlier layer's. */
static int set_key(struct profile *p, const char *key, const char *value, const char *file,
		   int line, struct st_error *err)
{
	struct profile_kv *kv = prof_find_kv(p->keys, key);
	const char *f = own_file(p->keys, file);
	char *v = strdup(value);

	if (!f || !v) {
		free(v);
		return st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", file);
	}
	if (kv) {
		free(kv->value);
		kv->value = v;
	} else {
		char *k = strdup(key);

		if (!k || prof_keys_add(p->keys, k, v, line)) {
			if (!k)
				free(v);
			return st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", file);
		}
		kv = &p->keys->kv[p->keys->count - 1];
	}
	kv->line = line;
	kv->file = f;
	return 0;
}

static const struct section *find_section(const struct file_read *f, const char *kind,
					  const char *name, size_t len)
{
	size_t kl = strlen(kind);

	for (size_t i = 0; i < f->n; i++) {
		const char *s = f->sec[i].name;
		if (!strncmp(s, kind, kl) && s[kl] == ':' && strlen(s + kl + 1) == len &&
		    !memcmp(s + kl + 1, name, len))
			return &f->sec[i];
	}
	return NULL;
}

/* A preset name as PrusaSlicer writes it in a value: quotes removed. */
static void unquote(const char **s, size_t *len)
{
	prof_trim(s, len);
	if (*len >= 2 && (*s)[0] == '"' && (*s)[*len - 1] == '"') {
		(*s)++;
		*len -= 2;
	}
}

/* Apply preset name of kind (its parents first) to p. */
static int apply_preset(struct profile *p, const struct file_read *f, const char *kind,
			const char *name, size_t len, int depth, struct st_error *err)
{
	const struct section *sec = find_section(f, kind, name, len);
	const struct profile_kv *inh;
	int rc = 0;

	if (!sec)
		return st_error_set(err, ST_ERR_ARG, "%s: no [%s:%.*s] preset%s", f->path, kind,
				    (int)(len > 80 ? 80 : len), name,
				    depth ? " (named by inherits)" : "");
	if (depth > BUNDLE_DEPTH_MAX)
		return st_error_set(err, ST_ERR_PARSE, "%s: [%s:%s]: inherits loops", f->path, kind,
				    sec->name);
	inh = prof_find_kv(&sec->keys, "inherits");
	if (inh) {
		const char *s = inh->value;

		while (rc == 0 && *s) {
			const char *semi = strchr(s, ';');
			size_t n = semi ? (size_t)(semi - s) : strlen(s);
			const char *t = s;

			unquote(&t, &n);
			if (n)
				rc = apply_preset(p, f, kind, t, n, depth + 1, err);
			s = semi ? semi + 1 : s + strlen(s);
		}
	}
	for (size_t i = 0; rc == 0 && i < sec->keys.count; i++) {
		const struct profile_kv *kv = &sec->keys.kv[i];

		if (strcmp(kv->key, "inherits"))
			rc = set_key(p, kv->key, kv->value, f->path, kv->line, err);
	}
	return rc;
}

/* The value of key that the printer preset resolved to, unquoted, or NULL. */
static const char *resolved(const struct profile *p, const char *key, size_t *len)
{
	const struct profile_kv *kv = prof_find_kv(p->keys, key);
	const char *s;

	if (!kv)
		return NULL;
	s = kv->value;
	*len = strlen(s);
	if (*len && s[0] == '"') { /* a list "a";"b": the first */
		const char *end = strstr(s + 1, "\";\"");
		if (end)
			*len = (size_t)(end - s) + 1;
	}
	unquote(&s, len);
	return *len ? s : NULL;
}

/* The value of key in preset sec of kind through its inherits (its own key,
 * else the last parent that has it), or NULL. */
static const char *preset_value(const struct file_read *f, const char *kind,
				const struct section *sec, const char *key, int depth)
{
	const struct profile_kv *kv = prof_find_kv(&sec->keys, key);
	const char *found = NULL;

	if (kv)
		return kv->value;
	if (depth > BUNDLE_DEPTH_MAX || !(kv = prof_find_kv(&sec->keys, "inherits")))
		return NULL;
	for (const char *s = kv->value; *s;) {
		const char *semi = strchr(s, ';'), *t = s, *v;
		size_t n = semi ? (size_t)(semi - s) : strlen(s);
		const struct section *parent;

		unquote(&t, &n);
		if (n && (parent = find_section(f, kind, t, n)) &&
		    (v = preset_value(f, kind, parent, key, depth + 1)))
			found = v;
		s = semi ? semi + 1 : s + strlen(s);
	}
	return found;
}

/* Is preset sec of kind for printer (p's keys so far): in its
 * compatible_printers list, else true by its compatible_printers_condition? */
static bool compatible(struct profile *p, const struct file_read *f, const char *kind,
		       const struct section *sec, const char *printer)
{
	const char *list = preset_value(f, kind, sec, "compatible_printers", 0);
	const char *cond = preset_value(f, kind, sec, "compatible_printers_condition", 0);
	struct st_error e = {0};
	bool ok = false;

	if (list && *list) {
		size_t n = strlen(printer);
		for (const char *at = strstr(list, printer); at; at = strstr(at + 1, printer))
			if ((at == list || at[-1] == '"' || at[-1] == ';') &&
			    (!at[n] || at[n] == '"' || at[n] == ';'))
				return true;
		return false;
	}
	if (!cond || !*cond)
		return true;
	size_t len = strlen(cond);
	char *expr = prof_dup(cond, len);
	if (!expr)
		return false;
	if (len >= 2 && expr[0] == '"' && expr[len - 1] == '"') {
		memmove(expr, expr + 1, len - 2);
		expr[len - 2] = '\0';
	}
	/* a condition that does not evaluate (a variable we lack) does not match */
	if (ph_eval_bool(expr, "compatible_printers_condition", p->vars, &ok, &e))
		ok = false;
	free(expr);
	return ok;
}

/* PrusaSlicer's choice when the printer's default preset of kind is missing:
 * the first non-abstract one compatible with it, one whose name starts with
 * the default's (want, wlen: "0.15mm 0.4nozzle" for "0.15mm 0.4nozzle V2")
 * first; NULL when none is. */
static const char *first_compatible(struct profile *p, const struct file_read *f,
				    const char *kind, const char *printer, const char *want,
				    size_t wlen, size_t *len)
{
	size_t kl = strlen(kind);

	for (int pass = want && wlen ? 0 : 1; pass < 2; pass++)
		for (size_t i = 0; i < f->n; i++) {
			const char *s = f->sec[i].name;

			if (strncmp(s, kind, kl) || s[kl] != ':' || s[kl + 1] == '*' ||
			    (pass == 0 && strncmp(s + kl + 1, want, wlen)))
				continue;
			if (compatible(p, f, kind, &f->sec[i], printer)) {
				*len = strlen(s + kl + 1);
				return s + kl + 1;
			}
		}
	return NULL;
}

/* The printers of a bundle, for the message when none is named. */
static void list_printers(const struct file_read *f, char *buf, size_t cap)
{
	size_t shown = 0;

	buf[0] = '\0';
	for (size_t i = 0; i < f->n; i++) {
		const char *s = f->sec[i].name;
		if (strncmp(s, "printer:", 8) || s[8] == '*')
			continue;
		if (shown++ == 3) {
			st_appendf(buf, cap, ", ...");
			return;
		}
		st_appendf(buf, cap, "%s'%s'", shown > 1 ? ", " : "", s + 8);
	}
}

/* A bundle: the printer preset, then its print and filament presets. */
static int apply_bundle(struct profile *p, const struct file_read *f,
			const struct profile_presets *pre, struct st_error *err)
{
	const char *kinds[] = {"print", "filament"};
	const char *names[2] = {pre ? pre->print : NULL, pre ? pre->filament : NULL};
	const char *dflt[] = {"default_print_profile", "default_filament_profile"};
	const char *ids[] = {"print_settings_id", "filament_settings_id"};
	char list[300];
	bool vars_built = false;
	int rc;

	if (!pre || !pre->printer) {
		list_printers(f, list, sizeof(list));
		return st_error_set(err, ST_ERR_ARG,
				    "%s is a PrusaSlicer bundle; choose its printer with "
				    "--printer-preset NAME (%s)",
				    f->path, list);
	}
	rc = apply_preset(p, f, "printer", pre->printer, strlen(pre->printer), 0, err);
	if (rc == 0)
		rc = set_key(p, "printer_settings_id", pre->printer, f->path, 0, err);
	for (int k = 0; rc == 0 && k < 2; k++) {
		size_t len = 0;
		const char *name = names[k];
		char *copy;

		if (name) {
			len = strlen(name);
		} else if ((name = resolved(p, dflt[k], &len))) {
			/* a multi-extruder printer's default filaments: "A; B"; the
			 * first extruder's prints */
			const char *semi = memchr(name, ';', len);
			if (semi)
				len = (size_t)(semi - name);
		}
		if (!names[k] && (!name || !find_section(f, kinds[k], name, len))) {
			/* the condition sees the printer's keys */
			if (!vars_built && (rc = prof_build_vars(p, err)))
				return rc;
			vars_built = true;
			name = first_compatible(p, f, kinds[k], pre->printer, name, name ? len : 0,
						&len);
		}
		if (!name)
			return st_error_set(err, ST_ERR_ARG,
					    "%s: printer '%s' names no %s preset; choose one with "
					    "--%s-preset NAME",
					    f->path, pre->printer, kinds[k], kinds[k]);
		copy = prof_dup(name, len);
		if (!copy)
			return st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", f->path);
		rc = apply_preset(p, f, kinds[k], copy, len, 0, err);
		if (rc == 0 && k == 1) { /* per filament in PrusaSlicer: a list of one */
			char *q = malloc(len + 3);

			if (!q)
				rc = st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", f->path);
			else {
				snprintf(q, len + 3, "\"%s\"", copy);
				rc = set_key(p, ids[k], q, f->path, 0, err);
				free(q);
			}
		} else if (rc == 0) {
			rc = set_key(p, ids[k], copy, f->path, 0, err);
		}
		free(copy);
	}
	return rc;
}

/* Whether path opens like a zip archive, as a 3MF does (meshio's rule). */
static bool opens_like_zip(const char *path)
{
	unsigned char magic[4] = {0};
	FILE *f = fopen(path, "rb");

	if (!f)
		return false;
	if (fread(magic, 1, sizeof(magic), f) != sizeof(magic))
		magic[0] = 0;
	fclose(f);
	return !memcmp(magic, "PK\3\4", 4);
}

/* A "; key = value" line (PrusaSlicer's config comment), not "; generated by". */
static bool is_key_comment(const char *line)
{
	size_t key;

	if (line[0] != ';' || line[1] != ' ')
		return false;
	key = strspn(line + 2, "abcdefghijklmnopqrstuvwxyz0123456789_");
	return key && line[2 + key + strspn(line + 2 + key, " \t")] == '=';
}

/*
 * The settings PrusaSlicer saves in a project 3MF (MESHIO_3MF_CONFIG_ENTRY),
 * one "; key = value" line per key (its G-code footer's form), read as a
 * flat config by turning each such "; " into blanks, so line numbers stay
 * the entry's.  *origin names the entry for messages (caller frees).
 */
static int read_3mf_config(const char *path, char **text, size_t *len, char **origin,
			   struct st_error *err)
{
	int rc = meshio_3mf_config(path, text, err);

	if (rc)
		return rc;
	if (!*text)
		return st_error_set(err, ST_ERR_PARSE,
				    "%s: a 3MF without PrusaSlicer settings (no " MESHIO_3MF_CONFIG_ENTRY
				    ": PrusaSlicer saves them with a project, not with "
				    "--export-3mf), so there is nothing to load",
				    path);
	*len = strlen(*text);
	for (char *line = *text, *end; line; line = end ? end + 1 : NULL) {
		end = strchr(line, '\n');
		if (is_key_comment(line))
			line[0] = line[1] = ' ';
	}
	*origin = malloc(strlen(path) + sizeof(MESHIO_3MF_CONFIG_ENTRY) + 2);
	if (!*origin) {
		free(*text);
		*text = NULL;
		return st_error_set(err, ST_ERR_NOMEM, "out of memory");
	}
	sprintf(*origin, "%s: %s", path, MESHIO_3MF_CONFIG_ENTRY);
	return 0;
}

/* One --load file: a flat config, or a bundle (it has preset sections), or
 * the settings a PrusaSlicer project 3MF carries. */
static int apply_file(struct profile *p, const char *path, const struct profile_presets *pre,
		      struct st_error *err)
{
	static const struct ini_handler handler = {on_section, on_entry, false, true};
	struct file_read f = {.path = path};
	bool bundle = false;
	char *text, *origin = NULL;
	size_t len;
	int rc;

	if (opens_like_zip(path))
		rc = read_3mf_config(path, &text, &len, &origin, err);
	else
		rc = ini_read_file(path, &text, &len, err);
	if (rc)
		return rc;
	if (origin)
		f.path = path = origin;
	rc = add_section(&f, "", 0, err);
	if (rc == 0)
		rc = ini_parse(text, len, path, &handler, &f, err);
	free(text);
	for (size_t i = 1; rc == 0 && i < f.n; i++)
		if (!strncmp(f.sec[i].name, "printer:", 8) || !strncmp(f.sec[i].name, "print:", 6) ||
		    !strncmp(f.sec[i].name, "filament:", 9))
			bundle = true;
	if (rc == 0 && bundle) {
		rc = apply_bundle(p, &f, pre, err);
	} else if (rc == 0) {
		const struct profile_keys *top = &f.sec[0].keys;

		if (f.n > 1)
			rc = st_error_set(err, ST_ERR_PARSE,
					  "%s: sections such as '[%s]' but no [printer:], [print:] "
					  "or [filament:] preset: neither a config nor a bundle",
					  path, f.sec[1].name);
		for (size_t i = 0; rc == 0 && i < top->count; i++)
			rc = set_key(p, top->kv[i].key, top->kv[i].value, path, top->kv[i].line,
				     err);
	}
	sections_free(&f);
	free(origin);
	return rc;
}

/*
 * PrusaSlicer's filament overrides: filament_retract_length and its
 * siblings replace the printer's values unless "nil".
 */
static int filament_overrides(struct profile *p, struct st_error *err)
{
	static const char *const keys[] = {"retract_length", "retract_speed", "deretract_speed",
					   "retract_lift", "retract_before_travel", "wipe",
					   "retract_layer_change", "retract_restart_extra",
					   "retract_before_wipe", "retract_lift_above",
					   "retract_lift_below"};
	char name[64];
	int rc = 0;

	for (size_t i = 0; rc == 0 && i < sizeof(keys) / sizeof(keys[0]); i++) {
		const struct profile_kv *kv;

		snprintf(name, sizeof(name), "filament_%s", keys[i]);
		kv = prof_find_kv(p->keys, name);
		if (kv && strcmp(kv->value, "nil") && *kv->value) {
			char *v = strdup(kv->value);
			const char *file = kv->file ? kv->file : p->path;

			rc = v ? set_key(p, keys[i], v, file, kv->line, err)
			       : st_error_set(err, ST_ERR_NOMEM, "out of memory");
			free(v);
		}
	}
	return rc;
}

int profile_load_layers(const struct profile *base, const struct profile_layer *layers,
			size_t n, const struct profile_presets *pre, struct profile **out,
			struct st_error *err)
{
	const char *origin = base ? base->path : NULL;
	struct profile *p;
	int rc = 0;

	if (!out || (n && !layers))
		return st_error_set(err, ST_ERR_ARG, "profile_load_layers: bad arguments");
	*out = NULL;
	for (size_t i = 0; !origin && i < n; i++)
		if (layers[i].path)
			origin = layers[i].path;
	if (!origin)
		origin = "settings";
	p = prof_new(pre && pre->printer ? pre->printer : origin, err);
	if (!p)
		return err && err->code ? err->code : ST_ERR_NOMEM;
	free((char *)p->path);
	p->path = strdup(origin);
	if (!p->path)
		rc = st_error_set(err, ST_ERR_NOMEM, "out of memory");
	for (size_t i = 0; rc == 0 && base && i < base->keys->count; i++) {
		const struct profile_kv *kv = &base->keys->kv[i];
		rc = set_key(p, kv->key, kv->value, kv->file ? kv->file : base->path, kv->line, err);
	}
	for (size_t i = 0; rc == 0 && i < n; i++) {
		if (layers[i].path)
			rc = apply_file(p, layers[i].path, pre, err);
		else if (layers[i].key && layers[i].value)
			rc = set_key(p, layers[i].key, layers[i].value,
				     layers[i].option ? layers[i].option : "--set", 0, err);
		if (rc == 0 && layers[i].path)
			rc = filament_overrides(p, err);
	}
	if (rc) {
		profile_free(p);
		return rc;
	}
	return prof_finish(p, p->path, out, err);
}
