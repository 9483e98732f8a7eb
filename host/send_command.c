/*
 * send_command.c - `stratum send --command LINE` (send.h): G-code lines
 * sent one at a time through serial/printer.h, each firmware reply printed
 * as it came, for scripts (M503, M114, M115).  Every line is checked
 * before the port is opened, so a bad third line leaves the first two
 * unsent.
 */
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "gcode.h"
#include "printer.h"
#include "send.h"
#include "st_error.h"

#define SC_CMD "stratum send"
#define SC_REPLY_MAX (64 * 1024) /* M503 of a big configuration is a few KiB */

bool send_command_add(const char *v, void *dest)
{
	struct send_commands *c = dest;

	if (!*v || c->n == SEND_COMMANDS_MAX)
		return false;
	c->line[c->n++] = v;
	return true;
}

/* One command and its reply lines as JSON (the reply's '\n's split it). */
static json_t *sc_json_reply(const char *line, const char *reply)
{
	json_t *o = json_object(), *lines = json_array();

	for (const char *p = reply; lines && *p;) {
		size_t n = strcspn(p, "\n");

		json_array_append_new(lines, json_stringn(p, n));
		p += n + (p[n] == '\n');
	}
	if (o) {
		json_object_set_new(o, "command", json_string(line));
		json_object_set_new(o, "reply", lines ? lines : json_array());
	} else {
		json_decref(lines);
	}
	return o;
}

/* Check every line as the printer would before any is sent; 0 or 65 with err set. */
static int sc_check(const struct send_commands *c, struct st_error *err)
{
	for (size_t i = 0; i < c->n; i++) {
		struct gcode_line g;
		struct st_error e = {0};

		if (gcode_parse(c->line[i], strlen(c->line[i]), 0, &g, &e)) {
			st_error_set(err, ST_ERR_PARSE, "--command '%s': %s; nothing was sent",
				     c->line[i], e.msg);
			return ST_EXIT_DATAERR;
		}
	}
	return 0;
}

int send_commands_run(const struct send_commands *c, const struct printer_ops *ops,
		      const struct printer_options *o, const char *printer, const char *port,
		      bool json)
{
	struct printer *pr = NULL;
	struct st_error err = {0};
	char firmware[96] = "", *reply = malloc(SC_REPLY_MAX);
	json_t *out = json ? json_object() : NULL, *replies = json ? json_array() : NULL;
	int status = 0, rc;

	if (!reply || (json && (!out || !replies))) {
		status = cmd_fail(SC_CMD, ST_EXIT_SOFTWARE, "out of memory");
		goto out_free;
	}
	if (!ops->text_replies) {
		st_error_set(&err, ST_ERR_UNSUPPORTED, "--command prints the firmware's text replies, "
			     "and printer '%s' (%s) answers in binary packets, not text; send it "
			     "G-code with 'stratum console --printer %s'", printer, ops->name, printer);
		status = ST_EXIT_USAGE;
		goto out_report;
	}
	if ((status = sc_check(c, &err)))
		goto out_report;
	if ((rc = printer_open(ops, o, &pr, &err))) {
		status = send_exit_for_open(rc);
		goto out_report;
	}
	printer_describe(pr, firmware, sizeof(firmware));
	for (size_t i = 0; i < c->n && !status; i++) {
		struct st_error e = {0};

		reply[0] = '\0';
		rc = printer_command(pr, c->line[i], reply, SC_REPLY_MAX, &e);
		if (json)
			json_array_append_new(replies, sc_json_reply(c->line[i], reply));
		else
			fputs(reply, stdout);
		if (rc) {
			st_error_set(&err, rc, "--command '%s': %s", c->line[i], e.msg);
			status = rc == ST_ERR_IO ? ST_EXIT_UNAVAILABLE
			       : rc == ST_ERR_PARSE ? ST_EXIT_DATAERR : ST_EXIT_FAILURE;
		}
	}
	printer_close(pr);
out_report:
	if (status)
		fprintf(stderr, SC_CMD ": %s\n", err.msg);
	if (json) {
		cmd_json_set(out, "b:ok", status == 0, "s:port", port, "s:printer", printer,
			     "s:protocol", ops->name, "s:firmware", firmware, "o:replies", replies,
			     NULL);
		replies = NULL;
		if (status)
			cmd_json_set(out, "s:error", err.msg, NULL);
		send_report_emit(out);
		out = NULL;
	}
out_free:
	json_decref(replies);
	json_decref(out);
	free(reply);
	return status;
}
