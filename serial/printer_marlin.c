/*
 * printer_marlin.c - the Marlin adapter of printer.h: the text protocol
 * driver (marlin.h) to a device path, a pty, tcp://, or port "sim", the
 * simulated Marlin printer (serial/sim/marlin_sim.h) run in this process.
 *
 * Each job command is submitted with its number in this run as its
 * "source line"; a ring of the last submissions maps the last acknowledged
 * one back to its file line, byte end, layer and Z, so progress is the byte
 * just past the last command the firmware took (where a resume starts).
 * Hold stops new lines (the firmware finishes what it holds); cancel and
 * stop end the stream with the printer still answering, for
 * printer_safe_stop.
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "gcode.h"
#include "marlin.h"
#include "printer.h"
#include "resume.h"
#include "sim/marlin_sim.h"
#include "st_clock.h"
#include "xport.h"

#define PM_STEP_MS 50	     /* longest wait for replies per loop turn */
#define PM_CMD_WAIT_MS 120000 /* longest wait for one printer command */
#define PM_STOP_MS 10000     /* safe stop: longest wait for its commands */
#define PM_POLL_S 5	     /* M105 period when idle without autoreport */
#define PM_PROGRESS_S 0.2    /* progress hook period */
#define PM_RING 2048	     /* submissions remembered: more than can be in flight */

_Static_assert(RESUME_LINE_MAX == MARLIN_CMD_MAX, "resume lines fit Marlin's limit");

/* Where one submitted command came from. */
struct pm_src {
	uint64_t line;	/* file line */
	int64_t end;	/* byte just past it */
	long layer;
	double z;
};

struct pm_state {
	char name[96];
	void (*trace)(void *ctx, const char *dir, const char *line); /* the caller's */
	void *trace_ctx;
	bool simulated;
	struct sim_marlin *sim; /* port = sim only */
	struct xport *x;
	struct marlin *m;
	time_t last_poll;
	char *reply;		/* printer_command's reply buffer while it runs */
	size_t reply_cap, reply_len;
	struct pm_src ring[PM_RING];
};

static void pm_free(struct pm_state *s)
{
	if (!s)
		return;
	marlin_free(s->m);
	printer_port_close(s->x);
	sim_marlin_free(s->sim);
	free(s);
}

/* Start the simulated printer of o on its own thread; its pty in *path. */
static int pm_start_sim(struct pm_state *s, const struct printer_options *o, const char **path,
			struct st_error *err)
{
	struct sim_marlin_options so;
	int rc;

	sim_marlin_options_init(&so);
	so.speedup = o->sim_speedup;
	so.baud = printer_sim_baud(o);
	if (o->rx_buffer > 0)
		so.rx_buffer = o->rx_buffer;
	if (o->bufsize > 0)
		so.bufsize = o->bufsize;
	so.advanced_ok = true;
	so.log_path = o->sim_log;
	if ((rc = sim_marlin_new(&so, &s->sim, err)) || (rc = sim_marlin_start_thread(s->sim, err)))
		return rc;
	*path = sim_marlin_slave_path(s->sim);
	return 0;
}

/* The driver's trace: while a command runs, its reply lines go to s->reply. */
static void pm_trace(void *ctx, const char *dir, const char *line)
{
	struct pm_state *s = ctx;
	size_t n = strcspn(line, "\r\n");

	if (s->trace)
		s->trace(s->trace_ctx, dir, line);
	if (!s->reply || dir[0] != '<' || s->reply_len + n + 2 > s->reply_cap)
		return;
	memcpy(s->reply + s->reply_len, line, n);
	s->reply_len += n;
	s->reply[s->reply_len++] = '\n';
	s->reply[s->reply_len] = '\0';
}

static int pm_open(const struct printer_options *o, void **state, struct st_error *err)
{
	struct pm_state *s = calloc(1, sizeof(*s));
	struct marlin_options mo;
	const char *path = o->port;
	struct st_error e = {0};
	int rc;

	if (!s)
		return st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", printer_name(o));
	snprintf(s->name, sizeof(s->name), "%s", printer_name(o));
	s->simulated = !strcmp(o->port, "sim");
	if (s->simulated && (rc = pm_start_sim(s, o, &path, &e))) {
		rc = st_error_set(err, rc, "%s: simulated printer: %s", s->name, e.msg);
		goto out_free;
	}
	if ((rc = printer_port_open(o, path, s->simulated, &s->x, err)))
		goto out_free;
	marlin_options_init(&mo);
	mo.rx_buffer = o->rx_buffer;
	mo.bufsize = o->bufsize;
	if (o->retry_ms > 0)
		mo.retry_ms = o->retry_ms;
	if (o->probe_ms > 0)
		mo.probe_ms = o->probe_ms;
	if (o->dead_ms > 0)
		mo.dead_ms = o->dead_ms;
	mo.trace = pm_trace;
	mo.trace_ctx = s;
	s->trace = o->trace;
	s->trace_ctx = o->trace_ctx;
	/* the simulator boots like a board; ptys and TCP bridges are not reset */
	mo.expect_reset = s->simulated ||
			  (o->dtr_reset && xport_backend_of(s->x) == XPORT_BACKEND_SERIALPORT);
	if ((rc = marlin_new(s->x, &mo, &s->m, &e)) || (rc = marlin_connect(s->m, &e))) {
		rc = st_error_set(err, rc == ST_ERR_INTERNAL ? ST_ERR_INTERNAL : ST_ERR_IO,
				  "%s: %s", s->name, e.msg);
		goto out_free;
	}
	*state = s;
	return 0;

out_free:
	pm_free(s);
	return rc;
}

static void pm_close(void *state)
{
	pm_free(state);
}

/* A command too long for Marlin, as the same error everywhere. */
static int pm_too_long(const char *path, uint64_t line, size_t len, struct st_error *err)
{
	return st_error_set(err, ST_ERR_PARSE, "%s: line %llu: the command is %zu bytes long; "
			    "Marlin takes at most %d (shorten it)", path,
			    (unsigned long long)line, len, MARLIN_CMD_MAX);
}

/* Open job's file at its offset with a reader; 0 or ST_ERR_IO. */
static int pm_reader(const struct printer_job *job, FILE **f, struct gcode_reader **r,
		     struct st_error *err)
{
	*r = NULL;
	*f = fopen(job->path, "rb");
	if (!*f)
		return st_error_set(err, ST_ERR_IO, "%s: cannot open: %s", job->path,
				    strerror(errno));
	if (fseeko(*f, (off_t)job->offset, SEEK_SET)) {
		fclose(*f);
		*f = NULL;
		return st_error_set(err, ST_ERR_IO, "%s: cannot read: %s", job->path,
				    strerror(errno));
	}
	if (gcode_reader_new(*f, job->path, r, err)) {
		fclose(*f);
		*f = NULL;
		return ST_ERR_NOMEM;
	}
	return 0;
}

/* The resume preamble of job into pre; how many lines (0 without resume). */
static int pm_preamble(const struct printer_job *job, char pre[][RESUME_LINE_MAX + 1],
		       uint64_t *n, struct st_error *err)
{
	struct resume_state rs;
	int rc;

	*n = 0;
	if (!job->resume)
		return 0;
	if ((rc = resume_locate(job->path, job->offset, job->saved, &rs, err)))
		return rc;
	*n = resume_preamble(&rs, pre, RESUME_LINES);
	return 0;
}

static int pm_check(const struct printer_options *o, const struct printer_job *job,
		    printer_warn_fn warn, void *warn_ctx, struct printer_file_info *info,
		    struct st_error *err)
{
	char pre[RESUME_LINES][RESUME_LINE_MAX + 1];
	struct gcode_reader *r;
	struct gcode_line g;
	FILE *f;
	int rc;

	(void)o;
	(void)warn;
	(void)warn_ctx;
	if (job->x3g)
		return st_error_set(err, ST_ERR_PARSE, "%s is X3G, which only Sailfish printers "
				    "take: send the G-code", job->path);
	if ((rc = pm_preamble(job, pre, &info->commands, err)) || (rc = pm_reader(job, &f, &r, err)))
		return rc;
	while ((rc = gcode_reader_next(r, 0, &g, err)) == 1) {
		if (g.kind == GCODE_KIND_HOST_ONLY || !g.text_len)
			continue;
		if (g.text_len > MARLIN_CMD_MAX) {
			rc = pm_too_long(job->path, job->first_line + gcode_reader_line(r),
					 g.text_len, err);
			break;
		}
		info->commands++;
	}
	info->lines = gcode_reader_line(r);
	gcode_reader_free(r);
	fclose(f);
	if (rc < 0) {
		char msg[sizeof(err->msg)];

		snprintf(msg, sizeof(msg), "%s", err->msg);
		return st_error_set(err, ST_ERR_PARSE, "%s; nothing was sent", msg);
	}
	return 0;
}

/* The driver's status as progress; the source ring gives line and position. */
static void pm_progress(struct pm_state *s, const struct printer_job *job,
			const struct marlin_status *st, uint64_t first_src, double t0,
			struct printer_progress *p)
{
	p->unit = "line";
	p->total = job->total;
	p->done = st->acked > first_src ? st->acked - first_src : 0;
	if (st->last_acked_src > 0 && st->acked > first_src) {
		const struct pm_src *src = &s->ring[st->last_acked_src % PM_RING];

		p->line = job->first_line + src->line;
		p->filepos = src->end;
		p->layer = src->layer;
		p->z = src->z;
	}
	p->tool = st->tool[0].present;
	p->bed = st->bed.present;
	p->tool_actual = st->tool[0].actual;
	p->tool_target = st->tool[0].target;
	p->bed_actual = st->bed.actual;
	p->bed_target = st->bed.target;
	p->resends = st->resends;
	p->seconds = st_mono_s() - t0;
}

/*
 * Tell the hook about every layer that started among the lines confirmed
 * since the last call (sources from..to-1; the newest, to, is told by the
 * caller): one driver step may confirm several short layers, and print's
 * journal must not skip them.  Sources older than the ring holds (newest
 * submitted - PM_RING) are gone and skipped.
 */
static void pm_tell_layers(struct pm_state *s, const struct printer_job *job, uint64_t from,
			   uint64_t to, uint64_t newest, const struct printer_progress *now,
			   long *layer_told)
{
	const uint64_t oldest = newest >= PM_RING ? newest - PM_RING + 1 : 1;

	for (uint64_t i = from > oldest ? from : oldest; i < to; i++) {
		const struct pm_src *src = &s->ring[i % PM_RING];
		struct printer_progress p = *now;

		if (src->layer == *layer_told)
			continue;
		p.line = job->first_line + src->line;
		p.filepos = src->end;
		p.layer = src->layer;
		p.z = src->z;
		p.done = now->done > to - i ? now->done - (to - i) : 0;
		*layer_told = src->layer;
		job->progress(job->ctx, &p);
	}
}

/* The counters of a Marlin stream, for reports. */
static void pm_counters(const struct marlin *m, const struct marlin_status *st,
			struct printer_result *res)
{
	const struct marlin_caps *c = marlin_caps(m);
	struct printer_counter v[] = {
		{"lines", (double)st->acked, false},
		{"lines_per_s", res->last.seconds > 0 ? (double)st->acked / res->last.seconds : 0,
		 true},
		{"resend_requests", (double)st->resend_requests, false},
		{"advanced_ok", c->advanced_ok, false},
	};

	memcpy(res->counters, v, sizeof(v));
	res->ncounters = sizeof(v) / sizeof(v[0]);
	res->bytes_acked = st->bytes_acked;
	res->bytes_written = st->bytes_written;
	res->errors = st->line_errors + st->other_errors;
	res->unknown_commands = st->unknown_commands;
	snprintf(res->detail, sizeof(res->detail),
		 "resends %llu (%llu requests), errors %llu, unknown commands %llu%s%s",
		 (unsigned long long)st->resends, (unsigned long long)st->resend_requests,
		 (unsigned long long)res->errors, (unsigned long long)st->unknown_commands,
		 st->last_warning[0] ? "\n  last warning: " : "", st->last_warning);
}

/* How a stream the driver ended means for the caller; err filled. */
static void pm_end(const struct pm_state *s, const struct marlin_status *st, int rc,
		   enum printer_control asked, struct printer_result *res, struct st_error *err)
{
	switch (st->fail) {
	case MARLIN_FAIL_CANCELLED:
		res->end = asked == PRINTER_STOP ? PRINTER_END_STOPPED : PRINTER_END_CANCELLED;
		res->safe_stop = true;
		break;
	case MARLIN_FAIL_PRINTER_CANCEL:
		res->end = PRINTER_END_FAILED;
		res->safe_stop = true;
		break;
	case MARLIN_FAIL_LINK:
		res->end = PRINTER_END_LINK_LOST;
		st_error_set(err, ST_ERR_IO, "%s: the link was lost: %s", s->name, st->fail_msg);
		break;
	case MARLIN_FAIL_FIRMWARE:
		res->end = PRINTER_END_FAILED;
		st_error_set(err, ST_ERR_INTERNAL, "%s: firmware error: %s", s->name, st->fail_msg);
		break;
	default:
		res->end = PRINTER_END_FAILED;
		if (!rc)
			st_error_set(err, ST_ERR_INTERNAL, "%s: the job ended for no reason given",
				     s->name);
	}
}


/* The next line job->inject has for between the file's lines, parsed into
 * g (its text in buf): true, or false when it has none.  One that does not
 * parse or is too long for the firmware is dropped: a caller's command must
 * not fail the print. */
static bool pm_injected(const struct printer_job *job, char *buf, size_t cap,
			struct gcode_line *g)
{
	while (job->inject && job->inject(job->ctx, buf, cap)) {
		struct st_error e;

		if (!gcode_parse(buf, strlen(buf), 0, g, &e) && g->text_len &&
		    g->kind != GCODE_KIND_HOST_ONLY && g->text_len <= MARLIN_CMD_MAX)
			return true;
	}
	return false;
}

/*
 * The operator's part of one turn of the stream: the next line job->inject
 * has goes in next, going or held (once the printer has run out what it
 * had, so at says where the file left the head).  A line sent while held
 * sets *back, and going again the way back there (resume_return) goes in
 * first, whole.  Returns 0, 1 while the way back waits for room (the
 * driver stays paused), or the driver's error.
 */
static int pm_operator(struct pm_state *s, const struct printer_job *job,
		       enum printer_control asked, const struct printer_progress *at, bool *back,
		       struct st_error *err)
{
	char line[GCODE_LINE_MAX + 1];
	struct gcode_line g;
	int rc = 0;

	if (asked == PRINTER_GO && *back) {
		char out[RESUME_LINES][RESUME_LINE_MAX + 1];
		struct resume_state rs;
		struct st_error e;
		size_t n = 0;

		if (marlin_next_room(s->m) < RESUME_LINES)
			return 1;
		/* a file that cannot be read back leaves the head where it is */
		if (!resume_scan(job->path, at->filepos, &rs, &e))
			n = resume_return(&rs, true, out, RESUME_LINES);
		for (size_t i = 0; i < n && rc >= 0; i++)
			rc = marlin_submit_next(s->m, out[i], err);
		*back = false;
		return rc < 0 ? rc : 0;
	}
	if ((asked == PRINTER_GO || (asked == PRINTER_HOLD && marlin_drained(s->m))) &&
	    marlin_next_room(s->m) && pm_injected(job, line, sizeof(line), &g)) {
		rc = marlin_submit_next(s->m, g.text, err);
		*back = *back || asked == PRINTER_HOLD;
	}
	return rc < 0 ? rc : 0;
}

static int pm_stream(void *state, const struct printer_job *job, struct printer_result *res,
		     struct st_error *err)
{
	struct pm_state *s = state;
	char pre[RESUME_LINES][RESUME_LINE_MAX + 1];
	uint64_t npre = 0, ipre = 0;
	struct marlin_status st;
	struct gcode_reader *r = NULL;
	struct gcode_line g;
	enum printer_control asked = PRINTER_GO;
	bool eof = false, back = false; /* back: operator lines ran while held */
	long layer = -1;
	double z = NAN, t0 = st_mono_s(), t_cb = 0;
	double m0 = s->sim ? sim_marlin_machine_s(s->sim) : NAN;
	long layer_told = -2; /* the layer the hook was last called with */
	uint64_t src_told = 0; /* the newest source the hook was told of */
	uint64_t first_src, k;
	FILE *f;
	int rc, bad = 0;

	res->last.filepos = job->saved ? job->saved : job->offset;
	res->last.layer = -1;
	res->last.z = NAN;
	if ((rc = pm_preamble(job, pre, &npre, err)) || (rc = pm_reader(job, &f, &r, err)))
		return rc;
	marlin_status(s->m, &st);
	first_src = st.acked;
	k = st.submitted;
	for (;;) {
		if (asked != PRINTER_CANCEL && asked != PRINTER_STOP) {
			asked = job->control ? job->control(job->ctx) : PRINTER_GO;
			/* An operator's line goes next, between two of the file's
			 * written ones, not behind the lines queued in the driver. */
			rc = asked == PRINTER_CANCEL || asked == PRINTER_STOP || ipre < npre ? 0
			     : pm_operator(s, job, asked, &res->last, &back, err);
			if (rc < 0)
				goto out_bad_line;
			if (asked == PRINTER_CANCEL || asked == PRINTER_STOP)
				marlin_request_cancel(s->m);
			else if (asked == PRINTER_HOLD || rc == 1)
				marlin_request_pause(s->m);
			else
				marlin_request_resume(s->m);
		}
		while (asked == PRINTER_GO && marlin_can_submit(s->m) && (ipre < npre || !eof)) {
			if (ipre < npre) {
				/* src 0: a preamble line, not the file's */
				rc = marlin_submit(s->m, pre[ipre++], 0, -1, NAN, err);
			} else if ((rc = gcode_reader_next(r, 0, &g, err)) == 0) {
				eof = true;
				break;
			} else if (rc == 1) {
				gcode_layer_follow(&g, &layer, &z);
				if (g.kind == GCODE_KIND_HOST_ONLY || !g.text_len)
					continue;
				printer_temp_offset(job, &g, false, MARLIN_CMD_MAX);
				if (g.text_len > MARLIN_CMD_MAX) {
					rc = pm_too_long(job->path, job->first_line +
							 gcode_reader_line(r), g.text_len, err);
				} else {
					k++;
					s->ring[k % PM_RING] = (struct pm_src){
						gcode_reader_line(r),
						job->offset + (int64_t)gcode_reader_bytes(r), layer, z};
					rc = marlin_submit(s->m, g.text, k, layer, z, err);
				}
			}
			if (rc < 0)
				goto out_bad_line;
		}
		if (eof && ipre == npre && marlin_idle(s->m))
			break;
		rc = marlin_step(s->m, PM_STEP_MS, err);
		marlin_status(s->m, &st);
		pm_progress(s, job, &st, first_src, t0, &res->last);
		/* held once the firmware has taken every line written to it */
		res->last.paused = asked == PRINTER_HOLD && marlin_drained(s->m);
		if (rc) {
			pm_end(s, &st, rc, asked, res, err);
			goto out_end;
		}
		/* every 200 ms, and at once on each new layer: the journal
		 * print keeps from the hook must not lag the printer by layers */
		if (job->progress && st.last_acked_src > src_told) {
			pm_tell_layers(s, job, src_told + 1, st.last_acked_src, k, &res->last,
				       &layer_told);
			src_told = st.last_acked_src;
		}
		if (job->progress &&
		    (st_mono_s() - t_cb >= PM_PROGRESS_S || res->last.layer != layer_told)) {
			t_cb = st_mono_s();
			layer_told = res->last.layer;
			job->progress(job->ctx, &res->last);
		}
	}
	res->end = PRINTER_END_DONE;
	res->last.filepos = job->offset + (int64_t)gcode_reader_bytes(r);
	goto out_end;

out_bad_line:
	/* what was sent stays sent; the caller stops the printer safely */
	marlin_request_cancel(s->m);
	marlin_step(s->m, 0, NULL);
	res->end = PRINTER_END_FAILED;
	res->safe_stop = true;
	bad = rc;
out_end:
	marlin_status(s->m, &st);
	pm_progress(s, job, &st, first_src, t0, &res->last);
	if (res->end == PRINTER_END_DONE)
		res->last.filepos = job->offset + (int64_t)gcode_reader_bytes(r);
	pm_counters(s->m, &st, res);
	if (s->sim)
		res->machine_s = sim_marlin_machine_s(s->sim) - m0;
	if (job->progress)
		job->progress(job->ctx, &res->last);
	gcode_reader_free(r);
	fclose(f);
	return bad;
}


/* Send g's text and wait until the firmware acknowledged it. */
static int pm_command_run(struct pm_state *s, const struct gcode_line *g, struct st_error *err)
{
	double until = st_mono_s() + PM_CMD_WAIT_MS / 1000.0;
	int rc;

	while ((rc = marlin_submit(s->m, g->text, 0, -1, NAN, err)) == 0)
		if ((rc = marlin_step(s->m, PM_STEP_MS, err)))
			return rc;
	if (rc < 0)
		return rc;
	while (!marlin_idle(s->m)) {
		if ((rc = marlin_step(s->m, PM_STEP_MS, err)))
			return rc;
		if (st_mono_s() > until)
			return st_error_set(err, ST_ERR_IO, "%s: no answer to %s within %d s",
					    s->name, g->text, PM_CMD_WAIT_MS / 1000);
	}
	return 0;
}

static int pm_command(void *state, const char *line, char *reply, size_t cap,
		      struct st_error *err)
{
	struct pm_state *s = state;
	struct gcode_line g;
	int rc = gcode_parse(line, strlen(line), 0, &g, err);

	if (rc || !g.text_len)
		return rc;
	if (g.text_len > MARLIN_CMD_MAX)
		return st_error_set(err, ST_ERR_PARSE, "the command is %zu bytes long; Marlin takes "
				    "at most %d", g.text_len, MARLIN_CMD_MAX);
	s->reply = cap ? reply : NULL;
	s->reply_cap = cap;
	s->reply_len = 0;
	rc = pm_command_run(s, &g, err);
	s->reply = NULL;
	return rc;
}

static int pm_poll(void *state, struct printer_progress *t, struct st_error *err)
{
	struct pm_state *s = state;
	struct marlin_status st;
	time_t now = time(NULL);
	int rc;

	/* Without autoreport the temperatures are asked for now and then. */
	if (!marlin_caps(s->m)->autoreport_temp && now - s->last_poll >= PM_POLL_S &&
	    marlin_idle(s->m)) {
		s->last_poll = now;
		if ((rc = marlin_submit(s->m, "M105", 0, -1, NAN, err)) < 0)
			return rc;
	}
	rc = marlin_step(s->m, 0, err);
	marlin_status(s->m, &st);
	t->tool = st.tool[0].present;
	t->bed = st.bed.present;
	t->tool_actual = st.tool[0].actual;
	t->tool_target = st.tool[0].target;
	t->bed_actual = st.bed.actual;
	t->bed_target = st.bed.target;
	if (rc)
		return st_error_set(err, ST_ERR_IO, "%s: %s", s->name,
				    st.fail_msg[0] ? st.fail_msg : err->msg);
	return 0;
}

static int pm_safe_stop(void *state, struct st_error *err)
{
	struct pm_state *s = state;
	struct st_error e = {0};

	if (marlin_safe_stop(s->m, PM_STOP_MS, &e))
		return st_error_set(err, ST_ERR_IO, "%s: safe stop failed: %s; switch the printer "
				    "off by hand", s->name, e.msg);
	return 0;
}

static void pm_describe(void *state, char *out, size_t cap)
{
	struct pm_state *s = state;
	const struct marlin_caps *c = marlin_caps(s->m);

	snprintf(out, cap, "%s%s", c->firmware_name[0] ? c->firmware_name : "Marlin",
		 s->simulated ? " (simulated printer)" : "");
}

struct marlin *printer_marlin_driver(const struct printer *p)
{
	if (printer_ops_of(p) != &printer_marlin_ops)
		return NULL;
	return ((struct pm_state *)printer_state(p))->m;
}

const struct printer_ops printer_marlin_ops = {
	.name = "marlin",
	.can_resume = true,
	.text_replies = true,
	.takes_injected = true,
	.open = pm_open,
	.close = pm_close,
	.check = pm_check,
	.stream = pm_stream,
	.command = pm_command,
	.poll = pm_poll,
	.safe_stop = pm_safe_stop,
	.describe = pm_describe,
};
