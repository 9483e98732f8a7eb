/*
 * cmd_jobs.c - `stratum jobs list|show ID|prune`: the jobs directory where
 * `stratum print` keeps each job's journal and sliced G-code so it can be
 * resumed (jobs.h, docs/printing.md).  Prune removes old jobs and keeps
 * the directory under a size cap, oldest first; a running job never, a
 * resumable one only with --resumable.
 */
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "commands.h"
#include "jobs.h"
#include "journal.h"
#include "st_error.h"

#define JOBS_CMD "stratum jobs"

struct jobs_args {
	const char *pos[2]; /* the action, the job */
	size_t npos;
	bool json, resumable, dry_run;
	int64_t older_than; /* s, -1 none */
	double max_mb;
	const char *older_given, *max_given;
};

static bool read_age(const char *v, void *dest)
{
	return jobs_parse_age(v, dest);
}

/* Parse argv; 0 to go on, -1 after --help, else the exit status. */
static int jobs_parse(int argc, char **argv, struct jobs_args *a)
{
	const struct cmd_opt opts[] = {
	    CMD_OPT_FLAG("--json", &a->json, "one JSON object on stdout"),
	    {"--older-than", 0, CMD_CUSTOM, &a->older_than, 0, 0, 0,
	     "an age such as 30d, 12h, 45m, 90s or 2w", "AGE",
	     "prune: the jobs last updated longer ago than AGE", read_age, &a->older_given},
	    {"--max-size", 0, CMD_DOUBLE, &a->max_mb, CMD_RANGE, 0, 1e9,
	     "a size in MB from %g (no cap) to %g", "MB",
	     "prune: then the oldest until the rest fit in MB, %g (no\n"
	     "cap) to %g (default %g; $" JOBS_MAX_ENV " changes it)",
	     NULL, &a->max_given},
	    CMD_OPT_FLAG("--resumable", &a->resumable,
			 "prune: jobs that could be resumed go too (never a running one)"),
	    CMD_OPT_FLAG("--dry-run", &a->dry_run, "prune: say what would go; remove nothing"),
	};
	const struct cmd_spec spec = {
	    .cmd = JOBS_CMD, CMD_TABLE(opts), .col = 20,
	    .head = "usage: stratum jobs list [--json]\n"
		    "       stratum jobs show ID [--json]\n"
		    "       stratum jobs prune [--older-than AGE] [--max-size MB] [--resumable]\n"
		    "                          [--dry-run] [--json]\n"
		    "\n"
		    "The jobs 'stratum print' keeps in the state directory (journal and sliced\n"
		    "G-code of each, so that 'stratum print --resume ID' can continue it):\n"
		    "list them, show one, or prune them.  Prune removes the jobs older than\n"
		    "AGE, then the oldest until the rest fit in the size cap; never a running\n"
		    "job, a resumable one (not printed to the end) only with --resumable.\n"
		    "'stratum print' prunes to the cap itself before each new job.\n"
		    "\n",
	    .tail = "\nExit status: 0 done, 1 the directory cannot be read or a file cannot be\n"
		    "removed, 2 usage or no such job.\n",
	    .pos = a->pos, .npos = 2, .ngot = &a->npos,
	    .extra = "one job at a time ('%s' and '%s')"};
	const char *act;
	int rc;

	memset(a, 0, sizeof(*a));
	a->older_than = -1;
	a->max_mb = (double)jobs_cap() / 1e6;
	if ((rc = cmd_parse(&spec, argc, argv)))
		return rc;
	act = a->pos[0];
	if (!act || (strcmp(act, "list") && strcmp(act, "show") && strcmp(act, "prune")))
		return cmd_refuse(&spec, "%s%s%s", act ? "'" : "", act ? act : "no action given",
				  act ? "' is not an action: list, show ID or prune" : "");
	if (!strcmp(act, "show") != (a->npos == 2))
		return cmd_fail(JOBS_CMD, ST_EXIT_USAGE, "%s",
				a->npos == 2 ? "only 'show' takes a job ID"
					     : "show needs a job ID ('stratum jobs list')");
	if (strcmp(act, "prune") && (a->older_given || a->max_given || a->resumable || a->dry_run))
		return cmd_fail(
		    JOBS_CMD, ST_EXIT_USAGE,
		    "--older-than, --max-size, --resumable and --dry-run go with 'prune'");
	return 0;
}

/* A size as "46.1 MB", "812 kB", "93 B". */
static void fmt_size(char *buf, size_t cap, uint64_t b)
{
	if (b >= 1000000)
		snprintf(buf, cap, "%.1f MB", (double)b / 1e6);
	else if (b >= 1000)
		snprintf(buf, cap, "%.0f kB", (double)b / 1e3);
	else
		snprintf(buf, cap, "%llu B", (unsigned long long)b);
}

/* An age as "40 s", "12 min", "5 h", "31 d". */
static void fmt_age(char *buf, size_t cap, int64_t s)
{
	if (s < 0)
		s = 0;
	if (s < 120)
		snprintf(buf, cap, "%lld s", (long long)s);
	else if (s < 2 * 3600)
		snprintf(buf, cap, "%lld min", (long long)(s / 60));
	else if (s < 2 * 86400)
		snprintf(buf, cap, "%lld h", (long long)(s / 3600));
	else
		snprintf(buf, cap, "%lld d", (long long)(s / 86400));
}

static json_t *entry_json(const struct jobs_entry *e)
{
	return json_pack("{s:s, s:s, s:s, s:s, s:I, s:I}", "id", e->id, "state", e->state,
			 "kind", jobs_kind_name(e->kind), "printer", e->printer, "updated",
			 (json_int_t)e->updated, "bytes", (json_int_t)e->bytes);
}

static int jobs_list_cmd(const struct jobs_args *a, const struct jobs_list *l)
{
	char size[32], age[32], cap[32];
	int64_t now = (int64_t)time(NULL);
	uint64_t capb = jobs_cap();

	if (a->json) {
		json_t *arr = json_array(), *o;
		for (size_t i = 0; i < l->n; i++)
			json_array_append_new(arr, entry_json(&l->v[i]));
		o = json_pack("{s:s, s:I, s:I, s:o}", "dir", l->dir, "bytes", (json_int_t)l->bytes,
			      "cap_bytes", (json_int_t)capb, "jobs", arr);
		return cmd_json_out(o, JSON_INDENT(2) | JSON_PRESERVE_ORDER) ? ST_EXIT_FAILURE : 0;
	}
	if (l->n)
		printf("%-24s %-10s %-10s %8s %10s  %s\n", "ID", "STATE", "KIND", "AGE", "SIZE",
		       "PRINTER");
	for (size_t i = 0; i < l->n; i++) {
		const struct jobs_entry *e = &l->v[i];
		const char *p = strrchr(e->printer, '/'), *name = p ? p + 1 : e->printer;
		int len = (int)strlen(name) - (cmd_has_ext(name, ".ini") ? 4 : 0);

		fmt_size(size, sizeof(size), e->bytes);
		fmt_age(age, sizeof(age), now - e->updated);
		/* the profile's name, as --printer takes it */
		printf("%-24s %-10s %-10s %8s %10s  %.*s\n", e->id, e->state, jobs_kind_name(e->kind),
		       age, size, *name ? len : 1, *name ? name : "-");
	}
	fmt_size(size, sizeof(size), l->bytes);
	fmt_size(cap, sizeof(cap), capb);
	printf("%zu job%s, %s in %s (cap %s%s)\n", l->n, l->n == 1 ? "" : "s", size, l->dir,
	       capb ? cap : "none", capb ? "; 'stratum jobs prune' trims to it" : "");
	return 0;
}

static int jobs_show_cmd(const struct jobs_args *a, const struct jobs_list *l)
{
	const struct jobs_entry *e = NULL;
	struct journal journal, *j = &journal;
	struct st_error err = {0};
	char size[32];

	for (size_t i = 0; i < l->n; i++)
		if (!strcmp(l->v[i].id, a->pos[1]))
			e = &l->v[i];
	if (!e || e->kind == JOBS_LEFTOVER ||
	    (e->kind == JOBS_RUNNING && !strcmp(e->state, "leftover")))
		return cmd_fail(JOBS_CMD, ST_EXIT_USAGE, "no job %s in %s%s", a->pos[1], l->dir,
				e ? " (files without a journal; 'stratum jobs prune' removes them)"
				  : "; 'stratum jobs list' shows them");
	if (journal_load(e->id, j, &err))
		return cmd_fail(JOBS_CMD, ST_EXIT_FAILURE, "%s", err.msg);
	if (a->json) {
		json_t *o = json_load_file(j->file, 0, NULL);
		if (o) {
			cmd_json_set(o, "s:kind", jobs_kind_name(e->kind), "s:journal", j->file,
				     "I:bytes", (json_int_t)e->bytes, NULL);
		}
		return cmd_json_out(o, JSON_INDENT(2) | JSON_PRESERVE_ORDER) ? ST_EXIT_FAILURE : 0;
	}
	fmt_size(size, sizeof(size), e->bytes);
	printf("job %s: %s (%s)\n", j->id, j->state, jobs_kind_name(e->kind));
	printf("  journal: %s\n  gcode: %s\n  sha256: %s\n  printer: %s\n  port: %s\n", j->file,
	       j->gcode, j->sha256, j->printer, j->port);
	printf("  confirmed: line %llu of %llu, ", (unsigned long long)j->last_line,
	       (unsigned long long)j->lines);
	if (j->layer < 0)
		printf("before the first layer");
	else
		printf("layer %ld", j->layer + 1);
	if (j->z == j->z) /* not NAN */
		printf(", Z %.2f mm", j->z);
	printf("\n  files here: %s\n", size);
	if (e->kind == JOBS_RESUMABLE)
		printf("  resume: stratum print --resume %s\n", j->id);
	return 0;
}

static int jobs_prune_cmd(const struct jobs_args *a, struct jobs_list *l)
{
	struct jobs_prune_opts o = {.now = (int64_t)time(NULL), .older_than = a->older_than,
				    .max_bytes = (uint64_t)(a->max_mb * 1e6),
				    .resumable = a->resumable};
	uint64_t freed = 0;
	size_t n = jobs_prune(l, &o, &freed), kept_resumable = 0, failed = 0;
	json_t *removed = json_array();
	char size[32], age[32];

	for (size_t i = 0; i < l->n; i++) {
		struct jobs_entry *e = &l->v[i];
		struct st_error err = {0};

		if (!e->pruned) {
			kept_resumable += e->kind == JOBS_RESUMABLE;
			continue;
		}
		if (!a->dry_run && jobs_remove(l, e, &err)) {
			fprintf(stderr, JOBS_CMD ": %s\n", err.msg);
			failed++;
			continue;
		}
		json_array_append_new(removed, json_string(e->id));
		if (!a->json) {
			fmt_size(size, sizeof(size), e->bytes);
			fmt_age(age, sizeof(age), o.now - e->updated);
			printf("%s %s (%s, %s, %s old)\n", a->dry_run ? "would remove" : "removed",
			       e->id, e->state, size, age);
		}
	}
	fmt_size(size, sizeof(size), freed);
	if (a->json) {
		json_t *r = json_pack("{s:b, s:b, s:o, s:I, s:I}", "ok", failed == 0, "dry_run",
				      a->dry_run, "removed", removed, "freed_bytes",
				      (json_int_t)freed, "kept", (json_int_t)(l->n - n));
		if (cmd_json_out(r, JSON_INDENT(2) | JSON_PRESERVE_ORDER))
			return ST_EXIT_FAILURE;
	} else {
		json_decref(removed);
		printf("%s %zu job%s (%s); kept %zu", a->dry_run ? "would remove" : "removed", n,
		       n == 1 ? "" : "s", size, l->n - n);
		if (kept_resumable && !a->resumable)
			printf(", %zu of them resumable (--resumable removes those too)",
			       kept_resumable);
		printf("\n");
	}
	return failed ? ST_EXIT_FAILURE : 0;
}

int cmd_jobs(int argc, char **argv)
{
	struct jobs_args a;
	struct jobs_list l;
	struct st_error err = {0};
	int status = jobs_parse(argc, argv, &a);

	if (status)
		return status < 0 ? ST_EXIT_OK : status;
	if (jobs_scan(&l, &err))
		return cmd_fail(JOBS_CMD, ST_EXIT_FAILURE, "%s", err.msg);
	if (!strcmp(a.pos[0], "list"))
		status = jobs_list_cmd(&a, &l);
	else if (!strcmp(a.pos[0], "show"))
		status = jobs_show_cmd(&a, &l);
	else
		status = jobs_prune_cmd(&a, &l);
	jobs_free(&l);
	return status;
}
