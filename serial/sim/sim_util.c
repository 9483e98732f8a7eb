/*
 * sim_util.c - helpers shared by the simulated printers (see sim_util.h).
 */
#define _GNU_SOURCE /* ppoll: the link's byte times are well under 1 ms */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <pty.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include "sim_util.h"
#include "st_clock.h"

double sim_clock(void)
{
	return st_mono_s();
}

double sim_heater_step(double temp, double target, double ambient, double heat_rate,
		       double cool_rate, double scaled)
{
	double goal = target > ambient ? target : ambient;
	double step = scaled * (goal > temp ? heat_rate : cool_rate);
	if (fabs(goal - temp) <= step)
		return goal;
	return temp + (goal > temp ? step : -step);
}

double sim_rand01(uint64_t *state)
{
	uint64_t x = *state;
	x ^= x >> 12;
	x ^= x << 25;
	x ^= x >> 27;
	*state = x;
	return (double)((x * 2685821657736338717ull) >> 11) * (1.0 / 9007199254740992.0);
}

int sim_pty_open(int *master, int *slave, char *path)
{
	struct termios tio;
	if (openpty(master, slave, path, NULL, NULL) < 0)
		return -1;
	if (tcgetattr(*slave, &tio) == 0) {
		cfmakeraw(&tio);
		tcsetattr(*slave, TCSANOW, &tio);
	}
	fcntl(*master, F_SETFL, fcntl(*master, F_GETFL) | O_NONBLOCK);
	fcntl(*master, F_SETFD, FD_CLOEXEC);
	fcntl(*slave, F_SETFD, FD_CLOEXEC);
	return 0;
}

void sim_pty_close(int *master, int *slave)
{
	if (*master >= 0)
		close(*master);
	if (*slave >= 0)
		close(*slave);
	*master = *slave = -1;
}

int sim_wait_input(int fd, bool want_in, double wake, uint8_t *buf, size_t *len, size_t cap,
		   double *arrived)
{
	struct pollfd pfd = {.fd = fd, .events = want_in && *len < cap ? POLLIN : 0};
	double left = wake - sim_clock();
	if (left < 0)
		left = 0;
	struct timespec ts = {(time_t)left, (long)((left - (double)(time_t)left) * 1e9)};
	int r = ppoll(&pfd, 1, &ts, NULL);
	if (r < 0 && errno != EINTR)
		return -1;
	if (r > 0 && (pfd.revents & POLLIN)) {
		ssize_t n = read(fd, buf + *len, cap - *len);
		if (n > 0) {
			*arrived = sim_clock();
			*len += (size_t)n;
		}
	}
	return 0;
}

/* Thread body: run the loop, keep its result. */
static void *sim_thread_main(void *arg)
{
	struct sim_thread *t = arg;
	t->rc = t->run(t->sim, &t->stop);
	return NULL;
}

int sim_thread_start(struct sim_thread *t, const char *who, struct st_error *err)
{
	if (t->on)
		return st_error_set(err, ST_ERR_ARG, "%s: thread already running", who);
	t->stop = 0;
	if (pthread_create(&t->thread, NULL, sim_thread_main, t))
		return st_error_set(err, ST_ERR_IO, "%s: cannot start a thread", who);
	t->on = true;
	return 0;
}

int sim_thread_stop(struct sim_thread *t)
{
	if (!t->on)
		return 0;
	t->stop = 1;
	pthread_join(t->thread, NULL);
	t->on = false;
	return t->rc;
}
