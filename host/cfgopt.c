/*
 * cfgopt.c - the settings options shared by the commands that slice
 * (cfgopt.h).
 */
#include "cfgopt.h"

#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "commands.h"
#include "meshio.h"
#include "settings.h"
#include "st_error.h"

/*
 * The settings options, described once: take() parses them by these
 * names, and --help (also docs/slicing.md's "Settings options" block), the
 * man pages and the completion print them from here.  --KEY-NAME stands
 * for every declared setting (cfgopt_each_setting).
 */
enum { OPT_LOAD, OPT_PRINTER_PRESET, OPT_PRINT_PRESET, OPT_FILAMENT_PRESET, OPT_SET, OPT_KEY };
static const struct cmd_opt cfg_opts[] = {
    [OPT_LOAD] = {"--load", 0, CMD_CUSTOM, NULL, 0, 0, 0, NULL, "FILE.ini",
		  "a PrusaSlicer config (File > Export Config, or\n"
		  "'prusa-slicer --save'), vendor bundle, or project\n"
		  "3MF (the settings it carries); repeat it: later\n"
		  "files replace the keys of earlier ones", NULL, NULL},
    [OPT_PRINTER_PRESET] = {"--printer-preset", 0, CMD_CUSTOM, NULL, 0, 0, 0, NULL, "NAME",
			    "the [printer:NAME] preset of a bundle given with --load", NULL,
			    NULL},
    [OPT_PRINT_PRESET] = {"--print-preset", 0, CMD_CUSTOM, NULL, 0, 0, 0, NULL, "NAME",
			  "its [print:NAME] (default: the printer's\n"
			  "default_print_profile)", NULL, NULL},
    [OPT_FILAMENT_PRESET] = {"--filament-preset", 0, CMD_CUSTOM, NULL, 0, 0, 0, NULL, "NAME",
			     "its [filament:NAME] (default: the printer's\n"
			     "default_filament_profile)", NULL, NULL},
    [OPT_SET] = {"--set", 0, CMD_CUSTOM, NULL, 0, 0, 0, NULL, "KEY=VALUE",
		 "any key, as in a profile file; repeatable", NULL, NULL},
    [OPT_KEY] = {"--KEY-NAME", 0, CMD_CUSTOM, NULL, 0, 0, 0, NULL, "VALUE",
		 "PrusaSlicer's spelling of any setting of 'stratum\n"
		 "printers --keys': --fill-density 20%%, --temperature 215,\n"
		 "--bed-temperature 60, --brim-width 5, --nozzle-diameter\n"
		 "0.6, --support-material (a flag; --no-support-material)", NULL, NULL},
};
#define CFG_COL 26 /* where the help text starts */
static const char usage_order[] =
    "  Order: --printer, then the --load files, then --set and --KEY-NAME in the\n"
    "  order given.  Keys Stratum does not honour are named in one warning.\n";

const struct cmd_opt *cfgopt_options(size_t *n)
{
	*n = sizeof(cfg_opts) / sizeof(cfg_opts[0]);
	return cfg_opts;
}

void cfgopt_each_setting(void (*fn)(const char *opt, bool flag, const char *help, void *ctx),
			 void *ctx)
{
	for (size_t i = 0; i < settings_count(); i++) {
		const struct setting *s = settings_at(i);
		char opt[72];
		size_t k;

		snprintf(opt, sizeof(opt), "--%s", s->name);
		for (k = 2; opt[k]; k++)
			opt[k] = opt[k] == '_' ? '-' : opt[k];
		fn(opt, s->type == SETTING_BOOL, s->help, ctx);
		if (s->type == SETTING_BOOL) {
			snprintf(opt, sizeof(opt), "--no-%s", s->name);
			for (k = 5; opt[k]; k++)
				opt[k] = opt[k] == '_' ? '-' : opt[k];
			fn(opt, true, s->help, ctx);
		}
	}
}

const char *cfgopt_usage_tail(void)
{
	return usage_order;
}

void cfgopt_usage(FILE *f)
{
	for (size_t k = 0; k < sizeof(cfg_opts) / sizeof(cfg_opts[0]); k++)
		cmd_usage_opt(&cfg_opts[k], CFG_COL, f);
	fputs(usage_order, f);
}

/* A layer setting key (copied into o) to value; 1, or ST_ERR_ARG with err set. */
static int add_key(struct cfgopt *o, const char *opt, const char *key, size_t klen,
		   const char *value, struct st_error *err)
{
	if (o->n == CFGOPT_MAX)
		return st_error_set(err, ST_ERR_ARG, "more than %d settings options", CFGOPT_MAX);
	if (klen == 0 || klen >= sizeof(o->keybuf[0]))
		return st_error_set(err, ST_ERR_ARG,
				    "%s wants KEY=VALUE with a key such as layer_height", opt);
	memcpy(o->keybuf[o->n], key, klen);
	o->keybuf[o->n][klen] = '\0';
	o->layer[o->n] = (struct profile_layer){NULL, o->keybuf[o->n], value, opt};
	o->n++;
	return 1;
}

/* --KEY-NAME: the declared setting it spells, or NULL. */
static const struct setting *spelled(const char *a, bool *negated, size_t *len)
{
	char key[64];
	size_t n = strcspn(a + 2, "=");

	*negated = !strncmp(a, "--no-", 5);
	if (*negated) {
		a += 3;
		n -= 3;
	}
	if (n >= sizeof(key))
		return NULL;
	for (size_t k = 0; k < n; k++)
		key[k] = a[2 + k] == '-' ? '_' : a[2 + k] == '_' ? '\0' : a[2 + k];
	key[n] = '\0';
	*len = n;
	if (strlen(key) != n)
		return NULL; /* PrusaSlicer spells keys with '-' only */
	return settings_find(key);
}

/* cfgopt_parse without the printing: 1, 0, or ST_ERR_ARG with err set. */
static int take(struct cfgopt *o, int argc, char **argv, int *i, struct st_error *err)
{
	const char *a = argv[*i], *v;
	const struct setting *s;
	bool neg;
	size_t n;

	if (cmd_is_opt(a, cfg_opts[OPT_LOAD].name)) {
		v = cmd_opt_value(argc, argv, i, cfg_opts[OPT_LOAD].name);
		if (!v || !*v)
			return st_error_set(err, ST_ERR_ARG, "--load needs a config file");
		if (o->n == CFGOPT_MAX)
			return add_key(o, cfg_opts[OPT_LOAD].name, "", 0, NULL, err);
		o->layer[o->n++] = (struct profile_layer){v, NULL, NULL, NULL};
		o->has_files = true;
		return 1;
	}
	{
		const char **slot[] = {&o->presets.printer, &o->presets.print,
				       &o->presets.filament};

		for (int k = 0; k < 3; k++) {
			const char *name = cfg_opts[OPT_PRINTER_PRESET + k].name;

			if (!cmd_is_opt(a, name))
				continue;
			v = cmd_opt_value(argc, argv, i, name);
			if (!v || !*v)
				return st_error_set(err, ST_ERR_ARG, "%s needs a preset name",
						    name);
			*slot[k] = v;
			return 1;
		}
	}
	if (cmd_is_opt(a, cfg_opts[OPT_SET].name)) {
		const char *eq, *name = cfg_opts[OPT_SET].name;

		v = cmd_opt_value(argc, argv, i, name);
		eq = v ? strchr(v, '=') : NULL;
		if (!eq)
			return add_key(o, name, "", 0, NULL, err);
		return add_key(o, name, v, (size_t)(eq - v), eq + 1, err);
	}
	if (strncmp(a, "--", 2) || !(s = spelled(a, &neg, &n)))
		return 0;
	if (s->type == SETTING_BOOL && !strchr(a, '='))
		return add_key(o, a, s->name, strlen(s->name), neg ? "0" : "1", err);
	if (neg)
		return 0;
	{
		char opt[80];
		snprintf(opt, sizeof(opt), "%.*s", (int)(n + 2), a);
		v = cmd_opt_value(argc, argv, i, opt);
		if (!v)
			return st_error_set(err, ST_ERR_ARG,
					    "%s needs a value (see 'stratum printers --keys')", opt);
		/* The option as written names it in messages (argv outlives the parse). */
		return add_key(o, a, s->name, strlen(s->name), v, err);
	}
}

int cfgopt_parse(struct cfgopt *o, const char *cmd, int argc, char **argv, int *i)
{
	struct st_error err = {0};
	int rc = take(o, argc, argv, i, &err);

	if (rc < 0)
		return cmd_fail(cmd, -1, "%s", err.msg);
	return rc;
}

/* The declared setting a form field name spells ("layer-height"), or NULL. */
static const struct setting *field_setting(const char *name)
{
	const struct setting *s;
	char opt[72];
	bool neg;
	size_t n;

	if ((size_t)snprintf(opt, sizeof(opt), "--%s", name) >= sizeof(opt) ||
	    strchr(name, '=') || !(s = spelled(opt, &neg, &n)) || neg)
		return NULL;
	return s;
}

bool cfgopt_is_field(const char *name)
{
	return !strcmp(name, "set") || field_setting(name);
}

int cfgopt_field(struct cfgopt *o, const char *name, const char *value, struct st_error *err)
{
	const char *eq = strchr(value, '=');
	const struct setting *s;

	/* set=KEY=VALUE is --set KEY=VALUE; layer-height=0.2 is --layer-height 0.2 */
	if (!strcmp(name, "set"))
		return add_key(o, "set", value, eq ? (size_t)(eq - value) : 0, eq ? eq + 1 : NULL,
			       err);
	if (!(s = field_setting(name)))
		return 0;
	return add_key(o, name, s->name, strlen(s->name), value, err);
}

int cfgopt_apply(const struct cfgopt *o, const struct profile *base, struct profile **out,
		 bool *usage, struct st_error *err)
{
	size_t files = 0;
	int rc;

	*out = NULL;
	*usage = true;
	/* The files alone first, so a bad file is the file's error and a bad
	 * option value is a usage error (exit 2). */
	while (files < o->n && o->layer[files].path)
		files++;
	for (size_t k = files; k < o->n; k++)
		if (o->layer[k].path)
			return st_error_set(err, ST_ERR_ARG,
					    "give every --load before --set and the --KEY-NAME "
					    "options (%s comes after one)",
					    o->layer[k].path);
	rc = profile_load_layers(base, o->layer, files, &o->presets, out, err);
	if (rc) {
		*usage = rc == ST_ERR_RANGE || rc == ST_ERR_ARG;
		return rc;
	}
	if (files < o->n) {
		struct profile *p = *out;

		*out = NULL;
		rc = profile_load_layers(p, o->layer + files, o->n - files, NULL, out, err);
		profile_free(p);
	}
	return rc;
}

int cfgopt_load(const struct cfgopt *o, const char *cmd, const char *printer,
		struct profile **out)
{
	struct st_error err = {0};
	struct profile *base = NULL;
	bool usage;
	int rc;

	*out = NULL;
	if (printer && (rc = profile_find(printer, &base, &err)))
		return cmd_fail(cmd, profile_exit_status(rc), "%s", err.msg);
	if (!o->n && !o->presets.printer) {
		*out = base;
		return 0;
	}
	rc = cfgopt_apply(o, base, out, &usage, &err);
	profile_free(base);
	if (!rc)
		return 0;
	fprintf(stderr, "%s: %s\n", cmd, err.msg);
	return usage ? ST_EXIT_USAGE : st_exit_for(rc);
}

void cfgopt_warn_unsupported(const struct profile *p, const char *cmd)
{
	char *list = NULL;

	if (profile_unsupported(p, &list) == 0 && list)
		fprintf(stderr, "%s: warning: not supported, ignored: %s\n", cmd, list);
	free(list);
}

/* Whether path names the same file as one of o's --load files. */
static bool is_loaded(const struct cfgopt *o, const char *path)
{
	struct stat a, b;

	if (stat(path, &a))
		return false;
	for (size_t i = 0; i < o->n; i++)
		if (o->layer[i].path && !stat(o->layer[i].path, &b) && a.st_dev == b.st_dev &&
		    a.st_ino == b.st_ino)
			return true;
	return false;
}

void cfgopt_note_project_settings(const struct cfgopt *o, const char *cmd,
				  const char *const *models, size_t n)
{
	for (size_t i = 0; i < n; i++) {
		struct st_error err = {0};
		char *text = NULL;

		/* Not a 3MF, or unreadable: the model reader says so, not this note. */
		if (strcmp(models[i], "-") && meshio_3mf_config(models[i], &text, &err) == 0 &&
		    text && !is_loaded(o, models[i]))
			fprintf(stderr,
				"%s: note: %s carries PrusaSlicer settings (" MESHIO_3MF_CONFIG_ENTRY
				"), not applied; add --load %s to slice with them\n",
				cmd, models[i], models[i]);
		free(text);
	}
}
