/*
 * farm_http.c - the farm view's HTTP server (libmicrohttpd; docs/serve.md
 * "The farm view"):
 *   GET /                 the page (no key: it holds no data)
 *   GET /api/farm         every node's printers (read role)
 *   POST /api/farm/jobs   a multipart form with file and profile: the job
 *                         goes to the first idle printer of that profile,
 *                         through its node's upload API (upload role)
 * Keys and roles are the node's (http_key_roles); the key is checked and
 * the size announced before a byte of the body is read, and a slow client
 * is closed as the node closes one (header_timeout_s, min_body_rate;
 * http_deadline.c).
 */
#include <curl/curl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "farm_int.h"
#include "http_int.h"

#define FARM_TRIES 8		/* printers tried for one job before giving up */
#define FARM_CONNECT_S 5	/* to reach a node */
#define FARM_SEND_S 600		/* to send it a job */

enum farm_route { FR_NONE, FR_STATE, FR_JOBS };

/* One request, from its first call to its completion. */
struct farm_req {
	enum farm_route route;
	int status; /* decided: answer this with msg */
	char msg[300];
	const char *who; /* the key's name */
	struct MHD_PostProcessor *pp;
	FILE *file; /* the job's file, unnamed (tmpfile) */
	uint64_t bytes, raw;
	bool has_file;
	char filename[NODE_FILE_NAME_MAX + 2];
	size_t filename_len;
	char profile[NODE_PATH_MAX];
	size_t profile_len;
};

static void fail(struct farm_req *r, int status, const char *msg)
{
	if (!r->status) {
		r->status = status;
		snprintf(r->msg, sizeof(r->msg), "%s", msg);
	}
}

static enum MHD_Result post_iter(void *cls, enum MHD_ValueKind kind, const char *key,
				 const char *filename, const char *type, const char *enc,
				 const char *data, uint64_t off, size_t size)
{
	struct farm_req *r = cls;

	(void)kind, (void)type, (void)enc;
	if (r->status)
		return MHD_YES;
	if (!strcmp(key, "file")) {
		/* a part starts at offset 0, the first part's later calls do not */
		if (r->has_file && off == 0 &&
		    (r->bytes || strcmp(filename ? filename : "", r->filename)))
			fail(r, MHD_HTTP_BAD_REQUEST, "the multipart form has more than one part "
						      "named 'file'; send one file per job");
		if (!r->has_file) {
			r->has_file = true;
			r->filename_len = filename ? strlen(filename) : 0;
			if (r->filename_len > NODE_FILE_NAME_MAX)
				r->filename_len = NODE_FILE_NAME_MAX + 1;
			memcpy(r->filename, filename ? filename : "", r->filename_len);
			r->file = tmpfile();
			if (!r->file)
				fail(r, MHD_HTTP_INTERNAL_SERVER_ERROR, "cannot hold the file");
		}
		if (r->file && size && fwrite(data, 1, size, r->file) != size)
			fail(r, MHD_HTTP_INTERNAL_SERVER_ERROR, "cannot hold the file");
		r->bytes += size;
	} else if (!strcmp(key, "profile")) {
		if (r->profile_len + size >= sizeof(r->profile))
			fail(r, MHD_HTTP_BAD_REQUEST, "profile: too long");
		else {
			memcpy(r->profile + r->profile_len, data, size);
			r->profile_len += size;
		}
	}
	return MHD_YES;
}

/* curl reads the job's file from the request's unnamed temporary file. */
static size_t read_file(char *buf, size_t size, size_t n, void *ctx)
{
	return fread(buf, size, n, ctx);
}

static int seek_file(void *ctx, curl_off_t off, int origin)
{
	return fseeko(ctx, (off_t)off, origin) ? CURL_SEEKFUNC_FAIL : CURL_SEEKFUNC_OK;
}

static size_t keep_answer(char *data, size_t size, size_t n, void *ctx)
{
	char *buf = ctx;
	size_t have = strlen(buf), add = size * n;

	if (have + add >= 4096)
		add = 4095 - have;
	memcpy(buf + have, data, add);
	buf[have + add] = '\0';
	return size * n;
}

/* Upload r's file to the printer at pick with print=true, as a slicer does.
 * Returns the HTTP status (0: no answer, why in err) and the node's answer. */
static long send_job(struct farm_req *r, const struct farm_pick *pick, char answer[4096],
		     char err[CURL_ERROR_SIZE])
{
	char url[sizeof(pick->url) + 32], header[NODE_KEY_MAX + 16];
	struct curl_slist *headers = NULL;
	curl_mime *form;
	curl_mimepart *part;
	long status = 0;
	CURL *c = curl_easy_init();

	answer[0] = err[0] = '\0';
	if (!c) {
		snprintf(err, CURL_ERROR_SIZE, "out of memory");
		return 0;
	}
	rewind(r->file);
	snprintf(url, sizeof(url), "%s/api/files/local", pick->url);
	snprintf(header, sizeof(header), "X-Api-Key: %s", pick->key);
	headers = curl_slist_append(headers, header);
	form = curl_mime_init(c);
	part = curl_mime_addpart(form);
	curl_mime_name(part, "print");
	curl_mime_data(part, "true", CURL_ZERO_TERMINATED);
	part = curl_mime_addpart(form);
	curl_mime_name(part, "file");
	curl_mime_filename(part, r->filename);
	curl_mime_data_cb(part, (curl_off_t)r->bytes, read_file, seek_file, NULL, r->file);
	curl_easy_setopt(c, CURLOPT_URL, url);
	curl_easy_setopt(c, CURLOPT_PROTOCOLS_STR, "http,https");
	curl_easy_setopt(c, CURLOPT_HTTPHEADER, headers);
	curl_easy_setopt(c, CURLOPT_MIMEPOST, form);
	curl_easy_setopt(c, CURLOPT_NOSIGNAL, 1L);
	curl_easy_setopt(c, CURLOPT_CONNECTTIMEOUT, (long)FARM_CONNECT_S);
	curl_easy_setopt(c, CURLOPT_TIMEOUT, (long)FARM_SEND_S);
	curl_easy_setopt(c, CURLOPT_ERRORBUFFER, err);
	curl_easy_setopt(c, CURLOPT_WRITEFUNCTION, keep_answer);
	curl_easy_setopt(c, CURLOPT_WRITEDATA, answer);
	curl_easy_setopt(c, CURLOPT_USERAGENT, "stratum-farm");
	if (curl_easy_perform(c) == CURLE_OK)
		curl_easy_getinfo(c, CURLINFO_RESPONSE_CODE, &status);
	curl_easy_cleanup(c);
	curl_mime_free(form);
	curl_slist_free_all(headers);
	return status;
}

/* The node's {"error": ...}, or its whole answer, or curl's reason. */
static void node_reason(const char *answer, const char *curl_err, char *out, size_t cap)
{
	json_t *o = json_loads(answer, 0, NULL);
	const char *e = json_string_value(json_object_get(o, "error"));

	snprintf(out, cap, "%.200s", e ? e : answer[0] ? answer : curl_err[0] ? curl_err
										  : "no answer");
	json_decref(o);
}

/* POST /api/farm/jobs once the form is read: pick, send, and on a refusal
 * (busy after all, the farm's key refused, unreachable) the next idle
 * printer. */
static enum MHD_Result dispatch(struct farm *f, struct MHD_Connection *c, struct farm_req *r)
{
	struct st_error err = {0};
	struct farm_pick pick;
	char answer[4096], curl_err[CURL_ERROR_SIZE], why[300] = "", msg[700], loc[1024];
	json_t *tried, *o;
	json_int_t job;
	long status = 0;
	int rc = 0;

	r->profile[r->profile_len] = '\0';
	if (!r->has_file || !r->profile[0])
		return http_send_error(c, MHD_HTTP_BAD_REQUEST, "a job is a multipart form with "
								"file and profile");
	if (node_check_file_name(r->filename, r->filename_len, &err)) {
		snprintf(msg, sizeof(msg), "bad file name: %s", err.msg);
		return http_send_error(c, MHD_HTTP_BAD_REQUEST, msg);
	}
	if (!node_file_kind(r->filename))
		return http_send_error(c, MHD_HTTP_UNSUPPORTED_MEDIA_TYPE, "a job is G-code "
					"(.gcode .gco .g), a model (.stl .obj .off .3mf) or .x3g");
	if (fflush(r->file))
		return http_send_error(c, MHD_HTTP_INTERNAL_SERVER_ERROR, "cannot hold the file");
	tried = json_array(); /* "NODE/PRINTER" of each printer that refused */
	for (int i = 0; i < FARM_TRIES && !(rc = farm_pick(f, r->profile, tried, &pick, &err));
	     i++) {
		status = send_job(r, &pick, answer, curl_err);
		if (status == MHD_HTTP_CREATED)
			break;
		farm_release(f, &pick);
		node_reason(answer, curl_err, why, sizeof(why));
		node_log("warning", NULL, 0, "farm: %s/%s did not take %s: %s%s", pick.node,
			 pick.printer, r->filename, status ? "" : "unreachable: ", why);
		if (status / 100 == 4 && status != MHD_HTTP_CONFLICT &&
		    status != MHD_HTTP_FORBIDDEN) {
			/* the file itself is refused: another printer would refuse it too
			 * (busy, or the farm's key refused, is that printer's alone) */
			json_decref(tried);
			snprintf(msg, sizeof(msg), "%s/%s refused the job: %s", pick.node,
				 pick.printer, why);
			return http_send_error(c, (unsigned)status, msg);
		}
		json_array_append_new(tried, json_sprintf("%s/%s", pick.node, pick.printer));
	}
	json_decref(tried);
	if (status != MHD_HTTP_CREATED && !rc)
		st_error_set(&err, ST_ERR_RANGE, "%d printers with the profile '%.100s' refused the "
				 "job", FARM_TRIES, r->profile);
	if (status != MHD_HTTP_CREATED) {
		snprintf(msg, sizeof(msg), "%s%s%s", err.msg, why[0] ? "; the last refusal: " : "",
			 why);
		return http_send_error(c, rc == ST_ERR_ARG ? MHD_HTTP_NOT_FOUND : MHD_HTTP_CONFLICT,
				       msg);
	}
	o = json_loads(answer, 0, NULL);
	job = json_integer_value(json_object_get(json_object_get(o, "stratum"), "job"));
	json_decref(o);
	node_log("info", NULL, 0, "farm: %s handed to %s/%s as job %lld (key %s)", r->filename,
		 pick.node, pick.printer, (long long)job, r->who ? r->who : "?");
	snprintf(loc, sizeof(loc), "%s/api/stratum/queue/%lld", pick.url, (long long)job);
	o = json_pack("{s:s,s:s,s:s,s:I,s:s}", "node", pick.node, "printer", pick.printer, "url",
		      pick.url, "job", job, "file", r->filename);
	return http_send_json(c, MHD_HTTP_CREATED, o, loc);
}

/* Decide what can be decided before the body: route, key, size. */
static void first_call(struct farm *f, struct MHD_Connection *c, const char *url,
		       const char *method, struct farm_req *r)
{
	const char *cl = MHD_lookup_connection_value(c, MHD_HEADER_KIND,
						     MHD_HTTP_HEADER_CONTENT_LENGTH);
	unsigned need;

	if (!strcmp(url, "/api/farm")) {
		r->route = FR_STATE;
		need = NODE_ROLE_READ;
		if (strcmp(method, "GET") && strcmp(method, "HEAD"))
			fail(r, MHD_HTTP_METHOD_NOT_ALLOWED, "method not allowed here (allowed: GET)");
	} else if (!strcmp(url, "/api/farm/jobs")) {
		r->route = FR_JOBS;
		need = NODE_ROLE_UPLOAD;
		if (strcmp(method, "POST"))
			fail(r, MHD_HTTP_METHOD_NOT_ALLOWED, "method not allowed here (allowed: POST)");
	} else {
		fail(r, MHD_HTTP_NOT_FOUND, "no such API call (GET /api/farm, POST /api/farm/jobs)");
		return;
	}
	if (!r->status && !(http_key_roles(&f->cfg.base, c, &r->who) & need))
		fail(r, MHD_HTTP_FORBIDDEN, r->who ? "the API key lacks the role this call needs"
						   : "a valid API key is needed (X-Api-Key)");
	if (r->status || r->route != FR_JOBS)
		return;
	if (cl && strtoull(cl, NULL, 10) > f->cfg.base.max_upload + HTTP_MULTIPART_SLACK)
		fail(r, MHD_HTTP_CONTENT_TOO_LARGE, "the job is larger than the farm's limit "
						    "(max_upload_mb)");
	else if (!(r->pp = MHD_create_post_processor(c, 65536, post_iter, r)))
		fail(r, MHD_HTTP_BAD_REQUEST, "a job is a multipart form with file and profile");
}

static enum MHD_Result handle_request(void *cls, struct MHD_Connection *c, const char *url,
				      const char *method, const char *version, const char *upload,
				      size_t *upload_size, void **con_cls)
{
	struct farm *f = cls;
	struct farm_req *r = *con_cls;

	(void)version;
	if (!r && !strcmp(method, "GET") && (!strcmp(url, "/") || !strcmp(url, "/index.html")))
		return http_send_page(c, farm_page);
	if (!r) {
		if (!(r = calloc(1, sizeof(*r))))
			return MHD_NO;
		*con_cls = r;
		first_call(f, c, url, method, r);
		if (r->status && http_refuse_at_once(c))
			return http_send_error(c, (unsigned)r->status, r->msg);
		return MHD_YES;
	}
	if (*upload_size) {
		r->raw += *upload_size;
		if (r->pp && r->raw > f->cfg.base.max_upload + HTTP_MULTIPART_SLACK)
			fail(r, MHD_HTTP_CONTENT_TOO_LARGE, "the job is larger than the farm's limit "
							    "(max_upload_mb)");
		if (!r->status && r->pp && MHD_post_process(r->pp, upload, *upload_size) != MHD_YES)
			fail(r, MHD_HTTP_BAD_REQUEST, "the multipart form is malformed");
		if (!r->status && !r->pp && r->raw > HTTP_DRAIN_MAX)
			fail(r, MHD_HTTP_CONTENT_TOO_LARGE, "the request body is too large");
		*upload_size = 0;
		if (r->status && r->raw > HTTP_DRAIN_MAX)
			return http_send_error(c, (unsigned)r->status, r->msg);
		return MHD_YES;
	}
	if (r->pp) {
		if (MHD_destroy_post_processor(r->pp) != MHD_YES)
			fail(r, MHD_HTTP_BAD_REQUEST, "the multipart form is incomplete (no closing "
						      "boundary)");
		r->pp = NULL;
	}
	if (r->status)
		return http_send_error(c, (unsigned)r->status, r->msg);
	if (r->route == FR_STATE)
		return http_send_json(c, MHD_HTTP_OK, farm_json(f), NULL);
	return dispatch(f, c, r);
}

/* Free a request's state once it is answered. */
static void free_request(void *request)
{
	struct farm_req *r = request;

	if (r->pp)
		MHD_destroy_post_processor(r->pp);
	if (r->file)
		fclose(r->file);
	free(r);
}

int farm_http_start(struct farm *f, struct st_error *err)
{
	const struct http_hooks hooks = {handle_request, free_request, NULL, f};
	const struct MHD_OptionItem extra[] = {
	    {MHD_OPTION_CONNECTION_LIMIT, (intptr_t)f->cfg.base.max_connections, NULL},
	    {MHD_OPTION_END, 0, NULL},
	};

	/* a thread per connection: a job being sent to a node holds its own */
	return http_server_start(&f->cfg.base,
				 MHD_USE_INTERNAL_POLLING_THREAD | MHD_USE_THREAD_PER_CONNECTION,
				 NULL, NULL, &hooks, extra, &f->httpd, &f->deadlines, &f->port, err);
}

void farm_http_stop(struct farm *f)
{
	http_server_stop(&f->httpd, &f->deadlines);
}
