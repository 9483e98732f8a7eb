/*
 * http.c - the node's HTTP API on libmicrohttpd (docs/serve.md): the
 * OctoPrint subset slicers use, under each printer's prefix and, for the
 * first printer, at /api/... as well; plus /api/stratum/... for what
 * OctoPrint has no call for (the queue, the bed-clear confirmation).
 * Here: responses, uploads and routing; the handlers are in http_api.c.
 *
 * A request is decided in the first call of the handler (route, key, size).
 * A refused one is answered once its body is read when that body is small
 * (HTTP_DRAIN_MAX): answering early leaves unread bytes that can make the
 * kernel reset the connection before the client reads the answer.  A client
 * waiting for "100 Continue", or one announcing a larger or chunked body,
 * is answered at once and its body never read (docs/serve.md, "Limits"):
 * nobody without a key can make the node read a gigabyte.
 */
#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <jansson.h>
#include <microhttpd.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cfgopt.h"
#include "gcode.h"
#include "http_int.h"
#include "st_append.h"
#include "st_grow.h"

#define HTTP_JSON_MAX 65536		/* body of a JSON command, bytes */
#define HTTP_POOL 4			/* HTTP threads */

/* ---- responses ---------------------------------------------------------- */

/* Answer with body (stolen; NULL = no body) and status, and the header
 * name: value when name is not NULL. */
static enum MHD_Result send_json_with(struct MHD_Connection *c, unsigned status, json_t *body,
				      const char *name, const char *value)
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
	if (name)
		MHD_add_response_header(resp, name, value);
	ret = MHD_queue_response(c, status, resp);
	MHD_destroy_response(resp);
	return ret;
}

enum MHD_Result http_send_json(struct MHD_Connection *c, unsigned status, json_t *body,
			       const char *location)
{
	return send_json_with(c, status, body, location ? MHD_HTTP_HEADER_LOCATION : NULL,
			      location);
}

/* The decided refusal of r ({"error": msg}); a 405 names the path's methods
 * in Allow, as OctoPrint's (Flask's) does. */
static enum MHD_Result send_refusal(struct MHD_Connection *c, const struct req *r)
{
	json_t *o = json_pack("{s:s}", "error", r->msg);

	return send_json_with(c, (unsigned)r->status, o, r->status == MHD_HTTP_METHOD_NOT_ALLOWED
			      ? MHD_HTTP_HEADER_ALLOW : NULL, r->allow);
}

/* {"error": msg} with status, as OctoPrint answers errors. */
enum MHD_Result http_send_error(struct MHD_Connection *c, unsigned status, const char *msg)
{
	json_t *o = json_object();

	json_object_set_new(o, "error", json_string(msg));
	return http_send_json(c, status, o, NULL);
}

enum MHD_Result http_send_page(struct MHD_Connection *c, const char *page)
{
	struct MHD_Response *resp = MHD_create_response_from_buffer(
		strlen(page), (void *)page, MHD_RESPMEM_PERSISTENT);
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

enum MHD_Result http_no_content(struct MHD_Connection *c)
{
	return http_send_json(c, MHD_HTTP_NO_CONTENT, NULL, NULL);
}

/* ---- upload -------------------------------------------------------------- */

/* Drop the upload's temporary file. */
static void upload_discard(struct req *r)
{
	st_file_abort(&r->out);
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
	} else if (!strcmp(key, "force")) {
		size_t l = strlen(r->force);
		field_add(r, r->force, sizeof(r->force), &l, key, data, size);
	} else if (!strcmp(key, "path")) {
		field_add(r, r->path, sizeof(r->path), &r->path_len, key, data, size);
	} else if (!strcmp(key, "foldername")) {
		field_add(r, r->foldername, sizeof(r->foldername), &r->foldername_len, key, data, size);
	} else if (cfgopt_is_field(key)) {
		/* a setting: its name and NUL open the pair, a NUL closes it */
		if (off == 0) {
			if (r->nsets++)
				field_add(r, r->sets, sizeof(r->sets), &r->sets_len, key, "", 1);
			field_add(r, r->sets, sizeof(r->sets), &r->sets_len, key, key,
				  strlen(key) + 1);
		}
		field_add(r, r->sets, sizeof(r->sets), &r->sets_len, key, data, size);
	} else if (!strcmp(key, "file")) {
		/* A second file part would be appended to the first: refuse the form.
		 * A part starts at offset 0; the first part's later calls do not. */
		if (r->has_file && off == 0 &&
		    (r->bytes || strcmp(filename ? filename : "", r->filename))) {
			upload_discard(r);
			req_fail(r, MHD_HTTP_BAD_REQUEST, "the multipart form has more than one "
							  "part named 'file'; send one file per upload");
			return MHD_YES;
		}
		if (!r->has_file) {
			r->has_file = true;
			flen = filename ? strlen(filename) : 0;
			if (flen > NODE_FILE_NAME_MAX)
				flen = NODE_FILE_NAME_MAX + 1; /* refused at the end */
			memcpy(r->filename, filename ? filename : "", flen);
			r->filename[flen] = '\0';
			r->filename_len = filename ? strlen(filename) : 0;
			if (st_file_begin_temp(&r->out, n->tmp_dir, "upload", NULL)) {
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
		if (r->out.f && size && fwrite(data, 1, size, r->out.f) != size) {
			node_log("error", r->p->cfg->name, 0, "writing an upload: %s",
				 strerror(errno));
			upload_discard(r);
			req_fail(r, MHD_HTTP_INSUFFICIENT_STORAGE, "cannot store the upload");
		}
	}
	/* Other fields (OctoPrint's userdata ...) are ignored. */
	return MHD_YES;
}

/* OctoPrint's true values for form booleans. */
static bool form_true(const char *v)
{
	return !strcasecmp(v, "true") || !strcasecmp(v, "yes") || !strcasecmp(v, "y") ||
	       !strcmp(v, "1");
}

/* The upload's per-job settings fields as the JSON of node_job.settings in
 * out, checked against p's profile; 0, or an HTTP status with msg. */
static int upload_settings(struct node_printer *p, const struct req *r, bool print, char *out,
			   size_t cap, char *msg, size_t msgcap)
{
	const char *s = r->sets, *end = r->sets + r->sets_len;
	struct st_error err = {0};
	struct profile *prof = NULL;
	json_t *arr = json_array();
	char *text = NULL, *list = NULL;
	int status = 0;

	if (!print)
		snprintf(msg, msgcap, "per-job settings (%.60s) come with print=true: they belong "
			 "to the job the upload queues", s);
	else if (node_file_kind(r->filename) != 'm')
		snprintf(msg, msgcap, "per-job settings (%.60s) apply to models the node slices; "
			 "%.100s is sliced already", s, r->filename);
	for (size_t k = 0; !msg[0] && k < r->nsets; k++) {
		const char *name = s, *value = s + strlen(s) + 1;

		s = value + strlen(value) + 1;
		if (value >= end || s > end + 1)
			snprintf(msg, msgcap, "the form field %.60s holds a NUL byte", name);
		else
			json_array_append_new(arr, json_pack("[ss]", name, value));
	}
	if (!msg[0] && (!(text = json_dumps(arr, JSON_COMPACT)) || strlen(text) >= cap))
		snprintf(msg, msgcap, "the per-job settings are longer than %zu bytes", cap - 1);
	if (!msg[0] && node_settings_profile(p, text, &prof, &err))
		snprintf(msg, msgcap, "per-job settings: %s", err.msg);
	if (msg[0]) {
		status = MHD_HTTP_BAD_REQUEST;
	} else {
		snprintf(out, cap, "%s", text);
		if (profile_unsupported(prof, &list) == 0 && list)
			node_log("warning", p->cfg->name, 0, "per-job settings of %s: not "
				 "supported, ignored: %s", r->filename, list);
	}
	free(list);
	free(text);
	json_decref(arr);
	profile_free(prof);
	return status;
}

/* Store the finished upload and queue or select it. */
static enum MHD_Result finish_upload(struct node *n, struct MHD_Connection *c, struct req *r)
{
	struct node_printer *p = r->p;
	char rel[HTTP_FIELD_MAX + NODE_FILE_NAME_MAX + 2], full[NODE_PATH_MAX + sizeof(rel)];
	char loc[2048], msg[400] = "", settings[NODE_SETTINGS_MAX] = "";
	const char *folder = r->path;
	struct st_error err = {0};
	bool print = form_true(r->print), select = print || form_true(r->select);
	int64_t id = 0;
	struct stat st;
	json_t *o;
	int rc;

	if (!r->has_file && r->foldername_len)
		return http_make_folder(n, c, r);
	if (!r->has_file)
		return http_send_error(c, MHD_HTTP_BAD_REQUEST, "no file part named 'file' in the "
							        "multipart form");
	if (node_check_file_name(r->filename, r->filename_len, &err)) {
		snprintf(msg, sizeof(msg), "bad file name: %s", err.msg);
		return http_send_error(c, MHD_HTTP_BAD_REQUEST, msg);
	}
	if (node_check_kind(p, r->filename, &err))
		return http_send_error(c, MHD_HTTP_UNSUPPORTED_MEDIA_TYPE, err.msg);
	if (r->nsets && (rc = upload_settings(p, r, print, settings, sizeof(settings), msg,
					      sizeof(msg))))
		return http_send_error(c, (unsigned)rc, msg);
	while (*folder == '/')
		folder++; /* "/" and "" both mean the top folder */
	if (strlen(folder) != r->path_len - (size_t)(folder - r->path) ||
	    http_check_rel(folder, strlen(folder), &err)) {
		snprintf(msg, sizeof(msg), "bad path: %s", err.msg[0] ? err.msg : "NUL byte");
		return http_send_error(c, MHD_HTTP_BAD_REQUEST, msg);
	}
	snprintf(rel, sizeof(rel), "%s%s%s", folder, *folder && folder[strlen(folder) - 1] != '/'
							 ? "/" : "", r->filename);
	if (st_file_finish(&r->out, NULL))
		return http_send_error(c, MHD_HTTP_INSUFFICIENT_STORAGE, "cannot store the upload");
	if ((rc = node_store_file(n, p, &r->out, rel, select, print, form_true(r->force), settings,
				   &id, &err)))
		return http_send_error(c, rc == ST_ERR_RANGE ? MHD_HTTP_CONFLICT
				       : MHD_HTTP_INTERNAL_SERVER_ERROR, err.msg);
	snprintf(full, sizeof(full), "%s/%s", p->files_dir, rel);
	node_log("info", p->cfg->name, id, "stored %s (%llu bytes)%s", rel,
		 (unsigned long long)r->bytes, print ? ", queued" : "");
	http_files_changed(p);
	stat(full, &st);
	o = json_pack("{s:{s:o},s:b,s:b,s:b}", "files", "local", http_file_json(c, r, rel, &st), "done",
		      1, "effectiveSelect", select, "effectivePrint", print);
	json_object_set_new(o, "stratum", id ? json_pack("{s:I}", "job", (json_int_t)id)
					     : json_null());
	http_url_for(c, r, "/api/files/local/", rel, loc, sizeof(loc));
	return http_send_json(c, MHD_HTTP_CREATED, o, loc);
}

/* ---- routing -------------------------------------------------------------- */

static const struct route routes[] = {
	{"GET", "/api/version", false, NODE_ROLE_READ, false, http_get_version},
	{"GET", "/api/server", false, NODE_ROLE_READ, false, http_get_server},
	{"POST", "/api/login", false, 0, false, http_post_login},
	{"GET", "/api/currentuser", false, NODE_ROLE_READ, false, http_get_currentuser},
	{"GET", "/api/system/commands", false, NODE_ROLE_CONTROL, false, http_get_system_commands},
	{"GET", "/api/system/commands/", true, NODE_ROLE_CONTROL, false, http_get_system_commands},
	{"GET", "/api/printer", false, NODE_ROLE_READ, false, http_get_printer},
	{"POST", "/api/printer/command", false, NODE_ROLE_CONTROL, false, http_post_command},
	{"GET", "/api/printer/tool", false, NODE_ROLE_READ, false, http_get_tool},
	{"POST", "/api/printer/tool", false, NODE_ROLE_CONTROL, false, http_post_tool},
	{"GET", "/api/printer/bed", false, NODE_ROLE_READ, false, http_get_bed},
	{"POST", "/api/printer/bed", false, NODE_ROLE_CONTROL, false, http_post_bed},
	{"GET", "/api/printer/chamber", false, NODE_ROLE_READ, false, http_chamber},
	{"POST", "/api/printer/chamber", false, NODE_ROLE_CONTROL, false, http_chamber},
	{"POST", "/api/printer/printhead", false, NODE_ROLE_CONTROL, false, http_post_printhead},
	{"GET", "/api/printer/sd", false, NODE_ROLE_READ, false, http_sd},
	{"POST", "/api/printer/sd", false, NODE_ROLE_CONTROL, false, http_sd},
	{"GET", "/api/job", false, NODE_ROLE_READ, false, http_get_job},
	{"POST", "/api/job", false, NODE_ROLE_CONTROL, false, http_post_job},
	{"GET", "/api/connection", false, NODE_ROLE_READ, false, http_get_connection},
	{"POST", "/api/connection", false, NODE_ROLE_CONTROL, false, http_post_connection},
	{"GET", "/api/settings", false, NODE_ROLE_READ, false, http_get_settings},
	{"POST", "/api/settings", false, NODE_ROLE_READ, false, http_post_settings},
	{"GET", "/api/printerprofiles", false, NODE_ROLE_READ, false, http_get_profiles},
	{"GET", "/api/printerprofiles/", true, NODE_ROLE_READ, false, http_get_profile},
	{"GET", "/api/files", false, NODE_ROLE_READ, false, http_get_files},
	{"GET", "/api/files/local", false, NODE_ROLE_READ, false, http_get_files},
	{"POST", "/api/files/local", false, NODE_ROLE_UPLOAD, true, finish_upload},
	{"GET", "/api/files/local/", true, NODE_ROLE_READ, false, http_get_file},
	{"POST", "/api/files/local/", true, NODE_ROLE_UPLOAD, false, http_post_file},
	{"DELETE", "/api/files/local/", true, NODE_ROLE_UPLOAD, false, http_delete_file},
	{"GET", "/downloads/files/local/", true, NODE_ROLE_READ, false, http_download_file},
	{"GET", "/api/stratum/queue", false, NODE_ROLE_READ, false, http_get_queue},
	{"GET", "/api/stratum/queue/", true, NODE_ROLE_READ, false, http_get_queue_job},
	{"POST", "/api/stratum/queue/", true, NODE_ROLE_CONTROL, false, http_post_queue_job},
	{"POST", "/api/stratum/bed-clear", false, NODE_ROLE_CONTROL, false, http_post_bed_clear},
	{"GET", "/api/stratum/node", false, NODE_ROLE_READ, false, http_get_node},
};

unsigned http_key_roles(const struct node_config *cfg, struct MHD_Connection *c,
			const char **who)
{
	const char *key = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "X-Api-Key");
	const char *auth = MHD_lookup_connection_value(c, MHD_HEADER_KIND,
						       MHD_HTTP_HEADER_AUTHORIZATION);

	*who = NULL;
	if (!key && auth && !strncasecmp(auth, "Bearer ", 7))
		key = auth + 7;
	if (!key)
		key = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "apikey");
	if (!key)
		return 0;
	return node_key_roles(cfg, key, who);
}

/* Refuse an upload body longer than the file limit and the form around it. */
static void upload_too_large(struct node *n, struct req *r)
{
	char msg[100];

	snprintf(msg, sizeof(msg), "the upload is larger than the node's limit of %llu bytes",
		 (unsigned long long)n->cfg.max_upload);
	req_fail(r, MHD_HTTP_CONTENT_TOO_LARGE, msg);
}

/* Add method (and HEAD after GET) to the request's Allow list, once. */
static void allow_add(struct req *r, const char *method)
{
	size_t m = strlen(method);

	for (const char *s = r->allow; (s = strstr(s, method)); s += m)
		if ((s == r->allow || s[-1] == ' ') && (s[m] == ',' || !s[m]))
			return;
	st_appendf(r->allow, sizeof(r->allow), "%s%s", r->allow[0] ? ", " : "", method);
	if (!strcmp(method, "GET"))
		allow_add(r, "HEAD");
}

/* Find the printer and route of url; sets r->p, r->base, r->route_path, r->rt,
 * r->allow (the methods of the path) and r->options for OPTIONS. */
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
	if (!r->p && (!strncmp(url, "/api/", 5) || !strncmp(url, "/downloads/", 11))) {
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
		if (!r->rt && (!strcmp(method, rt->method) ||
			       (!strcmp(method, "HEAD") && !strcmp(rt->method, "GET"))))
			r->rt = rt;
		allow_add(r, rt->method);
	}
	if (path_known) {
		allow_add(r, "OPTIONS");
		if (!strcmp(method, "OPTIONS"))
			r->options = true;
		else if (!r->rt)
			r->status = MHD_HTTP_METHOD_NOT_ALLOWED;
	}
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
		snprintf(r->msg, sizeof(r->msg), "method not allowed here (allowed: %s)", r->allow);
		return;
	}
	if (r->options)
		return; /* answered with Allow, no key needed: it tells nothing */
	if (!r->rt) {
		req_fail(r, MHD_HTTP_NOT_FOUND, "no such API call");
		return;
	}
	roles = http_key_roles(&n->cfg, c, &r->key_name);
	r->roles = roles;
	if (r->rt->role && !(roles & r->rt->role)) {
		req_fail(r, MHD_HTTP_FORBIDDEN, roles ? "the API key lacks the role this call needs"
						      : "a valid API key is needed (X-Api-Key)");
		return;
	}
	if (r->rt->upload) {
		if (len > n->cfg.max_upload + HTTP_MULTIPART_SLACK) {
			upload_too_large(n, r);
			return;
		}
		r->pp = MHD_create_post_processor(c, 65536, post_iter, r);
		if (!r->pp)
			req_fail(r, MHD_HTTP_BAD_REQUEST, "the upload is not multipart/form-data");
	} else if (len > HTTP_JSON_MAX) {
		req_fail(r, MHD_HTTP_CONTENT_TOO_LARGE, "the request body is too large");
	}
}

bool http_refuse_at_once(struct MHD_Connection *c)
{
	const char *e = MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_EXPECT);
	const char *cl = MHD_lookup_connection_value(c, MHD_HEADER_KIND,
						     MHD_HTTP_HEADER_CONTENT_LENGTH);
	const char *te = MHD_lookup_connection_value(c, MHD_HEADER_KIND,
						     MHD_HTTP_HEADER_TRANSFER_ENCODING);

	if (e && !strcasecmp(e, "100-continue"))
		return true;
	if (te)
		return true;
	return cl && strtoull(cl, NULL, 10) > HTTP_DRAIN_MAX;
}

/* The push API's paths (push.c), under a printer's prefix or, for the
 * first printer, at /sockjs/...; no key: the client authenticates with its
 * first message. */
static bool push_route(struct node *n, struct MHD_Connection *c, const char *url,
		       enum MHD_Result *ret)
{
	for (size_t i = 0; i < n->nprinters; i++) {
		const char *pre = n->printers[i].cfg->prefix;
		size_t len = strlen(pre);

		if (!strncmp(url, pre, len) && url[len] == '/')
			return node_push_route(n, &n->printers[i], c, url + len, ret);
	}
	return node_push_route(n, &n->printers[0], c, url, ret);
}

static enum MHD_Result handle_request(void *cls, struct MHD_Connection *c, const char *url,
				      const char *method, const char *version, const char *upload,
				      size_t *upload_size, void **con_cls)
{
	struct node *n = cls;
	struct req *r = *con_cls;
	enum MHD_Result ret;

	(void)version;
	if (!r && !strcmp(method, "GET") && (!strcmp(url, "/") || !strcmp(url, "/index.html")))
		return http_send_page(c, node_status_page); /* no data: no key */
	if (!r && !strcmp(method, "GET") && push_route(n, c, url, &ret))
		return ret;
	if (!r) {
		r = calloc(1, sizeof(*r));
		if (!r)
			return MHD_NO;
		*con_cls = r;
		first_call(n, c, url, method, r);
		if (r->status && http_refuse_at_once(c))
			return send_refusal(c, r);
		return MHD_YES;
	}
	if (*upload_size) {
		/* Counted here, not in post_iter: a chunked body that is no form
		 * (no boundary ever) reaches no field and would be read forever. */
		r->raw += *upload_size;
		if (r->pp && r->raw > n->cfg.max_upload + HTTP_MULTIPART_SLACK)
			upload_too_large(n, r);
		if (!r->status && r->pp) {
			if (MHD_post_process(r->pp, upload, *upload_size) != MHD_YES)
				req_fail(r, MHD_HTTP_BAD_REQUEST, "the multipart form is malformed");
		} else if (!r->status) {
			if (r->len + *upload_size > HTTP_JSON_MAX) {
				req_fail(r, MHD_HTTP_CONTENT_TOO_LARGE, "the request body is too large");
			} else {
				char *b = st_grow(r->body, &r->body_cap, r->len + *upload_size, 1);

				if (!b)
					return MHD_NO;
				memcpy(b + r->len, upload, *upload_size);
				r->body = b;
				r->len += *upload_size;
			}
		}
		*upload_size = 0;
		/* A chunked body has no end the node knows: refused, it is not read on. */
		if (r->status && MHD_lookup_connection_value(c, MHD_HEADER_KIND,
							     MHD_HTTP_HEADER_TRANSFER_ENCODING))
			return send_refusal(c, r);
		return MHD_YES;
	}
	/* The post processor tells only here whether the form was complete
	 * (its closing boundary came): a cut-off upload is refused, not stored. */
	if (r->pp) {
		if (MHD_destroy_post_processor(r->pp) != MHD_YES)
			req_fail(r, MHD_HTTP_BAD_REQUEST, "the multipart form is incomplete (no "
							  "closing boundary)");
		r->pp = NULL;
	}
	if (r->status)
		return send_refusal(c, r);
	if (r->options)
		return send_json_with(c, MHD_HTTP_OK, NULL, MHD_HTTP_HEADER_ALLOW, r->allow);
	return r->rt->fn(n, c, r);
}

/* Free a request's state once it is answered. */
static void free_request(void *request)
{
	struct req *r = request;

	if (r->pp)
		MHD_destroy_post_processor(r->pp);
	upload_discard(r);
	free(r->body);
	free(r);
}

/* Log every request's path.  Not its query: the status page takes the
 * API key from ?key= (page.c), and a secret must not reach the log. */
static void *log_uri(void *cls, const char *uri, struct MHD_Connection *c)
{
	size_t path_len = strcspn(uri, "?");

	(void)cls;
	(void)c;
	node_log("debug", NULL, 0, "request %.*s%s", (int)(path_len < 200 ? path_len : 200), uri,
		 uri[path_len] ? "?(query not logged)" : "");
	return NULL;
}

/*
 * The node's total connection limit.  libmicrohttpd divides
 * MHD_OPTION_CONNECTION_LIMIT among the pool's threads, and whichever
 * thread accepts a connection refuses it when its own share is full, so
 * the node refused clients with most of its slots free.  Each thread may
 * hold the whole limit; the total is counted here, a slot taken when a
 * connection is admitted and given back when it closes.  (The per-address
 * limit is libmicrohttpd's, kept for the whole daemon, and checked before
 * this.  A connection admitted here that libmicrohttpd then fails to set
 * up, out of memory, keeps its slot.)
 */
static enum MHD_Result admit(void *cls, const struct sockaddr *addr, socklen_t len)
{
	struct node *n = cls;
	unsigned held = atomic_load(&n->http_connections);

	(void)addr;
	(void)len;
	do {
		if (held >= n->cfg.max_connections)
			return MHD_NO;
	} while (!atomic_compare_exchange_weak(&n->http_connections, &held, held + 1));
	return MHD_YES;
}

/* A connection closed: its slot is free (admit). */
static void connection_closed(void *cls)
{
	struct node *n = cls;

	atomic_fetch_sub(&n->http_connections, 1);
}

int node_http_start(struct node *n, struct st_error *err)
{
	const struct http_hooks hooks = {handle_request, free_request, connection_closed, n};
	const struct MHD_OptionItem extra[] = {
	    {MHD_OPTION_THREAD_POOL_SIZE, HTTP_POOL, NULL},
	    {MHD_OPTION_CONNECTION_LIMIT, (intptr_t)(n->cfg.max_connections * HTTP_POOL), NULL},
	    {MHD_OPTION_URI_LOG_CALLBACK, (intptr_t)log_uri, n},
	    {MHD_OPTION_END, 0, NULL},
	};

	atomic_store(&n->http_connections, 0);
	return http_server_start(&n->cfg, MHD_USE_AUTO_INTERNAL_THREAD | MHD_ALLOW_UPGRADE, admit,
				 n, &hooks, extra, &n->httpd, &n->deadlines, &n->port, err);
}

void node_http_stop(struct node *n)
{
	node_push_stop(n); /* libmicrohttpd wants upgraded sockets closed first */
	http_server_stop(&n->httpd, &n->deadlines);
}
