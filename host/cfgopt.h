/*
 * cfgopt.h - the settings options `stratum slice` (and the commands that
 * slice) share: --load FILE (repeatable, later files win, as PrusaSlicer's),
 * --printer-preset/--print-preset/--filament-preset NAME for a PrusaSlicer
 * bundle, --set KEY=VALUE for any key, and PrusaSlicer's own spelling
 * --KEY-NAME VALUE of every declared setting (slicer/settings.h): a bool as
 * a flag, --no-KEY-NAME for 0.  Values are checked by the profile loader
 * against the same declarations as a profile file's (profile.h).
 *
 * The option text printed by cfgopt_usage is also docs/slicing.md's
 * (tests/check_slicecli.c compares them).
 */
#ifndef STRATUM_HOST_CFGOPT_H
#define STRATUM_HOST_CFGOPT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

#include "profile.h"

#define CFGOPT_MAX 256 /* layers on one command line */

struct cfgopt {
	struct profile_layer layer[CFGOPT_MAX]; /* in command-line order */
	size_t n;
	bool has_files; /* a --load was given */
	struct profile_presets presets;
	char keybuf[CFGOPT_MAX][64]; /* KEY of --set KEY=VALUE and --KEY-NAME */
};

/*
 * cfgopt_parse - read argv[*i] (and its value) when it is one of these
 * options.  Returns 1 when taken (*i moved past its value), 0 when it is
 * not one of them, or -1 after printing "CMD: ..." for a malformed one.
 */
int cfgopt_parse(struct cfgopt *o, const char *cmd, int argc, char **argv, int *i);

/*
 * cfgopt_field - one form field of a farm-node upload as the option of the
 * same name (docs/serve.md): "set" with "KEY=VALUE" is --set KEY=VALUE, a
 * PrusaSlicer spelling ("layer-height", "fill-density", "support-material"
 * with 1 or 0) is --KEY-NAME VALUE.  name and value must outlive o.
 * Returns 1 when taken, 0 when name is no settings field, or ST_ERR_ARG
 * with err set ("set" without KEY=, too many).
 */
int cfgopt_field(struct cfgopt *o, const char *name, const char *value, struct st_error *err);

/* cfgopt_is_field - whether cfgopt_field takes a field called name. */
bool cfgopt_is_field(const char *name);

/*
 * cfgopt_apply - cfgopt_load without the printing: 0, or the class with
 * err set and *usage true when the options (not a --load file) are at
 * fault.
 */
int cfgopt_apply(const struct cfgopt *o, const struct profile *base, struct profile **out,
		 bool *usage, struct st_error *err);

/*
 * cfgopt_load - the profile a command works with: --printer's profile
 * (@printer, NULL: none; profile_find) under the --load files and then the
 * key options, in order.  Returns 0, or the exit status with the message
 * printed: 2 for a bad option value or preset name, else as the profile's
 * own errors (profile_exit_status for @printer's).
 */
int cfgopt_load(const struct cfgopt *o, const char *cmd, const char *printer,
		struct profile **out);

/* cfgopt_usage - the options' help lines. */
void cfgopt_usage(FILE *f);

/* cfgopt_usage_tail - the lines cfgopt_usage ends with: the order the
 * settings options apply in. */
const char *cfgopt_usage_tail(void);

struct cmd_opt;
/* cfgopt_options - the options' table (*n entries; the last, --KEY-NAME,
 * stands for cfgopt_each_setting's); parsed by cfgopt_parse, not cmd_parse. */
const struct cmd_opt *cfgopt_options(size_t *n);

/* cfgopt_each_setting - fn for every --KEY-NAME option, --no-KEY-NAME too
 * for a bool (flag true: takes no value), with the setting's help line. */
void cfgopt_each_setting(void (*fn)(const char *opt, bool flag, const char *help, void *ctx),
			 void *ctx);

/*
 * cfgopt_warn_unsupported - print "CMD: warning: not supported, ignored:
 * KEY=VALUE, ..." on stderr when the profile sets keys Stratum does not
 * honour (profile_unsupported); nothing otherwise.
 */
void cfgopt_warn_unsupported(const struct profile *p, const char *cmd);

/*
 * cfgopt_note_project_settings - for each of the n models that is a 3MF
 * carrying PrusaSlicer settings (a saved project) but is not among o's
 * --load files, print "CMD: note: MODEL carries PrusaSlicer settings ...,
 * not applied; add --load MODEL to slice with them" on stderr: a model
 * gives only its meshes (docs/slicing.md).
 */
void cfgopt_note_project_settings(const struct cfgopt *o, const char *cmd,
				  const char *const *models, size_t n);

#endif /* STRATUM_HOST_CFGOPT_H */
