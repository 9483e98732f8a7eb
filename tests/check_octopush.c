/*
 * check_octopush.c - the node's push API (docs/serve.md, "Push API"),
 * part of the octoapi suite: SockJS over WebSocket, read by a client whose
 * WebSocket framing and masking wslay does, as OctoPrint's clients read it:
 * connected, auth with the passive login's session, history, current
 * messages with a print's progress, and the print's events.
 */
#include <arpa/inet.h>
#include <check.h>
#include <errno.h>
#include <fcntl.h>
#include <jansson.h>
#include <netinet/in.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>
#include <wslay/wslay.h>

#include "servetest.h"
#include "suites.h"
#include "testutil.h"

/* A WebSocket client of the push API (wslay does the framing and masking). */
struct ws {
	int fd;
	wslay_event_context_ptr ctx;
	char extra[4096]; /* bytes read past the handshake's answer */
	size_t extra_len, extra_off;
	bool sockjs;
	json_t *got; /* messages received, in order (SockJS frames unwrapped) */
	int frames_o, frames_h;
};

static ssize_t ws_recv(wslay_event_context_ptr ctx, uint8_t *buf, size_t len, int flags,
		       void *user)
{
	struct ws *w = user;
	ssize_t n;

	(void)flags;
	if (w->extra_off < w->extra_len) {
		n = (ssize_t)(w->extra_len - w->extra_off < len ? w->extra_len - w->extra_off : len);
		memcpy(buf, w->extra + w->extra_off, (size_t)n);
		w->extra_off += (size_t)n;
		return n;
	}
	n = recv(w->fd, buf, len, 0);
	if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK))
		wslay_event_set_error(ctx, WSLAY_ERR_WOULDBLOCK);
	else if (n <= 0)
		wslay_event_set_error(ctx, WSLAY_ERR_CALLBACK_FAILURE);
	return n > 0 ? n : -1;
}

static ssize_t ws_send(wslay_event_context_ptr ctx, const uint8_t *data, size_t len, int flags,
		       void *user)
{
	struct ws *w = user;
	ssize_t n = send(w->fd, data, len, MSG_NOSIGNAL);

	(void)flags;
	if (n < 0)
		wslay_event_set_error(ctx, errno == EAGAIN ? WSLAY_ERR_WOULDBLOCK
							   : WSLAY_ERR_CALLBACK_FAILURE);
	return n >= 0 ? n : -1;
}

static int ws_mask(wslay_event_context_ptr ctx, uint8_t *buf, size_t len, void *user)
{
	(void)ctx;
	(void)user;
	for (size_t i = 0; i < len; i++)
		buf[i] = (uint8_t)rand();
	return 0;
}

static void ws_msg(wslay_event_context_ptr ctx, const struct wslay_event_on_msg_recv_arg *arg,
		   void *user)
{
	struct ws *w = user;
	const char *t = (const char *)arg->msg;
	size_t i;
	json_t *a, *s;

	(void)ctx;
	if (arg->opcode != WSLAY_TEXT_FRAME)
		return;
	if (!w->sockjs) {
		json_array_append_new(w->got, json_loadb(t, arg->msg_length, 0, NULL));
		return;
	}
	if (arg->msg_length == 1 && t[0] == 'o')
		w->frames_o++;
	else if (arg->msg_length == 1 && t[0] == 'h')
		w->frames_h++;
	else if (arg->msg_length > 1 && t[0] == 'a' &&
		 (a = json_loadb(t + 1, arg->msg_length - 1, 0, NULL))) {
		json_array_foreach(a, i, s)
			json_array_append_new(w->got, json_loads(json_string_value(s), 0, NULL));
		json_decref(a);
	}
}

/* Open path with the WebSocket handshake (the standard's sample key and
 * its accept value). */
static void ws_open(struct ws *w, int port, const char *path, bool sockjs)
{
	struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
	struct wslay_event_callbacks cb = {ws_recv, ws_send, ws_mask, NULL, NULL, NULL, ws_msg};
	char req[512], head[4096];
	size_t got = 0;
	char *end = NULL;
	int n;

	memset(w, 0, sizeof(*w));
	w->sockjs = sockjs;
	w->got = json_array();
	w->fd = socket(AF_INET, SOCK_STREAM, 0);
	inet_pton(AF_INET, "127.0.0.1", &sa.sin_addr);
	ck_assert(connect(w->fd, (struct sockaddr *)&sa, sizeof(sa)) == 0);
	n = snprintf(req, sizeof(req), "GET %s HTTP/1.1\r\nHost: 127.0.0.1:%d\r\n"
		     "Upgrade: websocket\r\nConnection: Upgrade\r\n"
		     "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n"
		     "Sec-WebSocket-Version: 13\r\n\r\n", path, port);
	ck_assert(send(w->fd, req, (size_t)n, 0) == n);
	while (!end && got < sizeof(head) - 1) {
		ssize_t k = recv(w->fd, head + got, sizeof(head) - 1 - got, 0);

		ck_assert_msg(k > 0, "no handshake answer");
		got += (size_t)k;
		head[got] = '\0';
		end = strstr(head, "\r\n\r\n");
	}
	ck_assert_msg(!strncmp(head, "HTTP/1.1 101", 12), "%s", head);
	ck_assert_msg(sv_has_text(head, "Sec-WebSocket-Accept: s3pPLMBiTxaQ9kYGzzhZRbK+xOo="),
		      "%s", head);
	w->extra_len = got - (size_t)(end + 4 - head);
	memcpy(w->extra, end + 4, w->extra_len);
	fcntl(w->fd, F_SETFL, O_NONBLOCK);
	ck_assert(wslay_event_context_client_init(&w->ctx, &cb, w) == 0);
}

/* Send one client message (framed as SockJS's when the endpoint is). */
static void ws_say(struct ws *w, const char *json)
{
	json_t *a = json_pack("[s]", json);
	char *framed = json_dumps(a, JSON_COMPACT);
	const char *text = w->sockjs ? framed : json;
	struct wslay_event_msg m = {WSLAY_TEXT_FRAME, (const uint8_t *)text, strlen(text)};

	ck_assert(wslay_event_queue_msg(w->ctx, &m) == 0);
	free(framed);
	json_decref(a);
}

/* Run the client for up to ms; stop early once a message has key. */
static json_t *ws_until(struct ws *w, const char *key, int ms)
{
	for (int t = 0; t < ms; t += 20) {
		struct pollfd pfd = {w->fd, POLLIN | (wslay_event_want_write(w->ctx) ? POLLOUT : 0),
				     0};
		size_t i;
		json_t *m;

		poll(&pfd, 1, 20);
		if (pfd.revents & POLLIN || w->extra_off < w->extra_len)
			ck_assert_msg(wslay_event_recv(w->ctx) == 0, "the node closed the push client");
		if (wslay_event_want_write(w->ctx))
			wslay_event_send(w->ctx);
		json_array_foreach(w->got, i, m)
			if (key && json_object_get(m, key))
				return m;
	}
	return NULL;
}

static void ws_close(struct ws *w)
{
	wslay_event_context_free(w->ctx);
	close(w->fd);
	json_decref(w->got);
}

/* The messages received with key. */
static int count_of(struct ws *w, const char *key)
{
	size_t i;
	json_t *m;
	int n = 0;

	json_array_foreach(w->got, i, m)
		n += json_object_get(m, key) != NULL;
	return n;
}

/* The auth message of key (its header) named name: its passive login's session. */
static void auth_of(int port, const char *key, const char *name, char *out, size_t cap)
{
	struct resp r;

	sv_call(port, "POST", "/api/login", key, "{\"passive\":true}", 200, &r);
	ck_assert_msg(!strstr(r.body, key + strlen("X-Api-Key: ")), "the key is echoed: %s",
		      r.body);
	snprintf(out, cap, "{\"auth\":\"%s:%s\"}", name, sv_str(r.json, "session"));
	sv_resp_free(&r);
}

/* SockJS: info, "o", connected; auth with the login's session; history,
 * then current messages with the print's progress. */
START_TEST(test_push_sockjs)
{
	struct node_proc np;
	struct resp r;
	struct ws w;
	char auth[128];
	json_t *m, *cur;
	double completion = 0;

	sv_write_config(&np, TWO_PRINTERS, 8);
	sv_start(&np);
	sv_call(np.port, "GET", "/sockjs/info", NULL, NULL, 200, &r);
	ck_assert(json_is_true(json_object_get(r.json, "websocket")));
	sv_resp_free(&r);
	auth_of(np.port, "X-Api-Key: " KEY_CTL, "operator", auth, sizeof(auth));
	ws_open(&w, np.port, "/sockjs/123/abcdefgh/websocket", true);
	m = ws_until(&w, "connected", 3000);
	ck_assert_msg(m && w.frames_o == 1, "no open frame and connected message");
	ck_assert_str_eq(sv_str(json_object_get(m, "connected"), "version"), "1.10.0");
	/* nothing but connected before auth */
	ck_assert(!ws_until(&w, "current", 1200));
	ws_say(&w, auth);
	m = ws_until(&w, "history", 3000);
	ck_assert_msg(m, "no history after auth");
	ck_assert(json_object_get(json_object_get(m, "history"), "state"));
	sv_bed_clear(np.port, "", 204);
	ck_assert(sv_print_text(np.port, "", "long.gcode", "G1 X1\nG4 S2\nG1 X2\nG4 S2\n") == 1);
	for (int i = 0; i < 50 && completion <= 0; i++) {
		json_array_clear(w.got);
		m = ws_until(&w, "current", 2000);
		ck_assert_msg(m, "no current message");
		cur = json_object_get(m, "current");
		completion = json_number_value(json_object_get(json_object_get(cur, "progress"),
							       "completion"));
	}
	ck_assert_msg(completion > 0, "no progress in current");
	ck_assert_str_eq(sv_str(json_object_get(cur, "state"), "text"), "Printing");
	ck_assert_str_eq(sv_str(json_object_get(json_object_get(cur, "job"), "file"), "name"),
			 "long.gcode");
	ck_assert(json_is_array(json_object_get(cur, "temps")));
	ws_close(&w);
	sv_stop(&np);
}
END_TEST

/* The Creator Pro's second extruder in the history message: tool1's
 * actual and target as the Sailfish driver reads them, not null. */
START_TEST(test_push_history_tool1)
{
	struct node_proc np;
	struct ws w;
	char auth[128];
	json_t *m, *temps, *last = NULL;
	double target = 0;

	sv_write_config(&np, "[printer cp]\nprofile = flashforge-creator-pro\nport = sim\n"
			     "sim_speedup = 1000\n", 8);
	sv_start(&np);
	sv_operational(np.port, "");
	sv_expect(np.port, "POST", "/api/printer/tool", "X-Api-Key: " KEY_CTL,
		  "{\"command\":\"target\",\"targets\":{\"tool1\":150}}", 204);
	/* read every 2 s between jobs, sampled every 2 s */
	for (int i = 0; i < 400 && target != 150; i++) {
		m = sv_get_json(np.port, "/api/printer/tool?history=true&limit=1");
		target = json_number_value(json_object_get(json_object_get(json_array_get(
				json_object_get(m, "history"), 0), "tool1"), "target"));
		json_decref(m);
		if (target != 150)
			usleep(20000);
	}
	ck_assert_msg(target == 150, "no sample with tool1's target");
	auth_of(np.port, "X-Api-Key: " KEY_READ, "viewer", auth, sizeof(auth));
	ws_open(&w, np.port, "/sockjs/websocket", false);
	ws_say(&w, auth);
	m = ws_until(&w, "history", 3000);
	ck_assert_msg(m, "no history after auth");
	temps = json_object_get(json_object_get(m, "history"), "temps");
	last = json_object_get(json_array_get(temps, json_array_size(temps) - 1), "tool1");
	ck_assert_msg(json_number_value(json_object_get(last, "target")) == 150 &&
		      json_is_number(json_object_get(last, "actual")), "tool1 in history: %s",
		      json_dumps(last, JSON_COMPACT));
	ws_close(&w);
	sv_stop(&np);
}
END_TEST

/* The raw endpoint: plain JSON messages; a wrong session gets no state;
 * the client's throttle slows its current messages. */
START_TEST(test_push_raw)
{
	struct node_proc np;
	struct ws w;
	char auth[128];

	sv_write_config(&np, TWO_PRINTERS, 8);
	sv_start(&np);
	auth_of(np.port, "X-Api-Key: " KEY_READ, "viewer", auth, sizeof(auth));
	ws_open(&w, np.port, "/sockjs/websocket", false);
	ck_assert(ws_until(&w, "connected", 3000));
	ws_say(&w, "{\"auth\":\"viewer:0123456789abcdef0123456789abcdef\"}");
	ck_assert(!ws_until(&w, "current", 1500));
	ws_say(&w, auth);
	ck_assert(ws_until(&w, "current", 3000));
	/* 2 per second; {"throttle": 4} makes it one each 2 s */
	json_array_clear(w.got);
	ws_until(&w, NULL, 2200);
	ck_assert_msg(count_of(&w, "current") >= 3, "%d current in 2.2 s", count_of(&w, "current"));
	ws_say(&w, "{\"throttle\":4}");
	ws_until(&w, NULL, 600);
	json_array_clear(w.got);
	ws_until(&w, NULL, 3000);
	ck_assert_msg(count_of(&w, "current") >= 1 && count_of(&w, "current") <= 2,
		      "%d current in 3 s at throttle 4", count_of(&w, "current"));
	ws_close(&w);
	/* a printer's own push API, and no upgrade without its headers */
	ws_open(&w, np.port, "/p/ender/sockjs/websocket", false);
	ck_assert(ws_until(&w, "connected", 3000));
	ws_close(&w);
	sv_expect(np.port, "GET", "/sockjs/websocket", NULL, NULL, 400);
	sv_stop(&np);
}
END_TEST

/* The payload of the first event of type received, or NULL. */
static json_t *event_of(struct ws *w, const char *type)
{
	size_t i;
	json_t *m;

	json_array_foreach(w->got, i, m) {
		json_t *e = json_object_get(m, "event");
		const char *got = json_string_value(json_object_get(e, "type"));

		if (got && !strcmp(got, type))
			return json_object_get(e, "payload");
	}
	return NULL;
}

/* Run the client until an event of type has come (up to ms); whether it did. */
static bool ws_event(struct ws *w, const char *type, int ms)
{
	for (int t = 0; t < ms; t += 100) {
		ws_until(w, NULL, 100);
		if (event_of(w, type))
			return true;
	}
	return false;
}

/* A node with TWO_PRINTERS and a client on path, authenticated as the
 * read-only key, past its history message. */
static void open_authed(struct node_proc *np, struct ws *w, const char *path, bool sockjs)
{
	char auth[128];

	sv_write_config(np, TWO_PRINTERS, 8);
	sv_start(np);
	auth_of(np->port, "X-Api-Key: " KEY_READ, "viewer", auth, sizeof(auth));
	ws_open(w, np->port, path, sockjs);
	ws_say(w, auth);
	ck_assert(ws_until(w, "history", 3000));
}

/* Events as OctoPrint sends them for an upload, a print paused, resumed,
 * cancelled, and one done. */
START_TEST(test_push_events)
{
	struct node_proc np;
	struct ws w;

	open_authed(&np, &w, "/sockjs/1/x/websocket", true);
	sv_bed_clear(np.port, "", 204);
	ck_assert(!ws_event(&w, "UpdatedFiles", 700));
	ck_assert(sv_print_text(np.port, "", "a.gcode", "G1 X1\nG4 S20\n") == 1);
	ck_assert_msg(ws_event(&w, "UpdatedFiles", 3000), "no UpdatedFiles after an upload");
	ck_assert_msg(ws_event(&w, "PrintStarted", 5000), "no PrintStarted");
	sv_expect(np.port, "POST", "/api/job", "X-Api-Key: " KEY_CTL,
		  "{\"command\":\"pause\",\"action\":\"pause\"}", 204);
	ck_assert_msg(ws_event(&w, "PrintPaused", 5000), "no PrintPaused");
	sv_expect(np.port, "POST", "/api/job", "X-Api-Key: " KEY_CTL,
		  "{\"command\":\"pause\",\"action\":\"resume\"}", 204);
	ck_assert_msg(ws_event(&w, "PrintResumed", 5000), "no PrintResumed");
	sv_expect(np.port, "POST", "/api/job", "X-Api-Key: " KEY_CTL, "{\"command\":\"cancel\"}",
		  204);
	ck_assert_msg(ws_event(&w, "PrintCancelled", 5000), "no PrintCancelled");
	ck_assert(!ws_event(&w, "PrintDone", 600));
	sv_bed_clear(np.port, "", 204);
	ck_assert(sv_print_text(np.port, "", "b.gcode", "G1 X1\nG4 S1\n") == 2);
	ck_assert_msg(ws_event(&w, "PrintDone", 8000), "no PrintDone");
	ws_close(&w);
	sv_stop(&np);
}
END_TEST

/* The bed-clear gate and the queue in current messages: OctoPrint's state
 * text and flags, and Stratum's own object with the queued jobs. */
START_TEST(test_push_bed_gate)
{
	struct node_proc np;
	struct ws w;
	char auth[128];
	const char *text = "";
	json_t *m, *cur = NULL, *st;

	sv_write_config(&np, TWO_PRINTERS, 8);
	sv_start(&np);
	sv_wait_state(np.port, "", sv_print_text(np.port, "", "moved.gcode", "G28\n"), "done", 10);
	ck_assert(sv_print_text(np.port, "", "next.gcode", "G1 X1\n") == 2);
	auth_of(np.port, "X-Api-Key: " KEY_READ, "viewer", auth, sizeof(auth));
	ws_open(&w, np.port, "/sockjs/websocket", false);
	ws_say(&w, auth);
	for (int i = 0; i < 20 && strcmp(text, "Waiting for bed clear"); i++) {
		json_array_clear(w.got);
		m = ws_until(&w, "current", 2000);
		ck_assert_msg(m, "no current message");
		cur = json_object_get(m, "current");
		text = sv_str(json_object_get(cur, "state"), "text");
	}
	ck_assert_str_eq(text, "Waiting for bed clear");
	ck_assert(json_is_false(json_object_get(json_object_get(json_object_get(cur, "state"),
								"flags"), "ready")));
	st = json_object_get(cur, "stratum");
	ck_assert(json_is_false(json_object_get(st, "bedClear")));
	m = json_array_get(json_object_get(st, "waiting"), 0);
	ck_assert_str_eq(sv_str(m, "name"), "next.gcode");
	ck_assert_int_eq(json_integer_value(json_object_get(m, "position")), 1);
	ws_close(&w);
	sv_stop(&np);
}
END_TEST

/* A client that does not authenticate is closed after idle_timeout_s, as
 * an idle HTTP connection is: it cannot hold a push slot for ever. */
START_TEST(test_push_unauthenticated_closed)
{
	struct node_proc np;
	struct ws w;
	char text[1024];
	bool closed = false;

	sv_write_config(&np, TWO_PRINTERS, 8);
	snprintf(text, sizeof(text),
		 "[node]\nname = test-node\nlisten = 127.0.0.1:0\ndata_dir = data\n"
		 "idle_timeout_s = 2\n[key viewer]\nkey = " KEY_READ "\nroles = read\n"
		 "[printer mk3s]\nprofile = prusa-i3-mk3s\nport = test-instant\n");
	tu_write_str(np.config, text);
	sv_start(&np);
	ws_open(&w, np.port, "/sockjs/websocket", false);
	for (int t = 0; t < 5000 && !closed; t += 20) {
		struct pollfd pfd = {w.fd, POLLIN, 0};

		poll(&pfd, 1, 20);
		if ((pfd.revents & POLLIN || w.extra_off < w.extra_len) && wslay_event_recv(w.ctx))
			closed = true;
	}
	ck_assert_msg(closed, "an unauthenticated push client is still open after 5 s");
	ws_close(&w);
	sv_stop(&np);
}
END_TEST

/* An uploaded STL is sliced with slicingProgress messages as OctoPrint
 * sends them (progress never going back, ending at 100) between
 * SlicingStarted and SlicingDone; a model that cannot be read gives
 * SlicingFailed with the reason. */
START_TEST(test_push_slicing_progress)
{
	struct node_proc np;
	struct ws w;
	struct resp r;
	size_t len, i;
	char *stl = sv_cube_stl(&len);
	double last = -1.0;
	int nprog = 0;
	json_t *m, *e;

	open_authed(&np, &w, "/sockjs/websocket", false);
	sv_upload(np.port, "", KEY_UP, "cube.stl", 8, "", 0, "true", stl, len, NULL, true, &r);
	ck_assert_msg(r.status == 201, "%d %s", r.status, r.body);
	sv_resp_free(&r);
	ck_assert_msg(ws_event(&w, "SlicingDone", 20000), "no SlicingDone");
	e = event_of(&w, "SlicingStarted");
	ck_assert_msg(e, "no SlicingStarted");
	ck_assert_str_eq(sv_str(e, "stl"), "cube.stl");
	ck_assert_str_eq(sv_str(e, "gcode"), "cube.gcode");
	ck_assert(json_is_true(json_object_get(e, "progressAvailable")));
	ck_assert(json_is_number(json_object_get(event_of(&w, "SlicingDone"), "time")));
	json_array_foreach(w.got, i, m) {
		json_t *sp = json_object_get(m, "slicingProgress");
		double pct;

		if (!sp)
			continue;
		ck_assert_str_eq(sv_str(sp, "slicer"), "stratum");
		ck_assert_str_eq(sv_str(sp, "source_location"), "local");
		ck_assert_str_eq(sv_str(sp, "source_path"), "cube.stl");
		ck_assert_str_eq(sv_str(sp, "dest_location"), "local");
		ck_assert_str_eq(sv_str(sp, "dest_path"), "cube.gcode");
		pct = json_number_value(json_object_get(sp, "progress"));
		ck_assert_msg(pct >= last && pct >= 0.0 && pct <= 100.0, "progress %g after %g",
			      pct, last);
		last = pct;
		nprog++;
	}
	ck_assert_msg(nprog >= 2, "%d slicingProgress messages", nprog);
	ck_assert_msg(last == 100.0, "the last slicingProgress is at %g", last);
	/* a model that cannot be read: SlicingFailed, no slicingProgress at 100 */
	sv_bed_clear(np.port, "", 204);
	sv_upload_text(np.port, "", KEY_UP, "junk.stl", "solid x\nendsolid x\n", "true", &r);
	ck_assert_int_eq(r.status, 201);
	sv_resp_free(&r);
	ck_assert_msg(ws_event(&w, "SlicingFailed", 20000), "no SlicingFailed");
	e = event_of(&w, "SlicingFailed");
	ck_assert_str_eq(sv_str(e, "stl"), "junk.stl");
	ck_assert(strlen(sv_str(e, "reason")) > 0);
	ws_close(&w);
	free(stl);
	sv_stop(&np);
}
END_TEST

void octoapi_push_tcases(Suite *s)
{
	TCase *tc = tcase_create("push");

	tcase_set_timeout(tc, 60);
	tcase_add_test(tc, test_push_sockjs);
	tcase_add_test(tc, test_push_raw);
	tcase_add_test(tc, test_push_history_tool1);
	tcase_add_test(tc, test_push_events);
	tcase_add_test(tc, test_push_bed_gate);
	tcase_add_test(tc, test_push_unauthenticated_closed);
	tcase_add_test(tc, test_push_slicing_progress);
	suite_add_tcase(s, tc);
}
