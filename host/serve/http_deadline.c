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

int http_deadlines_start(const struct node_config *cfg, struct http_deadlines **out,
			 struct st_error *err)
{
	struct http_deadlines *d = calloc(1, sizeof(*d));
	pthread_condattr_t ca;

	if (!d)
		return st_error_set(err, ST_ERR_NOMEM, "out of memory");
	d->header_ms = (int64_t)cfg->header_timeout_s * 1000;
	d->min_bytes = (uint64_t)cfg->min_body_rate * cfg->header_timeout_s;
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

void http_deadlines_stop(struct http_deadlines **dp)
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

void http_deadline_open(struct http_deadlines *d, struct MHD_Connection *c,
			void **socket_context)
{
	const union MHD_ConnectionInfo *fd = MHD_get_connection_info(c,
								      MHD_CONNECTION_INFO_CONNECTION_FD);
	struct http_conn *k = calloc(1, sizeof(*k));

	*socket_context = k;
	if (!k || !fd || !d) {
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

void http_deadline_close(void **socket_context)
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

enum MHD_Result http_deadline_handle(MHD_AccessHandlerCallback handler, void *cls,
				     struct MHD_Connection *c, const char *url, const char *method,
				     const char *version, const char *upload, size_t *upload_size,
				     void **con_cls)
{
	bool first = !*con_cls;
	size_t piece = *upload_size;
	enum MHD_Result ret = handler(cls, c, url, method, version, upload, upload_size, con_cls);

	if (first && *con_cls)
		set_phase(c, PHASE_BODY, 0); /* the header came */
	else if (!first && piece)
		set_phase(c, PHASE_BODY, piece);
	else
		set_phase(c, PHASE_ANSWER, 0);
	return ret;
}

void http_deadline_next(struct MHD_Connection *c)
{
	set_phase(c, PHASE_HEADER, 0);
}
