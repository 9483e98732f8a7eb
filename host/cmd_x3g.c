/*
 * cmd_x3g.c - `stratum x3g IN.gcode -o OUT.x3g --printer NAME
 * [--flavor reprap|makerbot] [--json]` translates G-code for a Sailfish
 * printer into X3G (serial/x3g.h); `stratum x3g --decode FILE.x3g [--json]`
 * lists the commands of an X3G file, one per line.
 * Exit 0 done, 1 OUT could not be written, 2 usage, a printer that is not
 * a Sailfish one or G-code for another printer (host/guard.h), 65 bad G-code/X3G input or printer profile, 70 internal.
 *
 * The printer profile is mapped to struct x3g_machine here, so serial/
 * never includes host/.
 */
#include <errno.h>
#include <fcntl.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "clio.h"
#include "commands.h"
#include "gcode.h"
#include "guard.h"
#include "profile.h"
#include "profile_x3g.h"
#include "st_error.h"
#include "st_file.h"
#include "x3g.h"

#define X3G_CMD "stratum x3g"
#define X3G_JSON_WARNINGS 100	   /* warnings listed in --json output */
#define X3G_DECODE_MAX (1ul << 30) /* largest X3G file --decode reads, bytes */

struct x3g_args {
	const char *in, *out, *printer, *decode, *flavor;
	bool json, force;
};

/* Parse argv; 0 to go on, -1 after --help, else the exit status. */
static int parse_args(int argc, char **argv, struct x3g_args *a)
{
	const struct cmd_opt opts[] = {
	    CMD_OPT_STRING("--output", 'o', &a->out, CMD_NONEMPTY, NULL, "OUT",
	     "the X3G file (written only when the whole input translated);\n"
	     "'-': stdout, and IN '-' reads stdin"),
	    CMD_OPT_STRING("--printer", 0, &a->printer, CMD_NONEMPTY, NULL, "P",
	     "a sailfish printer profile ('stratum printers') or .ini file"),
	    CMD_OPT_STRING("--flavor", 0, &a->flavor, CMD_NONEMPTY, NULL, "F",
	     "reprap (default; makerware profiles: makerbot) or makerbot:\n"
	     "how M106/M107, M109 and T words are read, as GPX -r / -g"),
	    CMD_OPT_STRING("--decode", 0, &a->decode, CMD_NONEMPTY, NULL, "FILE",
	     "list FILE's commands instead of translating"),
	    CMD_OPT_FLAG("--force", &a->force, GUARD_FORCE_HELP),
	    CMD_OPT_FLAG("--json", &a->json,
	     "one JSON object on stdout instead of the text output"),
	};
	const struct cmd_spec spec = {
	    .cmd = X3G_CMD, CMD_TABLE(opts), .col = 21,
	    .head = "usage: stratum x3g IN.gcode -o OUT.x3g --printer NAME|FILE.ini\n"
		    "                   [--flavor reprap|makerbot] [--json] [--force]\n"
		    "       stratum x3g --decode FILE.x3g [--json]\n"
		    "\n"
		    "Translates G-code into X3G, the binary command stream of Sailfish printers\n"
		    "(FlashForge Creator Pro, Makerbot Replicator 1/2), as GPX does.  Commands\n"
		    "X3G cannot express are reported as warnings with their line number.\n"
		    "With --decode, lists the commands of an X3G file, one per line.\n"
		    "\n",
	    .tail = "\n"
		    "Exit status: 0 done, 1 OUT could not be written, 2 usage, not a sailfish\n"
		    "printer or G-code sliced for another printer, 65 bad G-code, X3G or printer\n"
		    "profile, 70 internal error.\n",
	    .pos = &a->in, .npos = 1,
	    .extra = "one G-code file at a time ('%s' and '%s'); name the output with -o"};
	int rc = cmd_parse(&spec, argc, argv);

	if (rc)
		return rc;
	if (a->decode) {
		if (a->in || a->out || a->printer || a->flavor || a->force)
			return cmd_fail(X3G_CMD, ST_EXIT_USAGE,
					"--decode takes only the X3G file (and --json)");
		return 0;
	}
	if (!a->in || !a->out || !a->printer)
		return cmd_refuse(&spec, "%s",
				  !a->in    ? "no G-code file given"
				  : !a->out ? "no output given (-o OUT.x3g)"
					    : "no printer given (--printer NAME)");
	if (a->flavor && strcmp(a->flavor, "reprap") && strcmp(a->flavor, "makerbot"))
		return cmd_fail(X3G_CMD, ST_EXIT_USAGE, "--flavor is reprap or makerbot, not '%s'",
				a->flavor);
	return 0;
}

struct x3g_run {
	const struct x3g_args *a;
	struct x3g_translator *t;
	FILE *out;
	uint64_t lines, commands, bytes, warnings;
	json_t *jwarn;
};

/* Write one call's output and show its warnings; returns an exit status. */
static int flush_call(struct x3g_run *r, int ncmds)
{
	const struct x3g_warning *w;
	size_t len, nw = x3g_warnings(r->t, &w);
	const uint8_t *bytes = x3g_output(r->t, &len);

	for (size_t i = 0; i < nw; i++) {
		fprintf(stderr, X3G_CMD ": %s:%llu: warning: %s\n", r->a->in,
			(unsigned long long)w[i].line, w[i].msg);
		if (r->jwarn && json_array_size(r->jwarn) < X3G_JSON_WARNINGS) {
			json_t *o = json_object();

			cmd_json_set(o, "I:line", (json_int_t)w[i].line, "s:message", w[i].msg, NULL);
			json_array_append_new(r->jwarn, o);
		}
	}
	r->commands += (uint64_t)ncmds;
	r->bytes += len;
	if (len && fwrite(bytes, 1, len, r->out) != len)
		return cmd_fail(X3G_CMD, ST_EXIT_FAILURE, "%s: write failed: %s", r->a->out,
				strerror(errno));
	return 0;
}

/* Read, translate and write everything; returns an exit status. */
static int translate_all(struct x3g_run *r, FILE *in)
{
	struct gcode_reader *rd;
	struct gcode_line line;
	struct st_error err = {0};
	int rc, status = 0;

	if (gcode_reader_new(in, r->a->in, &rd, &err))
		return cmd_fail(X3G_CMD, ST_EXIT_SOFTWARE, "%s", err.msg);
	while ((rc = gcode_reader_next(rd, 0, &line, &err)) > 0) {
		r->lines++;
		rc = x3g_translate(r->t, &line, gcode_reader_line(rd), &err);
		if (rc < 0)
			break;
		if ((status = flush_call(r, rc)))
			goto out;
	}
	if (rc < 0) {
		fprintf(stderr, X3G_CMD ": %s\n", err.msg);
		status = rc == ST_ERR_NOMEM || rc == ST_ERR_INTERNAL ? ST_EXIT_SOFTWARE
								     : ST_EXIT_DATAERR;
		goto out;
	}
	rc = x3g_finish(r->t, &err);
	status = rc < 0 ? ST_EXIT_SOFTWARE : flush_call(r, rc);
out:
	r->warnings = x3g_warning_total(r->t);
	gcode_reader_free(rd);
	return status;
}

/* Translate into a temporary file beside OUT, then rename it over OUT. */
static int translate_to_file(struct x3g_run *r, FILE *in)
{
	struct st_file_out out;
	struct st_error err = {0};
	int status;

	if (st_file_begin(&out, r->a->out, &err))
		return cmd_fail(X3G_CMD,
				err.code == ST_ERR_NOMEM ? ST_EXIT_SOFTWARE : ST_EXIT_FAILURE, "%s",
				err.msg);
	r->out = out.f;
	status = translate_all(r, in);
	r->out = NULL;
	if (status) {
		st_file_abort(&out);
		return status;
	}
	if (st_file_commit(&out, &err))
		return cmd_fail(X3G_CMD, ST_EXIT_FAILURE, "%s", err.msg);
	return 0;
}

static int run_translate(const struct x3g_args *a)
{
	struct x3g_run r = {.a = a};
	struct x3g_machine m;
	struct x3g_options opt = {0};
	struct profile *p = NULL;
	struct st_error err = {0};
	char name[X3G_BUILD_NAME_MAX + 1];
	FILE *in;
	int status;

	if (profile_find(a->printer, &p, &err))
		return cmd_fail(X3G_CMD, profile_exit_status(err.code), "%s", err.msg);
	if (p->protocol != PROFILE_PROTOCOL_SAILFISH) {
		status = cmd_fail(X3G_CMD, ST_EXIT_USAGE,
				  "printer '%s' speaks %s, not sailfish; X3G is for Sailfish "
				  "printers (send its G-code with 'stratum send')",
				  p->id, profile_protocol_name(p->protocol));
		goto out_profile;
	}
	if (profile_x3g_machine(p, &m, &opt.flavor, &err)) {
		status = cmd_fail(X3G_CMD, ST_EXIT_DATAERR, "%s", err.msg);
		goto out_profile;
	}
	if (a->flavor)
		opt.flavor = strcmp(a->flavor, "makerbot") ? X3G_FLAVOR_REPRAP : X3G_FLAVOR_MAKERBOT;
	x3g_build_name(a->out, name, sizeof(name));
	opt.build_name = name;
	if (x3g_new(&m, &opt, &r.t, &err)) {
		status =
		    cmd_fail(X3G_CMD, err.code == ST_ERR_NOMEM ? ST_EXIT_SOFTWARE : ST_EXIT_DATAERR,
			     "%s: %s", p->path, err.msg);
		goto out_profile;
	}
	in = fopen(a->in, "rb");
	if (!in) {
		status = cmd_fail(X3G_CMD, ST_EXIT_DATAERR, "%s: cannot open: %s", a->in,
				  strerror(errno));
		goto out_translator;
	}
	if ((status = guard_cli(X3G_CMD, a->in, p, a->force))) {
		fclose(in);
		goto out_translator;
	}
	if (a->json)
		r.jwarn = json_array();
	status = translate_to_file(&r, in);
	fclose(in);
	if (status == 0 && a->json) {
		json_t *o = json_object();

		cmd_json_set(o, "s:input", a->in, "s:output", a->out, "s:printer", p->id,
			     "s:flavor", opt.flavor == X3G_FLAVOR_REPRAP ? "reprap" : "makerbot",
			     "I:lines", (json_int_t)r.lines, "I:commands", (json_int_t)r.commands,
			     "I:bytes", (json_int_t)r.bytes, "I:warnings", (json_int_t)r.warnings,
			     "o:warning_list", r.jwarn, NULL);
		r.jwarn = NULL;
		cmd_json_out(o, JSON_INDENT(2));
	} else if (status == 0) {
		printf("%s: %llu lines -> %s: %llu commands, %llu bytes, %llu warnings\n", a->in,
		       (unsigned long long)r.lines, a->out, (unsigned long long)r.commands,
		       (unsigned long long)r.bytes, (unsigned long long)r.warnings);
	}
	json_decref(r.jwarn);
out_translator:
	x3g_free(r.t);
out_profile:
	profile_free(p);
	return status;
}

/* Read a whole file of at most X3G_DECODE_MAX bytes; NULL (message printed)
 * on failure. */
static uint8_t *read_all(const char *path, size_t *len)
{
	FILE *f = fopen(path, "rb");
	struct stat st;
	uint8_t *buf;

	if (!f || fstat(fileno(f), &st) != 0 || !S_ISREG(st.st_mode)) {
		fprintf(stderr, X3G_CMD ": %s: cannot open: %s\n", path,
			f ? "not a regular file" : strerror(errno));
		if (f)
			fclose(f);
		return NULL;
	}
	if ((unsigned long long)st.st_size > X3G_DECODE_MAX) {
		fprintf(stderr, X3G_CMD ": %s: larger than 1 GiB; not an X3G print\n", path);
		fclose(f);
		return NULL;
	}
	*len = (size_t)st.st_size;
	buf = malloc(*len ? *len : 1);
	if (!buf || fread(buf, 1, *len, f) != *len) {
		fprintf(stderr, X3G_CMD ": %s: read error\n", path);
		free(buf);
		buf = NULL;
	}
	fclose(f);
	return buf;
}

static json_t *command_json(const struct x3g_command *c)
{
	json_t *o = json_object(), *f = json_object();

	cmd_json_set(o, "I:offset", (json_int_t)c->offset, "i:code", (int)c->code, "s:name", c->name,
		     "I:length", (json_int_t)c->length, NULL);
	for (size_t i = 0; i < c->nfields; i++)
		json_object_set_new(f, c->fields[i].name, json_real(c->fields[i].value));
	json_object_set_new(o, "fields", f);
	if (c->has_text)
		json_object_set_new(o, "text", json_string(c->text));
	return o;
}

static int run_decode(const struct x3g_args *a)
{
	struct x3g_command c;
	struct st_error err = {0};
	size_t len, pos = 0, count = 0;
	uint8_t *buf = read_all(a->decode, &len);
	json_t *arr = a->json ? json_array() : NULL;
	char line[512];
	int rc = 0;

	if (!buf) {
		json_decref(arr);
		return ST_EXIT_DATAERR;
	}
	while (pos < len && (rc = x3g_decode(buf + pos, len - pos, pos, &c, &err)) > 0) {
		if (arr) {
			json_array_append_new(arr, command_json(&c));
		} else {
			x3g_format(&c, line, sizeof(line));
			printf("%zu: %s\n", pos, line);
		}
		pos += (size_t)rc;
		count++;
	}
	free(buf);
	if (rc < 0) {
		json_decref(arr);
		return cmd_fail(X3G_CMD, ST_EXIT_DATAERR, "%s: %s", a->decode, err.msg);
	}
	if (arr) {
		json_t *o = json_object();

		cmd_json_set(o, "s:input", a->decode, "I:bytes", (json_int_t)len, "o:commands", arr,
			     NULL);
		cmd_json_out(o, JSON_INDENT(2));
	} else {
		fprintf(stderr, "%s: %zu commands, %zu bytes\n", a->decode, count, len);
	}
	return 0;
}

int cmd_x3g(int argc, char **argv)
{
	struct x3g_args a = {0};
	struct clio io;
	int status = parse_args(argc, argv, &a);

	if (status)
		return status < 0 ? ST_EXIT_OK : status;
	/* "-": G-code (or X3G to decode) from stdin, X3G to stdout when whole */
	clio_init(&io, X3G_CMD);
	if (!(status = clio_input(&io, a.decode ? &a.decode : &a.in, a.decode ? ".x3g" : ".gcode")) &&
	    !(status = clio_output(&io, &a.out, true, ".x3g")))
		status = a.decode ? run_decode(&a) : run_translate(&a);
	return clio_finish(&io, status);
}
