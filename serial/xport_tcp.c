/*
 * xport_tcp.c - the "tcp" back end: tcp://HOST:PORT for serial bridges.
 *
 * Non-blocking connect bounded by connect_timeout_ms across all addresses
 * of HOST, TCP_NODELAY (G-code lines are small and latency-bound), send with
 * MSG_NOSIGNAL so a closed peer is an error, not SIGPIPE.
 */
#include <errno.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "xport_impl.h"

/* Longest host name we accept (RFC 1035 total length). */
#define TCP_HOST_MAX 255

/*
 * Split "tcp://HOST:PORT" into host (without [] for IPv6) and a decimal
 * port string.  Returns 0 or ST_ERR_ARG with err filled.
 */
static int parse_spec(const char *spec, char host[TCP_HOST_MAX + 1], char port[6],
		      struct st_error *err)
{
	const char *h = spec + 6, *colon, *hend;
	size_t hlen, plen;
	long value = 0;

	if (*h == '[') {
		hend = strchr(h, ']');
		if (!hend || hend[1] != ':')
			goto bad;
		h++;
		colon = hend + 1;
	} else {
		colon = strrchr(h, ':');
		if (!colon || memchr(h, ':', (size_t)(colon - h)))
			goto bad;
		hend = colon;
	}
	hlen = (size_t)(hend - h);
	plen = strlen(colon + 1);
	if (hlen == 0 || hlen > TCP_HOST_MAX || plen == 0)
		goto bad;
	for (const char *c = colon + 1; *c; c++) {
		if (*c < '0' || *c > '9' || value > 65535)
			goto bad_port;
		value = value * 10 + (*c - '0');
	}
	if (value < 1 || value > 65535)
		goto bad_port;
	memcpy(host, h, hlen);
	host[hlen] = '\0';
	snprintf(port, 6, "%ld", value);
	return 0;

bad_port:
	return st_error_set(err, ST_ERR_ARG,
			    "%s: port must be a number from 1 to 65535; write tcp://HOST:PORT", spec);
bad:
	return st_error_set(err, ST_ERR_ARG,
			    "%s: malformed address; write tcp://HOST:PORT, e.g. tcp://192.168.1.20:23 "
			    "or tcp://[::1]:5000",
			    spec);
}

/*
 * Start a non-blocking connect to one address and wait for it until
 * deadline.  Returns the connected fd, or -1 with errno set (ETIMEDOUT on
 * time-out).
 */
static int connect_one(const struct addrinfo *ai, int64_t deadline)
{
	int fd = socket(ai->ai_family, ai->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC,
			ai->ai_protocol);
	int e = 0;
	socklen_t elen = sizeof(e);

	if (fd < 0)
		return -1;
	if (connect(fd, ai->ai_addr, ai->ai_addrlen) == 0)
		return fd;
	if (errno != EINPROGRESS && errno != EINTR)
		goto out_close_fd;
	for (;;) {
		struct pollfd p = {.fd = fd, .events = POLLOUT};
		int64_t left = deadline - xport_now_ms();
		int n;

		if (left <= 0) {
			errno = ETIMEDOUT;
			goto out_close_fd;
		}
		n = poll(&p, 1, left > 60000 ? 60000 : (int)left);
		if (n < 0 && errno == EINTR)
			continue;
		if (n < 0)
			goto out_close_fd;
		if (n > 0)
			break;
	}
	if (getsockopt(fd, SOL_SOCKET, SO_ERROR, &e, &elen) < 0)
		goto out_close_fd;
	if (e) {
		errno = e;
		goto out_close_fd;
	}
	return fd;

out_close_fd:
	e = errno;
	close(fd);
	errno = e;
	return -1;
}

/* Resolve and connect; sets x->fd and x->kind. */
static int tcp_open(struct xport *x, const struct xport_options *opt, struct st_error *err)
{
	struct addrinfo hints = {0}, *res = NULL;
	char host[TCP_HOST_MAX + 1], port[6];
	int64_t deadline = xport_now_ms() + opt->connect_timeout_ms;
	int rc, fd = -1, e = 0, one = 1;

	rc = parse_spec(x->spec, host, port, err);
	if (rc < 0)
		return rc;
	hints.ai_family = AF_UNSPEC;
	hints.ai_socktype = SOCK_STREAM;
	hints.ai_flags = AI_NUMERICSERV;
	rc = getaddrinfo(host, port, &hints, &res);
	if (rc != 0)
		return st_error_set(err, ST_ERR_IO,
				    "%s: cannot resolve host '%s': %s; check the name or use "
				    "the bridge's IP address",
				    x->spec, host, rc == EAI_SYSTEM ? strerror(errno) : gai_strerror(rc));
	for (const struct addrinfo *ai = res; ai && fd < 0; ai = ai->ai_next) {
		fd = connect_one(ai, deadline);
		if (fd < 0)
			e = errno;
	}
	freeaddrinfo(res);
	if (fd < 0) {
		if (e == ECONNREFUSED)
			return st_error_set(err, ST_ERR_IO,
					    "%s: connection refused; is the serial bridge running "
					    "and listening on port %s?",
					    x->spec, port);
		if (e == ETIMEDOUT)
			return st_error_set(err, ST_ERR_IO,
					    "%s: connect timed out after %d ms; check the address "
					    "and that the bridge is reachable",
					    x->spec, opt->connect_timeout_ms);
		return st_error_set(err, ST_ERR_IO, "%s: cannot connect: %s", x->spec,
				    strerror(e));
	}
	/* Small writes must go out at once; failure here only costs latency. */
	(void)setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
	(void)setsockopt(fd, SOL_SOCKET, SO_KEEPALIVE, &one, sizeof(one));
	x->fd = fd;
	x->kind = "tcp";
	return 0;
}

/* One non-blocking receive; 0 from recv is the peer closing. */
static long tcp_read(struct xport *x, void *buf, size_t cap)
{
	for (;;) {
		ssize_t n = recv(x->fd, buf, cap, 0);

		if (n > 0)
			return (long)n;
		if (n == 0)
			return XPORT_STEP_GONE;
		switch (errno) {
		case EINTR:
			continue;
		case EAGAIN:
			return XPORT_STEP_AGAIN;
		case ECONNRESET:
		case ENOTCONN:
		case ETIMEDOUT:
		case EPIPE:
			return XPORT_STEP_GONE;
		default:
			x->sys_errno = errno;
			return XPORT_STEP_ERROR;
		}
	}
}

/* One non-blocking send, never raising SIGPIPE. */
static long tcp_write(struct xport *x, const void *buf, size_t len)
{
	for (;;) {
		ssize_t n = send(x->fd, buf, len, MSG_NOSIGNAL);

		if (n >= 0)
			return (long)n;
		switch (errno) {
		case EINTR:
			continue;
		case EAGAIN:
			return XPORT_STEP_AGAIN;
		case ECONNRESET:
		case ENOTCONN:
		case ETIMEDOUT:
		case EPIPE:
			return XPORT_STEP_GONE;
		default:
			x->sys_errno = errno;
			return XPORT_STEP_ERROR;
		}
	}
}

/* TCP has no device queue to wait for: the kernel owns sent bytes. */
static long tcp_outq(struct xport *x)
{
	(void)x;
	return -1;
}

/* Plain close: the kernel keeps sending what was queued, we do not wait. */
static void tcp_close(struct xport *x)
{
	if (x->fd >= 0)
		close(x->fd);
	x->fd = -1;
}

const struct xport_ops xport_tcp_ops = {
	.name = "tcp",
	.open = tcp_open,
	.read = tcp_read,
	.write = tcp_write,
	.outq = tcp_outq,
	.close = tcp_close,
};
