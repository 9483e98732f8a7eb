/*
 * printer_sailfish.c - the Sailfish adapter of printer.h (FlashForge
 * Creator Pro and kin): G-code is translated to X3G as it streams and X3G
 * files are cut into commands (sf_source.h), and the commands go out as
 * S3G packets through s3g_stream_pull (s3g.h), to a device path, a pty,
 * tcp://, or port "sim", the simulated Sailfish printer
 * (serial/sim/sailfish_sim.h) run in this process.
 *
 * Progress is the end of the G-code line (or X3G command) of the last
 * command the firmware took.  Hold stops feeding commands: the firmware
 * runs out what its 512-byte buffer holds and the stream shows paused once
 * the printer reports it is finished.  S3G's pause (query 8) is not used:
 * it toggles, so a resent packet after a lost reply would undo it, and
 * Sailfish moves the head on its own when it pauses.  An interrupted G-code
 * print resumes from the start of a layer (resume_from_layer), after the
 * preamble of resume_x3g_text (bed wait, Z set where it was, X/Y
 * homed, M132, nozzle wait), both through one translator so its positions
 * agree with the firmware's.  An X3G file has no layers to restart from.
 * An operator's G-code line (job->inject) goes through that translator too,
 * between two lines of the file, and so do the file's heater targets with
 * the operator's offsets; holds begin between lines for the same reason.
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "gcode.h"
#include "printer.h"
#include "resume.h"
#include "s3g.h"
#include "sf_source.h"
#include "sim/sailfish_sim.h"
#include "st_clock.h"
#include "xport.h"

#define PS_POLL_S 2	/* temperature queries between jobs (s) */
#define PS_HOLD_MS 250	/* status poll while a hold lasts (ms) */

struct ps_state {
	char name[96];
	bool simulated;
	struct sim_sailfish *sim; /* port = sim only */
	struct xport *x;
	struct s3g *d;
	struct x3g_machine m;
	struct x3g_options xo;
	char firmware[32];
	long baud;
	time_t last_poll;
};

/* One stream or check: what the source callbacks share. */
struct ps_run {
	struct ps_state *s;
	const struct printer_job *job;
	int64_t offset;	  /* byte the source reads from (a layer start for a resume) */
	char pre[RESUME_TEXT_MAX];
	bool has_pre;
	struct sfsrc_gcode g;
	struct sfsrc_x3g x;
	printer_warn_fn warn;
	void *warn_ctx;
	volatile sig_atomic_t stop; /* polled by the driver */
	enum printer_control asked;
	bool link_lost;		    /* a query failed while a hold lasted */
	bool seen_running;	    /* build statistics said running while held */
	bool back;		    /* operator lines ran while held: the way back is due */
	double t0;
	struct printer_progress *last;
	long layer_told;	    /* the layer the hook was last called with */
	char why[256];		    /* why the link was lost */
};

static void ps_free(struct ps_state *s)
{
	if (!s)
		return;
	s3g_free(s->d);
	printer_port_close(s->x);
	sim_sailfish_free(s->sim);
	free(s);
}

/* Start the simulated printer of o on its own thread; its pty in *path. */
static int ps_start_sim(struct ps_state *s, const struct printer_options *o, const char **path,
			struct st_error *err)
{
	struct sim_sailfish_options so;
	int rc;

	sim_sailfish_options_init(&so);
	so.speedup = o->sim_speedup;
	so.baud = printer_sim_baud(o);
	so.log_path = o->sim_log;
	if ((rc = sim_sailfish_new(&so, &s->sim, err)) ||
	    (rc = sim_sailfish_start_thread(s->sim, err)))
		return rc;
	*path = sim_sailfish_slave_path(s->sim);
	return 0;
}

static int ps_open(const struct printer_options *o, void **state, struct st_error *err)
{
	struct ps_state *s = calloc(1, sizeof(*s));
	struct s3g_options so;
	const char *path = o->port;
	struct st_error e = {0};
	uint16_t fw = 0;
	int rc;

	if (!s)
		return st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", printer_name(o));
	snprintf(s->name, sizeof(s->name), "%s", printer_name(o));
	s->m = o->machine;
	s->xo = o->x3g;
	s->baud = o->baud;
	s->simulated = !strcmp(o->port, "sim");
	if (s->simulated && (rc = ps_start_sim(s, o, &path, &e))) {
		rc = st_error_set(err, rc, "%s: simulated printer: %s", s->name, e.msg);
		goto out_free;
	}
	if ((rc = printer_port_open(o, path, s->simulated, &s->x, err)))
		goto out_free;
	s3g_options_init(&so);
	so.tools = s->m.extruder_count > 1 ? 2 : 1;
	if ((rc = s3g_new(s->x, &so, &s->d, &e))) {
		rc = st_error_set(err, rc, "%s: %s", s->name, e.msg);
		goto out_free;
	}
	/* the version query proves a Sailfish board answers S3G on the port */
	if (s3g_get_version(s->d, SFSRC_HOST_VERSION, &fw, &e)) {
		rc = st_error_set(err, ST_ERR_IO, "%s: no answer from a Sailfish printer on %s "
				  "(%s); check that it is switched on, not busy with an SD print, "
				  "and that the baud rate matches", s->name,
				  s->simulated ? "the simulated port" : o->port, e.msg);
		goto out_free;
	}
	snprintf(s->firmware, sizeof(s->firmware), "Sailfish %u.%u", fw / 100u, fw % 100u);
	*state = s;
	return 0;

out_free:
	ps_free(s);
	return rc;
}

static void ps_close(void *state)
{
	ps_free(state);
}

/* The driver's temperatures into p. */
static void ps_temps(const struct s3g_status *st, struct printer_progress *p)
{
	p->tool = st->tool_temp || st->tool_target;
	p->bed = st->platform_temp || st->platform_target;
	p->tool_actual = st->tool_temp;
	p->tool_target = st->tool_target;
	p->bed_actual = st->platform_temp;
	p->bed_target = st->platform_target;
	p->tool1 = st->tool1_temp || st->tool1_target; /* 0, 0: not read (one tool) */
	p->tool1_actual = st->tool1_temp;
	p->tool1_target = st->tool1_target;
}

/* G-code lines done: up to that of the last command taken (one pulled ahead at most). */
static uint64_t ps_lines_done(const struct ps_run *r, uint64_t done)
{
	if (r->job->x3g || done == 0)
		return 0;
	return done >= r->g.pulled ? r->g.line : r->g.prev_line;
}

/* The status as progress. */
static void ps_progress_of(struct ps_run *r, const struct s3g_status *st)
{
	struct printer_progress *p = r->last;
	uint64_t done = st->confirmed + st->skipped;
	uint64_t end = sfsrc_done_end(&r->g, &r->x, r->job->x3g, done);
	uint64_t line = ps_lines_done(r, done);

	p->unit = "command";
	p->done = done;
	p->total = r->job->total + r->g.inserted; /* the operator's commands count too */
	/* Within the preamble the saved position stands: the layer start would
	 * read as the layer before, which a second resume would print again. */
	p->filepos = end ? r->offset + (int64_t)end
			 : r->job->saved ? r->job->saved : r->job->offset;
	if (line)
		p->line = r->job->first_line + line;
	p->layer = r->job->x3g ? -1 : r->g.layer;
	p->z = NAN;
	ps_temps(st, p); /* paused is ps_hold's */
	p->resends = st->retries;
	p->seconds = st_mono_s() - r->t0;
}

/* Ask the hook; a cancel or stop sets the driver's stop flag. */
static enum printer_control ps_ask(struct ps_run *r)
{
	if (r->asked == PRINTER_CANCEL || r->asked == PRINTER_STOP)
		return r->asked;
	r->asked = r->job->control ? r->job->control(r->job->ctx) : PRINTER_GO;
	if (r->asked == PRINTER_CANCEL || r->asked == PRINTER_STOP)
		r->stop = 1;
	return r->asked;
}

/* s3g progress callback: status to the hook, requests into the stop flag. */
static void ps_progress(void *ctx, const struct s3g_status *st)
{
	struct ps_run *r = ctx;

	ps_progress_of(r, st);
	ps_ask(r);
	r->layer_told = r->last->layer;
	if (r->job->progress)
		r->job->progress(r->job->ctx, r->last);
}

/* Sleep ms milliseconds. */
static void ps_sleep_ms(long ms)
{
	struct timespec ts = {ms / 1000, (ms % 1000) * 1000000L};

	nanosleep(&ts, NULL);
}

/* The operator's waiting lines (job->inject) into the source, to go
 * before the file's next line with the stream's translator, as many as it
 * has room for; true when one did. */
static bool ps_operator_lines(struct ps_run *r)
{
	char line[GCODE_LINE_MAX + 1];
	bool any = false;

	while (!r->job->x3g && r->job->inject && sfsrc_gcode_insert_room(&r->g) > sizeof(line) &&
	       r->job->inject(r->job->ctx, line, sizeof(line)))
		any = sfsrc_gcode_insert(&r->g, line) || any;
	return any;
}

/* Going again after operator lines ran while held: the way back to where
 * the file left the head (resume_return), before the file's next line. */
static void ps_way_back(struct ps_run *r)
{
	char out[RESUME_LINES][RESUME_LINE_MAX + 1];
	struct resume_state rs;
	struct st_error e;
	size_t n = 0;

	r->back = false;
	/* a file that cannot be read back leaves the head where it is */
	if (!resume_scan(r->job->path, r->offset + (int64_t)r->g.end, &rs, &e))
		n = resume_return(&rs, !rs.rel_e, out, RESUME_LINES);
	for (size_t i = 0; i < n; i++)
		sfsrc_gcode_insert(&r->g, out[i]);
}

/*
 * Hold while the hook says so; the operator's lines go out meanwhile
 * (returns 1 with one in the source).  The printer is queried every PS_HOLD_MS:
 * finished means paused; a failed query or a reboot ends the stream as a
 * lost link.
 */
static int ps_hold(struct ps_run *r, struct st_error *err)
{
	struct s3g_build_stats b;
	struct s3g_temps t;
	struct st_error e = {0};
	bool done = false;

	while (ps_ask(r) == PRINTER_HOLD) {
		int rc = s3g_is_finished(r->s->d, &done, &e);

		if (!rc)
			rc = s3g_get_temps(r->s->d, &t, &e);
		if (!rc)
			rc = s3g_get_build_stats(r->s->d, &b, &e);
		if (!rc && b.state == S3G_BUILD_NONE && r->seen_running)
			rc = st_error_set(&e, ST_ERR_IO, "the printer reset while paused: it "
					  "answers as freshly booted");
		if (!rc && (b.state == S3G_BUILD_RUNNING || b.state == S3G_BUILD_PAUSED))
			r->seen_running = true;
		if (rc) {
			r->link_lost = true;
			snprintf(r->why, sizeof(r->why), "%s", e.msg);
			return st_error_set(err, ST_ERR_IO, "%s", e.msg);
		}
		ps_temps(s3g_status_get(r->s->d), r->last);
		r->last->paused = done;
		if (r->job->progress)
			r->job->progress(r->job->ctx, r->last);
		if (ps_operator_lines(r)) {
			r->back = true;
			return 1;
		}
		ps_sleep_ms(PS_HOLD_MS);
	}
	r->last->paused = false;
	return 0;
}

/* The file's next command. */
static int ps_next_of_file(struct ps_run *r, struct s3g_cmd *cmd, struct st_error *err)
{
	return r->job->x3g ? sfsrc_x3g_next(&r->x, cmd, err) : sfsrc_gcode_next(&r->g, cmd, err);
}

/* s3g_source_fn: hold, end on cancel or stop, the operator's lines, else
 * the file's next. */
static int ps_next(void *src, struct s3g_cmd *cmd, struct st_error *err)
{
	struct ps_run *r = src;
	int rc;

	if (r->stop)
		return 0; /* the driver sees the stop flag and ends as interrupted */
	/* a line's commands go out together: holds and the operator's lines
	 * come between lines, where the translator's position is the file's */
	if (!r->job->x3g && (sfsrc_gcode_mid_line(&r->g) || r->g.ins_pos < r->g.ins_len))
		return sfsrc_gcode_next(&r->g, cmd, err);
	if ((rc = ps_hold(r, err)) < 0)
		return rc;
	if (r->stop)
		return 0;
	if (rc == 0 && r->back)
		ps_way_back(r);
	else if (rc == 0)
		ps_operator_lines(r);
	/* a new layer is told at once, not at the next 0.1 s report: the
	 * journal print keeps from the hook must not lag by layers */
	if (!r->job->x3g && r->g.layer != r->layer_told)
		ps_progress(r, s3g_status_get(r->s->d));
	return ps_next_of_file(r, cmd, err);
}

/* Show a line's translator warnings through the caller's hook. */
static void ps_warn(void *ctx, const char *name, const struct x3g_warning *w, size_t n)
{
	struct ps_run *r = ctx;

	for (size_t i = 0; i < n; i++)
		r->warn(r->warn_ctx, name, w[i].line, w[i].msg);
}

/* The operator's temperature offsets on a line of the file. */
static void ps_edit(void *ctx, struct gcode_line *line)
{
	struct ps_run *r = ctx;

	printer_temp_offset(r->job, line, r->s->xo.flavor == X3G_FLAVOR_MAKERBOT, GCODE_LINE_MAX);
}

/* Open r's source over f from r->offset, preamble first; 0 or an error. */
static int ps_source_open(struct ps_run *r, FILE *f, struct st_error *err)
{
	int rc;

	if (fseeko(f, (off_t)r->offset, SEEK_SET))
		return st_error_set(err, ST_ERR_IO, "%s: cannot seek: %s", r->job->path,
				    strerror(errno));
	if (r->job->x3g) {
		sfsrc_x3g_open(&r->x, f);
		return 0;
	}
	r->g.warn = r->warn ? ps_warn : NULL;
	r->g.warn_ctx = r;
	r->g.edit = ps_edit;
	r->g.edit_ctx = r;
	if ((rc = sfsrc_gcode_open(&r->g, f, r->job->path, &r->s->m, &r->s->xo, err)))
		return rc;
	r->g.pre = r->has_pre ? r->pre : NULL;
	r->g.pre_len = r->has_pre ? strlen(r->pre) : 0;
	return 0;
}

static void ps_source_close(struct ps_run *r)
{
	if (!r->job->x3g)
		sfsrc_gcode_close(&r->g);
}

/* A run of job: resume setup (layer start, preamble) and the build name. */
static int ps_run_init(struct ps_run *r, struct ps_state *s, const struct printer_job *job,
		       char *build, size_t cap, struct st_error *err)
{
	int rc;

	memset(r, 0, sizeof(*r));
	r->s = s;
	r->job = job;
	r->offset = job->offset;
	if (job->resume) {
		if (job->x3g)
			return st_error_set(err, ST_ERR_UNSUPPORTED, "%s: an interrupted X3G print "
					    "cannot be resumed: it has no layers to restart from",
					    s->name);
		if ((rc = resume_x3g_text(job->path, r->offset, job->saved, r->pre, err)))
			return rc;
		r->has_pre = true;
	}
	/* named as `stratum x3g FILE -o NAME.x3g` names it */
	x3g_build_name(job->path, build, cap);
	s->xo.build_name = build;
	return 0;
}

static int ps_check(const struct printer_options *o, const struct printer_job *job,
		    printer_warn_fn warn, void *warn_ctx, struct printer_file_info *info,
		    struct st_error *err)
{
	struct ps_state *s = calloc(1, sizeof(*s)); /* no link: the translator's part */
	struct ps_run *r = malloc(sizeof(*r));
	char build[X3G_BUILD_NAME_MAX + 1];
	struct s3g_cmd c;
	FILE *f = NULL;
	int rc;

	if (!r || !s) {
		free(r);
		free(s);
		return st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", printer_name(o));
	}
	snprintf(s->name, sizeof(s->name), "%s", printer_name(o));
	s->m = o->machine;
	s->xo = o->x3g;
	if ((rc = ps_run_init(r, s, job, build, sizeof(build), err)))
		goto out;
	r->warn = warn;
	r->warn_ctx = warn_ctx;
	f = fopen(job->path, "rb");
	if (!f) {
		rc = st_error_set(err, ST_ERR_IO, "%s: cannot open: %s", job->path, strerror(errno));
		goto out;
	}
	if (!(rc = ps_source_open(r, f, err)))
		while ((rc = ps_next_of_file(r, &c, err)) > 0)
			info->commands++;
	if (!job->x3g && r->g.r) {
		info->lines = gcode_reader_line(r->g.r);
		info->warnings = x3g_warning_total(r->g.t);
	}
	ps_source_close(r);
	if (rc < 0) {
		char msg[sizeof(err->msg)];

		snprintf(msg, sizeof(msg), "%s", err->msg);
		rc = st_error_set(err, rc == ST_ERR_NOMEM || rc == ST_ERR_INTERNAL ? rc
										   : ST_ERR_PARSE,
				  "%s%s%s; nothing was sent", job->x3g ? job->path : "",
				  job->x3g ? ": " : "", msg);
	}
out:
	if (f)
		fclose(f);
	free(s);
	free(r);
	return rc < 0 ? rc : 0;
}

/* The counters of a Sailfish stream, for reports. */
static void ps_counters(const struct ps_run *r, const struct s3g_status *st,
			struct printer_result *res)
{
	double sec = st->elapsed_s;
	uint64_t lines = res->end == PRINTER_END_DONE && r->g.r ? gcode_reader_line(r->g.r)
								: ps_lines_done(r, st->confirmed +
										       st->skipped);
	double cap = r->s->baud / 10.0;
	double both = sec > 0 && cap > 0 ? (double)(st->bytes_out + st->bytes_in) / sec / cap : 0;
	struct printer_counter v[] = {
		{"commands", (double)st->confirmed, false},
		{"commands_total", (double)r->job->total, false},
		{"commands_per_s", sec > 0 ? (double)st->confirmed / sec : 0, true},
		{"packets", (double)st->packets, false},
		{"retries", (double)st->retries, false},
		{"overflows", (double)st->overflows, false},
		{"timeouts", (double)st->timeouts, false},
		{"garbled", (double)st->garbled, false},
		{"misread", (double)st->misread, false},
		{"resolved", (double)st->resolved, false},
		{"dup_risk", (double)st->dup_risk, false},
		{"drifts", (double)st->drifts, false},
		{"bytes_read", (double)st->bytes_in, false},
		{"link_fraction_both_ways", both, true},
		{"lines", (double)lines, false},
		{"lines_per_s", sec > 0 ? (double)lines / sec : 0, true},
	};
	size_t n = sizeof(v) / sizeof(v[0]) - (r->job->x3g ? 2 : 0);

	memcpy(res->counters, v, n * sizeof(v[0]));
	res->ncounters = n;
	/* confirmed commands as framed packets: start, length, CRC */
	res->bytes_acked = st->action_bytes + 3 * (uint64_t)st->confirmed;
	res->bytes_written = st->bytes_out;
	res->errors = st->errors;
	res->unknown_commands = st->skipped;
	if (r->job->x3g)
		res->last.line = 0;
	else if (res->end == PRINTER_END_DONE)
		res->last.line = r->job->first_line + lines;
	snprintf(res->detail, sizeof(res->detail),
		 "%llu packets: retries %llu, errors %llu, unsupported commands %llu, buffer "
		 "overflows %llu, time-outs %llu, garbled replies %llu (%llu settled by asking, "
		 "%llu resent unsure)",
		 (unsigned long long)st->packets, (unsigned long long)st->retries,
		 (unsigned long long)st->errors, (unsigned long long)st->skipped,
		 (unsigned long long)st->overflows, (unsigned long long)st->timeouts,
		 (unsigned long long)st->garbled, (unsigned long long)st->resolved, (unsigned long long)st->dup_risk);
	if (!r->job->x3g)
		snprintf(res->detail + strlen(res->detail), sizeof(res->detail) - strlen(res->detail),
			 "\n  G-code lines %llu", (unsigned long long)lines);
	snprintf(res->detail + strlen(res->detail), sizeof(res->detail) - strlen(res->detail),
		 "\n  link both ways %.1f%%", 100.0 * both);
}

/* How the stream ended; err filled when not done. */
static void ps_end(struct ps_run *r, const struct s3g_status *st, int rc,
		   struct printer_result *res, struct st_error *err)
{
	if (rc == 0 && st->interrupted) {
		res->end = r->asked == PRINTER_STOP ? PRINTER_END_STOPPED : PRINTER_END_CANCELLED;
		res->safe_stop = true;
		st_error_set(err, ST_ERR_IO, "%s: the job was cancelled after command %zu of %llu",
			     r->s->name, st->confirmed + st->skipped,
			     (unsigned long long)r->job->total);
	} else if (rc == 0) {
		res->end = PRINTER_END_DONE;
	} else if (r->link_lost || st->fail == S3G_FAIL_LINK) {
		/* the part may be fine: the job can be resumed */
		if (!r->link_lost)
			snprintf(r->why, sizeof(r->why), "%s", err->msg);
		st_error_set(err, ST_ERR_IO, "%s: the link was lost: %s", r->s->name, r->why);
		res->end = PRINTER_END_LINK_LOST;
	} else {
		/* the printer stopped the build (0x89 cancelled on its panel, 0x8B
		 * overheat) or a command could not be sent: the job fails */
		char msg[sizeof(err->msg)];

		snprintf(msg, sizeof(msg), "%s", err->msg);
		st_error_set(err, rc == ST_ERR_PARSE ? ST_ERR_PARSE : ST_ERR_IO, "%s: %s",
			     r->s->name, msg);
		res->end = PRINTER_END_FAILED;
		res->safe_stop = true;
	}
}

static int ps_stream(void *state, const struct printer_job *job, struct printer_result *res,
		     struct st_error *err)
{
	struct ps_state *s = state;
	struct ps_run *r = malloc(sizeof(*r));
	char build[X3G_BUILD_NAME_MAX + 1];
	struct s3g_status st;
	struct stat sb;
	FILE *f = NULL;
	double m0;
	int rc;

	if (!r)
		return st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", s->name);
	res->last.filepos = job->saved ? job->saved : job->offset;
	if ((rc = ps_run_init(r, s, job, build, sizeof(build), err)))
		goto out;
	r->last = &res->last;
	r->t0 = st_mono_s();
	m0 = s->sim ? sim_sailfish_machine_s(s->sim) : NAN;
	f = fopen(job->path, "rb");
	if (!f) {
		rc = st_error_set(err, ST_ERR_IO, "%s: cannot open: %s", job->path, strerror(errno));
		goto out;
	}
	if ((rc = ps_source_open(r, f, err)))
		goto out_source;
	/* a file that starts no build gets one of its own: the build's line
	 * count is what settles a lost reply (docs/streaming.md) */
	s3g_frame_builds(s->d, build);
	rc = s3g_stream_pull(s->d, ps_next, r, (size_t)job->total, ps_progress, r, &r->stop, &st,
			     err);
	s3g_frame_builds(s->d, NULL);
	ps_progress_of(r, &st);
	res->last.paused = false;
	ps_end(r, &st, rc, res, err);
	if (res->end == PRINTER_END_DONE && !fstat(fileno(f), &sb))
		res->last.filepos = (int64_t)sb.st_size;
	ps_counters(r, &st, res);
	if (s->sim)
		res->machine_s = sim_sailfish_machine_s(s->sim) - m0;
	if (job->progress)
		job->progress(job->ctx, &res->last);
	rc = 0;
out_source:
	ps_source_close(r);
out:
	if (f)
		fclose(f);
	s->xo.build_name = NULL;
	free(r);
	return rc < 0 ? rc : 0;
}

/* Send each command of one translated G-code line. */
static int ps_command(void *state, const char *line, char *reply, size_t cap,
		      struct st_error *err)
{
	struct ps_state *s = state;
	struct x3g_translator *t = NULL;
	struct gcode_line g;
	uint8_t resp[S3G_MAX_PAYLOAD];
	const uint8_t *out;
	size_t len, rlen, pos = 0;
	int rc = gcode_parse(line, strlen(line), 0, &g, err);

	(void)reply;
	(void)cap;
	if (rc || !g.text_len)
		return rc;
	/* A fresh translator: the head's position is not known between jobs. */
	if ((rc = x3g_new(&s->m, &s->xo, &t, err)) || (rc = x3g_translate(t, &g, 1, err)) < 0)
		goto out;
	out = x3g_output(t, &len);
	rc = 0;
	while (pos < len && !rc) {
		int k = s3g_action_length(out + pos, len - pos);

		if (k <= 0 || (size_t)k > len - pos) {
			rc = st_error_set(err, ST_ERR_INTERNAL, "%s: the translator wrote command "
					  "%u, which the S3G driver cannot send", g.text, out[pos]);
			break;
		}
		rc = s3g_transact(s->d, out + pos, (size_t)k, resp, sizeof(resp), &rlen, err);
		pos += (size_t)k;
	}
out:
	x3g_free(t);
	return rc < 0 ? rc : 0;
}

static int ps_poll(void *state, struct printer_progress *p, struct st_error *err)
{
	struct ps_state *s = state;
	struct s3g_temps t;
	struct st_error e = {0};
	time_t now = time(NULL);

	if (now - s->last_poll < PS_POLL_S)
		return 0;
	s->last_poll = now;
	if (s3g_get_temps(s->d, &t, &e))
		return st_error_set(err, ST_ERR_IO, "%s: %s", s->name, e.msg);
	ps_temps(s3g_status_get(s->d), p);
	return 0;
}

static int ps_safe_stop(void *state, struct st_error *err)
{
	struct ps_state *s = state;
	struct st_error e = {0};

	if (s3g_cancel(s->d, &e))
		return st_error_set(err, ST_ERR_IO, "%s: safe stop failed: %s; switch the printer "
				    "off by hand", s->name, e.msg);
	return 0;
}

static void ps_describe(void *state, char *out, size_t cap)
{
	struct ps_state *s = state;

	snprintf(out, cap, "%s%s", s->firmware, s->simulated ? " (simulated printer)" : "");
}

const struct printer_ops printer_sailfish_ops = {
	.name = "sailfish",
	.can_resume = true,
	.takes_x3g = true,
	.resume_from_layer = true,
	.takes_injected = true,
	.open = ps_open,
	.close = ps_close,
	.check = ps_check,
	.stream = ps_stream,
	.command = ps_command,
	.poll = ps_poll,
	.safe_stop = ps_safe_stop,
	.describe = ps_describe,
};
