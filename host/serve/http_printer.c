/*
 * http_printer.c - OctoPrint's printer component calls (docs/serve.md):
 * tool and bed (state; targets, tool select, extrude, flow rate), the print
 * head (jog, home, feed rate), and the answers OctoPrint gives for what a
 * printer of the node lacks (SD card, heated chamber).  A command becomes
 * G-code lines, checked by the parser and queued for the printer's worker
 * as POST /api/printer/command queues them.
 */
#include <jansson.h>
#include <math.h>
#include <stdarg.h>
#include <microhttpd.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gcode.h"
#include "http_int.h"
#include "st_append.h"

#define TEMP_MAX 400.0	  /* highest target accepted, degC (no FFF hot end goes higher) */
#define FEED_DEFAULT 6000 /* jog feed rate without "speed", mm/min */

/* Lines built by a command, checked before any is queued. */
struct lines {
	char l[NODE_CMD_QUEUE][NODE_CMD_MAX];
	size_t n;
	char msg[200]; /* why the command is refused (400), "" if not */
	bool in_print; /* may go between a print's lines (OctoPrint allows it then) */
};

static void add(struct lines *ls, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* Append one formatted line, parsed as G-code. */
static void add(struct lines *ls, const char *fmt, ...)
{
	struct gcode_line gl;
	struct st_error err = {0};
	va_list ap;

	if (ls->msg[0])
		return;
	if (ls->n == NODE_CMD_QUEUE) {
		snprintf(ls->msg, sizeof(ls->msg), "the command makes too many lines");
		return;
	}
	va_start(ap, fmt);
	vsnprintf(ls->l[ls->n], NODE_CMD_MAX, fmt, ap);
	va_end(ap);
	if (gcode_parse(ls->l[ls->n], strlen(ls->l[ls->n]), 0, &gl, &err))
		snprintf(ls->msg, sizeof(ls->msg), "not a G-code line: %.150s", err.msg);
	else
		ls->n++;
}

/* Queue ls (400 with its reason, if any). */
static enum MHD_Result send_lines(struct MHD_Connection *c, struct node_printer *p,
				  struct lines *ls)
{
	if (ls->msg[0])
		return http_send_error(c, MHD_HTTP_BAD_REQUEST, ls->msg);
	return http_queue_lines(c, p, ls->l, ls->n, ls->in_print);
}

/* The tool number of "toolN" for p, or -1. */
static int tool_index(const struct node_printer *p, const char *name)
{
	char *end;
	long i;

	if (strncmp(name, "tool", 4) || name[4] < '0' || name[4] > '9')
		return -1;
	i = strtol(name + 4, &end, 10);
	return *end || i >= p->prof->extruder_count ? -1 : (int)i;
}

/* A temperature target: a number 0..TEMP_MAX, else NAN. */
static double temp_of(const json_t *v)
{
	double t = json_is_number(v) ? json_number_value(v) : NAN;

	return t >= 0 && t <= TEMP_MAX ? t : NAN;
}

/* 409 unless p is connected (OctoPrint's state calls answer so). */
static bool operational(struct node *n, struct node_printer *p, struct http_view *v)
{
	http_take_view(n, p, v);
	return v->connected;
}

enum MHD_Result http_get_tool(struct node *n, struct MHD_Connection *c, struct req *r)
{
	struct http_view v;
	json_t *o;

	if (!operational(n, r->p, &v))
		return http_send_error(c, MHD_HTTP_CONFLICT, "Printer is not operational");
	o = http_temps_json(r->p, &v, true, false);
	http_add_history(c, r->p, o, true, false);
	return http_send_json(c, MHD_HTTP_OK, o, NULL);
}

#define OFFSET_MAX 50.0 /* OctoPrint's bound on a temperature offset, degC */

/*
 * The "offset" command: offsets, {"tool0": 5, ...}, or for the bed (offsets
 * NULL) the number bed.  Kept with the printer and added to the targets of
 * the file's lines as they stream (print.h), as OctoPrint does; only where
 * the stream can (Marlin, Sailfish): elsewhere an offset would be stored
 * and never applied, so it is refused.
 */
static enum MHD_Result set_offsets(struct node *n, struct MHD_Connection *c,
				   struct node_printer *p, const json_t *offsets, const json_t *bed)
{
	double tool[NODE_PRINT_TOOLS];
	bool set[NODE_PRINT_TOOLS] = {false};
	struct http_view v;
	const char *name;
	json_t *val;

	if (!operational(n, p, &v))
		return http_send_error(c, MHD_HTTP_CONFLICT, "Printer is not operational");
	if (!node_print_takes_commands(p->cfg, p->prof))
		return http_send_error(c, MHD_HTTP_BAD_REQUEST, "temperature offsets are applied by "
					"a Marlin or Sailfish printer's stream only: this printer's "
					"sends the file's temperatures as they are");
	if (!offsets) {
		if (!json_is_number(bed) || fabs(json_number_value(bed)) > OFFSET_MAX)
			return http_send_error(c, MHD_HTTP_BAD_REQUEST, "offset is degrees, -50 to 50");
		pthread_mutex_lock(&p->ctl.mu);
		p->ctl.bed_offset = json_number_value(bed);
		pthread_mutex_unlock(&p->ctl.mu);
		return http_no_content(c);
	}
	if (!json_is_object(offsets) || !json_object_size(offsets))
		return http_send_error(c, MHD_HTTP_BAD_REQUEST, "offsets is an object of tool names "
							       "and degrees");
	json_object_foreach((json_t *)offsets, name, val) {
		int i = tool_index(p, name);

		if (i < 0 || i >= NODE_PRINT_TOOLS || !json_is_number(val) ||
		    fabs(json_number_value(val)) > OFFSET_MAX)
			return http_send_error(c, MHD_HTTP_BAD_REQUEST, "offsets: a tool of this "
					       "printer and degrees, -50 to 50, each");
		tool[i] = json_number_value(val);
		set[i] = true;
	}
	pthread_mutex_lock(&p->ctl.mu);
	for (int i = 0; i < NODE_PRINT_TOOLS; i++)
		if (set[i])
			p->ctl.tool_offset[i] = tool[i];
	pthread_mutex_unlock(&p->ctl.mu);
	return http_no_content(c);
}

/* "target" of {"targets": {"tool0": 220, ...}}. */
static void tool_targets(struct node_printer *p, const json_t *targets, struct lines *ls)
{
	const char *name;
	json_t *v;

	if (!json_is_object(targets) || !json_object_size(targets))
		snprintf(ls->msg, sizeof(ls->msg), "targets is an object of tool names and degrees");
	json_object_foreach((json_t *)targets, name, v) {
		int i = tool_index(p, name);
		double t = temp_of(v);

		if (i < 0 || isnan(t)) {
			snprintf(ls->msg, sizeof(ls->msg), "targets: %.40s is no tool of this printer "
				 "or its value no temperature (0-%.0f)", name, TEMP_MAX);
			return;
		}
		if (p->prof->extruder_count > 1)
			add(ls, "M104 T%d S%g", i, t);
		else
			add(ls, "M104 S%g", t);
	}
}

enum MHD_Result http_post_tool(struct node *n, struct MHD_Connection *c, struct req *r)
{
	struct node_printer *p = r->p;
	struct lines ls = {.n = 0};
	enum MHD_Result ret;
	json_t *o = http_body_json(c, r, &ret);
	const char *cmd;
	double v;

	if (!o)
		return ret;
	cmd = json_string_value(json_object_get(o, "command"));
	if (!cmd) {
		snprintf(ls.msg, sizeof(ls.msg), "command is target, offset, select, extrude or "
						 "flowrate");
	} else if (!strcmp(cmd, "target")) {
		ls.in_print = true;
		tool_targets(p, json_object_get(o, "targets"), &ls);
	} else if (!strcmp(cmd, "offset")) {
		ret = set_offsets(n, c, p, json_object_get(o, "offsets"), NULL);
		json_decref(o);
		return ret;
	} else if (!strcmp(cmd, "select")) {
		const char *t = json_string_value(json_object_get(o, "tool"));
		int i = t ? tool_index(p, t) : -1;

		if (i < 0)
			snprintf(ls.msg, sizeof(ls.msg), "tool is tool0 ... tool%d",
				 p->prof->extruder_count - 1);
		else
			add(&ls, "T%d", i);
	} else if (!strcmp(cmd, "extrude")) {
		json_t *amount = json_object_get(o, "amount"), *speed = json_object_get(o, "speed");

		v = json_is_number(speed) ? json_number_value(speed) : 300;
		if (!json_is_number(amount) || fabs(json_number_value(amount)) > 1000 || v <= 0 ||
		    v > 100000) {
			snprintf(ls.msg, sizeof(ls.msg), "amount is mm of filament (at most 1000), "
							 "speed mm/min");
		} else {
			/* relative extrusion for the one move, then absolute again, as OctoPrint */
			add(&ls, "G91");
			add(&ls, "M83");
			add(&ls, "G1 E%g F%g", json_number_value(amount), v);
			add(&ls, "M82");
			add(&ls, "G90");
		}
	} else if (!strcmp(cmd, "flowrate")) {
		v = json_number_value(json_object_get(o, "factor"));
		if (v > 0 && v <= 2) /* OctoPrint takes 0.75 or 75 */
			v *= 100;
		ls.in_print = true;
		if (!json_is_number(json_object_get(o, "factor")) || v < 75 || v > 125)
			snprintf(ls.msg, sizeof(ls.msg), "factor is 75 to 125 (percent)");
		else
			add(&ls, "M221 S%.0f", v);
	} else {
		snprintf(ls.msg, sizeof(ls.msg), "command is target, offset, select, extrude or "
						 "flowrate");
	}
	json_decref(o);
	return send_lines(c, p, &ls);
}

enum MHD_Result http_get_bed(struct node *n, struct MHD_Connection *c, struct req *r)
{
	struct http_view v;
	json_t *o;

	if (!operational(n, r->p, &v))
		return http_send_error(c, MHD_HTTP_CONFLICT, "Printer is not operational");
	if (r->p->prof->bed_temperature <= 0)
		return http_send_error(c, MHD_HTTP_CONFLICT, "Printer does not have a heated bed");
	o = http_temps_json(r->p, &v, false, true);
	http_add_history(c, r->p, o, false, true);
	return http_send_json(c, MHD_HTTP_OK, o, NULL);
}

enum MHD_Result http_post_bed(struct node *n, struct MHD_Connection *c, struct req *r)
{
	struct lines ls = {.n = 0};
	enum MHD_Result ret;
	json_t *o;
	const char *cmd;
	double t;

	if (r->p->prof->bed_temperature <= 0)
		return http_send_error(c, MHD_HTTP_CONFLICT, "Printer does not have a heated bed");
	if (!(o = http_body_json(c, r, &ret)))
		return ret;
	cmd = json_string_value(json_object_get(o, "command"));
	t = temp_of(json_object_get(o, "target"));
	ls.in_print = true;
	if (cmd && !strcmp(cmd, "offset")) {
		ret = set_offsets(n, c, r->p, NULL, json_object_get(o, "offset"));
		json_decref(o);
		return ret;
	}
	if (cmd && !strcmp(cmd, "target") && !isnan(t))
		add(&ls, "M140 S%g", t);
	else
		snprintf(ls.msg, sizeof(ls.msg), "command is target, with target 0-%.0f", TEMP_MAX);
	json_decref(o);
	return send_lines(c, r->p, &ls);
}

/* The printers' profiles have no heated chamber: OctoPrint's answer. */
enum MHD_Result http_chamber(struct node *n, struct MHD_Connection *c, struct req *r)
{
	(void)n;
	(void)r;
	return http_send_error(c, MHD_HTTP_CONFLICT, "Printer does not have a heated chamber");
}

/* The node's printers are streamed over their link: no SD card, as
 * feature.sdSupport false in /api/settings says; OctoPrint's answer then. */
enum MHD_Result http_sd(struct node *n, struct MHD_Connection *c, struct req *r)
{
	(void)n;
	(void)r;
	return http_send_error(c, MHD_HTTP_NOT_FOUND, "SD support is disabled");
}

/* "jog": {"x", "y", "z" (mm), "absolute", "speed" (mm/min)}. */
static void jog(const json_t *o, struct lines *ls)
{
	static const char axes[] = "xyz";
	char move[NODE_CMD_MAX] = "G1";
	json_t *speed = json_object_get(o, "speed");
	bool absolute = json_is_true(json_object_get(o, "absolute")), any = false;

	for (int i = 0; i < 3; i++) {
		char key[2] = {axes[i], 0};
		json_t *v = json_object_get(o, key);

		if (!v)
			continue;
		if (!json_is_number(v) || fabs(json_number_value(v)) > 10000) {
			snprintf(ls->msg, sizeof(ls->msg), "%s is a distance in mm", key);
			return;
		}
		st_appendf(move, sizeof(move), " %c%g", 'X' + i, json_number_value(v));
		any = true;
	}
	if (!any || (speed && !json_is_number(speed) && !json_is_boolean(speed))) {
		snprintf(ls->msg, sizeof(ls->msg), "jog needs x, y or z (mm), and speed in mm/min");
		return;
	}
	st_appendf(move, sizeof(move), " F%g", json_is_number(speed) &&
		   json_number_value(speed) > 0 ? json_number_value(speed) : FEED_DEFAULT);
	add(ls, "%s", absolute ? "G90" : "G91");
	add(ls, "%s", move);
	if (!absolute)
		add(ls, "G90");
}

enum MHD_Result http_post_printhead(struct node *n, struct MHD_Connection *c, struct req *r)
{
	struct lines ls = {.n = 0};
	enum MHD_Result ret;
	json_t *o = http_body_json(c, r, &ret), *v;
	const char *cmd;
	size_t i;

	(void)n;
	if (!o)
		return ret;
	cmd = json_string_value(json_object_get(o, "command"));
	if (cmd && !strcmp(cmd, "jog")) {
		jog(o, &ls);
	} else if (cmd && !strcmp(cmd, "home")) {
		char line[32] = "G28";
		json_t *axes = json_object_get(o, "axes");

		json_array_foreach(axes, i, v) {
			const char *a = json_string_value(v);

			if (!a || strlen(a) != 1 || !strchr("xyz", a[0]) || strlen(line) > 20) {
				snprintf(ls.msg, sizeof(ls.msg), "axes is a list of x, y, z");
				break;
			}
			st_appendf(line, sizeof(line), " %c0", a[0] - 'a' + 'A');
		}
		if (!json_is_array(axes) || !json_array_size(axes))
			snprintf(ls.msg, sizeof(ls.msg), "axes is a list of x, y, z");
		add(&ls, "G91");
		add(&ls, "%s", line);
		add(&ls, "G90");
	} else if (cmd && !strcmp(cmd, "feedrate")) {
		double f = json_number_value(json_object_get(o, "factor"));

		if (f > 0 && f <= 2) /* OctoPrint takes 1.0 or 100 */
			f *= 100;
		ls.in_print = true;
		if (!json_is_number(json_object_get(o, "factor")) || f < 50 || f > 200)
			snprintf(ls.msg, sizeof(ls.msg), "factor is 50 to 200 (percent)");
		else
			add(&ls, "M220 S%.0f", f);
	} else {
		snprintf(ls.msg, sizeof(ls.msg), "command is jog, home or feedrate");
	}
	json_decref(o);
	return send_lines(c, r->p, &ls);
}
