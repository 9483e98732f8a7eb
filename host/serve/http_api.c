/*
 * http_api.c - the node's API handlers (docs/serve.md): the OctoPrint
 * subset (version, printer, job, connection, settings, printer profiles)
 * and /api/stratum/node; http.c routes requests to them.
 */
#include <ctype.h>
#include <errno.h>
#include <jansson.h>
#include <math.h>
#include <microhttpd.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "gcode.h"
#include "http_int.h"


/* ---- printer state ------------------------------------------------------- */

void http_take_view(struct node *n, struct node_printer *p, struct http_view *v)
{
	memset(v, 0, sizeof(*v));
	pthread_mutex_lock(&p->mu);
	v->connected = p->connected;
	snprintf(v->conn_error, sizeof(v->conn_error), "%s", p->conn_error);
	snprintf(v->link_desc, sizeof(v->link_desc), "%s", p->link_desc);
	v->printing = p->job_printing;
	v->job_id = p->job_id;
	pthread_mutex_lock(&p->ctl.mu);
	v->paused = v->printing && p->ctl.paused;
	v->pausing = v->printing && p->ctl.pause && !p->ctl.paused;
	v->filepos = p->ctl.filepos;
	v->size = p->ctl.size;
	v->layer = v->printing ? p->ctl.layer : -1;
	v->z = v->printing ? p->ctl.z : NAN;
	v->tool[0] = p->ctl.tool_actual;
	v->tool[1] = p->ctl.tool_target;
	v->bed[0] = p->ctl.bed_actual;
	v->bed[1] = p->ctl.bed_target;
	v->tool[2] = p->ctl.tool_offset[0];
	v->bed[2] = p->ctl.bed_offset;
	memcpy(v->tool_offset, p->ctl.tool_offset, sizeof(v->tool_offset));
	v->tool1[0] = p->ctl.tool1_actual;
	v->tool1[1] = p->ctl.tool1_target;
	pthread_mutex_unlock(&p->ctl.mu);
	pthread_mutex_unlock(&p->mu);
	v->has_job = node_queue_active(n->q, p->cfg->name, &v->job, NULL) == 1;
	if (v->has_job && !v->printing) {
		v->filepos = v->job.filepos;
		v->size = v->job.size;
	}
	node_queue_selected(n->q, p->cfg->name, v->selected, sizeof(v->selected));
	v->bed_clear = true; /* as a printer the queue has no row for yet */
	node_queue_bed_clear(n->q, p->cfg->name, &v->bed_clear);
}

/* OctoPrint's state text. */
const char *http_state_text(const struct http_view *v)
{
	if (v->has_job && v->job.state == NODE_JOB_PAUSED && !v->printing)
		return "Paused"; /* an interrupted print waiting for an operator */
	if (!v->connected)
		return v->conn_error[0] ? "Offline after error" : "Offline";
	if (v->printing)
		return v->paused ? "Paused" : v->pausing ? "Pausing" : "Printing";
	if (v->has_job && v->job.state == NODE_JOB_SLICING)
		return "Slicing";
	/* Stratum's gate: no print starts until an operator confirms the bed
	 * clear (POST /api/stratum/bed-clear); OctoPrint has no such state. */
	if (!v->bed_clear)
		return HTTP_STATE_BED;
	return "Operational";
}

/* {"actual", "target", "offset"} of t = {actual, target, offset}. */
static json_t *temp_json(const double t[3])
{
	json_t *o = json_object();

	json_object_set_new(o, "actual", json_real(t[0]));
	json_object_set_new(o, "target", json_real(t[1]));
	json_object_set_new(o, "offset", t[2] == floor(t[2]) ? json_integer((json_int_t)t[2])
							     : json_real(t[2]));
	return o;
}

json_t *http_temps_json(const struct node_printer *p, const struct http_view *v, bool tools,
			bool with_bed)
{
	json_t *o = json_object();
	char name[16];

	if (tools) {
		json_object_set_new(o, "tool0", temp_json(v->tool));
		for (int i = 1; i < p->prof->extruder_count; i++) {
			/* tool 1 as the driver reads it (Sailfish), the others unknown */
			bool known = i == 1 && !isnan(v->tool1[0]);

			snprintf(name, sizeof(name), "tool%d", i);
			json_object_set_new(o, name, json_pack("{s:o,s:o,s:f}", "actual",
							       known ? json_real(v->tool1[0])
								     : json_null(),
							       "target",
							       known ? json_real(v->tool1[1])
								     : json_null(),
							       "offset", i < NODE_PRINT_TOOLS
							       ? v->tool_offset[i] : 0.0));
		}
	}
	if (with_bed)
		json_object_set_new(o, "bed", temp_json(v->bed));
	return o;
}

json_t *http_temp_history(struct node_printer *p, int limit, bool tools, bool bed)
{
	json_t *arr = json_array();
	size_t n, first;
	char name[16];

	pthread_mutex_lock(&p->ctl.mu);
	n = limit > 0 && (size_t)limit < p->ntemps ? (size_t)limit : p->ntemps;
	first = (p->temps_next + NODE_TEMP_HISTORY - n) % NODE_TEMP_HISTORY;
	for (size_t i = 0; i < n; i++) {
		const struct node_temp_sample *t = &p->temps[(first + i) % NODE_TEMP_HISTORY];
		json_t *o = json_pack("{s:I}", "time", (json_int_t)t->time);

		if (tools) {
			json_object_set_new(o, "tool0", json_pack("{s:f,s:f}", "actual", t->tool[0],
								  "target", t->tool[1]));
			/* the second extruder's as the driver reads it (Sailfish),
			 * others unknown */
			for (int k = 1; k < p->prof->extruder_count; k++) {
				bool known = k == 1 && !isnan(t->tool1[0]) && !isnan(t->tool1[1]);

				snprintf(name, sizeof(name), "tool%d", k);
				json_object_set_new(o, name, known ? json_pack("{s:f,s:f}", "actual",
								t->tool1[0], "target", t->tool1[1])
							   : json_pack("{s:n,s:n}", "actual", "target"));
			}
		}
		if (bed)
			json_object_set_new(o, "bed", json_pack("{s:f,s:f}", "actual", t->bed[0],
								"target", t->bed[1]));
		json_array_append_new(arr, o);
	}
	pthread_mutex_unlock(&p->ctl.mu);
	return arr;
}

void http_add_history(struct MHD_Connection *c, struct node_printer *p, json_t *temps,
		      bool tools, bool bed)
{
	const char *h = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "history");
	const char *l = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "limit");
	char *end = NULL;
	long limit = l ? strtol(l, &end, 10) : 0;

	if (!h || (strcasecmp(h, "true") && strcmp(h, "1")))
		return;
	if (l && (*end || limit < 1))
		limit = 0; /* as OctoPrint: a bad limit is no limit */
	json_object_set_new(temps, "history", http_temp_history(p, (int)(limit > 100000 ? 0 : limit),
								tools, bed));
}

const char *http_tail(const struct req *r)
{
	return r->route_path + strlen(r->rt->path);
}

/* What OctoPrint has no field for: which port, simulated or not, firmware. */
static json_t *link_json(const struct node_printer *p, const struct http_view *v)
{
	return json_pack("{s:s,s:s,s:b,s:s,s:s*}", "printer", p->cfg->name, "port", p->cfg->port,
			 "simulated", node_port_simulated(p->cfg->port), "firmware", v->link_desc,
			 "error", v->conn_error[0] ? v->conn_error : NULL);
}

/* Completion in percent, or null. */
static json_t *completion_json(const struct http_view *v)
{
	return v->has_job && v->size > 0 ? json_real(100.0 * (double)v->filepos / (double)v->size)
					  : json_null();
}

/* Seconds left of v's job (-1 unknown) from est, the estimate of its file at
 * its position: the file's M73 R marks (what the slicer planned for the
 * part still to print), else its estimate scaled by the bytes left.
 * *origin is OctoPrint's printTimeLeftOrigin (NULL when unknown). */
static double time_left(const struct http_view *v, const struct node_gcode_estimate *est,
			const char **origin)
{
	double done = v->has_job && v->size > 0 ? (double)v->filepos / (double)v->size : 0;

	*origin = NULL;
	if (v->has_job && est->left_s >= 0) {
		*origin = "estimate";
		return est->left_s;
	}
	if (v->has_job && est->time_s >= 0) {
		*origin = "analysis";
		return est->time_s * (1 - done);
	}
	return -1;
}

json_t *node_printer_json(struct node *n, struct node_printer *p, int queue_limit)
{
	struct http_view v;
	struct node_gcode_estimate est;
	const char *origin;
	double left = -1;
	json_t *o;

	http_take_view(n, p, &v);
	if (v.has_job) {
		node_gcode_estimate(p, v.job.gcode, v.filepos, &est);
		left = time_left(&v, &est, &origin);
	}
	/* temperature as /api/printer has it (MQTT and the farm view show it) */
	o = json_pack("{s:s,s:s,s:s,s:o,s:o,s:{s:o,s:I,s:I,s:o},s:o,s:b}", "name",
		      p->cfg->name, "prefix", p->cfg->prefix, "state", http_state_text(&v), "link",
		      link_json(p, &v), "temperature", http_temps_json(p, &v, true, true), "progress", "completion", completion_json(&v), "filepos",
		      (json_int_t)(v.has_job ? v.filepos : 0), "size",
		      (json_int_t)(v.has_job ? v.size : 0), "printTimeLeft",
		      left >= 0 ? json_integer((json_int_t)left) : json_null(), "job",
		      v.has_job ? node_job_json(&v.job) : json_null(), "bedClear", v.bed_clear);
	json_object_set_new(o, "waiting", node_queue_waiting(n->q, p->cfg->name));
	if (o && queue_limit > 0)
		json_object_set_new(o, "queue", node_queue_list(n->q, p->cfg->name, queue_limit));
	return o;
}

/* ---- GET handlers -------------------------------------------------------- */

enum MHD_Result http_get_version(struct node *n, struct MHD_Connection *c, struct req *r)
{
	json_t *o = json_pack("{s:s,s:s,s:s,s:{s:s}}", "api", "0.1", "server",
			      HTTP_OCTOPRINT_VERSION, "text",
			      "OctoPrint " HTTP_OCTOPRINT_VERSION " (Stratum farm node)", "stratum",
			      "node", n->cfg.name);

	(void)r;
	return http_send_json(c, MHD_HTTP_OK, o, NULL);
}

json_t *http_flags_json(const struct http_view *v)
{
	/* ready: a print may start; not while a job holds the printer (paused,
	 * interrupted, slicing) nor while the bed waits to be confirmed clear */
	return json_pack("{s:b,s:b,s:b,s:b,s:b,s:b,s:b,s:b,s:b}", "operational", v->connected,
			 "printing", v->printing && !v->paused, "paused",
			 v->paused || (v->has_job && !v->printing && v->job.state == NODE_JOB_PAUSED),
			 "pausing", v->pausing, "cancelling", 0, "sdReady", 0, "error",
			 !v->connected && v->conn_error[0], "ready",
			 v->connected && !v->printing && !v->has_job && v->bed_clear, "closedOrError",
			 !v->connected);
}

enum MHD_Result http_get_printer(struct node *n, struct MHD_Connection *c, struct req *r)
{
	struct http_view v;
	const char *ex;
	json_t *o;

	http_take_view(n, r->p, &v);
	if (!v.connected)
		return http_send_error(c, MHD_HTTP_CONFLICT, "Printer is not operational");
	o = json_pack("{s:o,s:{s:b},s:{s:s,s:o}}", "temperature",
		      http_temps_json(r->p, &v, true, true), "sd", "ready", 0, "state", "text",
		      http_state_text(&v), "flags", http_flags_json(&v));
	http_add_history(c, r->p, json_object_get(o, "temperature"), true, true);
	json_object_set_new(o, "stratum", link_json(r->p, &v));
	/* ?exclude=temperature,sd,state leaves those out, as OctoPrint */
	if ((ex = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "exclude"))) {
		static const char *const parts[] = {"temperature", "sd", "state"};

		for (size_t i = 0; i < sizeof(parts) / sizeof(parts[0]); i++) {
			size_t len = strlen(parts[i]);

			for (const char *at = ex; (at = strstr(at, parts[i])); at += len)
				if ((at == ex || at[-1] == ',') && (!at[len] || at[len] == ','))
					json_object_del(o, parts[i]);
		}
	}
	return http_send_json(c, MHD_HTTP_OK, o, NULL);
}

/* A job name or null. */
static json_t *str_or_null(const char *s)
{
	return s && *s ? json_string(s) : json_null();
}

json_t *http_job_json(struct node *n, struct node_printer *p, struct http_view *out)
{
	struct http_view v;
	json_t *file, *progress, *o, *filament = json_null();
	const char *name = NULL;
	char sel[2 * NODE_PATH_MAX];
	struct node_gcode_estimate est;
	const char *origin;
	double left;
	struct stat st;

	http_take_view(n, p, &v);
	snprintf(sel, sizeof(sel), "%s/%s", p->files_dir, v.selected);
	node_gcode_estimate(p, v.has_job ? v.job.gcode : v.selected[0] ? sel : NULL,
			    v.has_job ? v.filepos : 0, &est);
	if (est.filament_mm >= 0 || est.filament_cm3 >= 0)
		filament = json_pack("{s:{s:o,s:o}}", "tool0", "length", est.filament_mm >= 0
				     ? json_real(est.filament_mm) : json_null(), "volume",
				     est.filament_cm3 >= 0 ? json_real(est.filament_cm3) : json_null());
	left = time_left(&v, &est, &origin);
	name = v.has_job ? v.job.name : v.selected;
	file = json_object();
	json_object_set_new(file, "name", str_or_null(name));
	json_object_set_new(file, "path", str_or_null(name));
	json_object_set_new(file, "display", str_or_null(name));
	json_object_set_new(file, "origin", name && *name ? json_string("local") : json_null());
	if (v.has_job && !stat(v.job.file, &st)) {
		json_object_set_new(file, "size", json_integer(st.st_size));
		json_object_set_new(file, "date", json_integer(st.st_mtime));
	} else {
		json_object_set_new(file, "size", json_null());
		json_object_set_new(file, "date", json_null());
	}
	progress = json_object();
	json_object_set_new(progress, "completion", completion_json(&v));
	json_object_set_new(progress, "filepos", v.has_job && v.size > 0 ? json_integer(v.filepos)
									 : json_null());
	json_object_set_new(progress, "printTime",
			    v.has_job && v.job.started ? json_integer(time(NULL) - v.job.started)
						       : json_null());
	/* Stratum's additions: the layer (1-based) and Z the printer confirmed */
	json_object_set_new(progress, "layer", v.layer >= 0 ? json_integer(v.layer + 1)
							    : json_null());
	json_object_set_new(progress, "z", isfinite(v.z) ? json_real(v.z) : json_null());
	json_object_set_new(progress, "printTimeLeft", left >= 0 ? json_integer((json_int_t)left)
								    : json_null());
	json_object_set_new(progress, "printTimeLeftOrigin", str_or_null(origin));
	o = json_pack("{s:{s:o,s:o,s:n,s:o,s:n},s:o,s:s}", "job", "file", file,
		      "estimatedPrintTime", est.time_s >= 0 ? json_integer((json_int_t)est.time_s)
							    : json_null(),
		      "lastPrintTime", "filament", filament, "user", "progress", progress, "state",
		      http_state_text(&v));
	json_object_set_new(o, "stratum", v.has_job ? node_job_json(&v.job) : json_null());
	if (out)
		*out = v;
	return o;
}

enum MHD_Result http_get_job(struct node *n, struct MHD_Connection *c, struct req *r)
{
	return http_send_json(c, MHD_HTTP_OK, http_job_json(n, r->p, NULL), NULL);
}

enum MHD_Result http_get_connection(struct node *n, struct MHD_Connection *c, struct req *r)
{
	struct node_printer *p = r->p;
	struct http_view v;
	json_t *o;

	http_take_view(n, p, &v);
	o = json_pack("{s:{s:s,s:s,s:I,s:s},s:{s:[s],s:[I],s:[{s:s,s:s}],s:s,s:I,s:s,s:b}}",
		      "current", "state", http_state_text(&v), "port", p->cfg->port, "baudrate",
		      (json_int_t)p->prof->baudrate, "printerProfile", p->cfg->name, "options",
		      "ports", p->cfg->port, "baudrates", (json_int_t)p->prof->baudrate,
		      "printerProfiles", "id", p->cfg->name, "name", p->prof->name,
		      "portPreference", p->cfg->port, "baudratePreference",
		      (json_int_t)p->prof->baudrate, "printerProfilePreference", p->cfg->name,
		      "autoconnect", 1);
	json_object_set_new(o, "stratum", link_json(p, &v));
	return http_send_json(c, MHD_HTTP_OK, o, NULL);
}

enum MHD_Result http_get_settings(struct node *n, struct MHD_Connection *c, struct req *r)
{
	struct node_printer *p = r->p;
	json_t *o = json_pack("{s:{s:b},s:{s:s},s:{s:b,s:b},s:{s:s,s:I,s:b},s:{s:b,s:s},"
			      "s:{s:s,s:s,s:I}}",
			      "api", "allowCrossOrigin", 0, "appearance", "name", p->cfg->name,
			      "feature", "sdSupport", 0, "gcodeViewer", 0, "serial", "port",
			      p->cfg->port, "baudrate", (json_int_t)p->prof->baudrate, "autoconnect",
			      1, "webcam", "webcamEnabled", 0, "streamUrl", "", "stratum", "node",
			      n->cfg.name, "printer", p->cfg->name, "maxUploadBytes",
			      (json_int_t)n->cfg.max_upload);
	return http_send_json(c, MHD_HTTP_OK, o, NULL);
}

/* POST /api/settings: the node's settings are its config file, read at
 * start; OctoPrint's answer to a user who may not change settings. */
enum MHD_Result http_post_settings(struct node *n, struct MHD_Connection *c, struct req *r)
{
	char msg[NODE_PATH_MAX + 120];

	(void)r;
	snprintf(msg, sizeof(msg), "the node's settings are its config file %s: change it there "
		 "and restart the node", n->cfg.path);
	return http_send_error(c, MHD_HTTP_FORBIDDEN, msg);
}

/* The URL of route path on this request's host and printer prefix. */
void http_url_for(struct MHD_Connection *c, const struct req *r, const char *path,
		  const char *name, char *out, size_t cap)
{
	const char *host = MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_HOST);
	size_t n;

	n = (size_t)snprintf(out, cap, "http://%s%s%s", host ? host : "localhost", r->base, path);
	/* Percent-encode the name: it may hold blanks and UTF-8; its folders
	 * stay apart by '/', as OctoPrint's links have them. */
	for (const unsigned char *s = (const unsigned char *)name; s && *s && n + 4 < cap; s++) {
		if (isalnum(*s) || strchr("-._~/", *s))
			out[n++] = (char)*s;
		else
			n += (size_t)snprintf(out + n, cap - n, "%%%02X", *s);
	}
	out[n < cap ? n : cap - 1] = '\0';
}

/* The printer's profile as OctoPrint's printer profile entry. */
static json_t *profile_json(struct node *n, struct MHD_Connection *c, struct req *r)
{
	const struct profile *pf = r->p->prof;
	char url[2048];
	json_t *offsets = json_array();

	http_url_for(c, r, "/api/printerprofiles/", r->p->cfg->name, url, sizeof(url));
	for (int i = 0; i < pf->extruder_count; i++)
		json_array_append_new(offsets, json_pack("[f,f]", pf->extruder_offset[i].x,
							 pf->extruder_offset[i].y));
	return json_pack("{s:s,s:s,s:s,s:s,s:b,s:b,s:s,"
		      "s:{s:s,s:s,s:f,s:f,s:f,s:b},s:b,s:b,"
		      "s:{s:{s:f,s:b},s:{s:f,s:b},s:{s:f,s:b},s:{s:f,s:b}},"
		      "s:{s:i,s:o,s:f,s:b}}",
		      "id", r->p->cfg->name, "name", pf->name, "model",
		      pf->printer_model, "color", "default", "current", 1, "default",
		      r->p == &n->printers[0], "resource", url, "volume", "formFactor",
		      "rectangular", "origin", "lowerleft", "width", pf->bed_max_x - pf->bed_min_x,
		      "depth", pf->bed_max_y - pf->bed_min_y, "height", pf->max_print_height,
		      "custom_box", 0, "heatedBed", pf->bed_temperature > 0, "heatedChamber", 0,
		      "axes", "x", "speed", pf->machine_max_feedrate[PROFILE_AXIS_X] * 60,
		      "inverted", 0, "y", "speed", pf->machine_max_feedrate[PROFILE_AXIS_Y] * 60,
		      "inverted", 0, "z", "speed", pf->machine_max_feedrate[PROFILE_AXIS_Z] * 60,
		      "inverted", 0, "e", "speed", pf->machine_max_feedrate[PROFILE_AXIS_E] * 60,
		      "inverted", 0, "extruder", "count", pf->extruder_count, "offsets", offsets,
		      "nozzleDiameter", pf->nozzle_diameter[0], "sharedNozzle", 0);
}

enum MHD_Result http_get_profiles(struct node *n, struct MHD_Connection *c, struct req *r)
{
	return http_send_json(c, MHD_HTTP_OK, json_pack("{s:{s:o}}", "profiles", r->p->cfg->name,
							profile_json(n, c, r)), NULL);
}

/* GET /api/printerprofiles/ID: the printer's own profile is its only one. */
enum MHD_Result http_get_profile(struct node *n, struct MHD_Connection *c, struct req *r)
{
	if (strcmp(http_tail(r), r->p->cfg->name))
		return http_send_error(c, MHD_HTTP_NOT_FOUND, "Profile not found");
	return http_send_json(c, MHD_HTTP_OK, profile_json(n, c, r), NULL);
}

/* The file entry OctoPrint gives for an uploaded file. */
json_t *http_file_json(struct MHD_Connection *c, const struct req *r, const char *rel,
		       const struct stat *st)
{
	char res[2048], dl[2048];
	const char *slash = strrchr(rel, '/');
	char kind = node_file_kind(rel);

	http_url_for(c, r, "/api/files/local/", rel, res, sizeof(res));
	http_url_for(c, r, "/downloads/files/local/", rel, dl, sizeof(dl));
	json_t *o = json_pack("{s:s,s:s,s:s,s:s,s:{s:s,s:s}}", "name", slash ? slash + 1 : rel,
			      "path", rel, "origin", "local", "type",
			      kind == 'm' ? "model" : "machinecode", "refs", "resource", res,
			      "download", dl);
	json_object_set_new(o, "typePath", kind == 'm' ? json_pack("[s,s]", "model", "stl")
				: json_pack("[s,s]", "machinecode", kind == 'x' ? "x3g" : "gcode"));
	if (st) {
		json_object_set_new(o, "size", json_integer(st->st_size));
		json_object_set_new(o, "date", json_integer(st->st_mtime));
	}
	return o;
}

/* Check a relative path of uploaded files ("a/b.gcode"); 0 or a message. */
int http_check_rel(const char *rel, size_t len, struct st_error *err)
{
	size_t start = 0;

	if (len >= HTTP_FIELD_MAX)
		return st_error_set(err, ST_ERR_PARSE, "the path is longer than %d bytes",
				    HTTP_FIELD_MAX - 1);
	for (size_t i = 0; i <= len; i++) {
		if (i < len && rel[i] != '/')
			continue;
		if (i > start && node_check_file_name(rel + start, i - start, err))
			return ST_ERR_PARSE;
		start = i + 1;
	}
	return 0;
}

/* ---- POST handlers with JSON bodies ------------------------------------------ */

/* The JSON object of the body, or NULL with the error answer sent in *ret. */
/* Every printer of the node at once, for the status page and farm tools. */
enum MHD_Result http_get_node(struct node *n, struct MHD_Connection *c, struct req *r)
{
	json_t *arr = json_array();

	(void)r;
	for (size_t i = 0; i < n->nprinters; i++)
		json_array_append_new(arr, node_printer_json(n, &n->printers[i], 10));
	/* maxUpload: the page refuses a larger file before sending it */
	return http_send_json(c, MHD_HTTP_OK, json_pack("{s:s,s:I,s:o}", "node", n->cfg.name,
						        "maxUpload", (json_int_t)n->cfg.max_upload,
						        "printers", arr), NULL);
}

json_t *http_body_json(struct MHD_Connection *c, struct req *r, enum MHD_Result *ret)
{
	json_error_t je;
	json_t *o = r->body ? json_loadb(r->body, r->len, 0, &je) : NULL;
	char msg[300];

	if (!o || !json_is_object(o)) {
		snprintf(msg, sizeof(msg), "the body is not a JSON object%s%s",
			 r->body ? ": " : "", r->body ? je.text : "");
		json_decref(o);
		*ret = http_send_error(c, MHD_HTTP_BAD_REQUEST, msg);
		return NULL;
	}
	return o;
}

enum MHD_Result http_start_selected(struct node *n, struct MHD_Connection *c,
				    struct node_printer *p)
{
	char rel[NODE_PATH_MAX], full[NODE_PATH_MAX + NODE_PATH_MAX], msg[400];
	int64_t id;
	struct node_job j;
	struct st_error err = {0};

	if (!p->connected)
		return http_send_error(c, MHD_HTTP_CONFLICT, "Printer is not operational");
	/* OctoPrint's printer has one job: start once, not one copy per click */
	if (node_queue_active(n->q, p->cfg->name, &j, NULL) == 1 ||
	    node_queue_next(n->q, p->cfg->name, &j, NULL) == 1) {
		snprintf(msg, sizeof(msg), "Printer already has an active print job (job %lld, "
			 "%.200s: %s)%s", (long long)j.id, j.name, node_job_state_name(j.state),
			 j.state == NODE_JOB_QUEUED ? "; more jobs are queued by an upload with "
			 "print=true" : ", did you mean 'restart'?");
		return http_send_error(c, MHD_HTTP_CONFLICT, msg);
	}
	node_queue_selected(n->q, p->cfg->name, rel, sizeof(rel));
	if (!rel[0])
		return http_send_error(c, MHD_HTTP_CONFLICT, "no file is selected; upload one with "
							     "select=true first");
	snprintf(full, sizeof(full), "%s/%s", p->files_dir, rel);
	if (access(full, R_OK))
		return http_send_error(c, MHD_HTTP_CONFLICT, "the selected file is gone");
	if (node_queue_add(n->q, p->cfg->name, rel, full, node_file_kind(rel), NULL, &id, &err))
		return http_send_error(c, MHD_HTTP_INTERNAL_SERVER_ERROR, err.msg);
	node_log("info", p->cfg->name, id, "queued %s", rel);
	pthread_cond_signal(&p->cv);
	return http_no_content(c);
}

/* The HTTP status for a control error class. */
static unsigned control_status(int rc)
{
	return rc == ST_ERR_RANGE ? MHD_HTTP_CONFLICT
	       : rc == ST_ERR_ARG ? MHD_HTTP_BAD_REQUEST
				  : MHD_HTTP_INTERNAL_SERVER_ERROR;
}

enum MHD_Result http_post_job(struct node *n, struct MHD_Connection *c, struct req *r)
{
	struct node_printer *p = r->p;
	enum MHD_Result ret;
	json_t *o = http_body_json(c, r, &ret);
	const char *cmd, *action;
	struct st_error err = {0};
	int rc;

	if (!o)
		return ret;
	cmd = json_string_value(json_object_get(o, "command"));
	action = json_string_value(json_object_get(o, "action"));
	if (!cmd) {
		ret = http_send_error(c, MHD_HTTP_BAD_REQUEST, "command is missing (start, restart, "
							       "cancel, pause)");
	} else if (!strcmp(cmd, "start")) {
		pthread_mutex_lock(&p->mu);
		ret = http_start_selected(n, c, p);
		pthread_mutex_unlock(&p->mu);
	} else if (!strcmp(cmd, "cancel") || !strcmp(cmd, "pause")) {
		rc = node_control_job(n, p, cmd, action, &err);
		ret = rc ? http_send_error(c, control_status(rc), err.msg) : http_no_content(c);
	} else if (!strcmp(cmd, "restart")) {
		int64_t id;

		rc = node_control_restart(n, p, &id, &err);
		ret = rc ? http_send_error(c, control_status(rc), err.msg) : http_no_content(c);
	} else {
		ret = http_send_error(c, MHD_HTTP_BAD_REQUEST, "command is start, restart, cancel "
							       "or pause");
	}
	json_decref(o);
	return ret;
}

enum MHD_Result http_queue_lines(struct MHD_Connection *c, struct node_printer *p,
				 char lines[][NODE_CMD_MAX], size_t count, bool in_print)
{
	enum MHD_Result ret;
	bool paused;

	pthread_mutex_lock(&p->mu);
	pthread_mutex_lock(&p->ctl.mu);
	paused = p->ctl.pause;
	pthread_mutex_unlock(&p->ctl.mu);
	if (!p->connected)
		ret = http_send_error(c, MHD_HTTP_CONFLICT, "Printer is not operational");
	else if (p->job_printing && !paused && !in_print)
		ret = http_send_error(c, MHD_HTTP_CONFLICT, "the printer is printing; this command is "
						            "taken while paused or between jobs");
	else if (p->job_printing && (p->job_x3g || !node_print_takes_commands(p->cfg, p->prof)))
		ret = http_send_error(c, MHD_HTTP_CONFLICT, p->job_x3g ?
				      "the printer is printing an X3G file, whose commands are "
				      "not G-code lines: commands are taken between jobs" :
				      "the printer is printing; its print stream takes no other "
				      "line: commands are taken between jobs");
	else if ((size_t)p->ncmds + count > NODE_CMD_QUEUE)
		ret = http_send_error(c, MHD_HTTP_CONFLICT, "the printer has too many commands waiting");
	else {
		memcpy(p->cmds[p->ncmds], lines, sizeof(lines[0]) * count);
		p->ncmds += (int)count;
		pthread_cond_signal(&p->cv);
		ret = http_no_content(c);
	}
	pthread_mutex_unlock(&p->mu);
	return ret;
}

enum MHD_Result http_post_command(struct node *n, struct MHD_Connection *c, struct req *r)
{
	struct node_printer *p = r->p;
	enum MHD_Result ret;
	json_t *o = http_body_json(c, r, &ret), *list, *one;
	char lines[NODE_CMD_QUEUE][NODE_CMD_MAX];
	size_t count = 0, i;

	(void)n;
	if (!o)
		return ret;
	list = json_object_get(o, "commands");
	one = json_object_get(o, "command");
	if (!list && json_is_string(one)) {
		list = json_pack("[O]", one);
	} else if (json_is_array(list)) {
		json_incref(list);
	} else {
		json_decref(o);
		return http_send_error(c, MHD_HTTP_BAD_REQUEST, "give command: \"G28\" or commands: "
							        "[\"G28\", ...]");
	}
	/* Check every line before any is queued. */
	ret = MHD_YES;
	json_array_foreach(list, i, one) {
		const char *s = json_string_value(one);
		struct gcode_line l;
		struct st_error err = {0};
		char msg[400];

		if (count == NODE_CMD_QUEUE) {
			ret = http_send_error(c, MHD_HTTP_BAD_REQUEST, "more than 16 commands at once");
			goto out;
		}
		if (!s || strlen(s) >= NODE_CMD_MAX || gcode_parse(s, strlen(s), 0, &l, &err)) {
			snprintf(msg, sizeof(msg), "command %zu is not a G-code line: %s", i + 1,
				 s ? err.msg : "not a string");
			ret = http_send_error(c, MHD_HTTP_BAD_REQUEST, msg);
			goto out;
		}
		snprintf(lines[count++], NODE_CMD_MAX, "%s", s);
	}
	ret = http_queue_lines(c, p, lines, count, true);
out:
	json_decref(list);
	json_decref(o);
	return ret;
}

enum MHD_Result http_post_connection(struct node *n, struct MHD_Connection *c, struct req *r)
{
	struct node_printer *p = r->p;
	enum MHD_Result ret;
	json_t *o = http_body_json(c, r, &ret);
	const char *cmd, *port;

	(void)n;
	if (!o)
		return ret;
	cmd = json_string_value(json_object_get(o, "command"));
	port = json_string_value(json_object_get(o, "port"));
	pthread_mutex_lock(&p->mu);
	if (cmd && !strcmp(cmd, "connect")) {
		if (port && strcmp(port, p->cfg->port)) {
			char msg[NODE_PATH_MAX + 100];

			snprintf(msg, sizeof(msg), "this printer's port is %s (set in the node's "
						   "config)", p->cfg->port);
			ret = http_send_error(c, MHD_HTTP_BAD_REQUEST, msg);
		} else {
			p->want_connect = true;
			pthread_cond_signal(&p->cv);
			ret = http_no_content(c);
		}
	} else if (cmd && !strcmp(cmd, "disconnect")) {
		if (p->job_printing) {
			ret = http_send_error(c, MHD_HTTP_CONFLICT, "the printer is printing; cancel the "
							            "job first");
		} else {
			p->want_disconnect = true;
			pthread_cond_signal(&p->cv);
			ret = http_no_content(c);
		}
	} else {
		ret = http_send_error(c, MHD_HTTP_BAD_REQUEST, "command is connect or disconnect");
	}
	pthread_mutex_unlock(&p->mu);
	json_decref(o);
	return ret;
}
