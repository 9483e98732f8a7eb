/*
 * print.c - the print step of the farm node (print.h) over serial/printer.h:
 * the test double for "test-instant", else the adapter the printer's
 * profile names (host/printer_profile.h).  The node's requests reach the
 * adapter through the control hook, its progress comes back through the
 * progress hook; both go through struct node_print_ctl.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "commands.h"
#include "marlin.h"
#include "print.h"
#include "printer_profile.h"
#include "resume.h"

struct node_link {
	char name[NODE_NAME_MAX + 8]; /* "printer NAME", for messages */
	struct printer *p;
	const struct printer_ops *ops;
	struct printer_options o; /* strings borrowed from the config and profile */
};

/* The options and operations for printer pc; 0 or the profile's error. */
static int options_for(const struct node_printer_config *pc, const struct profile *prof,
		       struct printer_options *o, const struct printer_ops **ops,
		       struct st_error *err)
{
	struct st_error e = {0};
	int rc = printer_profile_options(prof, pc->port, 0, o, ops, &e);

	if (rc)
		return st_error_set(err, rc, "printer %s: profile %s: %s", pc->name, prof->id, e.msg);
	if (!strcmp(pc->port, "test-instant"))
		*ops = &node_double_ops;
	o->name = pc->name;
	o->sim_speedup = pc->sim_speedup;
	o->sim_log = pc->sim_log[0] ? pc->sim_log : NULL;
	return 0;
}

bool node_print_resumable(const struct node_printer_config *pc, const struct profile *prof)
{
	struct printer_options o;
	const struct printer_ops *ops;

	return !options_for(pc, prof, &o, &ops, NULL) && printer_can_resume(ops);
}

bool node_port_simulated(const char *port)
{
	return !strcmp(port, "test-instant") || !strcmp(port, "sim");
}

int node_print_connect(const struct node_printer_config *pc, const struct profile *prof,
		       struct node_link **out, struct st_error *err)
{
	struct printer_options o;
	const struct printer_ops *ops;
	struct node_link *l;
	int rc;

	*out = NULL;
	if ((rc = options_for(pc, prof, &o, &ops, err)))
		return rc;
	l = calloc(1, sizeof(*l));
	if (!l)
		return st_error_set(err, ST_ERR_NOMEM, "printer %s: out of memory", pc->name);
	snprintf(l->name, sizeof(l->name), "printer %s", pc->name);
	o.name = l->name;
	l->ops = ops;
	l->o = o;
	if ((rc = printer_open(ops, &o, &l->p, err))) {
		free(l);
		return rc;
	}
	*out = l;
	return 0;
}

void node_print_disconnect(struct node_link *l)
{
	if (!l)
		return;
	printer_close(l->p);
	free(l);
}

/* The control hook: the node's requests, read under ctl->mu. */
static enum printer_control ctl_control(void *ctx)
{
	struct node_print_ctl *ctl = ctx;
	enum printer_control c;

	pthread_mutex_lock(&ctl->mu);
	c = ctl->stop ? PRINTER_STOP : ctl->cancel ? PRINTER_CANCEL
			: ctl->pause ? PRINTER_HOLD : PRINTER_GO;
	pthread_mutex_unlock(&ctl->mu);
	return c;
}

/* Temperatures reported into ctl; ctl->mu held. */
static void ctl_temps(struct node_print_ctl *ctl, const struct printer_progress *p)
{
	if (p->tool) {
		ctl->tool_actual = p->tool_actual;
		ctl->tool_target = p->tool_target;
	}
	if (p->bed) {
		ctl->bed_actual = p->bed_actual;
		ctl->bed_target = p->bed_target;
	}
	if (p->tool1) {
		ctl->tool1_actual = p->tool1_actual;
		ctl->tool1_target = p->tool1_target;
	}
}

/* The progress hook: position, layer, temperatures into ctl. */
static void ctl_progress(void *ctx, const struct printer_progress *p)
{
	struct node_print_ctl *ctl = ctx;

	pthread_mutex_lock(&ctl->mu);
	ctl->filepos = p->filepos;
	ctl->layer = p->layer;
	ctl->z = p->z;
	ctl->paused = p->paused;
	ctl_temps(ctl, p);
	pthread_mutex_unlock(&ctl->mu);
}

/* The inject hook: the operator's next command for between two lines. */
static bool ctl_inject(void *ctx, char *line, size_t cap)
{
	struct node_print_ctl *ctl = ctx;

	return ctl->next_command(ctl->commands, line, cap);
}

/* The temperature offset hook: the operator's offset for heater. */
static double ctl_temp_offset(void *ctx, int heater)
{
	struct node_print_ctl *ctl = ctx;
	double d = 0;

	pthread_mutex_lock(&ctl->mu);
	if (heater == PRINTER_HEATER_BED)
		d = ctl->bed_offset;
	else if (heater >= 0 && heater < NODE_PRINT_TOOLS)
		d = ctl->tool_offset[heater];
	pthread_mutex_unlock(&ctl->mu);
	return d;
}

bool node_print_takes_commands(const struct node_printer_config *pc, const struct profile *prof)
{
	struct printer_options o;
	const struct printer_ops *ops;

	return !options_for(pc, prof, &o, &ops, NULL) && ops->takes_injected;
}

/* After a stream that ended with the printer answering: leave it safe. */
static int safe_stop(struct node_link *l, int rc, struct st_error *err)
{
	struct st_error e = {0};

	if (!printer_safe_stop(l->p, &e))
		return rc;
	if (rc < 0) { /* the job's error stands; say the stop failed too */
		char msg[sizeof(err->msg)];

		snprintf(msg, sizeof(msg), "%s", err->msg);
		return st_error_set(err, rc, "%.180s; the safe stop failed too: %.60s", msg, e.msg);
	}
	return st_error_set(err, ST_ERR_IO, "%s", e.msg);
}

int node_print_file(struct node_link *l, const char *path, int64_t start, bool resume,
		    struct node_print_ctl *ctl, struct st_error *err)
{
	struct printer_job job = {
		.path = path,
		.offset = start,
		.resume = resume,
		.control = ctl_control,
		.progress = ctl_progress,
		.inject = ctl->next_command && l->ops->takes_injected ? ctl_inject : NULL,
		.temp_offset = l->ops->takes_injected ? ctl_temp_offset : NULL,
		.ctx = ctl,
	};
	struct printer_file_info info;
	struct printer_result res;
	struct marlin *m = printer_marlin_driver(l->p);
	struct marlin_status before, after;
	struct stat sb;
	int rc;

	job.x3g = cmd_has_ext(path, ".x3g");
	pthread_mutex_lock(&ctl->mu);
	if (!stat(path, &sb))
		ctl->size = sb.st_size;
	ctl->layer = -1;
	ctl->z = NAN;
	ctl->sent = m ? 0 : -1;
	pthread_mutex_unlock(&ctl->mu);
	if (resume && l->ops->resume_from_layer && !job.x3g) {
		long layer;

		if ((rc = resume_layer_start(path, start, &job.offset, &layer, err)))
			return rc;
		job.saved = start;
	}
	if ((rc = printer_check(l->ops, &l->o, &job, NULL, NULL, &info, err)))
		return rc;
	job.total = info.commands;
	if (m)
		marlin_status(m, &before);
	rc = printer_stream(l->p, &job, &res, err);
	if (m)
		marlin_status(m, &after);
	pthread_mutex_lock(&ctl->mu);
	ctl->paused = false;
	/* Marlin runs what it holds after a cancel (the safe stop breaks its
	 * waits): the lines written, not only those it confirmed, may move it.
	 * The job's numbered lines, each written once besides resends. */
	if (m)
		ctl->sent = (int64_t)((after.transmitted - before.transmitted) -
				      (after.resends - before.resends));
	pthread_mutex_unlock(&ctl->mu);
	switch (res.end) {
	case PRINTER_END_DONE:
		return rc ? rc : NODE_PRINT_DONE;
	case PRINTER_END_CANCELLED:
		return safe_stop(l, NODE_PRINT_CANCELLED, err);
	case PRINTER_END_STOPPED:
		return safe_stop(l, NODE_PRINT_STOPPED, err);
	case PRINTER_END_LINK_LOST:
		return NODE_PRINT_LINK_LOST;
	default:
		rc = rc ? rc : err->code ? err->code : ST_ERR_IO;
		return res.safe_stop ? safe_stop(l, rc, err) : rc;
	}
}

int node_print_command(struct node_link *l, const char *line, struct st_error *err)
{
	return printer_command(l->p, line, NULL, 0, err);
}

int node_print_poll(struct node_link *l, struct node_print_ctl *ctl, struct st_error *err)
{
	struct printer_progress t = {0};
	int rc = printer_poll(l->p, &t, err);

	pthread_mutex_lock(&ctl->mu);
	ctl_temps(ctl, &t);
	pthread_mutex_unlock(&ctl->mu);
	return rc;
}

void node_print_describe(struct node_link *l, char *out, size_t cap)
{
	printer_describe(l->p, out, cap);
}
