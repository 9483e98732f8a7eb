/*
 * print_marlin.c - the node's Marlin back end (print.h): streams a job with
 * the Marlin driver (serial/marlin.h) to a device path, a pty or tcp://,
 * or to `port = sim`, the simulated Marlin printer (serial/sim/) run in
 * this process with its motion, heating and link sped up.
 *
 * Progress is the byte offset just past the last command the firmware
 * acknowledged: each command is submitted with that offset as its "source
 * line", so status.last_acked_src is where a resume starts.  Pause stops
 * new lines (the firmware finishes what it holds); cancel and node stop
 * end with the driver's safe stop (heaters and motors off).
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "gcode.h"
#include "marlin.h"
#include "sim/marlin_sim.h"
#include "print.h"
#include "resume.h"
#include "simprinter.h"
#include "xport.h"

#define MARLIN_STEP_MS 50	 /* longest wait for replies per loop turn */
#define MARLIN_CMD_WAIT_MS 120000 /* longest wait for one printer command */
#define MARLIN_STOP_MS 10000	 /* safe stop: longest wait for its commands */
#define MARLIN_POLL_S 5		 /* M105 period when idle without autoreport */

_Static_assert(RESUME_LINE_MAX == MARLIN_CMD_MAX, "resume lines fit Marlin's limit");

struct mlink {
	char name[NODE_NAME_MAX];
	bool simulated;
	struct sim_marlin *sim; /* port = sim only */
	struct xport *x;
	struct marlin *m;
	time_t last_poll;
};

static double mono_now(void)
{
	struct timespec t;

	clock_gettime(CLOCK_MONOTONIC, &t);
	return (double)t.tv_sec + (double)t.tv_nsec * 1e-9;
}

static void mlink_free(struct mlink *s)
{
	if (!s)
		return;
	marlin_free(s->m);
	node_port_close(s->x);
	sim_marlin_free(s->sim);
	free(s);
}

/* Start the in-process simulated printer of pc; its pty path in *path. */
static int start_sim(struct mlink *s, const struct node_printer_config *pc,
		     const struct profile *prof, const char **path, struct st_error *err)
{
	int rc = simprinter_marlin(prof, pc->sim_speedup, pc->sim_log[0] ? pc->sim_log : NULL,
				   &s->sim, err);

	if (!rc)
		*path = sim_marlin_slave_path(s->sim);
	return rc;
}

static int marlin_connect_op(const struct node_printer_config *pc, const struct profile *prof,
			     void **state, struct st_error *err)
{
	struct mlink *s = calloc(1, sizeof(*s));
	struct marlin_options mo;
	const char *path = pc->port;
	struct st_error e = {0};
	int rc;

	if (!s)
		return st_error_set(err, ST_ERR_NOMEM, "printer %s: out of memory", pc->name);
	snprintf(s->name, sizeof(s->name), "%s", pc->name);
	if (prof->protocol != PROFILE_PROTOCOL_MARLIN) {
		rc = st_error_set(err, ST_ERR_UNSUPPORTED, "printer %s: profile %s speaks %s; the "
				  "Marlin back end drives Marlin printers only",
				  pc->name, prof->id, profile_protocol_name(prof->protocol));
		goto out_free;
	}
	s->simulated = !strcmp(pc->port, "sim");
	if (s->simulated && (rc = start_sim(s, pc, prof, &path, &e))) {
		rc = st_error_set(err, rc, "printer %s: simulated printer: %s", pc->name, e.msg);
		goto out_free;
	}
	if ((rc = node_port_open(pc, prof, path, s->simulated, &s->x, err)))
		goto out_free;
	marlin_options_init(&mo);
	mo.rx_buffer = prof->rx_buffer_size > 0 ? (unsigned)prof->rx_buffer_size : 0;
	/* the simulator boots like a board; ptys and TCP bridges are not reset */
	mo.expect_reset = s->simulated || (prof->dtr_reset &&
					   xport_backend_of(s->x) == XPORT_BACKEND_SERIALPORT);
	if ((rc = marlin_new(s->x, &mo, &s->m, &e)) || (rc = marlin_connect(s->m, &e))) {
		rc = st_error_set(err, rc == ST_ERR_INTERNAL ? ST_ERR_INTERNAL : ST_ERR_IO,
				  "printer %s: %s", pc->name, e.msg);
		goto out_free;
	}
	*state = s;
	return 0;

out_free:
	mlink_free(s);
	return rc;
}

static void marlin_disconnect_op(void *state)
{
	mlink_free(state);
}

/* Copy the driver's temperatures into ctl; ctl->mu held. */
static void take_temps(const struct marlin_status *st, struct node_print_ctl *ctl)
{
	if (st->tool[0].present) {
		ctl->tool_actual = st->tool[0].actual;
		ctl->tool_target = st->tool[0].target;
	}
	if (st->bed.present) {
		ctl->bed_actual = st->bed.actual;
		ctl->bed_target = st->bed.target;
	}
}

/* What a job ended by the driver's status means for the node; err filled. */
static int end_result(struct mlink *s, const struct marlin_status *st, int rc, bool stop,
		      struct st_error *err)
{
	struct st_error e = {0};

	switch (st->fail) {
	case MARLIN_FAIL_CANCELLED:
	case MARLIN_FAIL_PRINTER_CANCEL:
		if (marlin_safe_stop(s->m, MARLIN_STOP_MS, &e))
			return st_error_set(err, ST_ERR_IO, "printer %s: safe stop failed: %s",
					    s->name, e.msg);
		if (st->fail == MARLIN_FAIL_PRINTER_CANCEL)
			return NODE_PRINT_CANCELLED; /* cancelled on the printer's own screen */
		return stop ? NODE_PRINT_STOPPED : NODE_PRINT_CANCELLED;
	case MARLIN_FAIL_LINK:
		st_error_set(err, ST_ERR_IO, "printer %s: the link was lost: %s", s->name,
			     st->fail_msg);
		return NODE_PRINT_LINK_LOST;
	case MARLIN_FAIL_FIRMWARE:
		return st_error_set(err, ST_ERR_INTERNAL, "printer %s: firmware error: %s", s->name,
				    st->fail_msg);
	default:
		return rc ? rc : st_error_set(err, ST_ERR_INTERNAL, "printer %s: the job ended "
							      "for no reason given", s->name);
	}
}


/*
 * Follow ctl's requests; ctl->mu held.  Returns true when the job is to
 * end (cancel or stop requested).
 */
static bool follow_requests(struct mlink *s, struct node_print_ctl *ctl, bool *stop)
{
	if (ctl->stop || ctl->cancel) {
		*stop = ctl->stop;
		marlin_request_cancel(s->m);
		return true;
	}
	if (ctl->pause)
		marlin_request_pause(s->m);
	else
		marlin_request_resume(s->m);
	/* Held once the firmware has everything it was sent. */
	ctl->paused = ctl->pause && marlin_idle(s->m);
	return false;
}

static int marlin_print_op(void *state, const char *path, int64_t start, bool resume,
			   struct node_print_ctl *ctl, struct st_error *err)
{
	struct mlink *s = state;
	char pre[RESUME_LINES][RESUME_LINE_MAX + 1];
	size_t npre = 0, ipre = 0;
	struct marlin_status st;
	struct gcode_reader *r = NULL;
	struct gcode_line g;
	struct stat sb;
	bool eof = false, ending = false, stop = false, held = false;
	int64_t acked_pos = start;
	uint64_t first_n = 0;
	FILE *f;
	int rc = 0;

	if (resume) {
		struct resume_state rs;

		if ((rc = resume_scan(path, start, &rs, err)))
			return rc;
		npre = resume_preamble(&rs, pre, RESUME_LINES);
	}
	f = fopen(path, "rb");
	if (!f)
		return st_error_set(err, ST_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
	if (fstat(fileno(f), &sb) || fseeko(f, (off_t)start, SEEK_SET)) {
		rc = st_error_set(err, ST_ERR_IO, "%s: cannot read: %s", path, strerror(errno));
		goto out_close;
	}
	if ((rc = gcode_reader_new(f, path, &r, err)))
		goto out_close;
	marlin_status(s->m, &st);
	first_n = st.submitted;
	pthread_mutex_lock(&ctl->mu);
	ctl->size = sb.st_size;
	ctl->filepos = start;
	pthread_mutex_unlock(&ctl->mu);
	for (;;) {
		pthread_mutex_lock(&ctl->mu);
		if (!ending)
			ending = follow_requests(s, ctl, &stop);
		held = ctl->pause;
		pthread_mutex_unlock(&ctl->mu);
		while (!ending && !held && marlin_can_submit(s->m) && (ipre < npre || !eof)) {
			/* src 0 = a resume line, not a file position */
			if (ipre < npre) {
				rc = marlin_submit(s->m, pre[ipre++], 0, -1, NAN, err);
			} else if ((rc = gcode_reader_next(r, 0, &g, err)) == 0) {
				eof = true;
				break;
			} else if (rc == 1 && g.kind != GCODE_KIND_HOST_ONLY && g.text_len) {
				if (g.text_len > MARLIN_CMD_MAX)
					rc = st_error_set(err, ST_ERR_PARSE, "%s: line %llu: the "
							  "command is %zu bytes long; Marlin takes "
							  "at most %d", path,
							  (unsigned long long)gcode_reader_line(r),
							  g.text_len, MARLIN_CMD_MAX);
				else
					rc = marlin_submit(s->m, g.text,
							   (uint64_t)start + gcode_reader_bytes(r), -1,
							   NAN, err);
			}
			if (rc < 0)
				goto out_stop;
		}
		if (eof && ipre == npre && marlin_idle(s->m))
			break;
		rc = marlin_step(s->m, MARLIN_STEP_MS, err);
		marlin_status(s->m, &st);
		if (st.acked > first_n && st.last_acked_src)
			acked_pos = (int64_t)st.last_acked_src;
		pthread_mutex_lock(&ctl->mu);
		ctl->filepos = acked_pos;
		take_temps(&st, ctl);
		pthread_mutex_unlock(&ctl->mu);
		if (rc) {
			rc = end_result(s, &st, rc, stop, err);
			goto out_free;
		}
	}
	pthread_mutex_lock(&ctl->mu);
	ctl->filepos = sb.st_size;
	pthread_mutex_unlock(&ctl->mu);
	rc = NODE_PRINT_DONE;
	goto out_free;

out_stop:
	/* A bad line: what was sent stays sent; stop the printer safely. */
	{
		struct st_error e = {0};

		marlin_request_cancel(s->m);
		marlin_step(s->m, 0, &e);
		marlin_safe_stop(s->m, MARLIN_STOP_MS, &e);
	}
out_free:
	gcode_reader_free(r);
out_close:
	fclose(f);
	return rc;
}

/* Check a command line and return its cleaned text in g. */
static int clean_command(const char *line, struct gcode_line *g, struct st_error *err)
{
	int rc = gcode_parse(line, strlen(line), 0, g, err);

	if (rc)
		return rc;
	if (g->text_len > MARLIN_CMD_MAX)
		return st_error_set(err, ST_ERR_PARSE, "the command is %zu bytes long; Marlin takes "
				    "at most %d", g->text_len, MARLIN_CMD_MAX);
	return 0;
}

static int marlin_command_op(void *state, const char *line, struct st_error *err)
{
	struct mlink *s = state;
	struct gcode_line g;
	double until = mono_now() + MARLIN_CMD_WAIT_MS / 1000.0;
	int rc = clean_command(line, &g, err);

	if (rc || !g.text_len)
		return rc;
	while ((rc = marlin_submit(s->m, g.text, 0, -1, NAN, err)) == 0)
		if ((rc = marlin_step(s->m, MARLIN_STEP_MS, err)))
			return rc;
	if (rc < 0)
		return rc;
	while (!marlin_idle(s->m)) {
		if ((rc = marlin_step(s->m, MARLIN_STEP_MS, err)))
			return rc;
		if (mono_now() > until)
			return st_error_set(err, ST_ERR_IO, "printer %s: no answer to %s within "
					    "%d s", s->name, g.text, MARLIN_CMD_WAIT_MS / 1000);
	}
	return 0;
}

static int marlin_poll_op(void *state, struct node_print_ctl *ctl, struct st_error *err)
{
	struct mlink *s = state;
	struct marlin_status st;
	time_t now = time(NULL);
	int rc;

	/* Without autoreport the temperatures are asked for now and then. */
	if (!marlin_caps(s->m)->autoreport_temp && now - s->last_poll >= MARLIN_POLL_S &&
	    marlin_idle(s->m)) {
		s->last_poll = now;
		if ((rc = marlin_submit(s->m, "M105", 0, -1, NAN, err)) < 0)
			return rc;
	}
	rc = marlin_step(s->m, 0, err);
	marlin_status(s->m, &st);
	pthread_mutex_lock(&ctl->mu);
	take_temps(&st, ctl);
	pthread_mutex_unlock(&ctl->mu);
	if (rc)
		return st_error_set(err, ST_ERR_IO, "printer %s: %s", s->name,
				    st.fail_msg[0] ? st.fail_msg : err->msg);
	return 0;
}

static void marlin_describe_op(void *state, char *out, size_t cap)
{
	struct mlink *s = state;
	const struct marlin_caps *c = marlin_caps(s->m);

	snprintf(out, cap, "%s%s", c->firmware_name[0] ? c->firmware_name : "Marlin",
		 s->simulated ? " (simulated printer)" : "");
}

const struct node_printer_ops node_marlin_ops = {
	.name = "marlin",
	.can_resume = true,
	.connect = marlin_connect_op,
	.disconnect = marlin_disconnect_op,
	.print = marlin_print_op,
	.command = marlin_command_op,
	.poll = marlin_poll_op,
	.describe = marlin_describe_op,
};
