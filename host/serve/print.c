/*
 * print.c - the print step of the farm node (print.h): the one place that
 * chooses how a printer is driven: the test double for "test-instant",
 * the S3G driver for Sailfish profiles (print_sailfish.c), the Marlin
 * driver for everything else (print_marlin.c).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "print.h"
#include "xport.h"


struct node_link {
	const struct node_printer_ops *ops;
	void *state;
};

/* The back end for a port value and the profile's protocol. */
static const struct node_printer_ops *ops_for(const char *port, const struct profile *prof)
{
	if (!strcmp(port, "test-instant"))
		return &node_double_ops;
	if (prof->protocol == PROFILE_PROTOCOL_SAILFISH)
		return &node_sailfish_ops;
	return &node_marlin_ops;
}

bool node_print_resumable(const struct node_printer_config *pc, const struct profile *prof)
{
	return ops_for(pc->port, prof)->can_resume;
}

bool node_port_simulated(const char *port)
{
	return !strcmp(port, "test-instant") || !strcmp(port, "sim");
}

int node_print_connect(const struct node_printer_config *pc, const struct profile *prof,
		       struct node_link **out, struct st_error *err)
{
	const struct node_printer_ops *ops = ops_for(pc->port, prof);
	struct node_link *l;
	int rc;

	*out = NULL;
	l = calloc(1, sizeof(*l));
	if (!l)
		return st_error_set(err, ST_ERR_NOMEM, "printer %s: out of memory", pc->name);
	l->ops = ops;
	rc = ops->connect(pc, prof, &l->state, err);
	if (rc) {
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
	l->ops->disconnect(l->state);
	free(l);
}

int node_print_file(struct node_link *l, const char *path, int64_t start, bool resume,
		    struct node_print_ctl *ctl, struct st_error *err)
{
	return l->ops->print(l->state, path, start, resume, ctl, err);
}

int node_print_command(struct node_link *l, const char *line, struct st_error *err)
{
	return l->ops->command(l->state, line, err);
}

int node_print_poll(struct node_link *l, struct node_print_ctl *ctl, struct st_error *err)
{
	return l->ops->poll ? l->ops->poll(l->state, ctl, err) : 0;
}

void node_print_describe(struct node_link *l, char *out, size_t cap)
{
	if (l->ops->describe)
		l->ops->describe(l->state, out, cap);
	else
		snprintf(out, cap, "%s", l->ops->name);
}


int node_port_open(const struct node_printer_config *pc, const struct profile *prof,
		   const char *path, bool simulated, struct xport **x, struct st_error *err)
{
	struct xport_options xo = {0};
	struct st_error e = {0};

	xo.baudrate = (int)prof->baudrate;
	xo.dtr_reset = prof->dtr_reset && !simulated;
	if (xport_open(path, &xo, x, &e))
		return st_error_set(err, ST_ERR_IO, "printer %s: %s", pc->name, e.msg);
	return 0;
}

void node_port_close(struct xport *x)
{
	if (!x)
		return;
	xport_drain(x, 1000, NULL);
	xport_close(x);
}
