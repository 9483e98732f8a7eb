/*
 * fuzz_http.c - the farm node's HTTP handling (host/serve/http.c: request
 * line, headers, API key, JSON bodies, multipart uploads and the names in
 * them) with the real node running in this process on a loopback port, two
 * test-instant printers behind it.  Each input is sent as the bytes of one
 * connection; the answer is read to the end.  A crash in any of the node's
 * threads ends the run on the input that caused it.
 */
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <time.h>
#include <unistd.h>

#include "fuzz.h"
#include "node.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* The keys the seeds use (tests/fuzz/seeds/http). */
#define CONFIG                                                                            \
	"[node]\nname = fuzz\nlisten = 127.0.0.1:0\ndata_dir = data\nmax_upload_mb = 1\n"  \
	"[key slicer]\nkey = upload-key-0123456789\nroles = read, upload\n"                \
	"[key operator]\nkey = control-key-0123456789\nroles = read, upload, control\n"    \
	"[printer mk3s]\nprofile = prusa-i3-mk3s\nport = test-instant\n"                   \
	"[printer ff]\nprofile = flashforge-creator-pro\nport = test-instant\nprefix = /p/ff\n"

#define SILENCE_MS 50
#define NAP_US 50 /* between looks at the node's progress */

static uint16_t port;

static int64_t now_us(void)
{
	struct timespec t;

	clock_gettime(CLOCK_MONOTONIC, &t);
	return (int64_t)t.tv_sec * 1000000 + t.tv_nsec / 1000;
}

static void nap(void)
{
	struct timespec t = {.tv_nsec = NAP_US * 1000};

	nanosleep(&t, NULL);
}

static void start_node(void)
{
	static struct node_config cfg;
	struct st_error err = {0};
	struct node *n;
	char path[300];
	FILE *f;

	snprintf(path, sizeof(path), "%s/node.ini", fuzz_tmpdir());
	f = fopen(path, "w");
	if (!f || fputs(CONFIG, f) < 0 || fclose(f))
		abort();
	node_set_log(NULL, NULL);
	if (node_config_load(path, &cfg, &err) || node_new(&cfg, &n, &err) ||
	    node_start(n, &err)) {
		fprintf(stderr, "fuzz_http: %s\n", err.msg);
		abort();
	}
	port = node_port(n); /* the node runs until the process ends */
}

/* The node's end of the connection on fd: the descriptor of this process
 * (the node runs in it) whose peer is fd's own address; -1 while no node
 * thread has accepted the connection. */
static int node_side(int fd)
{
	struct sockaddr_in me, peer;
	socklen_t len = sizeof(me);

	if (getsockname(fd, (struct sockaddr *)&me, &len))
		return -1;
	/* accept() takes the lowest free descriptor: near fd */
	for (int k = 0; k < fd + 64; k++) {
		len = sizeof(peer);
		if (k != fd && !getpeername(k, (struct sockaddr *)&peer, &len) &&
		    len == sizeof(peer) && peer.sin_family == AF_INET &&
		    peer.sin_port == me.sin_port && peer.sin_addr.s_addr == me.sin_addr.s_addr)
			return k;
	}
	return -1;
}

/*
 * Wait until the node has read every byte sent on fd (its end's receive
 * queue is empty: what it read, its handler has seen), or has answered or
 * closed, or SILENCE_MS have passed.  Only then may the end of the input
 * go: libmicrohttpd's server (edge-triggered epoll) takes bytes and an end
 * already queued behind them in one event and does not come back for the
 * end, so the connection stayed open until the silence ran out.  Before,
 * the harness waited for the first byte of an answer, and a request the
 * node waits to see more of (most mutated ones) cost the whole silence.
 */
static void wait_read(int fd)
{
	int64_t deadline = now_us() + SILENCE_MS * 1000;
	int node_fd = -1;

	do {
		struct pollfd p = {.fd = fd, .events = POLLIN};
		int unread;

		if (poll(&p, 1, 0) != 0)
			return; /* an answer, or the node closed */
		if (node_fd < 0)
			node_fd = node_side(fd);
		if (node_fd >= 0 && !ioctl(node_fd, FIONREAD, &unread) && unread == 0)
			return;
		nap();
	} while (now_us() < deadline);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	struct sockaddr_in sa = {.sin_family = AF_INET};
	/* A keep-alive connection stays open after the answer: 50 ms of
	 * silence ends the read (the node answers in-process within that). */
	struct timeval tv = {.tv_usec = SILENCE_MS * 1000};
	char buf[4096];
	int fd;

	if (!port)
		start_node();
	sa.sin_port = htons(port);
	inet_pton(AF_INET, "127.0.0.1", &sa.sin_addr);
	fd = socket(AF_INET, SOCK_STREAM, 0);
	if (fd < 0)
		return 0;
	setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof(tv));
	tv.tv_sec = 2;
	tv.tv_usec = 0;
	setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof(tv));
	if (!connect(fd, (struct sockaddr *)&sa, sizeof(sa))) {
		for (size_t done = 0; done < size;) {
			ssize_t w = send(fd, data + done, size - done, MSG_NOSIGNAL);

			if (w <= 0)
				break; /* the node answered and closed early */
			done += (size_t)w;
		}
		wait_read(fd);
		shutdown(fd, SHUT_WR);
		while (recv(fd, buf, sizeof(buf), 0) > 0)
			;
	}
	close(fd);
	return 0;
}
