/*
 * http.c - the node's HTTP API on libmicrohttpd (docs/serve.md): the
 * OctoPrint subset slicers use, under each printer's prefix and, for the
 * first printer, at /api/... as well; plus /api/stratum/... for what
 * OctoPrint has no call for (the queue, the bed-clear confirmation).
 *
 * A request is decided in the first call of the handler (route, key, size)
 * but answered only once its body is read, unless the client waits for
 * "100 Continue": answering early otherwise leaves unread bytes that make
 * the kernel reset the connection before the client reads the answer.
 */
#include <arpa/inet.h>
#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <jansson.h>
#include <microhttpd.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "gcode.h"
#include "node_int.h"

#define HTTP_OCTOPRINT_VERSION "1.10.0" /* the OctoPrint API level answered */
#define HTTP_JSON_MAX 65536		/* body of a JSON command, bytes */
#define HTTP_FIELD_MAX 1024		/* a form field other than the file */
#define HTTP_MULTIPART_SLACK 65536	/* multipart headers around the file */
#define HTTP_POOL 4			/* HTTP threads */
#define HTTP_TIMEOUT_S 60		/* idle connection timeout */

struct req;
typedef enum MHD_Result (*route_fn)(struct node *n, struct MHD_Connection *c, struct req *r);

struct route {
	const char *method, *path;
	bool prefix; /* path is a prefix (a file name follows) */
	unsigned role;
	bool upload; /* body is multipart, streamed to a file */
	route_fn fn;
};

/* One request, from its first call to its completion. */
struct req {
	struct node_printer *p;
	const struct route *rt;
	char base[NODE_PREFIX_MAX]; /* the prefix the client used ("" for /api/...) */
	const char *route_path;	    /* url after base */
	int status;		    /* decided before the body: answer this */
	char msg[300];
	/* JSON body */
	char *body;
	size_t len;
	/* upload */
	struct MHD_PostProcessor *pp;
	int fd;
	char tmp[NODE_PATH_MAX];
	uint64_t bytes;
	bool has_file;
	char filename[NODE_FILE_NAME_MAX + 2];
	size_t filename_len;
	char print[16], select[16], path[HTTP_FIELD_MAX];
	size_t path_len;
};

/* ---- responses ---------------------------------------------------------- */

/* Answer with body (stolen; NULL = no body) and status. */
static enum MHD_Result send_json(struct MHD_Connection *c, unsigned status, json_t *body,
				 const char *location)
{
	char *text = body ? json_dumps(body, JSON_COMPACT) : NULL;
	struct MHD_Response *resp;
	enum MHD_Result ret;

	json_decref(body);
	resp = MHD_create_response_from_buffer(text ? strlen(text) : 0, text ? text : (void *)"",
					       text ? MHD_RESPMEM_MUST_FREE : MHD_RESPMEM_PERSISTENT);
	if (!resp) {
		free(text);
		return MHD_NO;
	}
	if (text)
		MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE, "application/json");
	MHD_add_response_header(resp, MHD_HTTP_HEADER_CACHE_CONTROL, "no-cache");
	if (location)
		MHD_add_response_header(resp, MHD_HTTP_HEADER_LOCATION, location);
	ret = MHD_queue_response(c, status, resp);
	MHD_destroy_response(resp);
	return ret;
}

/* {"error": msg} with status, as OctoPrint answers errors. */
static enum MHD_Result send_error(struct MHD_Connection *c, unsigned status, const char *msg)
{
	json_t *o = json_object();

	json_object_set_new(o, "error", json_string(msg));
	return send_json(c, status, o, NULL);
}

/* The status page (page.c); it holds no data, so it needs no key. */
static enum MHD_Result send_page(struct MHD_Connection *c)
{
	struct MHD_Response *resp = MHD_create_response_from_buffer(
		strlen(node_status_page), (void *)node_status_page, MHD_RESPMEM_PERSISTENT);
	enum MHD_Result ret;

	if (!resp)
		return MHD_NO;
	MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE, "text/html; charset=utf-8");
	MHD_add_response_header(resp, "Content-Security-Policy",
				"default-src 'self'; script-src 'unsafe-inline'; "
				"style-src 'unsafe-inline'");
	ret = MHD_queue_response(c, MHD_HTTP_OK, resp);
	MHD_destroy_response(resp);
	return ret;
}

static enum MHD_Result no_content(struct MHD_Connection *c)
{
	return send_json(c, MHD_HTTP_NO_CONTENT, NULL, NULL);
}

/* ---- printer state ------------------------------------------------------- */

/* A consistent view of a printer for one answer. */
struct view {
	bool connected, printing, paused, pausing;
	char conn_error[256];
	char link_desc[128];
	int64_t job_id;
	int64_t filepos, size;
	double tool[2], bed[2]; /* actual, target */
	bool has_job;
	struct node_job job; /* the active job (printing, paused, slicing), if has_job */
	char selected[NODE_PATH_MAX];
};

static void take_view(struct node *n, struct node_printer *p, struct view *v)
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
	v->tool[0] = p->ctl.tool_actual;
	v->tool[1] = p->ctl.tool_target;
	v->bed[0] = p->ctl.bed_actual;
	v->bed[1] = p->ctl.bed_target;
	pthread_mutex_unlock(&p->ctl.mu);
	pthread_mutex_unlock(&p->mu);
	v->has_job = node_queue_active(n->q, p->cfg->name, &v->job, NULL) == 1;
	if (v->has_job && !v->printing) {
		v->filepos = v->job.filepos;
		v->size = v->job.size;
	}
	node_queue_selected(n->q, p->cfg->name, v->selected, sizeof(v->selected));
}

/* OctoPrint's state text. */
static const char *state_text(const struct view *v)
{
	if (v->has_job && v->job.state == NODE_JOB_PAUSED && !v->printing)
		return "Paused"; /* an interrupted print waiting for an operator */
	if (!v->connected)
		return v->conn_error[0] ? "Offline after error" : "Offline";
	if (v->printing)
		return v->paused ? "Paused" : v->pausing ? "Pausing" : "Printing";
	if (v->has_job && v->job.state == NODE_JOB_SLICING)
		return "Slicing";
	return "Operational";
}

static json_t *temp_json(const double t[2])
{
	json_t *o = json_object();

	json_object_set_new(o, "actual", json_real(t[0]));
	json_object_set_new(o, "target", json_real(t[1]));
	json_object_set_new(o, "offset", json_integer(0));
	return o;
}

/* What OctoPrint has no field for: which port, simulated or not, firmware. */
static json_t *link_json(const struct node_printer *p, const struct view *v)
{
	return json_pack("{s:s,s:s,s:b,s:s,s:s*}", "printer", p->cfg->name, "port", p->cfg->port,
			 "simulated", node_port_simulated(p->cfg->port), "firmware", v->link_desc,
			 "error", v->conn_error[0] ? v->conn_error : NULL);
}

/* Completion in percent, or null. */
static json_t *completion_json(const struct view *v)
{
	return v->has_job && v->size > 0 ? json_real(100.0 * (double)v->filepos / (double)v->size)
					  : json_null();
}

json_t *node_printer_json(struct node *n, struct node_printer *p, int queue_limit)
{
	struct view v;
	bool clear = false;
	json_t *o;

	take_view(n, p, &v);
	node_queue_bed_clear(n->q, p->cfg->name, &clear);
	o = json_pack("{s:s,s:s,s:s,s:o,s:{s:o,s:o},s:{s:o,s:I,s:I},s:o,s:b}", "name",
		      p->cfg->name, "prefix", p->cfg->prefix, "state", state_text(&v), "link",
		      link_json(p, &v), "temperature", "tool0", temp_json(v.tool), "bed",
		      temp_json(v.bed), "progress", "completion", completion_json(&v), "filepos",
		      (json_int_t)(v.has_job ? v.filepos : 0), "size",
		      (json_int_t)(v.has_job ? v.size : 0), "job",
		      v.has_job ? node_job_json(&v.job) : json_null(), "bedClear", clear);
	if (o && queue_limit > 0)
		json_object_set_new(o, "queue", node_queue_list(n->q, p->cfg->name, queue_limit));
	return o;
}

/* ---- GET handlers -------------------------------------------------------- */

static enum MHD_Result get_version(struct node *n, struct MHD_Connection *c, struct req *r)
{
	json_t *o = json_object();

	(void)r;
	json_object_set_new(o, "api", json_string("0.1"));
	json_object_set_new(o, "server", json_string(HTTP_OCTOPRINT_VERSION));
	json_object_set_new(o, "text", json_string("OctoPrint " HTTP_OCTOPRINT_VERSION
						   " (Stratum farm node)"));
	json_object_set_new(o, "stratum", json_pack("{s:s}", "node", n->cfg.name));
	return send_json(c, MHD_HTTP_OK, o, NULL);
}

static enum MHD_Result get_printer(struct node *n, struct MHD_Connection *c, struct req *r)
{
	struct view v;
	json_t *o, *flags;

	take_view(n, r->p, &v);
	if (!v.connected)
		return send_error(c, MHD_HTTP_CONFLICT, "Printer is not operational");
	flags = json_object();
	json_object_set_new(flags, "operational", json_true());
	json_object_set_new(flags, "printing", json_boolean(v.printing && !v.paused));
	json_object_set_new(flags, "paused", json_boolean(v.paused || (v.has_job && !v.printing &&
								     v.job.state == NODE_JOB_PAUSED)));
	json_object_set_new(flags, "pausing", json_boolean(v.pausing));
	json_object_set_new(flags, "cancelling", json_false());
	json_object_set_new(flags, "sdReady", json_false());
	json_object_set_new(flags, "error", json_false());
	json_object_set_new(flags, "ready", json_boolean(!v.printing));
	json_object_set_new(flags, "closedOrError", json_false());
	o = json_pack("{s:{s:o,s:o},s:{s:b},s:{s:s,s:o}}", "temperature", "tool0", temp_json(v.tool),
		      "bed", temp_json(v.bed), "sd", "ready", 0, "state", "text", state_text(&v),
		      "flags", flags);
	json_object_set_new(o, "stratum", link_json(r->p, &v));
	return send_json(c, MHD_HTTP_OK, o, NULL);
}

/* A job name or null. */
static json_t *str_or_null(const char *s)
{
	return s && *s ? json_string(s) : json_null();
}

static enum MHD_Result get_job(struct node *n, struct MHD_Connection *c, struct req *r)
{
	struct view v;
	json_t *file, *progress, *o;
	const char *name = NULL;
	struct stat st;

	take_view(n, r->p, &v);
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
	json_object_set_new(progress, "printTimeLeft", json_null());
	json_object_set_new(progress, "printTimeLeftOrigin", json_null());
	o = json_pack("{s:{s:o,s:n,s:n,s:n},s:o,s:s}", "job", "file", file, "estimatedPrintTime",
		      "filament", "user", "progress", progress, "state", state_text(&v));
	json_object_set_new(o, "stratum", v.has_job ? node_job_json(&v.job) : json_null());
	return send_json(c, MHD_HTTP_OK, o, NULL);
}

static enum MHD_Result get_connection(struct node *n, struct MHD_Connection *c, struct req *r)
{
	struct node_printer *p = r->p;
	struct view v;
	json_t *o;

	take_view(n, p, &v);
	o = json_pack("{s:{s:s,s:s,s:I,s:s},s:{s:[s],s:[I],s:[{s:s,s:s}],s:s,s:I,s:s,s:b}}",
		      "current", "state", state_text(&v), "port", p->cfg->port, "baudrate",
		      (json_int_t)p->prof->baudrate, "printerProfile", p->cfg->name, "options",
		      "ports", p->cfg->port, "baudrates", (json_int_t)p->prof->baudrate,
		      "printerProfiles", "id", p->cfg->name, "name", p->prof->name,
		      "portPreference", p->cfg->port, "baudratePreference",
		      (json_int_t)p->prof->baudrate, "printerProfilePreference", p->cfg->name,
		      "autoconnect", 1);
	json_object_set_new(o, "stratum", link_json(p, &v));
	return send_json(c, MHD_HTTP_OK, o, NULL);
}

static enum MHD_Result get_settings(struct node *n, struct MHD_Connection *c, struct req *r)
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
	return send_json(c, MHD_HTTP_OK, o, NULL);
}

/* The URL of route path on this request's host and printer prefix. */
static void url_for(struct MHD_Connection *c, const struct req *r, const char *path,
		    const char *name, char *out, size_t cap)
{
	const char *host = MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_HOST);
	size_t n;

	n = (size_t)snprintf(out, cap, "http://%s%s%s", host ? host : "localhost", r->base, path);
	/* Percent-encode the name: it may hold blanks and UTF-8. */
	for (const unsigned char *s = (const unsigned char *)name; s && *s && n + 4 < cap; s++) {
		if (isalnum(*s) || strchr("-._~", *s))
			out[n++] = (char)*s;
		else
			n += (size_t)snprintf(out + n, cap - n, "%%%02X", *s);
	}
	out[n < cap ? n : cap - 1] = '\0';
}

static enum MHD_Result get_profiles(struct node *n, struct MHD_Connection *c, struct req *r)
{
	const struct profile *pf = r->p->prof;
	char url[2048];
	json_t *o, *offsets = json_array();

	(void)n;
	url_for(c, r, "/api/printerprofiles/", r->p->cfg->name, url, sizeof(url));
	for (int i = 0; i < pf->extruder_count; i++)
		json_array_append_new(offsets, json_pack("[f,f]", pf->extruder_offset[i].x,
							 pf->extruder_offset[i].y));
	o = json_pack("{s:{s:{s:s,s:s,s:s,s:s,s:b,s:b,s:s,"
		      "s:{s:s,s:s,s:f,s:f,s:f,s:b},s:b,s:b,"
		      "s:{s:{s:f,s:b},s:{s:f,s:b},s:{s:f,s:b},s:{s:f,s:b}},"
		      "s:{s:i,s:o,s:f,s:b}}}}",
		      "profiles", r->p->cfg->name, "id", r->p->cfg->name, "name", pf->name, "model",
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
	return send_json(c, MHD_HTTP_OK, o, NULL);
}

/* The file entry OctoPrint gives for an uploaded file. */
static json_t *file_json(struct MHD_Connection *c, const struct req *r, const char *rel,
			 const struct stat *st)
{
	char res[2048], dl[2048];
	const char *slash = strrchr(rel, '/');
	char kind = node_file_kind(rel);

	url_for(c, r, "/api/files/local/", rel, res, sizeof(res));
	url_for(c, r, "/downloads/files/local/", rel, dl, sizeof(dl));
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
static int check_rel(const char *rel, size_t len, struct st_error *err)
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

static enum MHD_Result get_file(struct node *n, struct MHD_Connection *c, struct req *r)
{
	const char *rel = r->route_path + strlen(r->rt->path);
	char full[NODE_PATH_MAX];
	struct st_error err;
	struct stat st;

	(void)n;
	if (check_rel(rel, strlen(rel), &err) || rel[0] == '/' || !rel[0])
		return send_error(c, MHD_HTTP_NOT_FOUND, "File not found");
	if (snprintf(full, sizeof(full), "%s/%s", r->p->files_dir, rel) >= (int)sizeof(full) ||
	    stat(full, &st) || !S_ISREG(st.st_mode))
		return send_error(c, MHD_HTTP_NOT_FOUND, "File not found");
	return send_json(c, MHD_HTTP_OK, file_json(c, r, rel, &st), NULL);
}

static enum MHD_Result get_queue(struct node *n, struct MHD_Connection *c, struct req *r)
{
	bool clear = false;
	json_t *o;

	node_queue_bed_clear(n->q, r->p->cfg->name, &clear);
	o = json_pack("{s:s,s:b,s:o}", "printer", r->p->cfg->name, "bedClear", clear, "jobs",
		      node_queue_list(n->q, r->p->cfg->name, 200));
	return send_json(c, MHD_HTTP_OK, o, NULL);
}

/* ---- POST handlers with JSON bodies ------------------------------------------ */

/* The JSON object of the body, or NULL with the error answer sent in *ret. */
/* Every printer of the node at once, for the status page and farm tools. */
static enum MHD_Result get_node(struct node *n, struct MHD_Connection *c, struct req *r)
{
	json_t *arr = json_array();

	(void)r;
	for (size_t i = 0; i < n->nprinters; i++)
		json_array_append_new(arr, node_printer_json(n, &n->printers[i], 10));
	return send_json(c, MHD_HTTP_OK, json_pack("{s:s,s:o}", "node", n->cfg.name, "printers",
						   arr), NULL);
}

static json_t *body_json(struct MHD_Connection *c, struct req *r, enum MHD_Result *ret)
{
	json_error_t je;
	json_t *o = r->body ? json_loadb(r->body, r->len, 0, &je) : NULL;
	char msg[300];

	if (!o || !json_is_object(o)) {
		snprintf(msg, sizeof(msg), "the body is not a JSON object%s%s",
			 r->body ? ": " : "", r->body ? je.text : "");
		json_decref(o);
		*ret = send_error(c, MHD_HTTP_BAD_REQUEST, msg);
		return NULL;
	}
	return o;
}

/* Queue the selected file (command "start"); p->mu held. */
static enum MHD_Result job_start(struct node *n, struct MHD_Connection *c, struct node_printer *p)
{
	char rel[NODE_PATH_MAX], full[NODE_PATH_MAX + NODE_PATH_MAX];
	int64_t id;
	struct st_error err = {0};

	node_queue_selected(n->q, p->cfg->name, rel, sizeof(rel));
	if (!rel[0])
		return send_error(c, MHD_HTTP_CONFLICT, "no file is selected; upload one with "
							"select=true first");
	snprintf(full, sizeof(full), "%s/%s", p->files_dir, rel);
	if (access(full, R_OK))
		return send_error(c, MHD_HTTP_CONFLICT, "the selected file is gone");
	if (node_queue_add(n->q, p->cfg->name, rel, full, node_file_kind(rel), &id, &err))
		return send_error(c, MHD_HTTP_INTERNAL_SERVER_ERROR, err.msg);
	node_log("info", p->cfg->name, id, "queued %s", rel);
	pthread_cond_signal(&p->cv);
	return no_content(c);
}

/* The HTTP status for a control error class. */
static unsigned control_status(int rc)
{
	return rc == ST_ERR_RANGE ? MHD_HTTP_CONFLICT
	       : rc == ST_ERR_ARG ? MHD_HTTP_BAD_REQUEST
				  : MHD_HTTP_INTERNAL_SERVER_ERROR;
}

static enum MHD_Result post_job(struct node *n, struct MHD_Connection *c, struct req *r)
{
	struct node_printer *p = r->p;
	enum MHD_Result ret;
	json_t *o = body_json(c, r, &ret);
	const char *cmd, *action;
	struct st_error err = {0};
	int rc;

	if (!o)
		return ret;
	cmd = json_string_value(json_object_get(o, "command"));
	action = json_string_value(json_object_get(o, "action"));
	if (!cmd) {
		ret = send_error(c, MHD_HTTP_BAD_REQUEST, "command is missing (start, cancel, "
							  "pause)");
	} else if (!strcmp(cmd, "start")) {
		pthread_mutex_lock(&p->mu);
		ret = job_start(n, c, p);
		pthread_mutex_unlock(&p->mu);
	} else if (!strcmp(cmd, "cancel") || !strcmp(cmd, "pause")) {
		rc = node_control_job(n, p, cmd, action, &err);
		ret = rc ? send_error(c, control_status(rc), err.msg) : no_content(c);
	} else {
		ret = send_error(c, MHD_HTTP_BAD_REQUEST, "command is start, cancel or pause");
	}
	json_decref(o);
	return ret;
}

static enum MHD_Result post_command(struct node *n, struct MHD_Connection *c, struct req *r)
{
	struct node_printer *p = r->p;
	enum MHD_Result ret;
	json_t *o = body_json(c, r, &ret), *list, *one;
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
		return send_error(c, MHD_HTTP_BAD_REQUEST, "give command: \"G28\" or commands: "
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
			ret = send_error(c, MHD_HTTP_BAD_REQUEST, "more than 16 commands at once");
			goto out;
		}
		if (!s || strlen(s) >= NODE_CMD_MAX || gcode_parse(s, strlen(s), 0, &l, &err)) {
			snprintf(msg, sizeof(msg), "command %zu is not a G-code line: %s", i + 1,
				 s ? err.msg : "not a string");
			ret = send_error(c, MHD_HTTP_BAD_REQUEST, msg);
			goto out;
		}
		snprintf(lines[count++], NODE_CMD_MAX, "%s", s);
	}
	pthread_mutex_lock(&p->mu);
	if (!p->connected)
		ret = send_error(c, MHD_HTTP_CONFLICT, "Printer is not operational");
	else if (p->job_printing)
		ret = send_error(c, MHD_HTTP_CONFLICT, "the printer is printing; commands are taken "
						       "between jobs");
	else if ((size_t)p->ncmds + count > NODE_CMD_QUEUE)
		ret = send_error(c, MHD_HTTP_CONFLICT, "the printer has too many commands waiting");
	else {
		memcpy(p->cmds[p->ncmds], lines, sizeof(lines[0]) * count);
		p->ncmds += (int)count;
		pthread_cond_signal(&p->cv);
		ret = no_content(c);
	}
	pthread_mutex_unlock(&p->mu);
out:
	json_decref(list);
	json_decref(o);
	return ret;
}

static enum MHD_Result post_connection(struct node *n, struct MHD_Connection *c, struct req *r)
{
	struct node_printer *p = r->p;
	enum MHD_Result ret;
	json_t *o = body_json(c, r, &ret);
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
			ret = send_error(c, MHD_HTTP_BAD_REQUEST, msg);
		} else {
			p->want_connect = true;
			pthread_cond_signal(&p->cv);
			ret = no_content(c);
		}
	} else if (cmd && !strcmp(cmd, "disconnect")) {
		if (p->job_printing) {
			ret = send_error(c, MHD_HTTP_CONFLICT, "the printer is printing; cancel the "
							       "job first");
		} else {
			p->want_disconnect = true;
			pthread_cond_signal(&p->cv);
			ret = no_content(c);
		}
	} else {
		ret = send_error(c, MHD_HTTP_BAD_REQUEST, "command is connect or disconnect");
	}
	pthread_mutex_unlock(&p->mu);
	json_decref(o);
	return ret;
}

static enum MHD_Result post_bed_clear(struct node *n, struct MHD_Connection *c, struct req *r)
{
	struct node_printer *p = r->p;
	struct node_job j;
	struct st_error err = {0};
	enum MHD_Result ret;

	pthread_mutex_lock(&p->mu);
	if (p->job_id || node_queue_active(n->q, p->cfg->name, &j, NULL) == 1) {
		ret = send_error(c, MHD_HTTP_CONFLICT, "a job is on the printer (printing, paused "
						       "or interrupted); finish or cancel it first");
	} else if (node_queue_set_bed_clear(n->q, p->cfg->name, true, &err)) {
		ret = send_error(c, MHD_HTTP_INTERNAL_SERVER_ERROR, err.msg);
	} else {
		node_log("info", p->cfg->name, 0, "bed confirmed clear");
		pthread_cond_signal(&p->cv);
		ret = no_content(c);
	}
	pthread_mutex_unlock(&p->mu);
	return ret;
}

/* ---- upload -------------------------------------------------------------- */

/* Drop the upload's temporary file. */
static void upload_discard(struct req *r)
{
	if (r->fd >= 0) {
		close(r->fd);
		r->fd = -1;
	}
	if (r->tmp[0]) {
		unlink(r->tmp);
		r->tmp[0] = '\0';
	}
}

/* Decide an error answer for the request (first one wins). */
static void req_fail(struct req *r, int status, const char *msg)
{
	if (!r->status) {
		r->status = status;
		snprintf(r->msg, sizeof(r->msg), "%s", msg);
	}
}

/* Append data to a form field buffer. */
static void field_add(struct req *r, char *dst, size_t cap, size_t *len, const char *key,
		      const char *data, size_t size)
{
	char msg[100];

	if (*len + size >= cap) {
		snprintf(msg, sizeof(msg), "the form field %s is longer than %zu bytes", key, cap - 1);
		req_fail(r, MHD_HTTP_BAD_REQUEST, msg);
		return;
	}
	memcpy(dst + *len, data, size);
	*len += size;
	dst[*len] = '\0';
}

static enum MHD_Result post_iter(void *cls, enum MHD_ValueKind kind, const char *key,
				 const char *filename, const char *content_type,
				 const char *transfer_encoding, const char *data, uint64_t off,
				 size_t size)
{
	struct req *r = cls;
	struct node *n = r->p->node;
	size_t flen;

	(void)kind;
	(void)content_type;
	(void)transfer_encoding;
	(void)off;
	/* A part without name= (or one libmicrohttpd could not read) has no
	 * key: it is no field of ours, like the unknown ones below. */
	if (r->status || !key)
		return MHD_YES; /* keep reading, answer at the end */
	if (!strcmp(key, "print")) {
		size_t l = strlen(r->print);
		field_add(r, r->print, sizeof(r->print), &l, key, data, size);
	} else if (!strcmp(key, "select")) {
		size_t l = strlen(r->select);
		field_add(r, r->select, sizeof(r->select), &l, key, data, size);
	} else if (!strcmp(key, "path")) {
		field_add(r, r->path, sizeof(r->path), &r->path_len, key, data, size);
	} else if (!strcmp(key, "file")) {
		if (!r->has_file) {
			r->has_file = true;
			flen = filename ? strlen(filename) : 0;
			if (flen > NODE_FILE_NAME_MAX)
				flen = NODE_FILE_NAME_MAX + 1; /* refused at the end */
			memcpy(r->filename, filename ? filename : "", flen);
			r->filename[flen] = '\0';
			r->filename_len = filename ? strlen(filename) : 0;
			r->fd = snprintf(r->tmp, sizeof(r->tmp), "%s/upload-XXXXXX", n->tmp_dir) <
					 (int)sizeof(r->tmp)
					? mkstemp(r->tmp)
					: -1;
			if (r->fd < 0) {
				r->tmp[0] = '\0';
				node_log("error", r->p->cfg->name, 0, "%s: cannot create an upload "
								      "file: %s", n->tmp_dir,
					 strerror(errno));
				req_fail(r, MHD_HTTP_INTERNAL_SERVER_ERROR, "cannot store the upload");
				return MHD_YES;
			}
		}
		r->bytes += size;
		if (r->bytes > n->cfg.max_upload) {
			char msg[100];

			snprintf(msg, sizeof(msg), "the file is larger than the node's limit of "
						   "%llu bytes", (unsigned long long)n->cfg.max_upload);
			upload_discard(r);
			req_fail(r, MHD_HTTP_CONTENT_TOO_LARGE, msg);
			return MHD_YES;
		}
		for (size_t done = 0; done < size && r->fd >= 0;) {
			ssize_t w = write(r->fd, data + done, size - done);

			if (w < 0 && errno == EINTR)
				continue;
			if (w <= 0) {
				node_log("error", r->p->cfg->name, 0, "writing an upload: %s",
					 strerror(errno));
				upload_discard(r);
				req_fail(r, MHD_HTTP_INSUFFICIENT_STORAGE, "cannot store the upload");
				break;
			}
			done += (size_t)w;
		}
	}
	/* Other fields (OctoPrint's userdata, foldername ...) are ignored. */
	return MHD_YES;
}

/* OctoPrint's true values for form booleans. */
static bool form_true(const char *v)
{
	return !strcasecmp(v, "true") || !strcasecmp(v, "yes") || !strcasecmp(v, "y") ||
	       !strcmp(v, "1");
}

/* Store the finished upload and queue or select it. */
static enum MHD_Result finish_upload(struct node *n, struct MHD_Connection *c, struct req *r)
{
	struct node_printer *p = r->p;
	char rel[HTTP_FIELD_MAX + NODE_FILE_NAME_MAX + 2], full[NODE_PATH_MAX + sizeof(rel)];
	char loc[2048], msg[400];
	const char *folder = r->path;
	struct st_error err = {0};
	bool print = form_true(r->print), select = print || form_true(r->select);
	int64_t id = 0;
	struct stat st;
	json_t *o;
	int rc;

	if (!r->has_file)
		return send_error(c, MHD_HTTP_BAD_REQUEST, "no file part named 'file' in the "
							   "multipart form");
	if (node_check_file_name(r->filename, r->filename_len, &err)) {
		snprintf(msg, sizeof(msg), "bad file name: %s", err.msg);
		return send_error(c, MHD_HTTP_BAD_REQUEST, msg);
	}
	if (node_check_kind(p, r->filename, &err))
		return send_error(c, MHD_HTTP_UNSUPPORTED_MEDIA_TYPE, err.msg);
	while (*folder == '/')
		folder++; /* "/" and "" both mean the top folder */
	if (strlen(folder) != r->path_len - (size_t)(folder - r->path) ||
	    check_rel(folder, strlen(folder), &err)) {
		snprintf(msg, sizeof(msg), "bad path: %s", err.msg[0] ? err.msg : "NUL byte");
		return send_error(c, MHD_HTTP_BAD_REQUEST, msg);
	}
	snprintf(rel, sizeof(rel), "%s%s%s", folder, *folder && folder[strlen(folder) - 1] != '/'
							 ? "/" : "", r->filename);
	if (fsync(r->fd) || close(r->fd)) {
		r->fd = -1;
		return send_error(c, MHD_HTTP_INSUFFICIENT_STORAGE, "cannot store the upload");
	}
	r->fd = -1;
	if ((rc = node_store_file(n, p, r->tmp, rel, select, print, &id, &err)))
		return send_error(c, rc == ST_ERR_RANGE ? MHD_HTTP_CONFLICT
				  : MHD_HTTP_INTERNAL_SERVER_ERROR, err.msg);
	r->tmp[0] = '\0';
	snprintf(full, sizeof(full), "%s/%s", p->files_dir, rel);
	node_log("info", p->cfg->name, id, "stored %s (%llu bytes)%s", rel,
		 (unsigned long long)r->bytes, print ? ", queued" : "");
	stat(full, &st);
	o = json_pack("{s:{s:o},s:b,s:b,s:b}", "files", "local", file_json(c, r, rel, &st), "done",
		      1, "effectiveSelect", select, "effectivePrint", print);
	json_object_set_new(o, "stratum", id ? json_pack("{s:I}", "job", (json_int_t)id)
					     : json_null());
	url_for(c, r, "/api/files/local/", rel, loc, sizeof(loc));
	return send_json(c, MHD_HTTP_CREATED, o, loc);
}

/* ---- routing -------------------------------------------------------------- */

static const struct route routes[] = {
	{"GET", "/api/version", false, NODE_ROLE_READ, false, get_version},
	{"GET", "/api/printer", false, NODE_ROLE_READ, false, get_printer},
	{"POST", "/api/printer/command", false, NODE_ROLE_CONTROL, false, post_command},
	{"GET", "/api/job", false, NODE_ROLE_READ, false, get_job},
	{"POST", "/api/job", false, NODE_ROLE_CONTROL, false, post_job},
	{"GET", "/api/connection", false, NODE_ROLE_READ, false, get_connection},
	{"POST", "/api/connection", false, NODE_ROLE_CONTROL, false, post_connection},
	{"GET", "/api/settings", false, NODE_ROLE_READ, false, get_settings},
	{"GET", "/api/printerprofiles", false, NODE_ROLE_READ, false, get_profiles},
	{"POST", "/api/files/local", false, NODE_ROLE_UPLOAD, true, finish_upload},
	{"GET", "/api/files/local/", true, NODE_ROLE_READ, false, get_file},
	{"GET", "/api/stratum/queue", false, NODE_ROLE_READ, false, get_queue},
	{"POST", "/api/stratum/bed-clear", false, NODE_ROLE_CONTROL, false, post_bed_clear},
	{"GET", "/api/stratum/node", false, NODE_ROLE_READ, false, get_node},
};

/* The roles of the request's key (X-Api-Key or Authorization: Bearer); 0 if none. */
static unsigned key_roles(struct node *n, struct MHD_Connection *c)
{
	const char *key = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "X-Api-Key");
	const char *auth = MHD_lookup_connection_value(c, MHD_HEADER_KIND,
						       MHD_HTTP_HEADER_AUTHORIZATION);
	unsigned roles = 0;

	if (!key && auth && !strncasecmp(auth, "Bearer ", 7))
		key = auth + 7;
	if (!key)
		return 0;
	/* Compare with every key in full so the time does not tell which matched. */
	for (size_t i = 0; i < n->cfg.nkeys; i++) {
		const char *s = n->cfg.keys[i].secret;
		size_t a = strlen(key), b = strlen(s);
		unsigned char diff = a != b;

		for (size_t k = 0; k < b; k++)
			diff |= (unsigned char)(s[k] ^ key[k < a ? k : 0]);
		if (!diff)
			roles |= n->cfg.keys[i].roles;
	}
	return roles;
}

/* Find the printer and route of url; sets r->p, r->base, r->route_path, r->rt. */
static void resolve(struct node *n, const char *url, const char *method, struct req *r)
{
	bool path_known = false;

	for (size_t i = 0; i < n->nprinters && !r->p; i++) {
		const char *pre = n->printers[i].cfg->prefix;
		size_t len = strlen(pre);

		if (!strncmp(url, pre, len) && url[len] == '/') {
			r->p = &n->printers[i];
			snprintf(r->base, sizeof(r->base), "%s", pre);
			r->route_path = url + len;
		}
	}
	if (!r->p && !strncmp(url, "/api/", 5)) {
		r->p = &n->printers[0];
		r->route_path = url;
	}
	if (!r->p)
		return;
	for (size_t i = 0; i < sizeof(routes) / sizeof(routes[0]); i++) {
		const struct route *rt = &routes[i];
		bool match = rt->prefix ? !strncmp(r->route_path, rt->path, strlen(rt->path))
					: !strcmp(r->route_path, rt->path);

		if (!match)
			continue;
		path_known = true;
		if (!strcmp(method, rt->method)) {
			r->rt = rt;
			return;
		}
	}
	if (path_known)
		r->status = MHD_HTTP_METHOD_NOT_ALLOWED;
}

/* First call: decide what we can before the body. */
static void first_call(struct node *n, struct MHD_Connection *c, const char *url,
		       const char *method, struct req *r)
{
	const char *cl = MHD_lookup_connection_value(c, MHD_HEADER_KIND,
						     MHD_HTTP_HEADER_CONTENT_LENGTH);
	unsigned long long len = cl ? strtoull(cl, NULL, 10) : 0;
	unsigned roles;

	resolve(n, url, method, r);
	if (r->status) {
		req_fail(r, r->status, "method not allowed here");
		return;
	}
	if (!r->rt) {
		req_fail(r, MHD_HTTP_NOT_FOUND, "no such API call");
		return;
	}
	roles = key_roles(n, c);
	if (!(roles & r->rt->role)) {
		req_fail(r, MHD_HTTP_FORBIDDEN, roles ? "the API key lacks the role this call needs"
						      : "a valid API key is needed (X-Api-Key)");
		return;
	}
	if (r->rt->upload) {
		if (len > n->cfg.max_upload + HTTP_MULTIPART_SLACK) {
			char msg[100];

			snprintf(msg, sizeof(msg), "the upload is larger than the node's limit of "
						   "%llu bytes", (unsigned long long)n->cfg.max_upload);
			req_fail(r, MHD_HTTP_CONTENT_TOO_LARGE, msg);
			return;
		}
		r->pp = MHD_create_post_processor(c, 65536, post_iter, r);
		if (!r->pp)
			req_fail(r, MHD_HTTP_BAD_REQUEST, "the upload is not multipart/form-data");
	} else if (len > HTTP_JSON_MAX) {
		req_fail(r, MHD_HTTP_CONTENT_TOO_LARGE, "the request body is too large");
	}
}

/* Whether the client sent the body already, or waits for 100 Continue. */
static bool waits_for_continue(struct MHD_Connection *c)
{
	const char *e = MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_EXPECT);

	return e && !strcasecmp(e, "100-continue");
}

static enum MHD_Result handle(void *cls, struct MHD_Connection *c, const char *url,
			      const char *method, const char *version, const char *upload,
			      size_t *upload_size, void **con_cls)
{
	struct node *n = cls;
	struct req *r = *con_cls;

	(void)version;
	if (!r && !strcmp(method, "GET") && (!strcmp(url, "/") || !strcmp(url, "/index.html")))
		return send_page(c);
	if (!r) {
		r = calloc(1, sizeof(*r));
		if (!r)
			return MHD_NO;
		r->fd = -1;
		*con_cls = r;
		first_call(n, c, url, method, r);
		/* Answer at once when no body is on its way. */
		if (r->status && waits_for_continue(c))
			return send_error(c, (unsigned)r->status, r->msg);
		return MHD_YES;
	}
	if (*upload_size) {
		if (!r->status && r->pp) {
			if (MHD_post_process(r->pp, upload, *upload_size) != MHD_YES)
				req_fail(r, MHD_HTTP_BAD_REQUEST, "the multipart form is malformed");
		} else if (!r->status) {
			if (r->len + *upload_size > HTTP_JSON_MAX) {
				req_fail(r, MHD_HTTP_CONTENT_TOO_LARGE, "the request body is too large");
			} else {
				char *b = realloc(r->body, r->len + *upload_size);

				if (!b)
					return MHD_NO;
				memcpy(b + r->len, upload, *upload_size);
				r->body = b;
				r->len += *upload_size;
			}
		}
		*upload_size = 0;
		return MHD_YES;
	}
	if (r->status)
		return send_error(c, (unsigned)r->status, r->msg);
	return r->rt->fn(n, c, r);
}

/* Free a request's state and log it once it is answered. */
static void completed(void *cls, struct MHD_Connection *c, void **con_cls,
		      enum MHD_RequestTerminationCode toe)
{
	struct req *r = *con_cls;

	(void)cls;
	(void)c;
	(void)toe;
	if (!r)
		return;
	if (r->pp)
		MHD_destroy_post_processor(r->pp);
	upload_discard(r);
	free(r->body);
	free(r);
	*con_cls = NULL;
}

/* Log every request: method, URL, client. */
static void *log_uri(void *cls, const char *uri, struct MHD_Connection *c)
{
	(void)cls;
	(void)c;
	node_log("debug", NULL, 0, "request %.200s", uri);
	return NULL;
}

int node_http_start(struct node *n, struct st_error *err)
{
	struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons(n->cfg.listen_port)};
	const union MHD_DaemonInfo *info;

	if (inet_pton(AF_INET, n->cfg.listen_addr, &sa.sin_addr) != 1)
		return st_error_set(err, ST_ERR_ARG, "listen address %s is not IPv4",
				    n->cfg.listen_addr);
	n->httpd = MHD_start_daemon(MHD_USE_AUTO_INTERNAL_THREAD, n->cfg.listen_port, NULL, NULL,
				    handle, n, MHD_OPTION_SOCK_ADDR, (struct sockaddr *)&sa,
				    MHD_OPTION_THREAD_POOL_SIZE, (unsigned)HTTP_POOL,
				    MHD_OPTION_CONNECTION_TIMEOUT, (unsigned)HTTP_TIMEOUT_S,
				    MHD_OPTION_NOTIFY_COMPLETED, completed, n,
				    MHD_OPTION_URI_LOG_CALLBACK, log_uri, n, MHD_OPTION_END);
	if (!n->httpd)
		return st_error_set(err, ST_ERR_IO, "cannot listen on %s:%u: %s", n->cfg.listen_addr,
				    n->cfg.listen_port, strerror(errno));
	info = MHD_get_daemon_info(n->httpd, MHD_DAEMON_INFO_BIND_PORT);
	n->port = info ? info->port : n->cfg.listen_port;
	return 0;
}

void node_http_stop(struct node *n)
{
	if (n->httpd)
		MHD_stop_daemon(n->httpd);
	n->httpd = NULL;
}
