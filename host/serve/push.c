/*
 * push.c - OctoPrint's push API (docs/serve.md, "Push API"): SockJS over
 * WebSocket, through libmicrohttpd's upgrade support with the WebSocket
 * framing of wslay.  /sockjs/info answers as SockJS's; a client opens
 * /sockjs/SERVER/SESSION/websocket (SockJS framing: "o", "a[...]", "h")
 * or /sockjs/websocket (raw: one message per frame), gets "connected",
 * sends {"auth": "NAME:SESSION"} with the session of its passive login,
 * and then gets "history" once, "current" every PUSH_RATE_MS as OctoPrint
 * sends them, "event" messages for the changes a tick sees, and
 * slicingProgress with the Slicing* events while the printer's worker
 * slices a model (at most every NODE_SLICING_EVERY_MS, and at start and
 * end).  One thread per client, at most PUSH_MAX.
 */
#include <errno.h>
#include <fcntl.h>
#include <jansson.h>
#include <microhttpd.h>
#include <openssl/evp.h>
#include <openssl/sha.h>
#include <poll.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#include <time.h>
#include <wslay/wslay.h>

#include "http_int.h"
#include "st_clock.h"

#define PUSH_MAX 32	    /* WebSocket clients at once */
#define PUSH_RATE_MS 500    /* "current" messages: OctoPrint's default rate */
#define PUSH_HEARTBEAT_MS 25000 /* SockJS heartbeat ("h") */
#define PUSH_POLL_MS 50
#define PUSH_IN_MAX 65536   /* a client message, bytes */
#define WS_GUID "258EAFA5-E914-47DA-95CA-C5AB0DC85B11" /* the WebSocket handshake's */

struct push_conn {
	struct node *n;
	struct node_printer *p;
	MHD_socket fd;
	struct MHD_UpgradeResponseHandle *urh;
	bool sockjs; /* SockJS framing, else raw messages */
	bool authed;
	bool history_due;
	int rate_ms; /* between current messages: PUSH_RATE_MS times the client's throttle */
	/* what the last tick saw, for events */
	bool seen, connected, paused;
	int64_t job; /* printing or paused, 0 none */
	int64_t temps_sent; /* time of the newest temperature sample sent */
	unsigned files_seen; /* the printer's files_version at the last tick */
	unsigned slicing_gen, slicing_seq; /* the printer's slicing last reported */
	char *extra; /* bytes MHD read past the request, read first */
	size_t extra_len, extra_off;
	wslay_event_context_ptr ctx;
};

void node_push_session(const char *secret, char out[NODE_PUSH_SESSION_LEN + 1])
{
	unsigned char md[SHA256_DIGEST_LENGTH];
	char buf[NODE_KEY_MAX + 32];
	int len = snprintf(buf, sizeof(buf), "stratum push session:%s", secret);

	SHA256((const unsigned char *)buf, (size_t)len, md);
	for (int i = 0; i < NODE_PUSH_SESSION_LEN / 2; i++)
		snprintf(out + 2 * i, 3, "%02x", md[i]);
}

/* Whether "NAME:SESSION" is the session of a key with the read role. */
static bool auth_ok(const struct node *n, const char *auth)
{
	const char *colon = strrchr(auth, ':');
	char s[NODE_PUSH_SESSION_LEN + 1];
	bool ok = false;

	if (!colon)
		return false;
	for (size_t i = 0; i < n->cfg.nkeys; i++) {
		const struct node_key *k = &n->cfg.keys[i];
		unsigned char diff = 0;

		if (strlen(k->name) != (size_t)(colon - auth) || strncmp(k->name, auth,
									 (size_t)(colon - auth)) ||
		    !(k->roles & NODE_ROLE_READ) || strlen(colon + 1) != NODE_PUSH_SESSION_LEN)
			continue;
		node_push_session(k->secret, s);
		for (int j = 0; j < NODE_PUSH_SESSION_LEN; j++)
			diff |= (unsigned char)(s[j] ^ colon[1 + j]);
		ok |= !diff;
	}
	return ok;
}

/* Queue one message (stolen), framed as the client's endpoint wants. */
static void push_msg(struct push_conn *pc, json_t *msg)
{
	char *text = json_dumps(msg, JSON_COMPACT), *framed = NULL;
	struct wslay_event_msg m = {.opcode = WSLAY_TEXT_FRAME};

	json_decref(msg);
	if (text && pc->sockjs) {
		json_t *a = json_pack("[s]", text);

		framed = json_dumps(a, JSON_COMPACT);
		json_decref(a);
		if (framed) {
			char *f = malloc(strlen(framed) + 2);

			if (f)
				sprintf(f, "a%s", framed);
			free(framed);
			framed = f;
		}
	}
	if (pc->sockjs ? framed != NULL : text != NULL) {
		m.msg = (const uint8_t *)(pc->sockjs ? framed : text);
		m.msg_length = strlen((const char *)m.msg);
		wslay_event_queue_msg(pc->ctx, &m);
	}
	free(framed);
	free(text);
}

/* A SockJS control frame ("o", "h"). */
static void push_control(struct push_conn *pc, const char *frame)
{
	struct wslay_event_msg m = {WSLAY_TEXT_FRAME, (const uint8_t *)frame, strlen(frame)};

	if (pc->sockjs)
		wslay_event_queue_msg(pc->ctx, &m);
}

/* One event message: type and the job's payload (NULL: none). */
static void push_event(struct push_conn *pc, const char *type, const struct node_job *j)
{
	json_t *payload = json_object();

	if (j) {
		json_object_set_new(payload, "name", json_string(j->name));
		json_object_set_new(payload, "path", json_string(j->name));
		json_object_set_new(payload, "origin", json_string("local"));
		json_object_set_new(payload, "size", json_integer(j->size));
		if (j->finished && j->started)
			json_object_set_new(payload, "time", json_integer(j->finished - j->started));
		if (j->state == NODE_JOB_FAILED)
			json_object_set_new(payload, "reason", json_string(j->error));
	}
	push_msg(pc, json_pack("{s:{s:s,s:o}}", "event", "type", type, "payload", payload));
}

/* OctoPrint's events for what changed since the last tick: Connected,
 * Disconnected, UpdatedFiles, PrintStarted, PrintPaused, PrintResumed,
 * PrintDone, PrintFailed, PrintCancelled.  A job that starts and ends between two
 * ticks (PUSH_RATE_MS) is not seen. */
static void push_events(struct push_conn *pc, const struct http_view *v)
{
	int64_t job = v->has_job && (v->printing || v->job.state == NODE_JOB_PAUSED) ? v->job.id
										       : 0;
	bool paused = job && (v->paused || v->job.state == NODE_JOB_PAUSED);
	struct node_job j;
	unsigned files;

	if (pc->seen && v->connected != pc->connected)
		push_event(pc, v->connected ? "Connected" : "Disconnected", NULL);
	if (pc->seen && pc->job && pc->job != job &&
	    node_queue_get(pc->n->q, pc->job, &j, NULL) == 1 &&
	    (j.state == NODE_JOB_DONE || j.state == NODE_JOB_FAILED ||
	     j.state == NODE_JOB_CANCELLED))
		push_event(pc, j.state == NODE_JOB_DONE ? "PrintDone" : j.state == NODE_JOB_FAILED
			   ? "PrintFailed" : "PrintCancelled", &j);
	files = atomic_load(&pc->p->files_version);
	if (pc->seen && files != pc->files_seen)
		push_msg(pc, json_pack("{s:{s:s,s:{s:s}}}", "event", "type", "UpdatedFiles",
				       "payload", "type", "printables"));
	pc->files_seen = files;
	if (pc->seen && job && job != pc->job)
		push_event(pc, "PrintStarted", &v->job);
	else if (pc->seen && job && paused != pc->paused)
		push_event(pc, paused ? "PrintPaused" : "PrintResumed", &v->job);
	pc->seen = true;
	pc->connected = v->connected;
	pc->job = job;
	pc->paused = paused;
}

/* A Slicing* event of s: OctoPrint's payload, with extra (stolen). */
static void push_slicing_event(struct push_conn *pc, const char *type,
			       const struct node_slicing *s, json_t *extra)
{
	json_t *payload = json_pack("{s:s,s:s,s:s,s:s,s:s}", "slicer", "stratum", "stl",
				    s->source, "stl_location", "local", "gcode", s->dest,
				    "gcode_location", "local");

	json_object_update(payload, extra);
	json_decref(extra);
	push_msg(pc, json_pack("{s:{s:s,s:o}}", "event", "type", type, "payload", payload));
}

/* What the printer's worker published of the model it slices since the
 * last look (node_int.h, struct node_slicing): SlicingStarted for a new
 * one, slicingProgress, then SlicingDone or SlicingFailed.  history: the
 * client has just authenticated, and only what comes next is news to it. */
static void push_slicing(struct push_conn *pc, bool history)
{
	struct node_slicing s;

	pthread_mutex_lock(&pc->p->slice_mu);
	s = pc->p->slicing;
	pthread_mutex_unlock(&pc->p->slice_mu);
	if (history || s.seq == pc->slicing_seq) {
		pc->slicing_gen = s.gen;
		pc->slicing_seq = s.seq;
		return;
	}
	if (s.gen != pc->slicing_gen)
		push_slicing_event(pc, "SlicingStarted", &s,
				   json_pack("{s:b}", "progressAvailable", 1));
	pc->slicing_gen = s.gen;
	pc->slicing_seq = s.seq;
	if (s.state != NODE_SLICING_FAILED)
		push_msg(pc, json_pack("{s:{s:s,s:s,s:s,s:s,s:s,s:f}}", "slicingProgress",
				       "slicer", "stratum", "source_location", "local",
				       "source_path", s.source, "dest_location", "local",
				       "dest_path", s.dest, "progress", s.percent));
	if (s.state == NODE_SLICING_DONE)
		push_slicing_event(pc, "SlicingDone", &s, json_pack("{s:f}", "time", s.elapsed_s));
	else if (s.state == NODE_SLICING_FAILED)
		push_slicing_event(pc, "SlicingFailed", &s,
				   json_pack("{s:s}", "reason", s.reason));
}

/* The "current" payload: temps the samples since the last message (the
 * node takes one each 2 s); as the body of "history", every sample the
 * node keeps.  The view it shows in *out. */
static json_t *current_json(struct push_conn *pc, bool history, struct http_view *out)
{
	struct http_view v;
	json_t *job = http_job_json(pc->n, pc->p, &v), *o;
	json_t *temps = http_temp_history(pc->p, history ? 0 : 1, true, true), *last;
	double now = (double)time(NULL);

	last = json_array_get(temps, json_array_size(temps) - 1);
	if (last && json_integer_value(json_object_get(last, "time")) == pc->temps_sent &&
	    !history)
		json_array_clear(temps);
	else if (last)
		pc->temps_sent = json_integer_value(json_object_get(last, "time"));

	o = json_pack("{s:{s:s,s:o,s:s},s:O,s:O,s:o,s:{},s:o,s:[],s:[],s:o,s:f}", "state", "text",
		      http_state_text(&v), "flags", http_flags_json(&v), "error", v.conn_error,
		      "job", json_object_get(job, "job"), "progress", json_object_get(job, "progress"),
		      "currentZ", v.printing && v.z == v.z ? json_real(v.z) : json_null(), "offsets",
		      "temps", temps, "logs", "messages", "busyFiles",
		      v.has_job ? json_pack("[{s:s,s:s}]", "origin", "local", "path", v.job.name)
				: json_array(), "serverTime", now);
	json_decref(job);
	/* what OctoPrint has no field for: the bed-clear gate and the queue */
	json_object_set_new(o, "stratum", http_queue_json(pc->n, pc->p, &v));
	*out = v;
	return o;
}

static ssize_t recv_cb(wslay_event_context_ptr ctx, uint8_t *buf, size_t len, int flags,
		       void *user)
{
	struct push_conn *pc = user;
	ssize_t got;

	(void)flags;
	if (pc->extra_off < pc->extra_len) {
		size_t k = pc->extra_len - pc->extra_off < len ? pc->extra_len - pc->extra_off : len;

		memcpy(buf, pc->extra + pc->extra_off, k);
		pc->extra_off += k;
		return (ssize_t)k;
	}
	got = recv(pc->fd, buf, len, 0);
	if (got < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR))
		wslay_event_set_error(ctx, WSLAY_ERR_WOULDBLOCK);
	else if (got <= 0)
		wslay_event_set_error(ctx, WSLAY_ERR_CALLBACK_FAILURE);
	return got > 0 ? got : -1;
}

static ssize_t send_cb(wslay_event_context_ptr ctx, const uint8_t *data, size_t len, int flags,
		       void *user)
{
	struct push_conn *pc = user;
	ssize_t sent = send(pc->fd, data, len, MSG_NOSIGNAL);

	(void)flags;
	if (sent < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR))
		wslay_event_set_error(ctx, WSLAY_ERR_WOULDBLOCK);
	else if (sent < 0)
		wslay_event_set_error(ctx, WSLAY_ERR_CALLBACK_FAILURE);
	return sent >= 0 ? sent : -1;
}

/* One client message: {"auth": "NAME:SESSION"}, or {"throttle": N} for
 * a current message every N ticks (OctoPrint's, 1-100); others
 * (subscription) change nothing here. */
static void on_message(struct push_conn *pc, const char *text, size_t len)
{
	json_t *o = json_loadb(text, len, 0, NULL);
	const char *auth = json_string_value(json_object_get(o, "auth"));
	json_t *throttle = json_object_get(o, "throttle");

	if (json_is_integer(throttle) && json_integer_value(throttle) >= 1 &&
	    json_integer_value(throttle) <= 100)
		pc->rate_ms = PUSH_RATE_MS * (int)json_integer_value(throttle);

	if (auth && !pc->authed && auth_ok(pc->n, auth)) {
		pc->authed = true;
		pc->history_due = true;
	} else if (auth && !pc->authed) {
		node_log("warning", pc->p->cfg->name, 0, "push API: an auth message with no valid "
			 "session");
	}
	json_decref(o);
}

static void msg_cb(wslay_event_context_ptr ctx, const struct wslay_event_on_msg_recv_arg *arg,
		   void *user)
{
	struct push_conn *pc = user;
	json_t *a;
	size_t i;
	json_t *s;

	(void)ctx;
	if (arg->opcode != WSLAY_TEXT_FRAME)
		return;
	if (!pc->sockjs) {
		on_message(pc, (const char *)arg->msg, arg->msg_length);
		return;
	}
	/* SockJS: a JSON array of messages, each a JSON text as a string */
	a = json_loadb((const char *)arg->msg, arg->msg_length, 0, NULL);
	json_array_foreach(a, i, s)
		if (json_is_string(s))
			on_message(pc, json_string_value(s), json_string_length(s));
	json_decref(a);
}

/* Close the client's socket, free it, and count it gone. */
static void push_release(struct push_conn *pc)
{
	struct node *n = pc->n;

	MHD_upgrade_action(pc->urh, MHD_UPGRADE_ACTION_CLOSE);
	free(pc->extra);
	free(pc);
	pthread_mutex_lock(&n->push_mu);
	n->npush--;
	pthread_cond_broadcast(&n->push_cv);
	pthread_mutex_unlock(&n->push_mu);
}

/* The client's thread: until it closes or the node stops. */
static void *push_main(void *arg)
{
	struct push_conn *pc = arg;
	struct node *n = pc->n;
	struct wslay_event_callbacks cb = {recv_cb, send_cb, NULL, NULL, NULL, NULL, msg_cb};
	int64_t now = st_mono_ms(), next_current = now, next_beat = now + PUSH_HEARTBEAT_MS;
	/* a client that does not authenticate is closed as an idle connection is */
	int64_t auth_by = now + (int64_t)n->cfg.idle_timeout_s * 1000;

	fcntl(pc->fd, F_SETFL, fcntl(pc->fd, F_GETFL) | O_NONBLOCK);
	if (!wslay_event_context_server_init(&pc->ctx, &cb, pc)) {
		wslay_event_config_set_max_recv_msg_length(pc->ctx, PUSH_IN_MAX);
		push_control(pc, "o");
		push_msg(pc, json_pack("{s:{s:s,s:s,s:n,s:s,s:s,s:b,s:b,s:[],s:b}}", "connected",
				       "version", HTTP_OCTOPRINT_VERSION, "display_version",
				       HTTP_OCTOPRINT_VERSION, "branch", "plugin_hash", "stratum",
				       "config_hash", "stratum", "debug", 0, "safe_mode", 0,
				       "permissions", "online", 1));
		for (;;) {
			struct pollfd pfd = {.fd = pc->fd};
			struct http_view v;
			bool stop;

			pthread_mutex_lock(&n->push_mu);
			stop = n->push_stop;
			pthread_mutex_unlock(&n->push_mu);
			if (stop || (!wslay_event_want_read(pc->ctx) &&
				     !wslay_event_want_write(pc->ctx)))
				break;
			now = st_mono_ms();
			if (!pc->authed && now >= auth_by)
				break;
			if (pc->history_due) {
				pc->history_due = false;
				push_msg(pc, json_pack("{s:o}", "history", current_json(pc, true, &v)));
				push_events(pc, &v);
				push_slicing(pc, true);
				next_current = now + PUSH_RATE_MS;
			} else if (pc->authed && now >= next_current) {
				json_t *cur = current_json(pc, false, &v);

				push_events(pc, &v);
				push_msg(pc, json_pack("{s:o}", "current", cur));
				next_current = now + pc->rate_ms;
			}
			if (pc->authed)
				push_slicing(pc, false);
			if (now >= next_beat) {
				push_control(pc, "h");
				next_beat = now + PUSH_HEARTBEAT_MS;
			}
			pfd.events = (short)((wslay_event_want_read(pc->ctx) ? POLLIN : 0) |
					     (wslay_event_want_write(pc->ctx) ? POLLOUT : 0));
			if (poll(&pfd, 1, PUSH_POLL_MS) < 0 && errno != EINTR)
				break;
			if ((pfd.revents & POLLIN || pc->extra_off < pc->extra_len) &&
			    wslay_event_recv(pc->ctx))
				break;
			if (pfd.revents & POLLOUT && wslay_event_send(pc->ctx))
				break;
			if (pfd.revents & (POLLERR | POLLNVAL))
				break;
		}
		wslay_event_context_free(pc->ctx);
	}
	push_release(pc);
	return NULL;
}

/* libmicrohttpd hands over the socket: the client's thread takes it. */
static void upgraded(void *cls, struct MHD_Connection *c, void *con_cls, const char *extra_in,
		     size_t extra_in_size, MHD_socket sock, struct MHD_UpgradeResponseHandle *urh)
{
	struct push_conn *pc = cls;
	pthread_t t;
	pthread_attr_t attr;

	(void)c;
	(void)con_cls;
	pc->fd = sock;
	pc->urh = urh;
	if (extra_in_size && (pc->extra = malloc(extra_in_size))) {
		memcpy(pc->extra, extra_in, extra_in_size);
		pc->extra_len = extra_in_size;
	}
	pthread_attr_init(&attr);
	pthread_attr_setdetachstate(&attr, PTHREAD_CREATE_DETACHED);
	if (pthread_create(&t, &attr, push_main, pc))
		push_release(pc);
	pthread_attr_destroy(&attr);
}

/* Whether part is one path segment of SockJS's server or session ids. */
static bool sockjs_id(const char *s, size_t len)
{
	if (!len || len > 64)
		return false;
	for (size_t i = 0; i < len; i++)
		if (s[i] == '/' || s[i] == '.' || (unsigned char)s[i] < 0x21)
			return false;
	return true;
}

/* Answer the WebSocket handshake of a client on printer p. */
static enum MHD_Result handshake(struct node *n, struct node_printer *p,
				 struct MHD_Connection *c, bool sockjs)
{
	const char *key = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Sec-WebSocket-Key");
	const char *up = MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_UPGRADE);
	unsigned char md[SHA_DIGEST_LENGTH];
	unsigned char accept[4 * ((SHA_DIGEST_LENGTH + 2) / 3) + 1];
	char buf[128];
	struct MHD_Response *resp;
	struct push_conn *pc;
	enum MHD_Result ret;

	if (!key || !up || strcasecmp(up, "websocket") || strlen(key) > 64)
		return http_send_error(c, MHD_HTTP_BAD_REQUEST, "Can \"Upgrade\" only to "
							        "\"WebSocket\"");
	pthread_mutex_lock(&n->push_mu);
	if (n->push_stop || n->npush >= PUSH_MAX) {
		pthread_mutex_unlock(&n->push_mu);
		return http_send_error(c, MHD_HTTP_SERVICE_UNAVAILABLE, "too many push clients");
	}
	n->npush++;
	pthread_mutex_unlock(&n->push_mu);
	snprintf(buf, sizeof(buf), "%s%s", key, WS_GUID);
	SHA1((const unsigned char *)buf, strlen(buf), md);
	EVP_EncodeBlock(accept, md, SHA_DIGEST_LENGTH);
	pc = calloc(1, sizeof(*pc));
	resp = pc ? MHD_create_response_for_upgrade(upgraded, pc) : NULL;
	if (!resp) {
		free(pc);
		pthread_mutex_lock(&n->push_mu);
		n->npush--;
		pthread_mutex_unlock(&n->push_mu);
		return MHD_NO;
	}
	pc->n = n;
	pc->p = p;
	pc->sockjs = sockjs;
	pc->rate_ms = PUSH_RATE_MS;
	MHD_add_response_header(resp, MHD_HTTP_HEADER_UPGRADE, "websocket");
	MHD_add_response_header(resp, "Sec-WebSocket-Accept", (const char *)accept);
	ret = MHD_queue_response(c, MHD_HTTP_SWITCHING_PROTOCOLS, resp);
	MHD_destroy_response(resp);
	return ret;
}

bool node_push_route(struct node *n, struct node_printer *p, struct MHD_Connection *c,
		     const char *path, enum MHD_Result *ret)
{
	const char *s, *slash;

	if (strncmp(path, "/sockjs/", 8))
		return false;
	s = path + 8;
	if (!strcmp(s, "info")) {
		*ret = http_send_json(c, MHD_HTTP_OK,
				      json_pack("{s:b,s:b,s:[s],s:I}", "websocket", 1,
						"cookie_needed", 0, "origins", "*:*", "entropy",
						(json_int_t)(st_mono_ms() & 0x7fffffff)), NULL);
		return true;
	}
	if (!strcmp(s, "websocket")) {
		*ret = handshake(n, p, c, false);
		return true;
	}
	/* SERVER/SESSION/websocket */
	if ((slash = strchr(s, '/')) && sockjs_id(s, (size_t)(slash - s)) &&
	    (s = strchr(slash + 1, '/')) && sockjs_id(slash + 1, (size_t)(s - slash - 1)) &&
	    !strcmp(s, "/websocket")) {
		*ret = handshake(n, p, c, true);
		return true;
	}
	return false;
}

void node_push_stop(struct node *n)
{
	pthread_mutex_lock(&n->push_mu);
	n->push_stop = true;
	while (n->npush > 0)
		pthread_cond_wait(&n->push_cv, &n->push_mu);
	pthread_mutex_unlock(&n->push_mu);
}
