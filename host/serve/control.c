/*
 * control.c - what the HTTP API and MQTT commands both do to a printer
 * (node_int.h): cancel, pause and resume its job, move, cancel and requeue
 * jobs of its queue, and store a received file into its files (queued or
 * not).  One place, so both ways of
 * steering a node behave the same.
 */
#include <errno.h>
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "cfgopt.h"
#include "guard.h"
#include "node_int.h"
#include "st_file.h"

/* Set what the worker's print should do (pause, resume, cancel); p->mu held. */
static void ctl_request(struct node_printer *p, int pause, bool cancel)
{
	pthread_mutex_lock(&p->ctl.mu);
	if (pause >= 0)
		p->ctl.pause = pause != 0;
	if (cancel)
		p->ctl.cancel = true;
	pthread_mutex_unlock(&p->ctl.mu);
}

/* "pause" with action pause/resume/toggle of job j; p->mu held. */
static int job_pause(struct node *n, struct node_printer *p, struct node_job *j,
		     const char *action, struct st_error *err)
{
	bool worker = p->job_printing && p->job_id == j->id;
	bool paused = j->state == NODE_JOB_PAUSED;
	bool want;

	if (!strcmp(action, "toggle"))
		want = !paused;
	else if (!strcmp(action, "pause") || !strcmp(action, "resume"))
		want = !strcmp(action, "pause");
	else
		return st_error_set(err, ST_ERR_ARG, "action is pause, resume or toggle");
	if (j->state == NODE_JOB_SLICING)
		return st_error_set(err, ST_ERR_RANGE, "the job is still slicing");
	if (want == paused)
		return 0;
	if (!worker) {
		/* An interrupted print: only resuming makes sense, and the worker does it. */
		if (want)
			return st_error_set(err, ST_ERR_RANGE, "the job is not printing");
		if (!node_print_resumable(p->cfg, p->prof))
			return st_error_set(err, ST_ERR_RANGE, "printer %s cannot resume an "
					    "interrupted print", p->cfg->name);
		/* Sailfish resumes restart a layer of the G-code; X3G has none. */
		if (j->kind == 'x')
			return st_error_set(err, ST_ERR_RANGE, "an interrupted X3G print cannot "
					    "be resumed (it has no layers to restart from); "
					    "cancel the job and print it again");
		j->resume = true;
		node_log("info", p->cfg->name, j->id, "resume of the interrupted print requested");
	} else {
		ctl_request(p, want, false);
		j->state = want ? NODE_JOB_PAUSED : NODE_JOB_PRINTING;
		node_log("info", p->cfg->name, j->id, "%s", want ? "paused" : "resumed");
	}
	if (node_queue_update(n->q, j, err))
		return ST_ERR_IO;
	pthread_cond_signal(&p->cv);
	return 0;
}

/* Cancel p's active job j: the worker's print stops safely, a job not on
 * the worker (interrupted, slicing) ends at once.  p->mu held. */
static int cancel_active(struct node *n, struct node_printer *p, struct node_job *j,
			 struct st_error *err)
{
	if (p->job_printing && p->job_id == j->id) {
		ctl_request(p, -1, true);
		node_log("info", p->cfg->name, j->id, "cancel requested");
		return 0;
	}
	j->state = NODE_JOB_CANCELLED;
	j->finished = time(NULL);
	node_log("info", p->cfg->name, j->id, "cancelled");
	return node_queue_update(n->q, j, err) ? ST_ERR_IO : 0;
}

int node_control_job(struct node *n, struct node_printer *p, const char *cmd,
		     const char *action, struct st_error *err)
{
	struct node_job j;
	int rc, have;

	pthread_mutex_lock(&p->mu);
	have = node_queue_active(n->q, p->cfg->name, &j, NULL);
	if (have != 1)
		rc = st_error_set(err, ST_ERR_RANGE, "no job is printing");
	else if (!strcmp(cmd, "cancel"))
		rc = cancel_active(n, p, &j, err);
	else if (!strcmp(cmd, "pause"))
		rc = job_pause(n, p, &j, action ? action : "toggle", err);
	else
		rc = st_error_set(err, ST_ERR_ARG, "command is cancel or pause, not '%s'", cmd);
	pthread_mutex_unlock(&p->mu);
	return rc;
}

int node_control_restart(struct node *n, struct node_printer *p, int64_t *id,
			 struct st_error *err)
{
	struct node_job j;
	int rc;

	*id = 0;
	pthread_mutex_lock(&p->mu);
	if (node_queue_active(n->q, p->cfg->name, &j, NULL) != 1 || j.state != NODE_JOB_PAUSED)
		rc = st_error_set(err, ST_ERR_RANGE, "Printer does not have an active print job "
				  "or is not paused");
	else if (!p->connected)
		rc = st_error_set(err, ST_ERR_RANGE, "Printer is not operational");
	else if (access(j.file, R_OK))
		rc = st_error_set(err, ST_ERR_RANGE, "the job's file %.200s is gone", j.name);
	else if (!(rc = cancel_active(n, p, &j, err)) &&
		 !(rc = node_queue_copy(n->q, &j, true, id, err))) {
		node_log("info", p->cfg->name, *id, "restart of job %lld: %s queued first",
			 (long long)j.id, j.name);
		pthread_cond_signal(&p->cv);
	}
	pthread_mutex_unlock(&p->mu);
	return rc;
}

int node_control_cancel(struct node *n, struct node_printer *p, int64_t id, struct st_error *err)
{
	struct node_job j;
	int rc;

	pthread_mutex_lock(&p->mu);
	if ((rc = node_queue_get(n->q, id, &j, err)) == 1 && strcmp(j.printer, p->cfg->name))
		rc = 0; /* another printer's */
	if (rc == 1 && j.state == NODE_JOB_QUEUED) {
		/* the worker takes a job only under p->mu: this one has not started */
		j.state = NODE_JOB_CANCELLED;
		j.finished = time(NULL);
		rc = node_queue_update(n->q, &j, err) ? ST_ERR_IO : 0;
		if (!rc)
			node_log("info", p->cfg->name, id, "cancelled before it started");
	} else if (rc == 1 && (j.state == NODE_JOB_SLICING || j.state == NODE_JOB_PRINTING ||
			       j.state == NODE_JOB_PAUSED)) {
		rc = cancel_active(n, p, &j, err);
	} else if (rc == 1) {
		rc = st_error_set(err, ST_ERR_RANGE, "job %lld is %s already", (long long)id,
				  node_job_state_name(j.state));
	} else if (rc == 0) {
		rc = st_error_set(err, ST_ERR_RANGE, "no job %lld", (long long)id);
	}
	pthread_mutex_unlock(&p->mu);
	return rc;
}

int node_control_move(struct node *n, struct node_printer *p, int64_t id, int64_t to,
		      struct st_error *err)
{
	struct node_job j;
	int rc;

	if (to < 1)
		return st_error_set(err, ST_ERR_ARG, "position is a whole number from 1 (1: the "
				    "next job to print)");
	rc = node_queue_move(n->q, p->cfg->name, id, to, err);
	if (rc == 0)
		return node_queue_get(n->q, id, &j, NULL) == 1 && !strcmp(j.printer, p->cfg->name)
			       ? st_error_set(err, ST_ERR_RANGE, "job %lld is %s: only a queued job "
					      "can be moved", (long long)id,
					      node_job_state_name(j.state))
			       : st_error_set(err, ST_ERR_RANGE, "no job %lld", (long long)id);
	if (rc < 0)
		return rc;
	node_log("info", p->cfg->name, id, "moved to position %lld of the queue", (long long)to);
	return 0;
}

int node_control_requeue(struct node *n, struct node_printer *p, int64_t id, int64_t *out,
			 struct st_error *err)
{
	struct node_job j;
	int rc = node_queue_get(n->q, id, &j, err);

	*out = 0;
	if (rc == 1 && strcmp(j.printer, p->cfg->name))
		rc = 0; /* another printer's */
	if (rc == 0)
		return st_error_set(err, ST_ERR_RANGE, "no job %lld", (long long)id);
	if (rc < 0)
		return rc;
	if (j.state != NODE_JOB_DONE && j.state != NODE_JOB_FAILED &&
	    j.state != NODE_JOB_CANCELLED)
		return st_error_set(err, ST_ERR_RANGE, "job %lld is %s: only a done, failed or "
				    "cancelled job is queued again", (long long)id,
				    node_job_state_name(j.state));
	if (access(j.file, R_OK))
		return st_error_set(err, ST_ERR_RANGE, "the file of job %lld, %.200s, is gone",
				    (long long)id, j.name);
	if ((rc = node_queue_copy(n->q, &j, false, out, err)))
		return rc;
	node_log("info", p->cfg->name, *out, "job %lld (%s) queued again", (long long)id, j.name);
	node_printer_wake(p);
	return 0;
}

int node_check_kind(const struct node_printer *p, const char *name, struct st_error *err)
{
	char kind = node_file_kind(name);
	bool sailfish = p->prof->protocol == PROFILE_PROTOCOL_SAILFISH;

	if (kind == 'g' || kind == 'm' || (kind == 'x' && sailfish))
		return 0;
	if (kind == 'x')
		return st_error_set(err, ST_ERR_UNSUPPORTED, "X3G files are for Sailfish "
				    "printers; printer %s takes G-code (.gcode, .gco, .g) and "
				    "models (.stl, .obj)", p->cfg->name);
	return st_error_set(err, ST_ERR_UNSUPPORTED, "only G-code (.gcode, .gco, .g)%s and "
			    "models (.stl, .obj) are accepted", sailfish ? ", X3G (.x3g)" : "");
}

/* mkdir each folder of rel under base (rel's last part is the file). */
static int make_folders(const char *base, const char *rel)
{
	char path[2 * NODE_PATH_MAX];
	size_t b = (size_t)snprintf(path, sizeof(path), "%s/", base);

	for (const char *s = rel; *s && b + 1 < sizeof(path); s++) {
		if (*s == '/') {
			path[b] = '\0';
			if (mkdir(path, 0750) && errno != EEXIST)
				return -1;
		}
		path[b++] = *s;
	}
	return 0;
}

int node_store_file(struct node *n, struct node_printer *p, struct st_file_out *tmp, const char *rel,
		    bool select, bool print, bool force, const char *settings, int64_t *id,
		    struct st_error *err)
{
	char full[2 * NODE_PATH_MAX];

	*id = 0;
	if (snprintf(full, sizeof(full), "%s/%s", p->files_dir, rel) >= (int)sizeof(full))
		return st_error_set(err, ST_ERR_ARG, "the file's path is too long");
	if (node_file_kind(rel) == 'g' && !force && guard_check_file(tmp->tmp, rel, p->prof, err))
		return err->code == ST_ERR_RANGE ? ST_ERR_RANGE : ST_ERR_IO;
	if (node_queue_file_busy(n->q, p->cfg->name, full))
		return st_error_set(err, ST_ERR_RANGE, "%.250s is being printed or waits in the "
				    "queue; send it under another name", rel);
	if (make_folders(p->files_dir, rel) || st_file_publish(tmp, full, NULL)) {
		node_log("error", p->cfg->name, 0, "%s: cannot store: %s", full, strerror(errno));
		return st_error_set(err, ST_ERR_IO, "cannot store the file");
	}
	if ((select || print) && node_queue_set_selected(n->q, p->cfg->name, rel, err))
		return ST_ERR_IO;
	if (print) {
		if (node_queue_add(n->q, p->cfg->name, rel, full, node_file_kind(rel), settings, id,
				   err))
			return ST_ERR_IO;
		node_printer_wake(p);
	}
	return 0;
}

int node_settings_profile(const struct node_printer *p, const char *settings,
			  struct profile **out, struct st_error *err)
{
	json_t *arr = json_loads(settings, 0, NULL), *pair;
	struct cfgopt *o = calloc(1, sizeof(*o)); /* large: off the worker's stack */
	bool usage;
	size_t i;
	int rc = 0;

	*out = NULL;
	if (!o)
		rc = st_error_set(err, ST_ERR_NOMEM, "per-job settings: out of memory");
	else if (!json_is_array(arr))
		rc = st_error_set(err, ST_ERR_PARSE, "per-job settings: not a list of [field, "
				  "value] pairs");
	json_array_foreach(arr, i, pair) {
		const char *name = json_string_value(json_array_get(pair, 0));
		const char *value = json_string_value(json_array_get(pair, 1));

		if (rc)
			break;
		if (!name || !value)
			rc = st_error_set(err, ST_ERR_PARSE, "per-job settings: pair %zu is not "
					  "[field, value]", i + 1);
		else if ((rc = cfgopt_field(o, name, value, err)) == 0)
			rc = st_error_set(err, ST_ERR_ARG,
					  "form field '%.60s' is no setting: give set=KEY=VALUE or "
					  "PrusaSlicer's spelling of a key ('stratum printers "
					  "--keys'), e.g. layer-height=0.2",
					  name);
		else if (rc > 0)
			rc = 0;
	}
	if (!rc)
		rc = cfgopt_apply(o, p->prof, out, &usage, err);
	free(o);
	json_decref(arr);
	return rc;
}
