/*
 * cmd_opts.c - the subcommands' option parser and --help text, read from
 * each command's option table (commands.h), and the helpers they share.
 */
#include <math.h>
#include <stdarg.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>

#include "cfgopt.h"
#include "commands.h"
#include "st_number.h"

void cmd_on_stop_signals(void (*handler)(int))
{
	struct sigaction sa;

	memset(&sa, 0, sizeof(sa));
	sa.sa_handler = handler;
	sigemptyset(&sa.sa_mask);
	sigaction(SIGINT, &sa, NULL);
	sigaction(SIGTERM, &sa, NULL);
}

const char *cmd_opt_value(int argc, char **argv, int *i, const char *name)
{
	size_t len = strlen(name);
	const char *a = argv[*i];

	if (!strcmp(a, name))
		return *i + 1 < argc ? argv[++*i] : NULL;
	if (!strncmp(a, name, len) && a[len] == '=')
		return a + len + 1;
	return NULL;
}

bool cmd_is_opt(const char *a, const char *name)
{
	size_t len = strlen(name);

	return !strncmp(a, name, len) && (a[len] == '\0' || a[len] == '=');
}

/* The table entry argv's a names (long name, NAME=..., or -L); NULL if none. */
static const struct cmd_opt *find_opt(const struct cmd_spec *spec, const char *a)
{
	for (size_t k = 0; k < spec->nopt; k++) {
		const struct cmd_opt *o = &spec->opt[k];

		if (o->letter && a[0] == '-' && a[1] == o->letter && !a[2])
			return o;
		if (o->kind == CMD_FLAG ? !strcmp(a, o->name) : cmd_is_opt(a, o->name))
			return o;
	}
	return NULL;
}

/* A number value into o->dest; false when it does not read or is out of range. */
static bool read_number(const struct cmd_opt *o, const char *v)
{
	double d;
	bool whole = o->kind != CMD_DOUBLE && !(o->flags & CMD_TRUNCATE);

	if (st_parse_double(v, strlen(v), 0, &d) != ST_NUMBER_OK || (whole && d != floor(d)))
		return false;
	if ((o->flags & CMD_RANGE) &&
	    (d > o->hi || d < o->lo || ((o->flags & CMD_ABOVE_LO) && d == o->lo)))
		return false;
	switch (o->kind) {
	case CMD_INT:
		*(int *)o->dest = (int)d;
		break;
	case CMD_LONG:
		*(long *)o->dest = (long)d;
		break;
	case CMD_UNSIGNED:
		*(unsigned *)o->dest = (unsigned)d;
		break;
	case CMD_U64:
		*(uint64_t *)o->dest = (uint64_t)d;
		break;
	default:
		*(double *)o->dest = d;
		break;
	}
	return true;
}

/* argv[*i] is option o: take its value; 0 or ST_EXIT_USAGE after the message. */
static int take_opt(const struct cmd_spec *spec, const struct cmd_opt *o, int argc, char **argv,
		    int *i)
{
	const char *a = argv[*i], *name = a[1] == '-' ? o->name : a, *v = NULL;
	char wants[200];

	snprintf(wants, sizeof(wants), o->wants ? o->wants : "a value", o->lo, o->hi);
	if ((o->flags & CMD_OPTIONAL) && !strcmp(a, o->name) &&
	    (*i + 1 == argc || argv[*i + 1][0] == '-')) {
		/* given without its value: leave dest as it is */
	} else if (o->kind != CMD_FLAG) {
		v = a[1] == '-' ? cmd_opt_value(argc, argv, i, o->name)
				: (*i + 1 < argc ? argv[++*i] : NULL);
		if (!v || (!*v && (o->flags & CMD_NONEMPTY)))
			return cmd_fail(spec->cmd, ST_EXIT_USAGE, "%s needs %s", name,
					o->kind == CMD_STRING ? wants : "a value");
	}
	if (o->kind == CMD_FLAG) {
		*(bool *)o->dest = true;
	} else if (o->kind == CMD_STRING) {
		if (v)
			*(const char **)o->dest = v;
	} else if (o->kind == CMD_CUSTOM ? !o->read(v, o->dest) : !read_number(o, v)) {
		fprintf(stderr, "%s: %s wants %s, not '%s'\n", spec->cmd, name, wants, v);
		return ST_EXIT_USAGE;
	}
	if (o->given)
		*o->given = o->name;
	return 0;
}

int cmd_parse(const struct cmd_spec *spec, int argc, char **argv)
{
	size_t npos = 0;

	for (int i = 1; i < argc; i++) {
		const char *a = argv[i];
		const struct cmd_opt *o;
		int rc;

		if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
			cmd_usage(spec, stdout);
			return -1;
		}
		/* stratum help --man/--completion/--options (host/cmd_help.c):
		 * the table described instead of parsed */
		if (i == 1 && !strncmp(a, "--help=", 7)) {
			if (cmd_describe(spec, a + 7, stdout))
				return ST_EXIT_USAGE;
			return -1;
		}
		if ((o = find_opt(spec, a)) != NULL) {
			rc = take_opt(spec, o, argc, argv, &i);
		} else if (spec->cfg && (rc = cfgopt_parse(spec->cfg, spec->cmd, argc, argv, &i))) {
			rc = rc < 0 ? ST_EXIT_USAGE : 0;
		} else if (a[0] == '-' && a[1]) {
			return cmd_refuse(spec, "unknown option '%s'", a);
		} else if (npos < spec->npos) {
			spec->pos[npos++] = a;
			if (spec->ngot)
				*spec->ngot = npos;
			rc = 0;
		} else if (spec->extra) {
			fprintf(stderr, "%s: ", spec->cmd);
			if (spec->npos > 1)
				fprintf(stderr, spec->extra, (int)spec->npos, a);
			else
				fprintf(stderr, spec->extra, spec->npos ? spec->pos[0] : "", a);
			fputc('\n', stderr);
			return ST_EXIT_USAGE;
		} else {
			return cmd_refuse(spec, "unexpected argument '%s'", a);
		}
		if (rc)
			return rc;
	}
	return 0;
}

/* The value at o->dest as a number (before parsing: the default), else 0. */
static double value_of(const struct cmd_opt *o)
{
	switch (o->kind) {
	case CMD_DOUBLE:
		return *(const double *)o->dest;
	case CMD_INT:
		return *(const int *)o->dest;
	case CMD_LONG:
		return (double)*(const long *)o->dest;
	case CMD_UNSIGNED:
		return *(const unsigned *)o->dest;
	case CMD_U64:
		return (double)*(const uint64_t *)o->dest;
	default:
		return 0;
	}
}

void cmd_opt_help(const struct cmd_opt *o, char *buf, size_t cap)
{
	snprintf(buf, cap, o->help ? o->help : "", o->lo, o->hi, value_of(o));
}

/* One option's help line(s): label, then the text, its '\n's indented to col. */
void cmd_usage_opt(const struct cmd_opt *o, int col, FILE *f)
{
	char label[80], text[CMD_HELP_MAX];
	const char *sp = o->arg ? " " : "", *arg = o->arg ? o->arg : "";
	int n = o->letter
		    ? snprintf(label, sizeof(label), "  -%c, %s%s%s", o->letter, o->name, sp, arg)
		    : snprintf(label, sizeof(label), "  %s%s%s", o->name, sp, arg);

	cmd_opt_help(o, text, sizeof(text));
	fprintf(f, "%-*s%s", col, label, n >= col ? "  " : "");
	for (const char *t = text; *t; t++) {
		fputc(*t, f);
		if (*t == '\n')
			fprintf(f, "%*s", col, "");
	}
	fputc('\n', f);
}

void cmd_usage(const struct cmd_spec *spec, FILE *f)
{
	fputs(spec->head, f);
	for (size_t k = 0; k < spec->nopt; k++)
		cmd_usage_opt(&spec->opt[k], spec->col, f);
	if (spec->mid)
		fputs(spec->mid, f);
	if (spec->cfg)
		cfgopt_usage(f);
	if (spec->tail)
		fputs(spec->tail, f);
}

int cmd_refuse(const struct cmd_spec *spec, const char *fmt, ...)
{
	va_list ap;

	flockfile(stderr); /* one message, whatever other threads write */
	fprintf(stderr, "%s: ", spec->cmd);
	va_start(ap, fmt);
	vfprintf(stderr, fmt, ap);
	va_end(ap);
	fputc('\n', stderr);
	cmd_usage(spec, stderr);
	funlockfile(stderr);
	return ST_EXIT_USAGE;
}
