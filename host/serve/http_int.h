/*
 * http_int.h - what the node's HTTP front (http.c: responses, upload,
 * routing) and its API handlers share: http_api.c (state, job, settings,
 * profiles), http_queue.c (Stratum's queue API), http_files.c (file list and operations, downloads),
 * http_printer.c (tool, bed, print head, SD, chamber) and http_account.c
 * (login, user, server, system commands); host/serve/ only.
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
#define HTTP_MULTIPART_SLACK 65536 /* multipart headers and fields around the file */
#define HTTP_DRAIN_MAX 65536	    /* body read before refusing, bytes */
#define HTTP_OCTOPRINT_VERSION "1.10.0" /* the OctoPrint version answered (/api/version, /api/server) */

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
	char allow[64];		    /* the methods of route_path, for Allow */
	bool options;		    /* an OPTIONS request: answered with allow */
	unsigned roles;		    /* of the request's key (enum node_role), 0 none */
	const char *key_name;	    /* that key's [key NAME], NULL none */
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
	char foldername[NODE_FILE_NAME_MAX + 2]; /* OctoPrint's new folder (no file part) */
	size_t foldername_len;
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
/* http_refuse_at_once - whether a refusal is answered before the body: the
 * client waits for 100 Continue, or the body is chunked or longer than
 * HTTP_DRAIN_MAX (answering early may reset a connection with unread
 * bytes, so a small body is read first).  The node's API and the farm's. */
bool http_refuse_at_once(struct MHD_Connection *c);
/* Answer with page, a static HTML page whose script is inline (page.c,
 * farm_page.c): nothing loaded from elsewhere (the Content-Security-Policy). */
enum MHD_Result http_send_page(struct MHD_Connection *c, const char *page);
/* Answer 204 No Content. */
enum MHD_Result http_no_content(struct MHD_Connection *c);
/* The roles of the request's key among cfg's keys (X-Api-Key, Authorization:
 * Bearer, or OctoPrint's ?apikey=, in that order); 0 if none.  *who the
 * key's name.  The node's API and the farm view's alike. */
unsigned http_key_roles(const struct node_config *cfg, struct MHD_Connection *c,
			const char **who);

/* ---- a printer's state for one answer (http_api.c) ---- */

/* A consistent view of a printer for one answer. */
struct http_view {
	bool connected, printing, paused, pausing;
	char conn_error[256];
	char link_desc[128];
	int64_t job_id;
	int64_t filepos, size;
	long layer;		/* of the last confirmed command (0-based), -1 unknown */
	double z;		/* its Z (mm), NAN unknown */
	double tool[3], bed[3]; /* actual, target, offset (tool 0) */
	double tool_offset[NODE_PRINT_TOOLS]; /* every tool's offset */
	double tool1[2]; /* the second extruder's actual, target; NAN unknown */
	bool has_job;
	struct node_job job; /* the active job (printing, paused, slicing), if has_job */
	char selected[NODE_PATH_MAX];
	bool bed_clear; /* an operator confirmed the bed clear since the last print */
};

/* The state text while the bed waits for an operator's confirmation. */
#define HTTP_STATE_BED "Waiting for bed clear"

void http_take_view(struct node *n, struct node_printer *p, struct http_view *v);
/* OctoPrint's state text of v ("Operational", "Printing", ...). */
const char *http_state_text(const struct http_view *v);
/* The temperature object of /api/printer and /api/printer/tool: tool0,
 * and tool1 ... for each further extruder of p's profile (actual and target
 * null unless read: Sailfish reads tool 1); bed when with_bed. */
json_t *http_temps_json(const struct node_printer *p, const struct http_view *v, bool tools,
			bool with_bed);
/* OctoPrint's state flags of v (operational, printing, paused, ready ...). */
json_t *http_flags_json(const struct http_view *v);
/* The /api/job answer for p (job, progress, state; stratum's job), and the
 * view it was made of in *out when out is not NULL. */
json_t *http_job_json(struct node *n, struct node_printer *p, struct http_view *out);
/* p's temperature history, oldest first, its last limit samples (0: all),
 * as OctoPrint's history entries ({"time", "tool0": {"actual", "target"},
 * "bed": ...}), with the tools and/or the bed. */
json_t *http_temp_history(struct node_printer *p, int limit, bool tools, bool bed);
/* Add "history" to the temperature object temps when the query asks for
 * it (?history=true, ?limit=N). */
void http_add_history(struct MHD_Connection *c, struct node_printer *p, json_t *temps,
		      bool tools, bool bed);
/* The JSON object of the body, or NULL with the error answer sent in *ret. */
json_t *http_body_json(struct MHD_Connection *c, struct req *r, enum MHD_Result *ret);
/* Queue count checked G-code lines for p's worker: sent between jobs or,
 * when the printer's link takes them (Marlin, Sailfish with a G-code file),
 * between two lines of the print: while it is paused (a jog, an extrusion:
 * OctoPrint takes them then) or, for in_print lines, while it runs.  204,
 * or 409 when not operational, the queue is full, or printing and the
 * lines cannot go in. */
enum MHD_Result http_queue_lines(struct MHD_Connection *c, struct node_printer *p,
				 char lines[][NODE_CMD_MAX], size_t count, bool in_print);
/* Queue p's selected file (POST /api/job "start"); p->mu held.  204, 409
 * when nothing is selected or the file is gone. */
enum MHD_Result http_start_selected(struct node *n, struct MHD_Connection *c,
				    struct node_printer *p);
/* Tell the push clients that p's files changed (UpdatedFiles). */
void http_files_changed(struct node_printer *p);
/* The route path after the route's prefix ("a/b.gcode" of /api/files/local/a/b.gcode). */
const char *http_tail(const struct req *r);

/* ---- handlers: each a route_fn ---- */

enum MHD_Result http_get_version(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_get_printer(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_get_job(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_get_connection(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_get_settings(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_post_settings(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_get_profiles(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_get_file(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_get_node(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_post_job(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_post_command(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_post_connection(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_get_profile(struct node *n, struct MHD_Connection *c, struct req *r);
/* http_queue.c; http_queue_json: p's queue for the push API's current
 * messages, {"bedClear", "waiting": [jobs in order, with "position"]}. */
json_t *http_queue_json(struct node *n, struct node_printer *p, const struct http_view *v);
enum MHD_Result http_get_queue(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_get_queue_job(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_post_queue_job(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_post_bed_clear(struct node *n, struct MHD_Connection *c, struct req *r);
/* http_files.c; http_make_folder: an upload form with foldername and no
 * file, OctoPrint's way to create a folder under path. */
enum MHD_Result http_make_folder(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_get_files(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_post_file(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_delete_file(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_download_file(struct node *n, struct MHD_Connection *c, struct req *r);
/* http_printer.c */
enum MHD_Result http_get_tool(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_post_tool(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_get_bed(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_post_bed(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_chamber(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_post_printhead(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_sd(struct node *n, struct MHD_Connection *c, struct req *r);
/* http_account.c */
enum MHD_Result http_get_server(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_post_login(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_get_currentuser(struct node *n, struct MHD_Connection *c, struct req *r);
enum MHD_Result http_get_system_commands(struct node *n, struct MHD_Connection *c, struct req *r);

/* What the upload answer (http.c) and the file calls use: the file's URL,
 * a checked relative path (0 or ST_ERR_ARG), a file's JSON. */
void http_url_for(struct MHD_Connection *c, const struct req *r, const char *path,
		  const char *name, char *out, size_t cap);
int http_check_rel(const char *rel, size_t len, struct st_error *err);
json_t *http_file_json(struct MHD_Connection *c, const struct req *r, const char *rel,
		       const struct stat *st);

/* push.c: OctoPrint's push API (SockJS over WebSocket).  node_push_route
 * answers path (after the printer's prefix) when it is one of /sockjs/...:
 * true with *ret.  node_push_stop closes every client and waits for their
 * threads (before the HTTP daemon stops).  node_push_session: the session
 * a key's passive login gives and its auth message carries (hex, derived
 * from the secret, which it does not reveal). */
#define NODE_PUSH_SESSION_LEN 32
bool node_push_route(struct node *n, struct node_printer *p, struct MHD_Connection *c,
		     const char *path, enum MHD_Result *ret);
void node_push_stop(struct node *n);
void node_push_session(const char *secret, char out[NODE_PUSH_SESSION_LEN + 1]);

/*
 * http_deadline.c - an HTTP server on libmicrohttpd with the bounds on a
 * slow client (docs/serve.md, "Limits") that libmicrohttpd's inactivity
 * time-out does not give: the header whole within cfg's header_timeout_s,
 * the body at min_body_rate.  The node's server (http.c) and the farm
 * view's (farm_http.c) each give their request handler and how to free
 * what it keeps per request; the bounds see every call of the handler and
 * every connection's start and close.
 */
struct http_hooks {
	/* libmicrohttpd's request handler, called with cls; it keeps its
	 * state in *con_cls from the first call on */
	MHD_AccessHandlerCallback handle;
	void (*free_request)(void *request); /* the state it kept, once answered */
	void (*closed)(void *cls);	     /* a connection closed; may be NULL */
	void *cls;
};
struct http_deadlines;
/*
 * http_server_start - listen on cfg's listen_addr:listen_port with
 * libmicrohttpd's flags, cfg's idle_timeout_s and max_connections_per_ip
 * and the options in extra (up to MHD_OPTION_END); accept (may be NULL)
 * admits a connection, with accept_cls.  Sets *httpd, *deadlines and *port
 * (the port bound: cfg's, or the one given for 0).  0, or ST_ERR_ARG (the
 * address is not IPv4), ST_ERR_IO (cannot listen) or ST_ERR_NOMEM with
 * nothing started.
 */
int http_server_start(const struct node_config *cfg, unsigned flags,
		      MHD_AcceptPolicyCallback accept, void *accept_cls,
		      const struct http_hooks *hooks, const struct MHD_OptionItem *extra,
		      struct MHD_Daemon **httpd, struct http_deadlines **deadlines, uint16_t *port,
		      struct st_error *err);
/* http_server_stop - stop the server (closing its connections), then its bounds. */
void http_server_stop(struct MHD_Daemon **httpd, struct http_deadlines **deadlines);

#endif /* STRATUM_HOST_SERVE_HTTP_INT_H */
