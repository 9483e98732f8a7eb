/*
 * http_deadline.c - the bounds on a slow client (docs/serve.md, "Limits"):
 * a request's header must be whole within header_timeout_s, and its body
 * must bring min_body_rate bytes a second over each header_timeout_s.
 *
 * libmicrohttpd has only an inactivity time-out (MHD_OPTION_CONNECTION_
 * TIMEOUT: reset by every byte), so a client sending one byte every 20 s
 * held its connection for ever, and a thousand of them the node's every
 * slot.  Its handler is first called once the header is whole, and again
 * for each piece of the body, so the node sees when a header ends and how
 * the body comes; a watchdog thread closes a connection past its bound by
 * shutting its socket down (libmicrohttpd then reads the end and closes it
 * as if the client had).  The socket is shut down under the lock that its
 * close notification takes, so it is always still the connection's own.
 * The server's own callbacks are called through these (struct http_hooks),
 * so the node and the farm view set their daemons up in one place.
 */
#include <arpa/inet.h>
#include <errno.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>

#include "http_int.h"
#include "st_clock.h"

#define DEADLINE_TICK_MS 200 /* how often the watchdog looks */

enum phase {
	PHASE_HEADER,	/* waiting for a request's header (a new or kept-alive connection) */
	PHASE_BODY,	/* the header came: reading the body */
	PHASE_ANSWER,	/* the request is read: answering (or upgraded to the push API) */
};

/* One connection, from its start to its close. */
struct http_conn {
	struct http_conn *prev, *next;
	struct http_deadlines *d;
	int fd;
	enum phase phase;
	int64_t since_ms;     /* the phase's start, or the body's current window */
	uint64_t window_bytes; /* body bytes in the current window */
	bool closing;	      /* shut down by the watchdog */
};

struct http_deadlines {
	pthread_mutex_t lock;
	pthread_cond_t wake;
	pthread_t thread;
	bool stop;
	struct http_conn *head;
	int64_t header_ms;  /* header_timeout_s; the body's window too */
	uint64_t min_bytes; /* min_body_rate x header_timeout_s; 0: the body is not bounded */
	struct http_hooks hooks;
};

static void conn_log(int fd, const char *why, unsigned secs)
{
	struct sockaddr_in sa;
	socklen_t len = sizeof(sa);
	char addr[INET_ADDRSTRLEN] = "?";

	if (!getpeername(fd, (struct sockaddr *)&sa, &len) && sa.sin_family == AF_INET)
		inet_ntop(AF_INET, &sa.sin_addr, addr, sizeof(addr));
	node_log("debug", NULL, 0, "closed a connection from %s: %s within %u s", addr, why, secs);
}

/* The watchdog's look at every connection; under d->lock. */
static void check_all(struct http_deadlines *d, int64_t now)
{
	for (struct http_conn *k = d->head; k; k = k->next) {
		const char *why = NULL;

		if (k->closing || k->phase == PHASE_ANSWER || now - k->since_ms < d->header_ms)
			continue;
		if (k->phase == PHASE_HEADER) {
			why = "its request header was not whole";
		} else if (k->window_bytes < d->min_bytes) {
			why = "its body did not bring min_body_rate bytes a second";
		} else {
			k->since_ms = now; /* the next window */
			k->window_bytes = 0;
			continue;
		}
		k->closing = true;
		conn_log(k->fd, why, (unsigned)(d->header_ms / 1000));
		shutdown(k->fd, SHUT_RDWR);
	}
}

static void *watchdog(void *arg)
{
	struct http_deadlines *d = arg;

	pthread_mutex_lock(&d->lock);
	while (!d->stop) {
		struct timespec ts;

		clock_gettime(CLOCK_MONOTONIC, &ts);
		ts.tv_nsec += DEADLINE_TICK_MS * 1000000L;
		ts.tv_sec += ts.tv_nsec / 1000000000L;
		ts.tv_nsec %= 1000000000L;
		pthread_cond_timedwait(&d->wake, &d->lock, &ts);
		if (!d->stop)
			check_all(d, st_mono_ms());
	}
	pthread_mutex_unlock(&d->lock);
	return NULL;
}

static int deadlines_start(const struct node_config *cfg, const struct http_hooks *hooks,
			   struct http_deadlines **out, struct st_error *err)
{
	struct http_deadlines *d = calloc(1, sizeof(*d));
	pthread_condattr_t ca;

	if (!d)
		return st_error_set(err, ST_ERR_NOMEM, "out of memory");
	d->header_ms = (int64_t)cfg->header_timeout_s * 1000;
	d->min_bytes = (uint64_t)cfg->min_body_rate * cfg->header_timeout_s;
	d->hooks = *hooks;
	pthread_mutex_init(&d->lock, NULL);
	pthread_condattr_init(&ca);
	pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
	pthread_cond_init(&d->wake, &ca);
	pthread_condattr_destroy(&ca);
	if (pthread_create(&d->thread, NULL, watchdog, d)) {
		pthread_cond_destroy(&d->wake);
		pthread_mutex_destroy(&d->lock);
		free(d);
		return st_error_set(err, ST_ERR_INTERNAL, "cannot start a thread: %s",
				    strerror(errno));
	}
	*out = d;
	return 0;
}

static void deadlines_stop(struct http_deadlines **dp)
{
	struct http_deadlines *d = *dp;

	if (!d)
		return;
	pthread_mutex_lock(&d->lock);
	d->stop = true;
	pthread_cond_signal(&d->wake);
	pthread_mutex_unlock(&d->lock);
	pthread_join(d->thread, NULL);
	/* The HTTP daemon is stopped first: every connection was closed. */
	pthread_cond_destroy(&d->wake);
	pthread_mutex_destroy(&d->lock);
	free(d);
	*dp = NULL;
}

/* A connection started: watch it from now. */
static void conn_open(struct http_deadlines *d, struct MHD_Connection *c, void **socket_context)
{
	const union MHD_ConnectionInfo *fd = MHD_get_connection_info(c,
								      MHD_CONNECTION_INFO_CONNECTION_FD);
	struct http_conn *k = calloc(1, sizeof(*k));

	*socket_context = k;
	if (!k || !fd) {
		/* Out of memory: the connection goes unwatched (idle_timeout_s still holds). */
		free(k);
		*socket_context = NULL;
		return;
	}
	k->d = d;
	k->fd = fd->connect_fd;
	k->phase = PHASE_HEADER;
	k->since_ms = st_mono_ms();
	pthread_mutex_lock(&d->lock);
	k->next = d->head;
	if (d->head)
		d->head->prev = k;
	d->head = k;
	pthread_mutex_unlock(&d->lock);
}

static void conn_close(void **socket_context)
{
	struct http_conn *k = *socket_context;

	if (!k)
		return;
	pthread_mutex_lock(&k->d->lock);
	if (k->prev)
		k->prev->next = k->next;
	else
		k->d->head = k->next;
	if (k->next)
		k->next->prev = k->prev;
	pthread_mutex_unlock(&k->d->lock);
	free(k);
	*socket_context = NULL;
}

/* Set c's phase (and count body bytes) under the lock. */
static void set_phase(struct MHD_Connection *c, enum phase phase, size_t bytes)
{
	const union MHD_ConnectionInfo *info =
		MHD_get_connection_info(c, MHD_CONNECTION_INFO_SOCKET_CONTEXT);
	struct http_conn *k = info ? info->socket_context : NULL;

	if (!k)
		return;
	pthread_mutex_lock(&k->d->lock);
	if (k->phase != phase) {
		k->phase = phase;
		k->since_ms = st_mono_ms();
		k->window_bytes = 0;
	}
	k->window_bytes += bytes;
	pthread_mutex_unlock(&k->d->lock);
}

/*
 * The server's handler, noting where the request is: its header came (the
 * first call, which keeps state in *con_cls), a piece of its body came, or
 * it is read and being answered (the last call, or a first one that
 * answered at once, as the page and the push API do; an upgrade is not
 * bounded here).
 */
static enum MHD_Result handle(void *cls, struct MHD_Connection *c, const char *url,
			      const char *method, const char *version, const char *upload,
			      size_t *upload_size, void **con_cls)
{
	struct http_deadlines *d = cls;
	bool first = !*con_cls;
	size_t piece = *upload_size;
	enum MHD_Result ret = d->hooks.handle(d->hooks.cls, c, url, method, version, upload,
					      upload_size, con_cls);

	if (first && *con_cls)
		set_phase(c, PHASE_BODY, 0); /* the header came */
	else if (!first && piece)
		set_phase(c, PHASE_BODY, piece);
	else
		set_phase(c, PHASE_ANSWER, 0);
	return ret;
}

/* A request is answered: its state freed, and a kept-alive connection
 * waits for the next header. */
static void completed(void *cls, struct MHD_Connection *c, void **con_cls,
		      enum MHD_RequestTerminationCode toe)
{
	struct http_deadlines *d = cls;

	(void)toe;
	set_phase(c, PHASE_HEADER, 0);
	if (*con_cls)
		d->hooks.free_request(*con_cls);
	*con_cls = NULL;
}

static void connection_event(void *cls, struct MHD_Connection *c, void **socket_context,
			     enum MHD_ConnectionNotificationCode code)
{
	struct http_deadlines *d = cls;

	if (code == MHD_CONNECTION_NOTIFY_STARTED) {
		conn_open(d, c, socket_context);
	} else if (code == MHD_CONNECTION_NOTIFY_CLOSED) {
		conn_close(socket_context);
		if (d->hooks.closed)
			d->hooks.closed(d->hooks.cls);
	}
}

int http_server_start(const struct node_config *cfg, unsigned flags,
		      MHD_AcceptPolicyCallback accept, void *accept_cls,
		      const struct http_hooks *hooks, const struct MHD_OptionItem *extra,
		      struct MHD_Daemon **httpd, struct http_deadlines **deadlines, uint16_t *port,
		      struct st_error *err)
{
	struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons(cfg->listen_port)};
	const union MHD_DaemonInfo *info;
	struct http_deadlines *d = NULL;

	if (inet_pton(AF_INET, cfg->listen_addr, &sa.sin_addr) != 1)
		return st_error_set(err, ST_ERR_ARG, "listen address %s is not IPv4",
				    cfg->listen_addr);
	if (deadlines_start(cfg, hooks, &d, err))
		return err->code;
	*httpd = MHD_start_daemon(flags, cfg->listen_port, accept, accept_cls, handle, d,
				  MHD_OPTION_SOCK_ADDR, (struct sockaddr *)&sa,
				  MHD_OPTION_CONNECTION_TIMEOUT, cfg->idle_timeout_s,
				  MHD_OPTION_PER_IP_CONNECTION_LIMIT, cfg->max_connections_per_ip,
				  MHD_OPTION_NOTIFY_CONNECTION, connection_event, d,
				  MHD_OPTION_NOTIFY_COMPLETED, completed, d, MHD_OPTION_ARRAY, extra,
				  MHD_OPTION_END);
	if (!*httpd) {
		int rc = st_error_set(err, ST_ERR_IO, "cannot listen on %s:%u: %s",
				      cfg->listen_addr, cfg->listen_port, strerror(errno));

		deadlines_stop(&d);
		return rc;
	}
	*deadlines = d;
	info = MHD_get_daemon_info(*httpd, MHD_DAEMON_INFO_BIND_PORT);
	*port = info ? info->port : cfg->listen_port;
	return 0;
}

void http_server_stop(struct MHD_Daemon **httpd, struct http_deadlines **deadlines)
{
	if (*httpd)
		MHD_stop_daemon(*httpd);
	*httpd = NULL;
	deadlines_stop(deadlines); /* every connection was closed */
}
