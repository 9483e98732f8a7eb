/*
 * print_stream.c - the streaming stage of `stratum print` (print_job.h):
 * one path through serial/printer.h whatever the printer's dialect, with
 * the job journal synced per layer and every few seconds, so `--resume
 * JOB` can continue after a crash, a power cut or a lost printer.
 */
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "gcode.h"
#include "print_job.h"
#include "printer_profile.h"
#include "send.h"
#include "st_clock.h"
#include "st_error.h"
#include "st_grow.h"

#define PRINT_SYNC_S 3.0 /* journal sync period besides every layer change */

/* Open path as a G-code reader (*f, *r); 0 or the exit status (message
 * printed). */
static int print_open(const char *path, FILE **f, struct gcode_reader **r)
{
	struct st_error err = {0};

	*f = fopen(path, "rb");
	if (!*f)
		return cmd_fail(PRINT_CMD, ST_EXIT_DATAERR, "cannot open %s: %s", path,
				strerror(errno));
	if (gcode_reader_new(*f, path, r, &err)) {
		fclose(*f);
		return cmd_fail(PRINT_CMD, ST_EXIT_SOFTWARE, "%s", err.msg);
	}
	return 0;
}

int print_scan(const char *path, struct print_layers *L)
{
	struct gcode_reader *r;
	struct gcode_line g;
	struct st_error err = {0};
	FILE *f;
	long layer = -1;
	int64_t before = 0;
	double stated = NAN, m73 = NAN; /* the file's own total estimate */
	int rc, status = 0;

	memset(L, 0, sizeof(*L));
	if ((status = print_open(path, &f, &r)))
		return status;
	while ((rc = gcode_reader_next(r, 0, &g, &err)) == 1) {
		long l;
		double z;
		enum gcode_layer_mark mark = gcode_layer_comment(&g, &l, &z);

		if (mark == GCODE_LAYER_START) {
			layer = l >= 0 ? l : layer + 1;
			if (layer < 0 || (size_t)layer > L->n + 100000) {
				status =
				    cmd_fail(PRINT_CMD, ST_EXIT_DATAERR,
					     "%s: line %llu: layer number %ld is out of order",
					     path, (unsigned long long)gcode_reader_line(r), layer);
				goto out;
			}
			while (L->n <= (size_t)layer) {
				void *p = st_grow(L->v, &L->cap, L->n + 1, sizeof(*L->v));
				if (!p) {
					status =
					    cmd_fail(PRINT_CMD, ST_EXIT_SOFTWARE, "out of memory");
					goto out;
				}
				L->v = p;
				L->v[L->n++] = (struct print_layer){gcode_reader_line(r), before, NAN, 0};
			}
			L->v[layer] = (struct print_layer){gcode_reader_line(r), before, z, 0};
		} else if (mark == GCODE_LAYER_Z && layer >= 0) {
			L->v[layer].z = z;
		}
		before = (int64_t)gcode_reader_bytes(r);
		if (g.has_comment && isnan(stated))
			stated = print_time_comment(g.comment);
		if (g.letter == 'M' && g.number == 73 && isnan(m73) && gcode_word_value(&g, 'R', &m73))
			m73 *= 60; /* minutes left at the start: the whole */
		if (g.kind == GCODE_KIND_HOST_ONLY || !g.text_len)
			continue;
		L->commands++;
	}
	L->lines = gcode_reader_line(r);
	if (rc < 0) {
		fprintf(stderr, PRINT_CMD ": %s; nothing was sent\n", err.msg);
		status = ST_EXIT_DATAERR;
	} else {
		print_estimate(path, L, !isnan(stated) ? stated : !isnan(m73) ? m73 : 0);
	}
out:
	gcode_reader_free(r);
	fclose(f);
	return status;
}

/* The layer (0-based) a file line belongs to, -1 before the first. */
static long print_layer_of(const struct print_layers *L, uint64_t line)
{
	size_t lo = 0, hi = L->n;

	while (lo < hi) {
		size_t mid = (lo + hi) / 2;
		if (L->v[mid].line <= line)
			lo = mid + 1;
		else
			hi = mid;
	}
	return (long)lo - 1;
}

/* -------- streaming through serial/printer.h, with the journal -------- */

/* What the stream's hooks share. */
struct print_run {
	struct send_progress p;
	struct print_job *job;
	volatile sig_atomic_t *stop;
	double last_sync;
	long last_layer;
	double est_base; /* a resume: the estimate of the layers skipped */
};

/* Sync the journal now; a failure is shown once, the print goes on. */
static void print_sync(struct print_job *job)
{
	struct st_error err = {0};
	static bool warned; /* once per process: a full disk is said once */

	if (!job->journal_on)
		return;
	if (!journal_save(&job->j, &err)) {
		job->journal_saved = true;
	} else if (!warned) {
		warned = true;
		fprintf(stderr, PRINT_CMD ": warning: %s; the print goes on but cannot be resumed "
				"from here\n", err.msg);
	}
}

/* Take the stream's progress into the job and the journal: the file line
 * of the last command the printer confirmed gives the layer. */
static void print_take(struct print_job *job, const struct printer_progress *p)
{
	job->done = p->done;
	job->resends = p->resends;
	if (job->input == PRINT_X3G) {
		job->total = p->total;
		return;
	}
	if (p->line) {
		job->last_line = p->line;
		job->layer = print_layer_of(&job->layers, job->last_line);
	}
	job->j.last_line = job->last_line;
	job->j.layer = job->layer;
	job->j.z = job->layer >= 0 ? job->layers.v[job->layer].z : NAN;
	if (p->tool) {
		job->j.tool_actual = p->tool_actual;
		job->j.tool_target = p->tool_target;
	}
	if (p->bed) {
		job->j.bed_actual = p->bed_actual;
		job->j.bed_target = p->bed_target;
	}
}

static enum printer_control print_control(void *ctx)
{
	return *((struct print_run *)ctx)->stop ? PRINTER_CANCEL : PRINTER_GO;
}

static void print_progress(void *ctx, const struct printer_progress *p)
{
	struct print_run *c = ctx;
	struct print_job *job = c->job;
	double now = st_mono_s();
	struct printer_progress v = *p;

	print_take(job, p);
	if (job->input != PRINT_X3G) { /* lines of the file, not of this run */
		v.unit = "line";
		v.done = job->last_line;
		v.total = job->layers.lines;
		v.layer = job->layer;
		c->p.est_done = print_est_done(&job->layers, job->layer, job->last_line) -
				c->est_base;
	}
	if (!job->a->json || c->p.tty)
		send_progress_show(&c->p, &v);
	if (job->layer != c->last_layer || now - c->last_sync >= PRINT_SYNC_S) {
		c->last_layer = job->layer;
		c->last_sync = now;
		print_sync(job);
	}
}

/* Where a stopped job got to; the journal saved in state. */
static void print_stopped_at(struct print_job *job, const char *state, int status)
{
	if (job->input == PRINT_X3G)
		fprintf(stderr, PRINT_CMD ": the printer confirmed command %llu of %llu\n",
			(unsigned long long)job->done, (unsigned long long)job->total);
	else if (job->layer >= 0)
		fprintf(stderr, PRINT_CMD ": the printer confirmed line %llu of %llu (layer %ld of "
				"%zu, Z %.2f mm)\n", (unsigned long long)job->last_line,
			(unsigned long long)job->layers.lines, job->layer + 1, job->layers.n,
			job->layers.v[job->layer].z);
	else
		fprintf(stderr, PRINT_CMD ": the printer confirmed line %llu of %llu (before the "
				"first layer)\n", (unsigned long long)job->last_line,
			(unsigned long long)job->layers.lines);
	if (!job->journal_on)
		return;
	snprintf(job->j.state, sizeof(job->j.state), "%s", state);
	print_sync(job);
	if (status != ST_EXIT_DATAERR && job->journal_saved)
		fprintf(stderr, PRINT_CMD ": the job is saved; continue it with 'stratum print "
				"--resume %s'\n", job->j.id);
}

int print_byte_after(const char *path, uint64_t line, int64_t *byte)
{
	struct gcode_reader *r;
	struct gcode_line g;
	struct st_error err = {0};
	FILE *f;
	int rc = 0;

	*byte = 0;
	if ((rc = print_open(path, &f, &r)))
		return rc;
	while (gcode_reader_line(r) < line && (rc = gcode_reader_next(r, 0, &g, &err)) == 1)
		*byte = (int64_t)gcode_reader_bytes(r);
	gcode_reader_free(r);
	fclose(f);
	if (rc < 0)
		return cmd_fail(PRINT_CMD, ST_EXIT_DATAERR, "%s", err.msg);
	return 0;
}

/* Check, connect, stream job->gcode to the printer of o; the exit status. */
static int print_on(struct print_job *job, const struct printer_ops *ops,
		    const struct printer_options *o)
{
	struct print_run run = {.job = job, .last_layer = -2};
	struct printer_job pj = {
		.path = job->gcode,
		.x3g = job->input == PRINT_X3G,
		.control = print_control,
		.progress = print_progress,
		.ctx = &run,
	};
	struct printer_file_info info;
	struct printer_result res;
	struct printer *pr = NULL;
	struct st_error err = {0};
	int rc, status;

	if (job->start_layer >= 0) {
		pj.offset = job->layers.v[job->start_layer].offset;
		pj.first_line = job->layers.v[job->start_layer].line - 1;
		pj.resume = true;
		pj.saved = job->saved;
	}
	if ((rc = printer_check(ops, o, &pj, send_warning, (void *)PRINT_CMD, &info, &err)))
		return cmd_fail(PRINT_CMD, send_exit_for_check(rc), "%s", err.msg);
	pj.total = info.commands;
	run.stop = send_catch_signals();
	if ((rc = printer_open(ops, o, &pr, &err)))
		return cmd_fail(PRINT_CMD, send_exit_for_open(rc), "%s", err.msg);
	printer_describe(pr, job->printer_desc, sizeof(job->printer_desc));
	send_progress_start(&run.p);
	run.p.cmd = PRINT_CMD;
	run.p.tag = "print";
	run.p.layers = job->layers.n;
	run.p.est_total = job->layers.est_total;
	if (job->start_layer >= 0) /* a resume: what is left of the estimate */
		run.est_base = job->layers.v[job->start_layer].est;
	run.p.est_total -= run.est_base;
	run.p.pace0 = job->simulated ? job->a->speedup : 1;
	job->total = job->input == PRINT_X3G ? info.commands : job->layers.lines;
	if (!job->a->json || run.p.tty)
		fprintf(stderr, PRINT_CMD ": printing on %s at %s, %llu %s\n", job->printer_desc,
			job->port, (unsigned long long)job->total,
			job->input == PRINT_X3G ? "commands" : "lines");
	print_sync(job);
	rc = printer_stream(pr, &pj, &res, &err);
	job->stream_s = res.last.seconds;
	job->machine_s = res.machine_s;
	send_progress_end(&run.p);
	print_take(job, &res.last);
	status = send_exit_for(&res, rc);
	if (status == ST_EXIT_OK) {
		if (job->input != PRINT_X3G)
			job->last_line = job->j.last_line = job->layers.lines;
		snprintf(job->j.state, sizeof(job->j.state), "done");
		print_sync(job);
	} else {
		snprintf(job->fail_buf, sizeof(job->fail_buf), "%s",
			 err.msg[0] ? err.msg : "the job was cancelled");
		job->fail = job->fail_buf;
		fprintf(stderr, PRINT_CMD ": %s\n", job->fail);
		/* the link still works: leave the printer safe */
		if (send_safe_stop(PRINT_CMD, pr, &res) && status == ST_EXIT_FAILURE)
			fprintf(stderr, PRINT_CMD ": switch the printer off by hand if it is "
					"still heating\n");
		print_stopped_at(job, res.end == PRINTER_END_LINK_LOST ? "link-lost"
				      : status == ST_EXIT_INTERRUPTED ? "cancelled" : "failed",
				 status);
	}
	printer_close(pr);
	return status;
}

/* Open the port the user asked for (or the simulator); 0 or exit status. */
int print_stream(struct print_job *job)
{
	const char *port = job->a->port ? job->a->port : "sim";
	struct printer_options o;
	const struct printer_ops *ops;
	int rc;

	job->simulated = !strcmp(port, "sim");
	if ((rc = printer_profile_cli(PRINT_CMD, job->prof, &port, 0, job->a->json,
				      &job->port_auto, &o, &ops)))
		return rc;
	o.sim_speedup = job->a->speedup;
	o.sim_log = job->a->sim_log;
	if (job->simulated && !job->a->json)
		fprintf(stderr, PRINT_CMD ": SIMULATION: no printer is used; printing to the "
				"built-in simulated %s printer, %gx faster than real time "
				"(choose a printer with --port PATH or --port auto)\n",
			ops->name, job->a->speedup);
	job->port = port;
	if (job->a->port != job->j.port) /* a resume names the journal's own */
		snprintf(job->j.port, sizeof(job->j.port), "%s", job->a->port ? job->a->port : "sim");
	return print_on(job, ops, &o);
}
