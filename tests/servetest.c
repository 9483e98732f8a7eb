/*
 * servetest.c - the helpers of servetest.h: the node as a child process,
 * raw HTTP requests, uploads as PrusaSlicer sends them, queue polling.
 */
#include <arpa/inet.h>
#include <check.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "fixtures.h"
#include "meshio.h"
#include "servetest.h"
#include "st_clock.h"
#include "testutil.h"

/* Write the config with printers (lines of "[printer ...]" sections). */
void sv_write_config(struct node_proc *np, const char *printers, int max_mb)
{
	char text[4096];

	ck_assert(snprintf(np->dir, sizeof(np->dir), "%s", tu_path("node")) < (int)sizeof(np->dir));
	mkdir(np->dir, 0700);
	snprintf(np->config, sizeof(np->config), "%s/node.ini", np->dir);
	snprintf(np->log, sizeof(np->log), "%s/node.log", np->dir);
	snprintf(text, sizeof(text),
		 "# test node\n[node]\nname = test-node\nlisten = 127.0.0.1:0\n"
		 "data_dir = data\nmax_upload_mb = %d\n\n"
		 "[key slicer]\nkey = " KEY_UP "\nroles = read, upload\n"
		 "[key operator]\nkey = " KEY_CTL "\nroles = read, upload, control\n"
		 "[key viewer]\nkey = " KEY_READ "\nroles = read\n\n%s",
		 max_mb, printers);
	tu_write_str(np->config, text);
}

/* Start the node of np's config; waits for its "listening" record. */
void sv_start(struct node_proc *np)
{
	sv_start_cmd(np, "serve");
}

void sv_start_cmd(struct node_proc *np, const char *command)
{
	const char *bin = getenv("STRATUM_BIN");
	char buf[8192];

	ck_assert_msg(bin != NULL, "STRATUM_BIN is not set");
	{
		struct stat st;

		np->log_end = stat(np->log, &st) ? 0 : (size_t)st.st_size;
	}
	np->pid = fork();
	ck_assert(np->pid >= 0);
	if (!np->pid) {
		int fd = open(np->log, O_WRONLY | O_CREAT | O_APPEND, 0600);

		dup2(fd, 2);
		execl(bin, bin, command, "--config", np->config, (char *)NULL);
		_exit(127);
	}
	np->port = 0;
	for (int i = 0; i < 1000 && !np->port; i++) {
		FILE *f = fopen(np->log, "r");
		size_t n = 0;
		char *at = NULL;

		/* This start's records only: the log is appended across restarts. */
		if (f && !fseek(f, (long)np->log_end, SEEK_SET))
			n = fread(buf, 1, sizeof(buf) - 1, f);
		if (f)
			fclose(f);
		buf[n] = '\0';
		at = strstr(buf, "listening on 127.0.0.1:");
		if (at)
			np->port = atoi(at + strlen("listening on 127.0.0.1:"));
		if (!np->port)
			usleep(10000);
	}
	ck_assert_msg(np->port > 0, "stratum %s did not start: %.3000s", command, buf);
}

/* Stop with SIGTERM and expect exit status 0. */
void sv_stop(struct node_proc *np)
{
	int st;

	ck_assert(kill(np->pid, SIGTERM) == 0);
	ck_assert(waitpid(np->pid, &st, 0) == np->pid);
	if (!WIFEXITED(st) || WEXITSTATUS(st)) {
		size_t len;
		char *log = tu_slurp(np->log, &len);

		/* the end of its log says why (a sanitizer's report, an error) */
		ck_abort_msg("exit status %d of the process of %s; its log ends: %s", st,
			     np->config, log + (len > 3000 ? len - 3000 : 0));
	}
}

/* Whether text contains needle, ignoring case (for header names). */
bool sv_has_text(const char *text, const char *needle)
{
	size_t n = strlen(needle);

	for (; *text; text++)
		if (!strncasecmp(text, needle, n))
			return true;
	return false;
}

void sv_resp_free(struct resp *r)
{
	free(r->body);
	json_decref(r->json);
	memset(r, 0, sizeof(*r));
}

/* Send req (len bytes) to the node and read the whole answer (Connection: close). */
void sv_http_raw(int port, const char *req, size_t len, struct resp *r)
{
	struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
	struct timeval tv = {.tv_sec = 20};
	size_t cap = 1 << 16, got = 0;
	char *buf = malloc(cap), *end;
	int fd = socket(AF_INET, SOCK_STREAM, 0);
	ssize_t n;

	memset(r, 0, sizeof(*r));
	ck_assert(fd >= 0 && buf);
	inet_pton(AF_INET, "127.0.0.1", &sa.sin_addr);
	setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof(tv));
	ck_assert_msg(connect(fd, (struct sockaddr *)&sa, sizeof(sa)) == 0, "connect: %s",
		      strerror(errno));
	for (size_t done = 0; done < len; done += (size_t)n) {
		n = send(fd, req + done, len - done, MSG_NOSIGNAL);
		if (n <= 0)
			break; /* the node may answer and close early: read what it said */
	}
	while ((n = recv(fd, buf + got, cap - got - 1, 0)) > 0) {
		got += (size_t)n;
		if (got + 1 == cap) {
			buf = realloc(buf, cap *= 2);
			ck_assert(buf);
		}
	}
	close(fd);
	buf[got] = '\0';
	ck_assert_msg(sscanf(buf, "HTTP/1.1 %d", &r->status) == 1, "no HTTP answer: '%s'", buf);
	end = strstr(buf, "\r\n\r\n");
	ck_assert(end);
	snprintf(r->head, sizeof(r->head), "%.*s", (int)(end - buf), buf);
	r->body = strdup(end + 4);
	r->json = json_loads(r->body, JSON_DECODE_ANY, NULL);
	free(buf);
}

/* A request without body (or a JSON one) with the key header given (may be NULL). */
void sv_http(int port, const char *method, const char *path, const char *auth,
		 const char *json_body, struct resp *r)
{
	char req[8192];
	int n = snprintf(req, sizeof(req),
			 "%s %s HTTP/1.1\r\nHost: 127.0.0.1:%d\r\nUser-Agent: PrusaSlicer/2.7.1\r\n"
			 "Accept: */*\r\n%s%s%sConnection: close\r\n",
			 method, path, port, auth ? auth : "", auth ? "\r\n" : "", "");
	if (json_body)
		n += snprintf(req + n, sizeof(req) - (size_t)n,
			      "Content-Type: application/json\r\nContent-Length: %zu\r\n\r\n%s",
			      strlen(json_body), json_body);
	else
		n += snprintf(req + n, sizeof(req) - (size_t)n, "\r\n");
	sv_http_raw(port, req, (size_t)n, r);
}

/* A request whose answer must have status want; the body is not needed. */
void sv_expect(int port, const char *method, const char *path, const char *auth,
		   const char *json_body, int want)
{
	struct resp r;

	sv_http(port, method, path, auth, json_body, &r);
	ck_assert_msg(r.status == want, "%s %s: %d, not %d: %s", method, path, r.status, want,
		      r.body);
	sv_resp_free(&r);
}

/*
 * The multipart upload as PrusaSlicer sends it (Http::form_add "print",
 * "path", then form_add_file "file"; libcurl's mime layout).  path_len and
 * name_len allow NUL bytes; extra_headers go before the body.
 */
void sv_upload(int port, const char *prefix, const char *key, const char *name,
		   size_t name_len, const char *path, size_t path_len, const char *print,
		   const void *data, size_t size, const char *extra_headers, bool send_body,
		   struct resp *r)
{
	size_t cap = size + 4096 + name_len + path_len, n = 0, body_start;
	char *req = malloc(cap), head[1024];
	int hn;

	ck_assert(req);
#define PUT(s, l) (memcpy(req + n, (s), (l)), n += (l))
#define PUTS(s) PUT((s), strlen(s))
	PUTS("--" BOUNDARY "\r\nContent-Disposition: form-data; name=\"print\"\r\n\r\n");
	PUTS(print);
	PUTS("\r\n--" BOUNDARY "\r\nContent-Disposition: form-data; name=\"path\"\r\n\r\n");
	PUT(path, path_len);
	PUTS("\r\n--" BOUNDARY "\r\nContent-Disposition: form-data; name=\"file\"; filename=\"");
	PUT(name, name_len);
	PUTS("\"\r\nContent-Type: application/octet-stream\r\n\r\n");
	PUT(data, size);
	PUTS("\r\n--" BOUNDARY "--\r\n");
	body_start = n;
	hn = snprintf(head, sizeof(head),
		      "POST %s/api/files/local HTTP/1.1\r\nHost: 127.0.0.1:%d\r\n"
		      "User-Agent: PrusaSlicer/2.7.1\r\nAccept: */*\r\n%s%s%s"
		      "Connection: close\r\nContent-Length: %zu\r\n%s"
		      "Content-Type: multipart/form-data; boundary=" BOUNDARY "\r\n\r\n",
		      prefix, port, key ? "X-Api-Key: " : "", key ? key : "", key ? "\r\n" : "",
		      body_start, extra_headers ? extra_headers : "");
	{
		char *all = malloc((size_t)hn + n);

		ck_assert(all);
		memcpy(all, head, (size_t)hn);
		memcpy(all + hn, req, n);
		sv_http_raw(port, all, (size_t)hn + (send_body ? n : 0), r);
		free(all);
	}
	free(req);
#undef PUT
#undef PUTS
}

/* Upload a G-code text as PrusaSlicer does. */
void sv_upload_text(int port, const char *prefix, const char *key, const char *name,
			const char *gcode, const char *print, struct resp *r)
{
	sv_upload(port, prefix, key, name, strlen(name), "", 0, print, gcode, strlen(gcode), NULL,
	       true, r);
}

/* The state of job id in printer's queue (GET .../api/stratum/queue). */
const char *sv_job_state(int port, const char *prefix, long long id, bool *interrupted)
{
	static char state[32];
	char path[256];
	struct resp r;
	size_t i;
	json_t *j;

	snprintf(path, sizeof(path), "%s/api/stratum/queue", prefix);
	sv_http(port, "GET", path, "X-Api-Key: " KEY_READ, NULL, &r);
	ck_assert_int_eq(r.status, 200);
	state[0] = '\0';
	json_array_foreach(json_object_get(r.json, "jobs"), i, j) {
		if (json_integer_value(json_object_get(j, "id")) == id) {
			snprintf(state, sizeof(state), "%s",
				 json_string_value(json_object_get(j, "state")));
			if (interrupted)
				*interrupted = json_is_true(json_object_get(j, "interrupted"));
		}
	}
	sv_resp_free(&r);
	return state;
}

/* Wait up to secs for job id to reach state. */
void sv_wait_state(int port, const char *prefix, long long id, const char *want, int secs)
{
	const char *s = "";

	for (int i = 0; i < secs * 50; i++) {
		s = sv_job_state(port, prefix, id, NULL);
		if (!strcmp(s, want))
			return;
		usleep(20000);
	}
	ck_abort_msg("job %lld is '%s', not '%s'", id, s, want);
}

/* The job number of an upload answer. */
long long sv_job_of(const struct resp *r)
{
	return (long long)json_integer_value(
		json_object_get(json_object_get(r->json, "stratum"), "job"));
}

void sv_bed_clear(int port, const char *prefix, int want_status)
{
	char path[256];
	struct resp r;

	snprintf(path, sizeof(path), "%s/api/stratum/bed-clear", prefix);
	sv_http(port, "POST", path, "X-Api-Key: " KEY_CTL, "{}", &r);
	ck_assert_msg(r.status == want_status, "bed-clear: %d %s", r.status, r.body);
	sv_resp_free(&r);
}

/* Upload a G-code text to print on prefix's printer; the job number. */
long long sv_print_text(int port, const char *prefix, const char *name, const char *gcode)
{
	struct resp r;
	long long id;

	sv_upload_text(port, prefix, KEY_UP, name, gcode, "true", &r);
	ck_assert_msg(r.status == 201, "%d %s", r.status, r.body);
	id = sv_job_of(&r);
	sv_resp_free(&r);
	return id;
}

/* GET path with the read key; the JSON answer (caller decrefs). */
void sv_operational(int port, const char *prefix)
{
	char path[128];
	struct resp r;

	snprintf(path, sizeof(path), "%s/api/printer", prefix);
	for (int i = 0; i < 500; i++) {
		int status;

		sv_http(port, "GET", path, "X-Api-Key: " KEY_READ, NULL, &r);
		status = r.status;
		sv_resp_free(&r);
		if (status == 200)
			return;
		usleep(20000);
	}
	ck_abort_msg("%s is not operational", prefix);
}

void sv_marlin_log(const char *path, const char *first, void (*fn)(void *ctx, const char *text),
		   void *ctx)
{
	FILE *log = fopen(path, "r");
	char line[512];
	const char *text;
	long n, last = -1;
	bool started = false;

	ck_assert_msg(log, "no simulator log %s", path);
	while (tu_marlin_log_next(log, line, sizeof(line), &n, &text)) {
		started = started || !strcmp(text, first);
		if (!started)
			continue;
		ck_assert_msg(last < 0 || n == last + 1, "line %ld ran after line %ld", n, last);
		last = n;
		fn(ctx, text);
	}
	fclose(log);
	ck_assert_msg(started, "'%s' did not run (%s)", first, path);
}

json_t *sv_get_json(int port, const char *path)
{
	struct resp r;
	json_t *o;

	sv_http(port, "GET", path, "X-Api-Key: " KEY_READ, NULL, &r);
	ck_assert_msg(r.status == 200, "GET %s: %d %s", path, r.status, r.body);
	o = json_incref(r.json);
	sv_resp_free(&r);
	return o;
}

/* sv_http whose answer must have status want. */
void sv_call(int port, const char *method, const char *path, const char *auth,
	     const char *body, int want, struct resp *r)
{
	sv_http(port, method, path, auth, body, r);
	ck_assert_msg(r->status == want, "%s %s: %d, not %d: %s", method, path, r->status, want,
		      r->body);
}

/* The string member key of o, which must be there. */
const char *sv_str(const json_t *o, const char *key)
{
	const char *s = json_string_value(json_object_get(o, key));

	ck_assert_msg(s, "no string %s in %s", key, json_dumps(o, 0));
	return s;
}

char *sv_cube_stl(size_t *len)
{
	const char *path = tu_path("cube.stl");
	struct st_error err = {0};
	struct mesh *m = fx_box(0, 0, 0, 10, 10, 5);
	FILE *f;
	char *buf;

	ck_assert_int_eq(meshio_write_stl(path, m, MESHIO_STL_BINARY, &err), 0);
	mesh_free(m);
	f = fopen(path, "rb");
	ck_assert(f);
	buf = malloc(4096);
	*len = fread(buf, 1, 4096, f);
	fclose(f);
	return buf;
}

/* Whether the server has closed fd (a read finds its end or a reset). */
static bool closed_by_server(int fd)
{
	char buf[256];
	ssize_t k;

	while ((k = recv(fd, buf, sizeof(buf), MSG_DONTWAIT)) > 0)
		;
	return k == 0 || (k < 0 && errno != EAGAIN && errno != EWOULDBLOCK);
}

void sv_trickle(int port, const char *const head[2], double closed_at[2], double max_s)
{
	struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
	int fd[2];
	double t0;

	inet_pton(AF_INET, "127.0.0.1", &sa.sin_addr);
	for (int i = 0; i < 2; i++) {
		fd[i] = socket(AF_INET, SOCK_STREAM, 0);
		ck_assert(fd[i] >= 0);
		ck_assert_msg(connect(fd[i], (struct sockaddr *)&sa, sizeof(sa)) == 0,
			      "connect: %s", strerror(errno));
		ck_assert(send(fd[i], head[i], strlen(head[i]), MSG_NOSIGNAL) ==
			  (ssize_t)strlen(head[i]));
		closed_at[i] = 0;
	}
	t0 = st_mono_s();
	while (st_mono_s() - t0 < max_s && !(closed_at[0] && closed_at[1])) {
		usleep(250000);
		for (int i = 0; i < 2; i++) {
			if (closed_at[i])
				continue;
			if (closed_by_server(fd[i]))
				closed_at[i] = st_mono_s() - t0;
			else
				send(fd[i], i ? "x" : "X", 1, MSG_NOSIGNAL);
		}
	}
	close(fd[0]);
	close(fd[1]);
}
