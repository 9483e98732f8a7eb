/*
 * printer.c - the dialect-independent half of printer.h: the handle over
 * an ops table, and the port helpers the adapters share.
 */
#include "printer.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gcode.h"
#include "xport.h"

#define PRINTER_SIM_BAUD_MAX 20000000.0 /* sped-up simulated link, bits/s */

struct printer {
	const struct printer_ops *ops;
	void *state;
};

void printer_options_init(struct printer_options *o)
{
	memset(o, 0, sizeof(*o));
	o->baud = 115200;
	o->sim_speedup = 1000;
}

const char *printer_name(const struct printer_options *o)
{
	return o->name ? o->name : o->port ? o->port : "printer";
}

unsigned printer_sim_baud(const struct printer_options *o)
{
	double baud = (double)(o->baud > 0 ? o->baud : 115200) * o->sim_speedup;

	return (unsigned)(baud > PRINTER_SIM_BAUD_MAX ? PRINTER_SIM_BAUD_MAX : baud);
}

int printer_port_open(const struct printer_options *o, const char *path, bool simulated,
		      struct xport **x, struct st_error *err)
{
	struct xport_options xo = {0};
	struct st_error e = {0};

	xo.baudrate = (int)o->baud;
	xo.dtr_reset = o->dtr_reset && !simulated;
	if (xport_open(path, &xo, x, &e))
		return st_error_set(err, ST_ERR_IO, "%s: %s", printer_name(o), e.msg);
	return 0;
}

void printer_port_close(struct xport *x)
{
	if (!x)
		return;
	xport_drain(x, 1000, NULL);
	xport_close(x);
}

int printer_open(const struct printer_ops *ops, const struct printer_options *o,
		 struct printer **out, struct st_error *err)
{
	struct printer *p;
	int rc;

	*out = NULL;
	p = calloc(1, sizeof(*p));
	if (!p)
		return st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", printer_name(o));
	p->ops = ops;
	if ((rc = ops->open(o, &p->state, err))) {
		free(p);
		return rc;
	}
	*out = p;
	return 0;
}

void printer_close(struct printer *p)
{
	if (!p)
		return;
	p->ops->close(p->state);
	free(p);
}

const struct printer_ops *printer_ops_of(const struct printer *p)
{
	return p->ops;
}

void *printer_state(const struct printer *p)
{
	return p->state;
}

int printer_check(const struct printer_ops *ops, const struct printer_options *o,
		  const struct printer_job *job, printer_warn_fn warn, void *warn_ctx,
		  struct printer_file_info *info, struct st_error *err)
{
	memset(info, 0, sizeof(*info));
	return ops->check(o, job, warn, warn_ctx, info, err);
}

int printer_stream(struct printer *p, const struct printer_job *job, struct printer_result *res,
		   struct st_error *err)
{
	memset(res, 0, sizeof(*res));
	res->last.layer = -1;
	res->machine_s = NAN;
	return p->ops->stream(p->state, job, res, err);
}

int printer_command(struct printer *p, const char *line, char *reply, size_t cap,
		    struct st_error *err)
{
	if (reply && cap)
		reply[0] = '\0';
	return p->ops->command(p->state, line, reply, cap, err);
}

int printer_poll(struct printer *p, struct printer_progress *t, struct st_error *err)
{
	return p->ops->poll ? p->ops->poll(p->state, t, err) : 0;
}

int printer_safe_stop(struct printer *p, struct st_error *err)
{
	return p->ops->safe_stop ? p->ops->safe_stop(p->state, err) : 0;
}

void printer_describe(struct printer *p, char *out, size_t cap)
{
	if (p->ops->describe)
		p->ops->describe(p->state, out, cap);
	else
		snprintf(out, cap, "%s", p->ops->name);
}

bool printer_can_resume(const struct printer_ops *ops)
{
	return ops->can_resume;
}

void printer_temp_offset(const struct printer_job *job, struct gcode_line *g, bool m109_bed,
			 size_t text_max)
{
	char text[GCODE_LINE_MAX + 1];
	double s, t = 0, delta, set;
	bool bed = g->number == 140 || g->number == 190 || (g->number == 109 && m109_bed);
	size_t len;
	int n;

	if (!job->temp_offset || g->letter != 'M' ||
	    (g->number != 104 && g->number != 109 && g->number != 140 && g->number != 190) ||
	    !gcode_word_value(g, 'S', &s) || s <= 0)
		return;
	gcode_word_value(g, 'T', &t);
	delta = job->temp_offset(job->ctx, bed ? PRINTER_HEATER_BED : (int)t);
	if (delta == 0 || !isfinite(delta))
		return;
	set = s + delta > 0 ? s + delta : 0;
	len = (size_t)snprintf(text, sizeof(text), "M%d", g->number);
	for (size_t i = 0; i < g->nwords && len < sizeof(text); i++) {
		const struct gcode_word *w = &g->words[i];

		n = !w->has_value ? snprintf(text + len, sizeof(text) - len, " %c", w->letter)
		    : snprintf(text + len, sizeof(text) - len, " %c%.10g", w->letter,
			       w->letter == 'S' ? set : w->value);
		len += (size_t)n;
	}
	if (len >= sizeof(text) || len > text_max)
		return;
	memcpy(g->text, text, len + 1);
	g->text_len = len;
	for (size_t i = 0; i < g->nwords; i++)
		if (g->words[i].letter == 'S')
			g->words[i].value = set;
}
