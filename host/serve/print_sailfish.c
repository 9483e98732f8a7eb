/*
 * print_sailfish.c - the node's Sailfish back end (print.h) for profiles
 * with `protocol = sailfish` (FlashForge Creator Pro and kin): G-code is
 * translated to X3G as it streams and X3G files are cut into commands
 * (host/sf_source.h, the sources `stratum send` uses), and the commands go
 * out as S3G packets through s3g_stream_pull (serial/s3g.h), to a device
 * path, a pty or tcp://, or to `port = sim`, the simulated Sailfish
 * printer (serial/sim/sailfish_sim.h) run in this process, sped up.
 *
 * Progress is the end of the G-code line (or X3G command) of the last
 * command the firmware took.  Pause stops feeding commands: the firmware
 * runs out what its 512-byte buffer holds and the job shows paused once
 * the printer reports it is finished.  S3G's pause (query 8) is not used:
 * it toggles, so a resent packet after a lost reply would undo it, and
 * Sailfish moves the head on its own when it pauses.  Cancel and node
 * stop end with s3g_cancel (abort, heaters off, motors off).  An
 * interrupted G-code print resumes as `stratum print --resume` does: from
 * the start of the layer that holds the saved position, after the
 * preamble of resume_x3g_text (bed wait, Z set where it was, X/Y homed,
 * M132, nozzle wait), both through one translator so its positions agree
 * with the firmware's.  An X3G file has no layers to restart from.
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <time.h>

#include "profile_x3g.h"
#include "print.h"
#include "resume.h"
#include "s3g.h"
#include "sf_source.h"
#include "sim/sailfish_sim.h"
#include "simprinter.h"
#include "xport.h"

#define SF_POLL_S 2		 /* temperature queries between jobs (s) */
#define SF_HOLD_MS 250		 /* status poll while a pause holds (ms) */

struct slink {
	char name[NODE_NAME_MAX];
	bool simulated;
	struct sim_sailfish *sim; /* port = sim only */
	struct xport *x;
	struct s3g *d;
	struct x3g_machine m;
	struct x3g_options xo;
	char firmware[32];
	time_t last_poll;
};

/* One print: what the stream's callbacks share. */
struct sf_run {
	struct slink *s;
	struct node_print_ctl *ctl;
	bool x3g;
	int64_t start;	  /* the saved position a resume starts from, else 0 */
	int64_t offset;	  /* byte the G-code source reads from (a layer start) */
	const char *pre;  /* resume preamble lines, or NULL */
	struct sfsrc_gcode g;
	struct sfsrc_x3g x;
	volatile sig_atomic_t stop; /* polled by the driver */
	bool node_stop;		    /* it was the node shutting down, not a cancel */
	bool link_lost;		    /* a query failed while a pause held */
	bool seen_running;	    /* build statistics said running while held */
	char why[256];		    /* why the link was lost */
};

static void slink_free(struct slink *s)
{
	if (!s)
		return;
	s3g_free(s->d);
	node_port_close(s->x);
	sim_sailfish_free(s->sim);
	free(s);
}

/* Start the in-process simulated printer of pc; its pty path in *path. */
static int start_sim(struct slink *s, const struct node_printer_config *pc,
		     const struct profile *prof, const char **path, struct st_error *err)
{
	int rc = simprinter_sailfish(prof, pc->sim_speedup, pc->sim_log[0] ? pc->sim_log : NULL,
				     &s->sim, err);

	if (!rc)
		*path = sim_sailfish_slave_path(s->sim);
	return rc;
}

static int sf_connect_op(const struct node_printer_config *pc, const struct profile *prof,
			 void **state, struct st_error *err)
{
	struct slink *s = calloc(1, sizeof(*s));
	const char *path = pc->port;
	struct st_error e = {0};
	uint16_t fw = 0;
	int rc;

	if (!s)
		return st_error_set(err, ST_ERR_NOMEM, "printer %s: out of memory", pc->name);
	snprintf(s->name, sizeof(s->name), "%s", pc->name);
	if ((rc = profile_x3g_machine(prof, &s->m, &s->xo.flavor, &e))) {
		rc = st_error_set(err, rc, "printer %s: profile %s: %s", pc->name, prof->id, e.msg);
		goto out_free;
	}
	s->simulated = !strcmp(pc->port, "sim");
	if (s->simulated && (rc = start_sim(s, pc, prof, &path, &e))) {
		rc = st_error_set(err, rc, "printer %s: simulated printer: %s", pc->name, e.msg);
		goto out_free;
	}
	if ((rc = node_port_open(pc, prof, path, s->simulated, &s->x, err)))
		goto out_free;
	if ((rc = s3g_new(s->x, NULL, &s->d, &e))) {
		rc = st_error_set(err, rc, "printer %s: %s", pc->name, e.msg);
		goto out_free;
	}
	/* the version query proves a Sailfish board answers S3G on the port */
	if (s3g_get_version(s->d, SFSRC_HOST_VERSION, &fw, &e)) {
		rc = st_error_set(err, ST_ERR_IO, "printer %s: no answer from a Sailfish printer "
				  "on %s (%s); check that it is switched on, not busy with an SD "
				  "print, and that the baud rate matches", pc->name, pc->port, e.msg);
		goto out_free;
	}
	snprintf(s->firmware, sizeof(s->firmware), "Sailfish %u.%u", fw / 100u, fw % 100u);
	*state = s;
	return 0;

out_free:
	slink_free(s);
	return rc;
}

static void sf_disconnect_op(void *state)
{
	slink_free(state);
}

/* Copy the driver's temperatures into ctl; ctl->mu held. */
static void take_temps(const struct s3g_status *st, struct node_print_ctl *ctl)
{
	ctl->tool_actual = st->tool_temp;
	ctl->tool_target = st->tool_target;
	ctl->bed_actual = st->platform_temp;
	ctl->bed_target = st->platform_target;
}

/* Where the file is done after the commands the printer took. */
static int64_t done_pos(const struct sf_run *r, const struct s3g_status *st)
{
	uint64_t end = sfsrc_done_end(&r->g, &r->x, r->x3g, st->confirmed + st->skipped);

	/* Within the preamble the saved position stands: the layer start would
	 * read as the layer before, which a second resume would print again. */
	return end ? r->offset + (int64_t)end : r->start;
}

/* Follow ctl's cancel and stop; ctl->mu held.  True when the job is to end. */
static bool follow_stop(struct sf_run *r)
{
	if (r->ctl->cancel || r->ctl->stop) {
		r->node_stop = r->ctl->stop && !r->ctl->cancel;
		r->stop = 1;
		return true;
	}
	return false;
}

/* s3g progress callback: status into ctl, requests into the stop flag. */
static void sf_progress(void *ctx, const struct s3g_status *st)
{
	struct sf_run *r = ctx;

	pthread_mutex_lock(&r->ctl->mu);
	r->ctl->filepos = done_pos(r, st);
	take_temps(st, r->ctl);
	follow_stop(r);
	pthread_mutex_unlock(&r->ctl->mu);
}

/*
 * Hold while a pause is asked for; ctl->mu held (released while asking the
 * printer).  The printer is queried every SF_HOLD_MS: finished means
 * paused, a failed query or a reboot ends the print as a lost link.
 */
static int hold(struct sf_run *r, struct st_error *err)
{
	struct node_print_ctl *ctl = r->ctl;
	struct s3g_build_stats b;
	struct s3g_temps t;
	struct st_error e = {0};
	bool done = false;

	while (ctl->pause && !follow_stop(r)) {
		struct timespec ts;
		int rc;

		pthread_mutex_unlock(&ctl->mu);
		rc = s3g_is_finished(r->s->d, &done, &e);
		if (!rc)
			rc = s3g_get_temps(r->s->d, &t, &e);
		if (!rc)
			rc = s3g_get_build_stats(r->s->d, &b, &e);
		if (!rc && b.state == S3G_BUILD_NONE && r->seen_running)
			rc = st_error_set(&e, ST_ERR_IO, "the printer reset while paused: it "
					  "answers as freshly booted");
		if (!rc && (b.state == S3G_BUILD_RUNNING || b.state == S3G_BUILD_PAUSED))
			r->seen_running = true;
		pthread_mutex_lock(&ctl->mu);
		if (rc) {
			r->link_lost = true;
			snprintf(r->why, sizeof(r->why), "%s", e.msg);
			return st_error_set(err, ST_ERR_IO, "%s", e.msg);
		}
		take_temps(s3g_status_get(r->s->d), ctl);
		ctl->paused = done;
		if (ctl->pause && !ctl->cancel && !ctl->stop) {
			clock_gettime(CLOCK_REALTIME, &ts);
			ts.tv_nsec += SF_HOLD_MS * 1000000L;
			ts.tv_sec += ts.tv_nsec / 1000000000L;
			ts.tv_nsec %= 1000000000L;
			pthread_cond_timedwait(&ctl->cv, &ctl->mu, &ts);
		}
	}
	ctl->paused = false;
	return 0;
}

/* s3g_source_fn: hold on pause, end on cancel or stop, else the file's next. */
static int sf_next(void *src, struct s3g_cmd *cmd, struct st_error *err)
{
	struct sf_run *r = src;
	bool ended;
	int rc = 0;

	pthread_mutex_lock(&r->ctl->mu);
	if (!follow_stop(r))
		rc = hold(r, err);
	ended = r->stop;
	pthread_mutex_unlock(&r->ctl->mu);
	if (rc < 0)
		return rc;
	if (ended)
		return 0; /* the driver sees the stop flag and ends as interrupted */
	return r->x3g ? sfsrc_x3g_next(&r->x, cmd, err) : sfsrc_gcode_next(&r->g, cmd, err);
}

/* Open r's source over f from r->offset, preamble first; 0 or an error. */
static int source_open(struct sf_run *r, FILE *f, const char *path, struct st_error *err)
{
	int rc;

	if (fseeko(f, (off_t)r->offset, SEEK_SET))
		return st_error_set(err, ST_ERR_IO, "%s: cannot seek: %s", path, strerror(errno));
	if (r->x3g) {
		sfsrc_x3g_open(&r->x, f);
		return 0;
	}
	if ((rc = sfsrc_gcode_open(&r->g, f, path, &r->s->m, &r->s->xo, err)))
		return rc;
	r->g.pre = r->pre;
	r->g.pre_len = r->pre ? strlen(r->pre) : 0;
	return 0;
}

/* A resume: the layer to start from and the preamble into pre; 0 or an error. */
static int resume_setup(struct sf_run *r, const char *path, int64_t start,
			char pre[RESUME_TEXT_MAX], struct st_error *err)
{
	long layer;
	int rc;

	if (r->x3g)
		return st_error_set(err, ST_ERR_UNSUPPORTED, "printer %s: an interrupted X3G "
				    "print cannot be resumed: it has no layers to restart from",
				    r->s->name);
	if ((rc = resume_layer_start(path, start, &r->offset, &layer, err)) ||
	    (rc = resume_x3g_text(path, r->offset, pre, err)))
		return rc;
	r->start = start;
	r->pre = pre;
	return 0;
}

/* Count the commands of the file, checking every one: a bad file sends nothing. */
static int check_file(struct sf_run *r, FILE *f, const char *path, uint64_t *n,
		      struct st_error *err)
{
	struct s3g_cmd c;
	int rc = source_open(r, f, path, err);

	*n = 0;
	while (!rc && (rc = r->x3g ? sfsrc_x3g_next(&r->x, &c, err)
				   : sfsrc_gcode_next(&r->g, &c, err)) > 0)
		(*n)++;
	if (!r->x3g)
		sfsrc_gcode_close(&r->g);
	if (rc < 0) {
		char msg[sizeof(err->msg)];

		snprintf(msg, sizeof(msg), "%s", err->msg);
		return st_error_set(err, rc, "%s%s%s; nothing was sent", r->x3g ? path : "",
				    r->x3g ? ": " : "", msg);
	}
	return 0;
}

/* The safe stop after a stream that ended with the printer still answering. */
static int safe_stop(struct slink *s, struct st_error *err)
{
	struct st_error e = {0};

	if (s3g_cancel(s->d, &e))
		return st_error_set(err, ST_ERR_IO, "printer %s: safe stop failed: %s; switch "
				    "the printer off by hand", s->name, e.msg);
	return 0;
}

static int sf_print_op(void *state, const char *path, int64_t start, bool resume,
		       struct node_print_ctl *ctl, struct st_error *err)
{
	struct slink *s = state;
	struct sf_run *r;
	struct s3g_status st;
	char build[X3G_BUILD_NAME_MAX + 1];
	char pre[RESUME_TEXT_MAX];
	struct stat sb;
	uint64_t total = 0;
	size_t n = strlen(path);
	FILE *f;
	int rc;

	r = calloc(1, sizeof(*r));
	if (!r)
		return st_error_set(err, ST_ERR_NOMEM, "printer %s: out of memory", s->name);
	r->s = s;
	r->ctl = ctl;
	r->x3g = n > 4 && !strcasecmp(path + n - 4, ".x3g");
	if ((resume || start) && (rc = resume_setup(r, path, start, pre, err)))
		goto out_free;
	profile_x3g_build_name(path, build, sizeof(build));
	s->xo.build_name = build;
	f = fopen(path, "rb");
	if (!f) {
		rc = st_error_set(err, ST_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
		goto out_free;
	}
	if (fstat(fileno(f), &sb)) {
		rc = st_error_set(err, ST_ERR_IO, "%s: cannot read: %s", path, strerror(errno));
		goto out_close;
	}
	if ((rc = check_file(r, f, path, &total, err)))
		goto out_close;
	pthread_mutex_lock(&ctl->mu);
	ctl->size = sb.st_size;
	ctl->filepos = r->start;
	pthread_mutex_unlock(&ctl->mu);
	if ((rc = source_open(r, f, path, err)))
		goto out_source;
	rc = s3g_stream_pull(s->d, sf_next, r, (size_t)total, sf_progress, r, &r->stop, &st, err);
	pthread_mutex_lock(&ctl->mu);
	ctl->paused = false;
	ctl->filepos = rc == 0 && !st.interrupted ? sb.st_size : done_pos(r, &st);
	pthread_mutex_unlock(&ctl->mu);
	if (rc == 0 && st.interrupted) {
		if ((rc = safe_stop(s, err)) == 0)
			rc = r->node_stop ? NODE_PRINT_STOPPED : NODE_PRINT_CANCELLED;
	} else if (rc == 0) {
		rc = NODE_PRINT_DONE;
	} else if (r->link_lost || st.fail == S3G_FAIL_LINK) {
		/* The part may be fine: the worker offers the job for resume like a crash. */
		if (!r->link_lost)
			snprintf(r->why, sizeof(r->why), "%s", err->msg);
		st_error_set(err, ST_ERR_IO, "printer %s: the link was lost: %s", s->name, r->why);
		rc = NODE_PRINT_LINK_LOST;
	} else {
		/* The printer stopped the build (0x89 cancelled on its panel, 0x8B
		 * overheat) or a command could not be sent: the job fails, and the
		 * printer is left safe. */
		struct st_error e = {0};
		char msg[256];

		snprintf(msg, sizeof(msg), "%s", err->msg);
		rc = st_error_set(err, rc == ST_ERR_PARSE ? ST_ERR_PARSE : ST_ERR_IO,
				  "printer %s: %s%s", s->name, msg,
				  safe_stop(s, &e) ? "; the safe stop failed too" : "");
	}
out_source:
	if (!r->x3g)
		sfsrc_gcode_close(&r->g);
out_close:
	fclose(f);
out_free:
	s->xo.build_name = NULL;
	free(r);
	return rc;
}

/* Send each command of one translated G-code line. */
static int sf_command_op(void *state, const char *line, struct st_error *err)
{
	struct slink *s = state;
	struct x3g_translator *t = NULL;
	struct gcode_line g;
	uint8_t resp[S3G_MAX_PAYLOAD];
	const uint8_t *out;
	size_t len, rlen, pos = 0;
	int rc = gcode_parse(line, strlen(line), 0, &g, err);

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

static int sf_poll_op(void *state, struct node_print_ctl *ctl, struct st_error *err)
{
	struct slink *s = state;
	struct s3g_temps t;
	struct st_error e = {0};
	time_t now = time(NULL);

	if (now - s->last_poll < SF_POLL_S)
		return 0;
	s->last_poll = now;
	if (s3g_get_temps(s->d, &t, &e))
		return st_error_set(err, ST_ERR_IO, "printer %s: %s", s->name, e.msg);
	pthread_mutex_lock(&ctl->mu);
	take_temps(s3g_status_get(s->d), ctl);
	pthread_mutex_unlock(&ctl->mu);
	return 0;
}

static void sf_describe_op(void *state, char *out, size_t cap)
{
	struct slink *s = state;

	snprintf(out, cap, "%s%s", s->firmware, s->simulated ? " (simulated printer)" : "");
}

const struct node_printer_ops node_sailfish_ops = {
	.name = "sailfish",
	.can_resume = true,
	.connect = sf_connect_op,
	.disconnect = sf_disconnect_op,
	.print = sf_print_op,
	.command = sf_command_op,
	.poll = sf_poll_op,
	.describe = sf_describe_op,
};
