/*
 * check_serve.c - `stratum serve` end to end: the node runs as a child
 * process on a loopback port and the tests speak HTTP to it over plain
 * sockets, sending requests byte for byte as PrusaSlicer's libcurl does
 * (the version check, the multipart upload: fields print, path, file, in
 * that order, curl's boundary form, X-Api-Key).  Covered: auth (403),
 * roles, oversize uploads (413, with and without Expect: 100-continue),
 * hostile file names, STL upload sliced and printed, two printers with
 * their own queues, pause/resume/cancel, kill -9 and restart with the queue
 * intact and the interrupted job marked, the bed-clear gate, and config
 * errors.  Printers use `port = test-instant` (docs/serve.md).
 */
#include <arpa/inet.h>
#include <check.h>
#include <errno.h>
#include <fcntl.h>
#include <jansson.h>
#include <netinet/in.h>
#include <signal.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "fixtures.h"
#include "meshio.h"
#include "suites.h"
#include "testutil.h"

#define KEY_UP "upload-key-0123456789"	   /* read, upload */
#define KEY_CTL "control-key-0123456789"   /* read, upload, control */
#define KEY_READ "read-only-key-0123456789" /* read */
#define BOUNDARY "------------------------d74496d66958873e" /* curl's form: 24 '-' + 16 hex */

/* A running node. */
struct node_proc {
	pid_t pid;
	int port;
	size_t log_end; /* log bytes before the current start */
	char dir[400], log[512], config[512];
};

/* Write the config with printers (lines of "[printer ...]" sections). */
static void write_config(struct node_proc *np, const char *printers, int max_mb)
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

#define TWO_PRINTERS                                                                 \
	"[printer mk3s]\nprofile = prusa-i3-mk3s\nport = test-instant\n\n"          \
	"[printer ender]\nprofile = creality-ender-3\nport = test-instant\n"

/* Start the node of np's config; waits for its "listening" record. */
static void node_start(struct node_proc *np)
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
		execl(bin, bin, "serve", "--config", np->config, (char *)NULL);
		_exit(127);
	}
	np->port = 0;
	for (int i = 0; i < 1000 && !np->port; i++) {
		FILE *f = fopen(np->log, "r");
		size_t n = f ? fread(buf, 1, sizeof(buf) - 1, f) : 0;
		char *at = NULL;

		if (f)
			fclose(f);
		buf[n] = '\0';
		/* The last "listening" line: the log is appended across restarts. */
		for (char *s = buf; (s = strstr(s, "listening on 127.0.0.1:")); s++)
			at = s;
		if (at && (!np->log_end || at > buf + np->log_end))
			np->port = atoi(at + strlen("listening on 127.0.0.1:"));
		if (!np->port)
			usleep(10000);
	}
	ck_assert_msg(np->port > 0, "the node did not start: %s", buf);
}

/* Stop with SIGTERM and expect exit status 0. */
static void node_stop(struct node_proc *np)
{
	int st;

	ck_assert(kill(np->pid, SIGTERM) == 0);
	ck_assert(waitpid(np->pid, &st, 0) == np->pid);
	ck_assert_msg(WIFEXITED(st) && WEXITSTATUS(st) == 0, "serve exit status %d", st);
}

/* Whether text contains needle, ignoring case (for header names). */
static bool has_text(const char *text, const char *needle)
{
	size_t n = strlen(needle);

	for (; *text; text++)
		if (!strncasecmp(text, needle, n))
			return true;
	return false;
}

/* An HTTP answer. */
struct resp {
	int status;
	char head[4096];
	char *body; /* NUL-terminated, malloc'd */
	json_t *json;
};

static void resp_free(struct resp *r)
{
	free(r->body);
	json_decref(r->json);
	memset(r, 0, sizeof(*r));
}

/* Send req (len bytes) to the node and read the whole answer (Connection: close). */
static void http_raw(int port, const char *req, size_t len, struct resp *r)
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
static void http(int port, const char *method, const char *path, const char *auth,
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
	http_raw(port, req, (size_t)n, r);
}

/* A request whose answer must have status want; the body is not needed. */
static void expect(int port, const char *method, const char *path, const char *auth,
		   const char *json_body, int want)
{
	struct resp r;

	http(port, method, path, auth, json_body, &r);
	ck_assert_msg(r.status == want, "%s %s: %d, not %d: %s", method, path, r.status, want,
		      r.body);
	resp_free(&r);
}

/*
 * The multipart upload as PrusaSlicer sends it (Http::form_add "print",
 * "path", then form_add_file "file"; libcurl's mime layout).  path_len and
 * name_len allow NUL bytes; extra_headers go before the body.
 */
static void upload(int port, const char *prefix, const char *key, const char *name,
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
		http_raw(port, all, (size_t)hn + (send_body ? n : 0), r);
		free(all);
	}
	free(req);
#undef PUT
#undef PUTS
}

/* Upload a G-code text as PrusaSlicer does. */
static void upload_text(int port, const char *prefix, const char *key, const char *name,
			const char *gcode, const char *print, struct resp *r)
{
	upload(port, prefix, key, name, strlen(name), "", 0, print, gcode, strlen(gcode), NULL,
	       true, r);
}

/* The state of job id in printer's queue (GET .../api/stratum/queue). */
static const char *job_state(int port, const char *prefix, long long id, bool *interrupted)
{
	static char state[32];
	char path[256];
	struct resp r;
	size_t i;
	json_t *j;

	snprintf(path, sizeof(path), "%s/api/stratum/queue", prefix);
	http(port, "GET", path, "X-Api-Key: " KEY_READ, NULL, &r);
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
	resp_free(&r);
	return state;
}

/* Wait up to secs for job id to reach state. */
static void wait_state(int port, const char *prefix, long long id, const char *want, int secs)
{
	const char *s = "";

	for (int i = 0; i < secs * 50; i++) {
		s = job_state(port, prefix, id, NULL);
		if (!strcmp(s, want))
			return;
		usleep(20000);
	}
	ck_abort_msg("job %lld is '%s', not '%s'", id, s, want);
}

/* The job number of an upload answer. */
static long long job_of(const struct resp *r)
{
	return (long long)json_integer_value(
		json_object_get(json_object_get(r->json, "stratum"), "job"));
}

static void bed_clear(int port, const char *prefix, int want_status)
{
	char path[256];
	struct resp r;

	snprintf(path, sizeof(path), "%s/api/stratum/bed-clear", prefix);
	http(port, "POST", path, "X-Api-Key: " KEY_CTL, "{}", &r);
	ck_assert_msg(r.status == want_status, "bed-clear: %d %s", r.status, r.body);
	resp_free(&r);
}

/* ---- tests ---------------------------------------------------------------- */

START_TEST(test_version_as_prusaslicer)
{
	struct node_proc np;
	struct resp r;
	const char *text;

	write_config(&np, TWO_PRINTERS, 8);
	node_start(&np);
	http(np.port, "GET", "/api/version", "X-Api-Key: " KEY_UP, NULL, &r);
	ck_assert_int_eq(r.status, 200);
	ck_assert_msg(has_text(r.head, "Content-Type: application/json"), "%s", r.head);
	/* PrusaSlicer's test(): "api" present, "text" starting with "OctoPrint". */
	ck_assert_str_eq(json_string_value(json_object_get(r.json, "api")), "0.1");
	ck_assert(json_is_string(json_object_get(r.json, "server")));
	text = json_string_value(json_object_get(r.json, "text"));
	ck_assert(text && !strncmp(text, "OctoPrint", 9));
	resp_free(&r);
	/* Bearer works as well, and under the printer's prefix. */
	expect(np.port, "GET", "/p/ender/api/version", "Authorization: Bearer " KEY_READ, NULL, 200);
	node_stop(&np);
}
END_TEST

START_TEST(test_auth)
{
	struct node_proc np;
	struct resp r;

	write_config(&np, TWO_PRINTERS, 8);
	node_start(&np);
	http(np.port, "GET", "/api/version", NULL, NULL, &r);
	ck_assert_int_eq(r.status, 403);
	ck_assert(json_is_string(json_object_get(r.json, "error")));
	resp_free(&r);
	expect(np.port, "GET", "/api/job", "X-Api-Key: " KEY_UP "x", NULL, 403);
	expect(np.port, "GET", "/api/job", "X-Api-Key: upload-key-012345678", NULL, 403); /* a prefix of a key is not the key */
	expect(np.port, "GET", "/api/printer", "Authorization: Bearer nope-nope-nope-nope", NULL, 403);
	/* Roles: read cannot upload; upload cannot control. */
	upload_text(np.port, "", KEY_READ, "a.gcode", "G28\n", "false", &r);
	ck_assert_int_eq(r.status, 403);
	resp_free(&r);
	upload_text(np.port, "", NULL, "a.gcode", "G28\n", "true", &r);
	ck_assert_int_eq(r.status, 403);
	resp_free(&r);
	expect(np.port, "POST", "/api/job", "X-Api-Key: " KEY_UP, "{\"command\":\"cancel\"}", 403);
	expect(np.port, "POST", "/api/printer/command", "X-Api-Key: " KEY_READ,
	     "{\"command\":\"G28\"}", 403);
	/* Nothing was stored by the refused uploads. */
	ck_assert(!tu_file_exists(tu_path("node/data/files/mk3s/a.gcode")));
	node_stop(&np);
}
END_TEST

START_TEST(test_upload_as_prusaslicer)
{
	struct node_proc np;
	struct resp r;
	json_t *local;
	long long id;
	const char *gcode = "; sliced elsewhere\nM104 S215\nG28\nG1 X10 Y10 F3000\nM140 S60\n";

	write_config(&np, TWO_PRINTERS, 8);
	node_start(&np);
	upload_text(np.port, "", KEY_UP, "part one.gcode", gcode, "true", &r);
	ck_assert_msg(r.status == 201, "%d %s", r.status, r.body);
	ck_assert_msg(has_text(r.head, "\r\nLocation: http://127.0.0.1:"), "%s", r.head);
	ck_assert_msg(strstr(r.head, "/api/files/local/part%20one.gcode"), "%s", r.head);
	local = json_object_get(json_object_get(r.json, "files"), "local");
	ck_assert_str_eq(json_string_value(json_object_get(local, "name")), "part one.gcode");
	ck_assert_str_eq(json_string_value(json_object_get(local, "origin")), "local");
	ck_assert(json_is_string(json_object_get(json_object_get(local, "refs"), "resource")));
	ck_assert(json_is_true(json_object_get(r.json, "done")));
	ck_assert(json_is_true(json_object_get(r.json, "effectivePrint")));
	id = job_of(&r);
	ck_assert(id > 0);
	resp_free(&r);
	wait_state(np.port, "/p/mk3s", id, "done", 10);
	/* Stored as is. */
	{
		FILE *f = fopen(tu_path("node/data/files/mk3s/part one.gcode"), "rb");
		char buf[256] = {0};

		ck_assert(f);
		ck_assert(fread(buf, 1, sizeof(buf) - 1, f) == strlen(gcode));
		fclose(f);
		ck_assert_str_eq(buf, gcode);
	}
	/* The job API names the file; the printer reports the temperatures it set. */
	http(np.port, "GET", "/api/job", "X-Api-Key: " KEY_READ, NULL, &r);
	ck_assert_int_eq(r.status, 200);
	ck_assert_str_eq(json_string_value(json_object_get(
				 json_object_get(json_object_get(r.json, "job"), "file"), "name")),
			 "part one.gcode");
	resp_free(&r);
	http(np.port, "GET", "/api/printer", "X-Api-Key: " KEY_READ, NULL, &r);
	ck_assert_int_eq(r.status, 200);
	ck_assert(json_real_value(json_object_get(
			  json_object_get(json_object_get(r.json, "temperature"), "tool0"),
			  "target")) == 215);
	resp_free(&r);
	/* GET /api/job always has job.file.name, null when nothing is selected. */
	http(np.port, "GET", "/p/ender/api/job", "X-Api-Key: " KEY_READ, NULL, &r);
	ck_assert_int_eq(r.status, 200);
	ck_assert(json_is_null(json_object_get(
		json_object_get(json_object_get(r.json, "job"), "file"), "name")));
	resp_free(&r);
	/* The other OctoPrint calls slicers read. */
	http(np.port, "GET", "/api/connection", "X-Api-Key: " KEY_READ, NULL, &r);
	ck_assert_int_eq(r.status, 200);
	ck_assert_str_eq(json_string_value(json_object_get(json_object_get(r.json, "current"),
							   "state")), "Operational");
	resp_free(&r);
	expect(np.port, "GET", "/api/settings", "X-Api-Key: " KEY_READ, NULL, 200);
	http(np.port, "GET", "/api/printerprofiles", "X-Api-Key: " KEY_READ, NULL, &r);
	ck_assert_int_eq(r.status, 200);
	ck_assert(json_real_value(json_object_get(json_object_get(json_object_get(json_object_get(
			  r.json, "profiles"), "mk3s"), "volume"), "width")) > 200);
	resp_free(&r);
	node_stop(&np);
}
END_TEST

START_TEST(test_oversize)
{
	struct node_proc np;
	struct resp r;
	size_t big = (1u << 20) + 30000; /* over 1 MiB, within the multipart slack */
	size_t huge = 3u << 20;		 /* the announced body of the first request */
	char *data = malloc(huge);

	ck_assert(data);
	memset(data, ';', huge);
	data[big - 1] = '\n';
	write_config(&np, TWO_PRINTERS, 1);
	node_start(&np);
	/* curl sends Expect: 100-continue for a large body and waits: answered at once. */
	upload(np.port, "", KEY_UP, "big.gcode", 9, "", 0, "false", data, huge,
	       "Expect: 100-continue\r\n", false, &r);
	ck_assert_int_eq(r.status, 413);
	resp_free(&r);
	/* A body over the limit sent in full is counted and refused. */
	upload(np.port, "", KEY_UP, "big.gcode", 9, "", 0, "false", data, big, NULL, true, &r);
	ck_assert_msg(r.status == 413, "%d %s", r.status, r.body);
	resp_free(&r);
	ck_assert(!tu_file_exists(tu_path("node/data/files/mk3s/big.gcode")));
	/* Just under the limit is fine. */
	upload(np.port, "", KEY_UP, "big.gcode", 9, "", 0, "false", data, 1u << 20, NULL, true,
	       &r);
	ck_assert_msg(r.status == 201, "%d %s", r.status, r.body);
	resp_free(&r);
	free(data);
	node_stop(&np);
}
END_TEST

START_TEST(test_hostile_names)
{
	static const struct {
		const char *name;
		size_t len;
		const char *path;
		size_t path_len;
		int status;
	} cases[] = {
		{"../x.gcode", 10, "", 0, 400},
		{"/tmp/x.gcode", 12, "", 0, 400},
		{"..\\x.gcode", 10, "", 0, 400},
		{".hidden.gcode", 13, "", 0, 400},
		{"x.gcode", 7, "../..", 5, 400},
		{"x.gcode", 7, "/../../tmp", 10, 400},
		{"x.gcode", 7, "a\0b", 3, 400},
		{"x\tx.gcode", 9, "", 0, 400},
		{"x.exe", 5, "", 0, 415},
		{"", 0, "", 0, 400},
	};
	char longname[400];
	struct node_proc np;
	struct resp r;

	write_config(&np, TWO_PRINTERS, 8);
	node_start(&np);
	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		upload(np.port, "", KEY_UP, cases[i].name, cases[i].len, cases[i].path,
		       cases[i].path_len, "false", "G28\n", 4, NULL, true, &r);
		ck_assert_msg(r.status == cases[i].status, "case %zu: %d %s", i, r.status, r.body);
		ck_assert(json_is_string(json_object_get(r.json, "error")));
		resp_free(&r);
	}
	memset(longname, 'a', sizeof(longname));
	memcpy(longname + sizeof(longname) - 6, ".gcode", 6);
	upload(np.port, "", KEY_UP, longname, sizeof(longname), "", 0, "false", "G28\n", 4, NULL,
	       true, &r);
	ck_assert_msg(r.status == 400, "%d %s", r.status, r.body);
	resp_free(&r);
	/* Nothing landed outside the files folder or in it. */
	ck_assert(!tu_file_exists(tu_path("node/data/files/x.gcode")));
	ck_assert(!tu_file_exists(tu_path("node/data/x.gcode")));
	ck_assert(!tu_file_exists(tu_path("node/x.gcode")));
	ck_assert(!tu_file_exists(tu_path("node/data/files/mk3s/x.exe")));
	/* A folder given in path is fine when its parts are. */
	upload(np.port, "", KEY_UP, "x.gcode", 7, "plates/left", 11, "false", "G28\n", 4, NULL,
	       true, &r);
	ck_assert_msg(r.status == 201, "%d %s", r.status, r.body);
	resp_free(&r);
	ck_assert(tu_file_exists(tu_path("node/data/files/mk3s/plates/left/x.gcode")));
	node_stop(&np);
}
END_TEST

/* An STL cube as a string of bytes. */
static char *cube_stl(size_t *len)
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

START_TEST(test_stl_two_printers)
{
	struct node_proc np;
	struct resp r;
	size_t len;
	char *stl = cube_stl(&len);
	long long a, b, c;

	write_config(&np, TWO_PRINTERS, 8);
	node_start(&np);
	upload(np.port, "/p/mk3s", KEY_UP, "cube.stl", 8, "", 0, "true", stl, len, NULL, true, &r);
	ck_assert_msg(r.status == 201, "%d %s", r.status, r.body);
	a = job_of(&r);
	resp_free(&r);
	upload_text(np.port, "/p/ender", KEY_UP, "hold.gcode", "G28\nG4 P1500\nG1 X5\n", "true", &r);
	ck_assert_int_eq(r.status, 201);
	b = job_of(&r);
	resp_free(&r);
	/* Both printers work at once: ender holds in its dwell while mk3s slices and prints. */
	wait_state(np.port, "/p/ender", b, "printing", 5);
	wait_state(np.port, "/p/mk3s", a, "done", 30);
	ck_assert_str_eq(job_state(np.port, "/p/ender", b, NULL), "printing");
	/* Each queue holds its own jobs only. */
	ck_assert_str_eq(job_state(np.port, "/p/mk3s", b, NULL), "");
	ck_assert_str_eq(job_state(np.port, "/p/ender", a, NULL), "");
	wait_state(np.port, "/p/ender", b, "done", 10);
	/* The sliced G-code is the profile's (PrusaSlicer-style layer comments). */
	{
		char path[600];
		FILE *f;
		char buf[1 << 16];
		size_t n;

		snprintf(path, sizeof(path), "%s/data/sliced/job-%lld.gcode", np.dir, a);
		f = fopen(path, "r");
		ck_assert_msg(f, "no %s", path);
		n = fread(buf, 1, sizeof(buf) - 1, f);
		buf[n] = '\0';
		fclose(f);
		ck_assert(strstr(buf, ";LAYER_CHANGE"));
	}
	/* Between jobs the printer waits until the bed is cleared. */
	upload_text(np.port, "/p/mk3s", KEY_UP, "next.gcode", "G28\n", "true", &r);
	c = job_of(&r);
	resp_free(&r);
	usleep(1500000);
	ck_assert_str_eq(job_state(np.port, "/p/mk3s", c, NULL), "queued");
	bed_clear(np.port, "/p/mk3s", 204);
	wait_state(np.port, "/p/mk3s", c, "done", 5);
	/* A model that is no solid fails with a message, the node goes on. */
	upload_text(np.port, "/p/ender", KEY_UP, "junk.stl", "solid x\nendsolid x\n", "true", &r);
	ck_assert_int_eq(r.status, 201);
	wait_state(np.port, "/p/ender", job_of(&r), "failed", 10);
	resp_free(&r);
	free(stl);
	node_stop(&np);
}
END_TEST

START_TEST(test_pause_resume_cancel)
{
	struct node_proc np;
	struct resp r;
	long long id;

	write_config(&np, TWO_PRINTERS, 8);
	node_start(&np);
	upload_text(np.port, "", KEY_UP, "long.gcode", "G28\nG4 P400\nG4 P400\nG4 P400\nG4 P20000\n",
		    "true", &r);
	id = job_of(&r);
	resp_free(&r);
	wait_state(np.port, "", id, "printing", 5);
	/* Overwriting the file being printed is refused. */
	upload_text(np.port, "", KEY_UP, "long.gcode", "G28\n", "false", &r);
	ck_assert_int_eq(r.status, 409);
	resp_free(&r);
	expect(np.port, "POST", "/api/job", "X-Api-Key: " KEY_CTL,
	     "{\"command\":\"pause\",\"action\":\"pause\"}", 204);
	ck_assert_str_eq(job_state(np.port, "", id, NULL), "paused");
	usleep(300000);
	http(np.port, "GET", "/api/job", "X-Api-Key: " KEY_READ, NULL, &r);
	ck_assert_str_eq(json_string_value(json_object_get(r.json, "state")), "Paused");
	resp_free(&r);
	/* Commands are taken between jobs only. */
	expect(np.port, "POST", "/api/printer/command", "X-Api-Key: " KEY_CTL,
	     "{\"commands\":[\"M105\"]}", 409);
	expect(np.port, "POST", "/api/job", "X-Api-Key: " KEY_CTL,
	     "{\"command\":\"pause\",\"action\":\"resume\"}", 204);
	ck_assert_str_eq(job_state(np.port, "", id, NULL), "printing");
	expect(np.port, "POST", "/api/job", "X-Api-Key: " KEY_CTL, "{\"command\":\"cancel\"}", 204);
	wait_state(np.port, "", id, "cancelled", 5);
	expect(np.port, "POST", "/api/job", "X-Api-Key: " KEY_CTL, "{\"command\":\"cancel\"}", 409); /* nothing printing */
	/* A bad command line is refused whole; a good one is accepted. */
	expect(np.port, "POST", "/api/printer/command", "X-Api-Key: " KEY_CTL,
	     "{\"commands\":[\"M105\",\"G1 X1 X2\"]}", 400);
	expect(np.port, "POST", "/api/printer/command", "X-Api-Key: " KEY_CTL,
	     "{\"command\":\"M105\"}", 204);
	expect(np.port, "POST", "/api/job", "X-Api-Key: " KEY_CTL, "not json", 400);
	node_stop(&np);
}
END_TEST

START_TEST(test_kill9_restart)
{
	struct node_proc np;
	struct resp r;
	long long a, b;
	bool interrupted = false;
	int st;

	write_config(&np, TWO_PRINTERS, 8);
	node_start(&np);
	upload_text(np.port, "", KEY_UP, "first.gcode", "G28\nG1 X1\nG4 S30\nG1 X2\nG1 X3\n", "true",
		    &r);
	a = job_of(&r);
	resp_free(&r);
	upload_text(np.port, "", KEY_UP, "second.gcode", "G28\n", "true", &r);
	b = job_of(&r);
	resp_free(&r);
	wait_state(np.port, "", a, "printing", 5);
	usleep(1200000); /* the progress ticker stores the position */
	ck_assert(kill(np.pid, SIGKILL) == 0);
	ck_assert(waitpid(np.pid, &st, 0) == np.pid);

	node_start(&np);
	/* Same jobs; the print is marked interrupted and not restarted on its own. */
	ck_assert_str_eq(job_state(np.port, "", a, &interrupted), "paused");
	ck_assert(interrupted);
	ck_assert_str_eq(job_state(np.port, "", b, NULL), "queued");
	http(np.port, "GET", "/api/job", "X-Api-Key: " KEY_READ, NULL, &r);
	ck_assert_str_eq(json_string_value(json_object_get(r.json, "state")), "Paused");
	ck_assert_str_eq(json_string_value(json_object_get(
				 json_object_get(json_object_get(r.json, "job"), "file"), "name")),
			 "first.gcode");
	ck_assert(json_integer_value(json_object_get(json_object_get(r.json, "progress"),
						     "filepos")) >= 14);
	resp_free(&r);
	usleep(1200000);
	ck_assert_str_eq(job_state(np.port, "", a, NULL), "paused");
	ck_assert_str_eq(job_state(np.port, "", b, NULL), "queued");
	/* The bed is not clear while the interrupted part is on it. */
	bed_clear(np.port, "", 409);
	/* Resume: it continues after the dwell it was in, then waits for the bed. */
	expect(np.port, "POST", "/api/job", "X-Api-Key: " KEY_CTL,
	     "{\"command\":\"pause\",\"action\":\"resume\"}", 204);
	wait_state(np.port, "", a, "done", 5);
	ck_assert_str_eq(job_state(np.port, "", b, NULL), "queued");
	bed_clear(np.port, "", 204);
	wait_state(np.port, "", b, "done", 5);
	node_stop(&np);
}
END_TEST

START_TEST(test_not_operational)
{
	struct node_proc np;
	struct resp r;

	write_config(&np, "[printer real]\nprofile = generic-marlin\nport = /dev/ttyACM9\n", 8);
	node_start(&np);
	expect(np.port, "GET", "/api/printer", "X-Api-Key: " KEY_READ, NULL, 409);
	http(np.port, "GET", "/p/real/api/connection", "X-Api-Key: " KEY_READ, NULL, &r);
	ck_assert_int_eq(r.status, 200);
	ck_assert_str_eq(json_string_value(json_object_get(json_object_get(r.json, "current"),
							   "state")), "Offline after error");
	resp_free(&r);
	/* Uploads still queue; nothing prints until the printer is there. */
	upload_text(np.port, "", KEY_UP, "wait.gcode", "G28\n", "true", &r);
	ck_assert_int_eq(r.status, 201);
	usleep(1200000);
	ck_assert_str_eq(job_state(np.port, "", job_of(&r), NULL), "queued");
	resp_free(&r);
	expect(np.port, "GET", "/api/nothing", "X-Api-Key: " KEY_READ, NULL, 404);
	node_stop(&np);
}
END_TEST

START_TEST(test_config_errors)
{
	static const struct {
		const char *text, *want;
	} cases[] = {
		{"[node]\ndata_dir = d\nlisten = 1.2.3:80\n", "line 3: listen:"},
		{"[node]\ndata_dir = d\n[key a]\nkey = short\nroles = read\n", "line 4: key:"},
		{"[node]\ndata_dir = d\n[key a]\nkey = 0123456789abcdef\nroles = read, admin\n",
		 "line 5: roles:"},
		{"[node]\ndata_dir = d\nmax_upload = 5\n", "line 3: unknown key 'max_upload'"},
		{"[node]\ndata_dir = d\n[key a]\nkey = 0123456789abcdef\nroles = read\n",
		 "no [printer NAME]"},
		{"[node]\ndata_dir = d\n[printer p]\nprofile = generic-marlin\nport = sim\n",
		 "no [key NAME]"},
		{"[node]\ndata_dir = d\n[key a]\nkey = 0123456789abcdef\nroles = read\n"
		 "[printer p]\nprofile = generic-marlin\nport = sim\nprefix = /api/x\n",
		 "line 9: prefix:"},
		{"[node]\ndata_dir = d\n[key a]\nkey = 0123456789abcdef\nroles = read\n"
		 "[printer p]\nprofile = no-such-printer\nport = sim\n",
		 "[printer p]"},
	};
	char out[4096];

	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		const char *path = tu_path("bad-node.ini");
		int rc;

		tu_write_str(path, cases[i].text);
		rc = tu_run(out, sizeof(out), "serve --config %s", path);
		ck_assert_msg(rc == 65, "case %zu: exit %d: %s", i, rc, out);
		ck_assert_msg(strstr(out, cases[i].want), "case %zu: %s", i, out);
	}
	ck_assert_int_eq(tu_run(out, sizeof(out), "serve"), 2);
	ck_assert_int_eq(tu_run(out, sizeof(out), "serve --config %s", tu_path("missing.ini")), 65);
}
END_TEST

Suite *serve_suite(void)
{
	Suite *s = suite_create("serve");
	TCase *tc = tcase_create("node");

	tcase_set_timeout(tc, 60);
	tcase_add_test(tc, test_version_as_prusaslicer);
	tcase_add_test(tc, test_auth);
	tcase_add_test(tc, test_upload_as_prusaslicer);
	tcase_add_test(tc, test_oversize);
	tcase_add_test(tc, test_hostile_names);
	tcase_add_test(tc, test_stl_two_printers);
	tcase_add_test(tc, test_pause_resume_cancel);
	tcase_add_test(tc, test_kill9_restart);
	tcase_add_test(tc, test_not_operational);
	tcase_add_test(tc, test_config_errors);
	suite_add_tcase(s, tc);
	return s;
}
