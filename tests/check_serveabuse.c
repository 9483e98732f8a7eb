/*
 * check_serveabuse.c - `stratum serve` bounded under abuse (issue 20 item 4):
 * a chunked body refused and its connection ended, malformed multipart
 * forms and a second file part refused whole, tmp/ cleaned at start, keys
 * in a query kept out of the log, per-address connection limits, slow
 * headers and bodies cut, the key checked before a body is read, a part
 * without a name.  Part of the `serve` suite (check_serve.c).
 */

#include <arpa/inet.h>
#include <check.h>
#include <errno.h>
#include <fcntl.h>
#include <jansson.h>
#include <math.h>
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

#include <mosquitto.h>
#include <pthread.h>
#include <sqlite3.h>

#include "fixtures.h"
#include "gcode.h"
#include "meshio.h"
#include "mqtttest.h"
#include "sfcheck.h"
#include "st_clock.h"
#include "suites.h"
#include "servetest.h"
#include "testutil.h"

/*
 * Send a chunked body to path with key for up to 3 s; returns the bytes
 * sent before the node ended the connection (or all of them if it never did).
 */
static size_t chunked_sent(int port, const char *path, const char *key, const char *type)
{
	struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
	struct timeval tv = {.tv_sec = 1};
	static char chunk[65536 + 16];
	char head[512];
	int fd = socket(AF_INET, SOCK_STREAM, 0), n;
	size_t sent = 0;
	time_t t0 = time(NULL);

	ck_assert(fd >= 0);
	inet_pton(AF_INET, "127.0.0.1", &sa.sin_addr);
	setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof(tv));
	ck_assert(connect(fd, (struct sockaddr *)&sa, sizeof(sa)) == 0);
	n = snprintf(head, sizeof(head), "POST %s HTTP/1.1\r\nHost: x\r\nX-Api-Key: %s\r\n"
			 "Content-Type: %s\r\nTransfer-Encoding: chunked\r\n\r\n", path, key, type);
	ck_assert(send(fd, head, (size_t)n, MSG_NOSIGNAL) == n);
	memcpy(chunk, "10000\r\n", 7);
	memset(chunk + 7, ' ', 65536);
	memcpy(chunk + 7 + 65536, "\r\n", 2);
	while (time(NULL) - t0 < 3) {
		ssize_t k = send(fd, chunk, 65536 + 9, MSG_NOSIGNAL);

		if (k <= 0 && errno != EAGAIN)
			break;
		sent += k > 0 ? (size_t)k : 0;
	}
	close(fd);
	return sent;
}

/* A chunked body has no length to refuse up front: once refused in its
 * course (too large), the node stops reading it (issue 20). */
START_TEST(test_chunked_refused_stops)
{
	struct node_proc np;
	size_t sent;

	sv_write_config(&np, TWO_PRINTERS, 1);
	sv_start(&np);
	sent = chunked_sent(np.port, "/api/job", KEY_CTL, "application/json");
	ck_assert_msg(sent < (16u << 20), "%zu bytes", sent);
	sent = chunked_sent(np.port, "/api/files/local", KEY_UP,
			    "multipart/form-data; boundary=" BOUNDARY);
	ck_assert_msg(sent < (16u << 20), "%zu bytes", sent);
	sv_expect(np.port, "GET", "/api/version", "X-Api-Key: " KEY_READ, NULL, 200);
	sv_stop(&np);
}
END_TEST

/* POST a multipart body (boundary BOUNDARY) to /api/files/local with KEY_UP. */
static void post_form(int port, const char *body, struct resp *r)
{
	char req[4096];
	int n = snprintf(req, sizeof(req),
			 "POST /api/files/local HTTP/1.1\r\nHost: 127.0.0.1:%d\r\n"
			 "X-Api-Key: " KEY_UP "\r\nConnection: close\r\nContent-Length: %zu\r\n"
			 "Content-Type: multipart/form-data; boundary=" BOUNDARY "\r\n\r\n%s",
			 port, strlen(body), body);

	ck_assert(n < (int)sizeof(req));
	sv_http_raw(port, req, (size_t)n, r);
}

/* Whether dir holds no entry but . and .. */
static bool dir_empty(const char *dir)
{
	char cmd[600];

	snprintf(cmd, sizeof(cmd), "test -z \"$(ls -A '%s')\"", dir);
	return system(cmd) == 0;
}

/* Forms the node must refuse whole (issue 20): cut off before the closing
 * boundary, or with two file parts; nothing is stored of either. */
START_TEST(test_malformed_forms)
{
#define FILE_PART(name) "--" BOUNDARY "\r\nContent-Disposition: form-data; name=\"file\"; " \
			"filename=\"" name "\"\r\nContent-Type: application/octet-stream\r\n\r\n"
	static const char cut[] = FILE_PART("cut.gcode") "G28\nG1 X10\n";
	static const char two[] = FILE_PART("a.gcode") "G28\n\r\n" FILE_PART("b.gcode")
		"G1 X5\n\r\n--" BOUNDARY "--\r\n";
	static const char same[] = FILE_PART("a.gcode") "G28\n\r\n" FILE_PART("a.gcode")
		"G1 X5\n\r\n--" BOUNDARY "--\r\n";
	static const char ok[] = FILE_PART("ok.gcode") "G28\n\r\n--" BOUNDARY "--\r\n";
	struct node_proc np;
	struct resp r;

	sv_write_config(&np, TWO_PRINTERS, 8);
	sv_start(&np);
	post_form(np.port, cut, &r);
	ck_assert_msg(r.status == 400 && sv_has_text(r.body, "closing boundary"), "%d %s", r.status,
		      r.body);
	sv_resp_free(&r);
	post_form(np.port, two, &r);
	ck_assert_msg(r.status == 400 && sv_has_text(r.body, "more than one"), "%d %s", r.status,
		      r.body);
	sv_resp_free(&r);
	post_form(np.port, same, &r);
	ck_assert_msg(r.status == 400, "%d %s", r.status, r.body);
	sv_resp_free(&r);
	ck_assert(!tu_file_exists(tu_path("node/data/files/mk3s/cut.gcode")));
	ck_assert(!tu_file_exists(tu_path("node/data/files/mk3s/a.gcode")));
	ck_assert(!tu_file_exists(tu_path("node/data/files/mk3s/b.gcode")));
	ck_assert(dir_empty(tu_path("node/data/tmp")));
	post_form(np.port, ok, &r);
	ck_assert_msg(r.status == 201, "%d %s", r.status, r.body);
	sv_resp_free(&r);
	ck_assert(tu_file_exists(tu_path("node/data/files/mk3s/ok.gcode")));
	sv_stop(&np);
#undef FILE_PART
}
END_TEST

/* An upload cut off by a crash leaves its temporary file; the next start
 * removes it (issue 20). */
START_TEST(test_tmp_cleaned_at_start)
{
	struct node_proc np;

	sv_write_config(&np, TWO_PRINTERS, 8);
	sv_start(&np);
	sv_stop(&np);
	tu_write_str(tu_path("node/data/tmp/upload-Ab12Cd"), "G28\nG1 X");
	tu_write_str(tu_path("node/data/tmp/mqtt-Ef34Gh"), "G28\n");
	sv_start(&np);
	ck_assert(!tu_file_exists(tu_path("node/data/tmp/upload-Ab12Cd")));
	ck_assert(!tu_file_exists(tu_path("node/data/tmp/mqtt-Ef34Gh")));
	ck_assert(dir_empty(tu_path("node/data/tmp")));
	sv_expect(np.port, "GET", "/api/version", "X-Api-Key: " KEY_READ, NULL, 200);
	sv_stop(&np);
}
END_TEST

/* Keys in a query (the status page's ?key=, OctoPrint's ?apikey=) stay out
 * of the node's log (issue 20). */
START_TEST(test_query_keys_not_logged)
{
	struct node_proc np;
	struct resp r;
	FILE *f;
	char *log;
	long size;

	sv_write_config(&np, TWO_PRINTERS, 8);
	sv_start(&np);
	sv_http(np.port, "GET", "/?key=" KEY_READ, NULL, NULL, &r);
	ck_assert_int_eq(r.status, 200);
	sv_resp_free(&r);
	sv_expect(np.port, "GET", "/api/version?apikey=" KEY_CTL, "X-Api-Key: " KEY_READ, NULL, 200);
	/* OctoPrint's ?apikey= form is accepted (check_octoapi.c); as every query, not logged */
	sv_expect(np.port, "GET", "/api/job?x=1&apikey=" KEY_UP, NULL, NULL, 200);
	sv_stop(&np);
	ck_assert((f = fopen(np.log, "r")) != NULL);
	fseek(f, 0, SEEK_END);
	size = ftell(f);
	rewind(f);
	ck_assert((log = calloc(1, (size_t)size + 1)) != NULL);
	ck_assert(fread(log, 1, (size_t)size, f) == (size_t)size);
	fclose(f);
	ck_assert_msg(strstr(log, "request /api/version"), "%s", log);
	ck_assert_msg(!strstr(log, KEY_READ) && !strstr(log, KEY_CTL) && !strstr(log, KEY_UP),
		      "%s", log);
	free(log);
}
END_TEST

/* A connection to the node from loopback address src (127.0.0.x). */
static int connect_from(int port, const char *src)
{
	struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
	struct sockaddr_in me = {.sin_family = AF_INET};
	struct timeval tv = {.tv_sec = 5};
	int fd = socket(AF_INET, SOCK_STREAM, 0);

	ck_assert(fd >= 0);
	inet_pton(AF_INET, "127.0.0.1", &sa.sin_addr);
	inet_pton(AF_INET, src, &me.sin_addr);
	ck_assert(bind(fd, (struct sockaddr *)&me, sizeof(me)) == 0);
	setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof(tv));
	ck_assert_msg(connect(fd, (struct sockaddr *)&sa, sizeof(sa)) == 0, "connect: %s",
		      strerror(errno));
	return fd;
}

/* The status of GET /api/version from src; 0 when the node closed the
 * connection without an answer. */
static int version_from(int port, const char *src)
{
	char req[256], buf[1024];
	int fd = connect_from(port, src), status = 0;
	int n = snprintf(req, sizeof(req), "GET /api/version HTTP/1.1\r\nHost: x\r\n"
			 "X-Api-Key: " KEY_READ "\r\nConnection: close\r\n\r\n");
	struct timeval tv = {.tv_sec = 1}; /* a full node leaves it in the kernel's queue */
	ssize_t k;

	setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof(tv));
	send(fd, req, (size_t)n, MSG_NOSIGNAL);
	k = recv(fd, buf, sizeof(buf) - 1, 0);
	buf[k > 0 ? k : 0] = '\0';
	close(fd);
	if (sscanf(buf, "HTTP/1.1 %d", &status) != 1)
		status = 0;
	return status;
}

/* Slow clients hold connections (issue 20): those from one address are
 * capped so others are still answered, all of them are capped, and a
 * silent one is closed after idle_timeout_s. */
START_TEST(test_connection_limits)
{
	static const char limits[] =
		"[node]\nname = test-node\nlisten = 127.0.0.1:0\ndata_dir = data\n"
		"max_connections = 12\nmax_connections_per_ip = 5\nidle_timeout_s = 3\n"
		"[key viewer]\nkey = " KEY_READ "\nroles = read\n"
		"[printer mk3s]\nprofile = prusa-i3-mk3s\nport = test-instant\n";
	struct node_proc np;
	int held[12];
	char buf[64];

	sv_write_config(&np, TWO_PRINTERS, 8);
	tu_write_str(np.config, limits);
	sv_start(&np);
	for (int i = 0; i < 5; i++)
		held[i] = connect_from(np.port, "127.0.0.1");
	usleep(200000);
	ck_assert_int_eq(version_from(np.port, "127.0.0.1"), 0);
	ck_assert_int_eq(version_from(np.port, "127.0.0.2"), 200);
	/* The node frees that connection's place a moment after its answer:
	 * five more from 127.0.0.2 at once found its address still at one and
	 * the fifth was refused (then 127.0.0.4 got the free place). */
	usleep(200000);
	/* 5 + 5 + 2 = 12 held: the node is full for every address. */
	for (int i = 5; i < 10; i++)
		held[i] = connect_from(np.port, "127.0.0.2");
	for (int i = 10; i < 12; i++)
		held[i] = connect_from(np.port, "127.0.0.3");
	usleep(200000);
	ck_assert_int_eq(version_from(np.port, "127.0.0.4"), 0);
	/* Silent for idle_timeout_s: the node closed them all. */
	sleep(5);
	for (int i = 0; i < 12; i++) {
		ck_assert_msg(recv(held[i], buf, sizeof(buf), 0) == 0, "connection %d is open", i);
		close(held[i]);
	}
	ck_assert_int_eq(version_from(np.port, "127.0.0.1"), 200);
	sv_stop(&np);
}
END_TEST

/*
 * A slow-loris client (issue 20): one byte every 250 ms never lets
 * idle_timeout_s (3 s) run out, yet a header not whole within
 * header_timeout_s (1 s), and a body below min_body_rate over that time,
 * lose their connection; a client sending its request at once is answered.
 */
START_TEST(test_slow_header_and_body)
{
	static const char cfg[] =
		"[node]\nname = test-node\nlisten = 127.0.0.1:0\ndata_dir = data\n"
		"idle_timeout_s = 3\nheader_timeout_s = 1\nmin_body_rate = 1000\n"
		"[key slicer]\nkey = " KEY_UP "\nroles = read, upload\n"
		"[key viewer]\nkey = " KEY_READ "\nroles = read\n"
		"[printer mk3s]\nprofile = prusa-i3-mk3s\nport = test-instant\n";
	static const char *const head[2] = {
		"GET /api/version HTTP/1.1\r\nHost: x\r\nX-Api-Key: " KEY_UP "\r\n",
		"POST /api/files/local HTTP/1.1\r\nHost: x\r\nX-Api-Key: " KEY_UP "\r\n"
		"Content-Type: multipart/form-data; boundary=" BOUNDARY "\r\n"
		"Content-Length: 100000\r\n\r\n--" BOUNDARY "\r\n"};
	struct node_proc np;
	double closed_at[2];

	sv_write_config(&np, TWO_PRINTERS, 8);
	tu_write_str(np.config, cfg);
	sv_start(&np);
	sv_trickle(np.port, head, closed_at, 2.8);
	ck_assert_msg(closed_at[0] > 0.8 && closed_at[0] < 2.0,
		      "a header trickled kept its connection (closed at %.1f s)", closed_at[0]);
	ck_assert_msg(closed_at[1] > 0.8 && closed_at[1] < 2.0,
		      "a body trickled kept its connection (closed at %.1f s)", closed_at[1]);
	ck_assert_int_eq(version_from(np.port, "127.0.0.1"), 200);
	sv_stop(&np);
}
END_TEST

/*
 * Send the head of a request announcing a 1 GB body and a few bytes of it,
 * then wait at most 3 s for the answer (issue 20): a refused request is
 * answered without its body being read.  Returns the status, 0 if none came.
 */
static int refused_at_once(int port, const char *method, const char *path, const char *key,
			   const char *type)
{
	struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
	struct timeval tv = {.tv_sec = 3};
	char req[1024], buf[4096] = "";
	int fd = socket(AF_INET, SOCK_STREAM, 0), n, status = 0;
	size_t got = 0;
	ssize_t k;

	ck_assert(fd >= 0);
	inet_pton(AF_INET, "127.0.0.1", &sa.sin_addr);
	setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof(tv));
	ck_assert(connect(fd, (struct sockaddr *)&sa, sizeof(sa)) == 0);
	n = snprintf(req, sizeof(req),
		     "%s %s HTTP/1.1\r\nHost: 127.0.0.1:%d\r\n%s%s%sContent-Type: %s\r\n"
		     "Content-Length: 1073741824\r\n\r\n--" BOUNDARY "\r\nContent-Disp",
		     method, path, port, key ? "X-Api-Key: " : "", key ? key : "",
		     key ? "\r\n" : "", type);
	ck_assert(send(fd, req, (size_t)n, MSG_NOSIGNAL) == n);
	while (got < sizeof(buf) - 1 && !strstr(buf, "\r\n\r\n") &&
	       (k = recv(fd, buf + got, sizeof(buf) - 1 - got, 0)) > 0) {
		got += (size_t)k;
		buf[got] = '\0';
	}
	buf[got] = '\0';
	close(fd);
	if (sscanf(buf, "HTTP/1.1 %d", &status) != 1)
		status = 0;
	return status;
}

START_TEST(test_refused_before_body)
{
	static const char multipart[] = "multipart/form-data; boundary=" BOUNDARY;
	struct node_proc np;
	struct timespec t0, t1;

	sv_write_config(&np, TWO_PRINTERS, 8);
	sv_start(&np);
	clock_gettime(CLOCK_MONOTONIC, &t0);
	ck_assert_int_eq(refused_at_once(np.port, "POST", "/api/files/local", NULL, multipart),
			 403);
	ck_assert_int_eq(refused_at_once(np.port, "POST", "/p/mk3s/api/files/local", "wrong-key",
					 multipart), 403);
	ck_assert_int_eq(refused_at_once(np.port, "POST", "/api/files/local", KEY_READ, multipart),
			 403);
	ck_assert_int_eq(refused_at_once(np.port, "POST", "/api/job", NULL, "application/json"),
			 403);
	ck_assert_int_eq(refused_at_once(np.port, "POST", "/api/nothing", KEY_CTL,
					 "application/json"), 404);
	/* With a key, a body over the limit is refused as promptly. */
	ck_assert_int_eq(refused_at_once(np.port, "POST", "/api/files/local", KEY_UP, multipart),
			 413);
	ck_assert_int_eq(refused_at_once(np.port, "POST", "/api/job", KEY_CTL, "application/json"),
			 413);
	clock_gettime(CLOCK_MONOTONIC, &t1);
	ck_assert_msg(t1.tv_sec - t0.tv_sec < 5, "%ld s", (long)(t1.tv_sec - t0.tv_sec));
	sv_expect(np.port, "GET", "/api/version", "X-Api-Key: " KEY_READ, NULL, 200);
	sv_stop(&np);
}
END_TEST

/*
 * Multipart parts without a usable name (issue 17, found by fuzzing): a bare
 * "Content-Disposition: form-data" or a mangled name= gives libmicrohttpd's
 * callback a NULL key, which once crashed the node.  Each is an unknown part:
 * the node answers 400 (no 'file' part) or stores the real file beside it,
 * and keeps serving.
 */
START_TEST(test_nameless_part)
{
	static const char *const parts[] = {
		"Content-Disposition: form-data\r\n\r\nx",
		"Content-Disposition: form-data; name\r\n\r\nx",
		"Content-Disposition: form-data; filename=\"a.gcode\"\r\n\r\nG28\n",
		"Content-Disposition: form-data; nam=\"file\"; filename=\"a.gcode\"\r\n\r\nG28\n",
	};
	struct node_proc np;
	struct resp r;

	sv_write_config(&np, TWO_PRINTERS, 8);
	sv_start(&np);
	for (size_t i = 0; i < sizeof(parts) / sizeof(parts[0]); i++) {
		for (int with_file = 0; with_file < 2; with_file++) {
			char body[1024], req[2048];
			int bn = snprintf(body, sizeof(body), "--" BOUNDARY "\r\n%s\r\n%s--" BOUNDARY
							      "--\r\n",
					  parts[i],
					  with_file ? "--" BOUNDARY "\r\nContent-Disposition: form-data; "
						      "name=\"file\"; filename=\"ok.gcode\"\r\n"
						      "Content-Type: application/octet-stream\r\n\r\n"
						      "G28\n\r\n"
						    : "");
			int n = snprintf(req, sizeof(req),
					 "POST /api/files/local HTTP/1.1\r\nHost: 127.0.0.1:%d\r\n"
					 "X-Api-Key: " KEY_UP "\r\nConnection: close\r\n"
					 "Content-Length: %d\r\nContent-Type: multipart/form-data; "
					 "boundary=" BOUNDARY "\r\n\r\n%s",
					 np.port, bn, body);

			sv_http_raw(np.port, req, (size_t)n, &r);
			ck_assert_msg(r.status == (with_file ? 201 : 400), "part %zu, file %d: %d %s",
				      i, with_file, r.status, r.body);
			sv_resp_free(&r);
			sv_expect(np.port, "GET", "/api/version", "X-Api-Key: " KEY_READ, NULL, 200);
		}
	}
	ck_assert(tu_file_exists(tu_path("node/data/files/mk3s/ok.gcode")));
	sv_stop(&np);
}
END_TEST

void serve_abuse_tcases(Suite *s)
{
	TCase *tc = tcase_create("abuse");

	tcase_set_timeout(tc, 60);
	tcase_add_test(tc, test_chunked_refused_stops);
	tcase_add_test(tc, test_malformed_forms);
	tcase_add_test(tc, test_tmp_cleaned_at_start);
	tcase_add_test(tc, test_query_keys_not_logged);
	tcase_add_test(tc, test_connection_limits);
	tcase_add_test(tc, test_slow_header_and_body);
	tcase_add_test(tc, test_refused_before_body);
	tcase_add_test(tc, test_nameless_part);
	suite_add_tcase(s, tc);
}
