/*
 * log.c - the node's one log sink (node.h node_set_log): records are one
 * line, "level=L printer=P job=N msg=...", so journald and grep take them
 * as they are.
 */
#include <stdarg.h>
#include <stdio.h>

#include "node_int.h"
#include "st_append.h"

/* The process's one log sink (docs/architecture.md convention 10's allowed exception). */
static node_log_fn log_fn;
static void *log_ctx;

void node_set_log(node_log_fn fn, void *ctx)
{
	log_fn = fn;
	log_ctx = ctx;
}

void node_log(const char *level, const char *printer, int64_t job, const char *fmt, ...)
{
	char msg[512], line[700];
	va_list ap;

	if (!log_fn)
		return;
	va_start(ap, fmt);
	vsnprintf(msg, sizeof(msg), fmt, ap);
	va_end(ap);
	/* Newlines in a message (a client's text) would split the record. */
	for (char *s = msg; *s; s++)
		if (*s == '\n' || *s == '\r')
			*s = ' ';
	snprintf(line, sizeof(line), "level=%s", level);
	if (printer)
		st_appendf(line, sizeof(line), " printer=%s", printer);
	if (job > 0)
		st_appendf(line, sizeof(line), " job=%lld", (long long)job);
	st_appendf(line, sizeof(line), " msg=\"%s\"", msg);
	log_fn(line, log_ctx);
}
