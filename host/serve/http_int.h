/*
 * http_int.h - what the node's HTTP front (http.c: responses, upload,
 * routing) and its API handlers (http_api.c) share; host/serve/ only.
 */
#ifndef STRATUM_HOST_SERVE_HTTP_INT_H
#define STRATUM_HOST_SERVE_HTTP_INT_H

#include "st_file.h"
#include <jansson.h>
#include <microhttpd.h>
#include <stdbool.h>
#include <stdint.h>
#include <sys/stat.h>

#include "node_int.h"

#define HTTP_FIELD_MAX 1024 /* a form field other than the file */

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
	size_t len, body_cap;
	/* upload */
	struct MHD_PostProcessor *pp;
	struct st_file_out out; /* the upload's temporary file (st_file.h) */
	uint64_t bytes; /* of the file part */
	uint64_t raw;	/* of the whole body, as received */
	bool has_file;
	char filename[NODE_FILE_NAME_MAX + 2];
	size_t filename_len;
	char print[16], select[16], force[16], path[HTTP_FIELD_MAX];
	size_t path_len;
	/* per-job settings fields as "name\0value\0" pairs (cfgopt_field) */
	char sets[NODE_SETTINGS_MAX];
	size_t sets_len, nsets;
};

/* ---- responses (http.c) ---- */

/* Answer with body (stolen; NULL = no body) and status; location may be NULL. */
enum MHD_Result http_send_json(struct MHD_Connection *c, unsigned status, json_t *body,
			       const char *location);
/* Answer {"error": msg} with status. */
enum MHD_Result http_send_error(struct MHD_Connection *c, unsigned status, const char *msg);
/* Answer 204 No Content. */
enum MHD_Result http_no_content(struct MHD_Connection *c);

/* ---- handlers (http_api.c): each a route_fn ---- */

enum MHD_Result http_get_version(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_get_printer(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_get_job(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_get_connection(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_get_settings(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_get_profiles(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_get_file(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_get_queue(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_get_node(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_post_job(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_post_command(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_post_connection(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_post_bed_clear(struct node *n, struct MHD_Connection *c, struct req *r);

/* What the upload answer (http.c) uses: the file's URL, a checked relative
 * path (0 or ST_ERR_ARG), a file's JSON. */
void http_url_for(struct MHD_Connection *c, const struct req *r, const char *path,
		  const char *name, char *out, size_t cap);
int http_check_rel(const char *rel, size_t len, struct st_error *err);
json_t *http_file_json(struct MHD_Connection *c, const struct req *r, const char *rel,
		       const struct stat *st);

#endif /* STRATUM_HOST_SERVE_HTTP_INT_H */
