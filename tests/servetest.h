/*
 * servetest.h - what the suites that run `stratum serve` share (check_serve.c,
 * check_octoapi.c): a node as a child process on a loopback port with a
 * config of test keys, and HTTP spoken to it over plain sockets, byte for
 * byte as PrusaSlicer's libcurl sends it.
 */
#ifndef STRATUM_TESTS_SERVETEST_H
#define STRATUM_TESTS_SERVETEST_H

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>
#include <sys/types.h>

#define KEY_UP "upload-key-0123456789"	   /* read, upload */
#define KEY_CTL "control-key-0123456789"   /* read, upload, control */
#define KEY_READ "read-only-key-0123456789" /* read */
#define BOUNDARY "------------------------d74496d66958873e" /* curl's form: 24 '-' + 16 hex */
#define TWO_PRINTERS                                                                 \
	"[printer mk3s]\nprofile = prusa-i3-mk3s\nport = test-instant\n\n"          \
	"[printer ender]\nprofile = creality-ender-3\nport = test-instant\n"

/* A running node. */
struct node_proc {
	pid_t pid;
	int port;
	size_t log_end; /* log bytes before the current start */
	char dir[400], log[512], config[512];
};

/* An HTTP answer. */
struct resp {
	int status;
	char head[4096];
	char *body; /* NUL-terminated, malloc'd */
	json_t *json;
};

/* sv_write_config - np's config (test-node, the three keys above, listen on
 * any free port) with printers, lines of "[printer ...]" sections. */
void sv_write_config(struct node_proc *np, const char *printers, int max_mb);
/* sv_start - start the node of np's config; waits for its "listening" record. */
void sv_start(struct node_proc *np);
/* sv_start_cmd - the same for `stratum COMMAND --config` (serve, farm). */
void sv_start_cmd(struct node_proc *np, const char *command);
/* sv_stop - stop with SIGTERM and expect exit status 0. */
void sv_stop(struct node_proc *np);
/* sv_has_text - whether text contains needle, ignoring case (header names). */
bool sv_has_text(const char *text, const char *needle);
void sv_resp_free(struct resp *r);
/* sv_http_raw - send req (len bytes) and read the whole answer (Connection: close). */
void sv_http_raw(int port, const char *req, size_t len, struct resp *r);
/* sv_http - a request without body, or with a JSON one; auth is a header
 * line without CRLF ("X-Api-Key: ..."), or NULL. */
void sv_http(int port, const char *method, const char *path, const char *auth,
	     const char *json_body, struct resp *r);
/* sv_expect - a request whose answer must have status want. */
void sv_expect(int port, const char *method, const char *path, const char *auth,
	       const char *json_body, int want);
/* sv_call - sv_http whose answer must have status want; r keeps it (free it). */
void sv_call(int port, const char *method, const char *path, const char *auth,
	     const char *body, int want, struct resp *r);
/* sv_str - the string member key of o; aborts the test when there is none. */
const char *sv_str(const json_t *o, const char *key);
/*
 * sv_upload - the multipart upload as PrusaSlicer sends it (fields print,
 * path, then file; libcurl's layout).  path_len and name_len allow NUL
 * bytes; extra_headers go before the body; send_body false sends the head only.
 */
void sv_upload(int port, const char *prefix, const char *key, const char *name,
	       size_t name_len, const char *path, size_t path_len, const char *print,
	       const void *data, size_t size, const char *extra_headers, bool send_body,
	       struct resp *r);
/*
 * sv_trickle - the slow client (issue 20): send head[0], a request header
 * not yet whole, and head[1], a header with the start of a body, on two
 * connections to port, then one byte on each every 250 ms for up to max_s;
 * closed_at[i] is when the server closed connection i (s), 0 if it did not.
 */
void sv_trickle(int port, const char *const head[2], double closed_at[2], double max_s);
/* sv_cube_stl - a 10 x 10 x 5 mm binary STL box as bytes (malloc'd; free it). */
char *sv_cube_stl(size_t *len);
/* sv_upload_text - upload a G-code text as PrusaSlicer does. */
void sv_upload_text(int port, const char *prefix, const char *key, const char *name,
		    const char *gcode, const char *print, struct resp *r);
/* sv_job_state - the state of job id in prefix's queue (GET .../api/stratum/queue). */
const char *sv_job_state(int port, const char *prefix, long long id, bool *interrupted);
/* sv_wait_state - wait up to secs for job id to reach state want. */
void sv_wait_state(int port, const char *prefix, long long id, const char *want, int secs);
/* sv_job_of - the job number of an upload answer. */
long long sv_job_of(const struct resp *r);
/* sv_bed_clear - confirm prefix's bed clear; the answer must be want_status. */
void sv_bed_clear(int port, const char *prefix, int want_status);
/* sv_print_text - upload a G-code text to print on prefix's printer; the job number. */
long long sv_print_text(int port, const char *prefix, const char *name, const char *gcode);
/* sv_operational - wait until prefix's printer is connected (its worker
 * connects it after the node listens). */
void sv_operational(int port, const char *prefix);
/* sv_marlin_log - the numbered lines the simulated Marlin printer ran (its
 * log at path), from the one whose text is first on: each one's text, in
 * turn, to fn, once its number is checked to follow the last one's; the
 * driver's unnumbered probes are left out. */
void sv_marlin_log(const char *path, const char *first, void (*fn)(void *ctx, const char *text),
		   void *ctx);
/* sv_get_json - GET path with the read key; the JSON answer (caller decrefs). */
json_t *sv_get_json(int port, const char *path);

#endif /* STRATUM_TESTS_SERVETEST_H */
