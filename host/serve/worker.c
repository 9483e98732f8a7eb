/*
 * worker.c - one thread per printer (node_int.h): connects the printer when
 * asked, slices uploaded models, and prints the queue one job at a time,
 * waiting for an operator to confirm the bed is clear between jobs.  Every
 * change of a job's state is written to the queue before it takes effect
 * on the printer side, so a crash never loses what was printing.
 */
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "node_int.h"
#include "profile_slicer.h"
#include "slicejob.h"
#include "st_clock.h"

#define WORKER_IDLE_MS 1000 /* idle wake-up, for requests that did not signal */

void node_printer_wake(struct node_printer *p)
{
	pthread_mutex_lock(&p->mu);
	pthread_cond_signal(&p->cv);
	pthread_mutex_unlock(&p->mu);
}

/* Where the slicer's phases (slicer_config.progress) lie in the whole job,
 * as slicingProgress reports it; the repair's phases come before, in
 * [0, SLICING_REPAIR_SHARE). */
#define SLICING_REPAIR_SHARE 0.30
static const struct {
	const char *stage; /* the phase's name, up to its counts */
	double from, to;
} slicing_phases[] = {
	{"cutting the model into layers", 0.30, 0.35},
	{"slicing layer", 0.35, 0.90},
	{"writing the G-code", 0.90, 1.00},
};

/* Publish s's fraction for the push API's clients; slice_mu held. */
static void slicing_publish(struct node_slicing *s, int64_t now)
{
	s->percent = 100.0 * s->fraction;
	s->published_ms = now;
	s->seq++;
}

/* Progress callback of the repair and the slicer (any thread): the job's
 * fraction never goes back, and is published at most every
 * NODE_SLICING_EVERY_MS. */
static void slicing_progress(void *ctx, const char *stage, double done)
{
	struct node_printer *p = ctx;
	struct node_slicing *s = &p->slicing;
	double from = 0.0, to = SLICING_REPAIR_SHARE, f;
	int64_t now = st_mono_ms();

	for (size_t i = 0; i < sizeof(slicing_phases) / sizeof(slicing_phases[0]); i++)
		if (!strncmp(stage, slicing_phases[i].stage, strlen(slicing_phases[i].stage))) {
			from = slicing_phases[i].from;
			to = slicing_phases[i].to;
		}
	f = from + (to - from) * (done < 0.0 ? 0.0 : done > 1.0 ? 1.0 : done);
	pthread_mutex_lock(&p->slice_mu);
	if (f > s->fraction && f < 1.0) /* 100 % is said by slicing_end */
		s->fraction = f;
	if (now - s->published_ms >= NODE_SLICING_EVERY_MS)
		slicing_publish(s, now);
	pthread_mutex_unlock(&p->slice_mu);
}

/* Job j's model starts being sliced: slicingProgress at 0. */
static void slicing_begin(struct node_printer *p, const struct node_job *j)
{
	struct node_slicing *s = &p->slicing;
	const char *dot = strrchr(j->name, '.');
	int stem = dot ? (int)(dot - j->name) : (int)strlen(j->name);

	pthread_mutex_lock(&p->slice_mu);
	s->gen++;
	s->state = NODE_SLICING_RUNNING;
	snprintf(s->source, sizeof(s->source), "%s", j->name);
	/* OctoPrint's default destination: the model's name, .gcode */
	snprintf(s->dest, sizeof(s->dest), "%.*s.gcode", stem < 240 ? stem : 240, j->name);
	s->fraction = 0.0;
	s->reason[0] = '\0';
	s->t0_ms = st_mono_ms();
	slicing_publish(s, s->t0_ms);
	pthread_mutex_unlock(&p->slice_mu);
}

/* The slicing ended: 100 % and done, or failed with why. */
static void slicing_end(struct node_printer *p, bool ok, const char *why)
{
	struct node_slicing *s = &p->slicing;
	int64_t now = st_mono_ms();

	pthread_mutex_lock(&p->slice_mu);
	s->state = ok ? NODE_SLICING_DONE : NODE_SLICING_FAILED;
	if (ok)
		s->fraction = 1.0;
	snprintf(s->reason, sizeof(s->reason), "%s", ok ? "" : why);
	s->elapsed_s = (double)(now - s->t0_ms) / 1000.0;
	slicing_publish(s, now);
	pthread_mutex_unlock(&p->slice_mu);
}

/* Slice job j's model into out as `stratum slice` does (slicejob.h), with
 * the job's own settings over the printer's profile. */
static int slice_model(struct node_printer *p, const struct node_job *j, const char *out,
		       struct st_error *err)
{
	struct slicer_config cfg;
	struct slicejob_result res;
	struct profile *job_prof = NULL;
	int rc;

	if (!out[0])
		return st_error_set(err, ST_ERR_RANGE, "the data directory's path is too long");
	if (j->settings[0] && (rc = node_settings_profile(p, j->settings, &job_prof, err)))
		return rc;
	/* cfg points into the profile (start G-code ...): it lives to the end */
	rc = profile_slicer_config(job_prof ? job_prof : p->prof, &cfg, err);
	cfg.threads = p->node->cfg.slice_threads;
	cfg.progress = slicing_progress;
	cfg.progress_ctx = p;
	if (!rc)
		rc = slicer_config_check(&cfg, err);
	if (!rc) {
		const char *in[1] = {j->file};
		rc = slicejob_slice(in, 1, &cfg, false, out, NULL, &res, err);
		slicejob_result_free(&res);
	}
	profile_free(job_prof);
	return rc;
}

/* Write j back; a failing database is logged (the job goes on in memory). */
static void save(struct node_printer *p, const struct node_job *j)
{
	struct st_error err = {0};

	if (node_queue_update(p->node->q, j, &err))
		node_log("error", p->cfg->name, j->id, "%s", err.msg);
}

/* Slice job j (a model without G-code yet); p->mu held on entry and exit. */
static void run_slicing(struct node_printer *p, struct node_job *j)
{
	struct st_error err = {0};
	char out[NODE_PATH_MAX];
	int rc;

	j->state = NODE_JOB_SLICING;
	save(p, j);
	p->job_id = j->id;
	if (snprintf(out, sizeof(out), "%s/job-%lld.gcode", p->node->sliced_dir,
		     (long long)j->id) >= (int)sizeof(out))
		out[0] = '\0'; /* slice_model refuses it */
	node_log("info", p->cfg->name, j->id, "slicing %s with profile %s%s%.1000s", j->name,
		 p->prof->id, j->settings[0] ? " and the job's settings " : "", j->settings);
	pthread_mutex_unlock(&p->mu);
	slicing_begin(p, j);
	rc = slice_model(p, j, out, &err);
	slicing_end(p, !rc, err.msg);
	pthread_mutex_lock(&p->mu);
	p->job_id = 0;
	/* The API may have cancelled it meanwhile. */
	if (node_queue_get(p->node->q, j->id, j, &err) != 1 || j->state != NODE_JOB_SLICING)
		return;
	if (rc) {
		j->state = NODE_JOB_FAILED;
		j->finished = time(NULL);
		snprintf(j->error, sizeof(j->error), "%.60s: %.190s", j->name, err.msg);
		node_log("error", p->cfg->name, j->id, "slicing failed: %s", j->error);
	} else {
		j->state = NODE_JOB_QUEUED;
		memcpy(j->gcode, out, sizeof(j->gcode));
		node_log("info", p->cfg->name, j->id, "sliced into %s", out);
	}
	save(p, j);
}

/* Close a link that failed (unplugged, firmware halted); p->mu held. */
static void drop_link(struct node_printer *p, const char *why)
{
	node_print_disconnect(p->link);
	p->link = NULL;
	p->connected = false;
	p->link_desc[0] = '\0';
	snprintf(p->conn_error, sizeof(p->conn_error), "%s", why);
	node_log("error", p->cfg->name, 0, "disconnected: %s (POST %s/api/connection "
		 "{\"command\":\"connect\"} to reconnect)", why, p->cfg->prefix);
}

/*
 * After job j ended (done, failed, cancelled): the bed waits for an
 * operator, unless no command of j that moves the machine reached the
 * printer (confirmed, up to j's filepos, or written: sent, -1 unknown).
 * Such a job left the bed as it found it, clear (a print starts only on a
 * clear bed), so the next one need not wait.  A resumed job's part is on
 * the bed whatever this run did.  p->mu held.
 */
static void bed_after(struct node_printer *p, const struct node_job *j, bool resumed,
		      int64_t sent)
{
	struct st_error err = {0};

	if (resumed || node_gcode_moved(j->gcode, j->filepos, sent)) {
		node_log("info", p->cfg->name, 0, "waiting for the bed to be cleared "
						  "(POST %s/api/stratum/bed-clear)", p->cfg->prefix);
		return;
	}
	if (node_queue_set_bed_clear(p->node->q, p->cfg->name, true, &err))
		node_log("error", p->cfg->name, j->id, "%s", err.msg);
	else
		node_log("info", p->cfg->name, j->id, "no command of the job that moves the "
			 "printer reached it: the bed is still clear");
}

/* Take the first waiting printer command into line (cap bytes); p->mu held. */
static bool pop_command(struct node_printer *p, char *line, size_t cap)
{
	if (!p->ncmds)
		return false;
	snprintf(line, cap, "%s", p->cmds[0]);
	memmove(p->cmds[0], p->cmds[1], sizeof(p->cmds[0]) * (size_t)(--p->ncmds));
	return true;
}

/* The print's source of commands for between its lines (print.h). */
static bool next_command(void *commands, char *line, size_t cap)
{
	struct node_printer *p = commands;
	bool got;

	pthread_mutex_lock(&p->mu);
	got = pop_command(p, line, cap);
	pthread_mutex_unlock(&p->mu);
	return got;
}

/* Print job j; p->mu held on entry and exit. */
static void run_print(struct node_printer *p, struct node_job *j)
{
	struct node *n = p->node;
	struct st_error err = {0};
	bool resume = j->resume;
	int64_t start = resume ? j->filepos : 0, sent;
	int rc;

	/* The bed is taken before the first byte goes out, so a crash leaves it so. */
	if (node_queue_set_bed_clear(n->q, p->cfg->name, false, &err)) {
		node_log("error", p->cfg->name, j->id, "%s", err.msg);
		return;
	}
	j->state = NODE_JOB_PRINTING;
	j->resume = false;
	j->error[0] = '\0';
	j->filepos = start;
	if (!j->started)
		j->started = time(NULL);
	save(p, j);
	p->job_id = j->id;
	p->job_printing = true;
	p->job_x3g = j->kind == 'x';
	pthread_mutex_lock(&p->ctl.mu);
	p->ctl.pause = p->ctl.cancel = p->ctl.paused = false;
	p->ctl.next_command = next_command;
	p->ctl.commands = p;
	p->ctl.filepos = start;
	p->ctl.size = j->size;
	pthread_mutex_unlock(&p->ctl.mu);
	node_log("info", p->cfg->name, j->id, "%s %s from byte %lld", resume ? "resuming" : "printing",
		 j->name, (long long)start);
	pthread_mutex_unlock(&p->mu);
	rc = node_print_file(p->link, j->gcode, start, resume, &p->ctl, &err);
	pthread_mutex_lock(&p->mu);
	p->job_printing = false;
	p->job_id = 0;
	if (node_queue_get(n->q, j->id, j, &err) != 1)
		return;
	pthread_mutex_lock(&p->ctl.mu);
	j->filepos = p->ctl.filepos;
	j->size = p->ctl.size;
	sent = p->ctl.sent;
	pthread_mutex_unlock(&p->ctl.mu);
	switch (rc) {
	case NODE_PRINT_DONE:
		j->state = NODE_JOB_DONE;
		j->interrupted = false;
		break;
	case NODE_PRINT_CANCELLED:
		j->state = NODE_JOB_CANCELLED;
		break;
	case NODE_PRINT_STOPPED:
		j->state = NODE_JOB_PAUSED;
		j->interrupted = true;
		break;
	case NODE_PRINT_LINK_LOST:
		/* The part may be fine: offered for resume like a crash. */
		j->state = NODE_JOB_PAUSED;
		j->interrupted = true;
		snprintf(j->error, sizeof(j->error), "%s", err.msg);
		drop_link(p, err.msg);
		break;
	default:
		j->state = NODE_JOB_FAILED;
		snprintf(j->error, sizeof(j->error), "%s", err.msg);
		if (rc == ST_ERR_INTERNAL) /* a halted board answers nothing until reset */
			drop_link(p, err.msg);
		break;
	}
	if (j->state != NODE_JOB_PAUSED)
		j->finished = time(NULL);
	save(p, j);
	node_log(j->state == NODE_JOB_FAILED ? "error" : "info", p->cfg->name, j->id, "%s%s%s",
		 node_job_state_name(j->state), j->error[0] ? ": " : "", j->error);
	if (j->state != NODE_JOB_PAUSED)
		bed_after(p, j, resume, sent);
}

/* One step of work; p->mu held.  True when something was done. */
static bool step(struct node_printer *p)
{
	struct st_error err = {0};
	struct node_job j;
	bool clear = false;
	int rc = node_queue_next(p->node->q, p->cfg->name, &j, &err);

	if (rc < 0)
		node_log("error", p->cfg->name, 0, "%s", err.msg);
	if (rc != 1)
		return false;
	if (j.kind == 'm' && !j.gcode[0]) {
		run_slicing(p, &j);
		return true;
	}
	if (!p->connected)
		return false;
	/* A resumed print continues on its own part: no clear bed needed. */
	if (!j.resume && (node_queue_bed_clear(p->node->q, p->cfg->name, &clear) || !clear))
		return false;
	run_print(p, &j);
	return true;
}

/* Connect or disconnect as asked; p->mu held.  True when something was done. */
static bool connection(struct node_printer *p)
{
	struct st_error err = {0};
	struct node_link *l;
	int rc;

	if (p->want_disconnect) {
		p->want_disconnect = false;
		node_print_disconnect(p->link);
		p->link = NULL;
		p->connected = false;
		p->link_desc[0] = '\0';
		node_log("info", p->cfg->name, 0, "disconnected");
		return true;
	}
	if (!p->want_connect)
		return false;
	p->want_connect = false;
	if (p->connected)
		return false;
	pthread_mutex_unlock(&p->mu);
	rc = node_print_connect(p->cfg, p->prof, &l, &err);
	pthread_mutex_lock(&p->mu);
	if (rc) {
		snprintf(p->conn_error, sizeof(p->conn_error), "%s", err.msg);
		node_log("error", p->cfg->name, 0, "cannot connect: %s", err.msg);
	} else {
		p->link = l;
		p->connected = true;
		p->conn_error[0] = '\0';
		node_print_describe(l, p->link_desc, sizeof(p->link_desc));
		node_log(node_port_simulated(p->cfg->port) ? "warning" : "info", p->cfg->name, 0,
			 "connected on %s: %s%s", p->cfg->port, p->link_desc,
			 node_port_simulated(p->cfg->port) ? "; this is not a real printer" : "");
	}
	return true;
}

/* Send one waiting printer command; p->mu held.  True when one was sent. */
static bool command(struct node_printer *p)
{
	char line[NODE_CMD_MAX];
	struct st_error err = {0};

	if (!p->connected || !pop_command(p, line, sizeof(line)))
		return false;
	pthread_mutex_unlock(&p->mu);
	if (node_print_command(p->link, line, &err))
		node_log("error", p->cfg->name, 0, "command %s: %s", line, err.msg);
	pthread_mutex_lock(&p->mu);
	return true;
}

/* Wait for a signal or the idle period, reading the printer first; p->mu held. */
static void idle(struct node_printer *p)
{
	struct st_error err = {0};
	struct timespec t;

	if (p->connected && node_print_poll(p->link, &p->ctl, &err))
		drop_link(p, err.msg);
	clock_gettime(CLOCK_REALTIME, &t);
	t.tv_sec += WORKER_IDLE_MS / 1000;
	pthread_cond_timedwait(&p->cv, &p->mu, &t);
}

void *node_worker_main(void *arg)
{
	struct node_printer *p = arg;

	pthread_mutex_lock(&p->mu);
	while (!p->stop) {
		if (connection(p) || command(p) || step(p))
			continue;
		if (!p->stop)
			idle(p);
	}
	node_print_disconnect(p->link);
	p->link = NULL;
	p->connected = false;
	pthread_mutex_unlock(&p->mu);
	return NULL;
}
