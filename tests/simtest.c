/*
 * simtest.c - the helpers of simtest.h.
 */
#include <check.h>
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <unistd.h>

#include "gcode.h"
#include "sim/marlin_sim.h"
#include "simtest.h"
#include "st_clock.h"
#include "testutil.h"

/* Options for fast tests: high speedup, fast link. */
void fast_opts(struct sim_marlin_options *o)
{
	sim_marlin_options_init(o);
	o->speedup = 100;
	o->baud = 1000000;
}

/* Read one line (without "\n") within timeout seconds; -1 on time-out,
 * -2 on hang-up. */
int cl_line(struct client *c, char *out, size_t cap, double timeout)
{
	double end = st_mono_s() + timeout;
	for (;;) {
		char *nl = memchr(c->buf, '\n', c->len);
		if (nl) {
			size_t n = (size_t)(nl - c->buf);
			size_t k = n < cap - 1 ? n : cap - 1;
			memcpy(out, c->buf, k);
			out[k] = '\0';
			memmove(c->buf, nl + 1, c->len - n - 1);
			c->len -= n + 1;
			return (int)k;
		}
		double left = end - st_mono_s();
		if (left <= 0)
			return -1;
		struct pollfd p = {.fd = c->fd, .events = POLLIN};
		int r = poll(&p, 1, (int)(left * 1000) + 1);
		if (r <= 0)
			continue;
		if (p.revents & POLLIN) {
			ssize_t n = read(c->fd, c->buf + c->len, sizeof(c->buf) - c->len - 1);
			if (n > 0) {
				c->len += (size_t)n;
				continue;
			}
			if (n == 0 || errno != EAGAIN)
				return -2;
		} else if (p.revents & (POLLHUP | POLLERR)) {
			return -2;
		}
	}
}

/* Read lines until one starts with prefix; fails the test on time-out. */
void cl_expect(struct client *c, const char *prefix, char *out, size_t cap, double timeout)
{
	char line[512];
	double end = st_mono_s() + timeout;
	for (;;) {
		double left = end - st_mono_s();
		int n = cl_line(c, line, sizeof(line), left > 0 ? left : 0);
		ck_assert_msg(n >= 0, "no line starting with '%s' within %.1f s", prefix, timeout);
		if (!strncmp(line, prefix, strlen(prefix))) {
			if (out)
				snprintf(out, cap, "%s", line);
			return;
		}
	}
}

/* The next line must be exactly want. */
void cl_next_is(struct client *c, const char *want)
{
	char line[512];
	ck_assert_int_ge(cl_line(c, line, sizeof(line), 2.0), 0);
	ck_assert_str_eq(line, want);
}

void cl_send(struct client *c, const char *text)
{
	size_t n = strlen(text), off = 0;
	while (off < n) {
		ssize_t w = write(c->fd, text + off, n - off);
		ck_assert_int_gt(w, 0);
		off += (size_t)w;
	}
}

/* Send "N<n> <cmd>*<cs>\n". */
void cl_send_n(struct client *c, long n, const char *cmd)
{
	char line[200];
	ck_assert_int_gt(gcode_format_numbered(line, sizeof(line) - 1, n, cmd), 0);
	strcat(line, "\n");
	cl_send(c, line);
}

/* Start a simulator with o on a thread and connect to it past its boot. */
void cl_start(struct client *c, struct sim_marlin_options *o)
{
	struct st_error err = {0};
	struct termios tio;
	memset(c, 0, sizeof(*c));
	if (!o->log_fp && !o->log_path) {
		c->log = tmpfile();
		ck_assert_ptr_nonnull(c->log);
		o->log_fp = c->log;
	}
	ck_assert_int_eq(sim_marlin_new(o, &c->sim, &err), 0);
	c->fd = open(sim_marlin_slave_path(c->sim), O_RDWR | O_NOCTTY | O_NONBLOCK);
	ck_assert_int_ge(c->fd, 0);
	ck_assert_int_eq(tcgetattr(c->fd, &tio), 0);
	cfmakeraw(&tio);
	ck_assert_int_eq(tcsetattr(c->fd, TCSANOW, &tio), 0);
	ck_assert_int_eq(sim_marlin_start_thread(c->sim, &err), 0);
	cl_expect(c, "start", NULL, 0, 2.0);
	cl_expect(c, "echo:Hardcoded Default Settings Loaded", NULL, 0, 2.0);
	usleep(60000); /* past the boot time (1.5 s / speedup) */
}

void cl_stop(struct client *c)
{
	sim_marlin_stop(c->sim);
	sim_marlin_free(c->sim);
	close(c->fd);
	if (c->log)
		fclose(c->log);
}

/* Whole execution log as a string (static buffer). */
const char *cl_log(struct client *c)
{
	static char text[4096];
	size_t n;
	fflush(c->log);
	rewind(c->log);
	n = fread(text, 1, sizeof(text) - 1, c->log);
	text[n] = '\0';
	return text;
}
