/*
 * xport.c - the transport interface: spec parsing and back-end choice, and
 * the bounded waiting loops every back end shares (poll() against a
 * monotonic deadline, EINTR restarted, partial writes looped).
 */
#include <errno.h>
#include <limits.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include "xport_impl.h"
#include "st_clock.h"

/* Unix98 pty slaves use majors 136..143 (Linux devices.txt). */
#define PTY_SLAVE_MAJOR_FIRST 136
#define PTY_SLAVE_MAJOR_LAST 143

/* Monotonic milliseconds, for deadlines that ignore wall-clock jumps. */
int64_t xport_now_ms(void)
{
	return st_mono_ms();
}

/* Sleep the full ms even if signals interrupt nanosleep. */
void xport_sleep_ms(int ms)
{
	struct timespec ts = {ms / 1000, (long)(ms % 1000) * 1000000L};

	while (nanosleep(&ts, &ts) < 0 && errno == EINTR)
		;
}

int64_t xport_clock_ms(struct xport *x)
{
	return x && x->ops->clock_us ? x->ops->clock_us(x) / 1000 : xport_now_ms();
}

double xport_clock_s(struct xport *x)
{
	return x && x->ops->clock_us ? (double)x->ops->clock_us(x) * 1e-6 : st_mono_s();
}

void xport_pause_ms(struct xport *x, int ms)
{
	if (x && x->ops->pause_ms)
		x->ops->pause_ms(x, ms);
	else
		xport_sleep_ms(ms);
}

/* Milliseconds left on x's clock until deadline, never negative, as poll()
 * wants it. */
static int ms_left(struct xport *x, int64_t deadline)
{
	int64_t left = deadline - xport_clock_ms(x);

	if (left <= 0)
		return 0;
	return left > INT_MAX ? INT_MAX : (int)left;
}

int xport_open_error(const char *spec, const char *what, int e, struct st_error *err)
{
	switch (e) {
	case ENOENT:
	case ENXIO:
	case ENODEV:
		return st_error_set(err, ST_ERR_IO,
				    "%s: %s: no such port (%s); is the printer plugged in and "
				    "powered? `stratum ports` lists the ports found",
				    spec, what, strerror(e));
	case EACCES:
	case EPERM:
		return st_error_set(err, ST_ERR_IO,
				    "%s: %s: permission denied; add yourself to the dialout group "
				    "(sudo usermod -aG dialout $USER) and log in again",
				    spec, what);
	case EBUSY:
		return st_error_set(err, ST_ERR_IO,
				    "%s: %s: port is busy; close the other program using it "
				    "(slicer, OctoPrint, ModemManager) and try again",
				    spec, what);
	case ENOTTY:
	case EINVAL:
		return st_error_set(err, ST_ERR_ARG,
				    "%s: %s: not a serial port (%s); give the printer's device, "
				    "e.g. /dev/ttyUSB0, or see `stratum ports`",
				    spec, what, strerror(e));
	default:
		return st_error_set(err, ST_ERR_IO, "%s: %s: %s", spec, what, strerror(e));
	}
}

bool xport_baud_to_speed(int baud, unsigned int *speed)
{
	static const struct {
		int baud;
		speed_t speed;
	} table[] = {
		{1200, B1200},	   {2400, B2400},     {4800, B4800},	 {9600, B9600},
		{19200, B19200},   {38400, B38400},   {57600, B57600},	 {115200, B115200},
		{230400, B230400}, {460800, B460800}, {500000, B500000}, {576000, B576000},
		{921600, B921600}, {1000000, B1000000},
	};

	for (size_t i = 0; i < sizeof(table) / sizeof(table[0]); i++) {
		if (table[i].baud == baud) {
			*speed = table[i].speed;
			return true;
		}
	}
	return false;
}

int xport_tty_raw(int fd, bool set_speed, unsigned int speed)
{
	struct termios t;

	if (tcgetattr(fd, &t) < 0)
		return errno;
	cfmakeraw(&t);
	t.c_cflag &= ~(tcflag_t)(CSIZE | PARENB | CSTOPB | CRTSCTS | HUPCL);
	t.c_cflag |= CS8 | CLOCAL | CREAD;
	t.c_iflag &= ~(tcflag_t)(IXON | IXOFF | IXANY);
	t.c_cc[VMIN] = 1;
	t.c_cc[VTIME] = 0;
	if (set_speed && (cfsetispeed(&t, speed) < 0 || cfsetospeed(&t, speed) < 0))
		return errno;
	while (tcsetattr(fd, TCSANOW, &t) < 0) {
		if (errno != EINTR)
			return errno;
	}
	return 0;
}

int xport_tty_modem(int fd, bool reset)
{
	int lines = TIOCM_DTR | TIOCM_RTS;

	if (reset) {
		int dtr = TIOCM_DTR;

		if (ioctl(fd, TIOCMBIC, &dtr) < 0)
			return errno;
		xport_sleep_ms(XPORT_RESET_PULSE_MS);
	}
	if (ioctl(fd, TIOCMBIS, &lines) < 0)
		return errno;
	return 0;
}

/* True when path (already resolved) names a pty slave. */
static bool is_pty_slave(const char *path, const struct stat *st)
{
	unsigned int maj;

	if (!strncmp(path, "/dev/pts/", 9))
		return true;
	if (!S_ISCHR(st->st_mode))
		return false;
	maj = major(st->st_rdev);
	return maj >= PTY_SLAVE_MAJOR_FIRST && maj <= PTY_SLAVE_MAJOR_LAST;
}

/* Fill x->path and pick the device back end for a path spec. */
static int choose_device(struct xport *x, enum xport_backend forced, struct st_error *err)
{
	struct stat st;
	char *real = realpath(x->spec, NULL);

	if (!real) {
		if (errno == ENOMEM)
			return st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", x->spec);
		return xport_open_error(x->spec, "cannot open", errno, err);
	}
	x->path = real;
	if (stat(real, &st) < 0)
		return xport_open_error(x->spec, "cannot open", errno, err);
	if (!S_ISCHR(st.st_mode))
		return st_error_set(err, ST_ERR_ARG,
				    "%s: not a serial port (not a character device); give the "
				    "printer's device, e.g. /dev/ttyUSB0, or tcp://HOST:PORT",
				    x->spec);
	x->is_pty = is_pty_slave(real, &st);
	if (x->is_pty && forced == XPORT_BACKEND_SERIALPORT)
		return st_error_set(err, ST_ERR_ARG,
				    "%s: is a pseudo-terminal, which libserialport cannot open; "
				    "leave the back end on auto",
				    x->spec);
	if (forced == XPORT_BACKEND_FD || x->is_pty) {
		x->ops = &xport_fd_ops;
		x->backend = XPORT_BACKEND_FD;
	} else {
		x->ops = &xport_sp_ops;
		x->backend = XPORT_BACKEND_SERIALPORT;
	}
	return 0;
}

int xport_open(const char *spec, const struct xport_options *opt, struct xport **out,
	       struct st_error *err)
{
	struct xport_options o = {0};
	struct xport *x;
	bool tcp;
	int rc;

	if (out)
		*out = NULL;
	if (!spec || !*spec || !out)
		return st_error_set(err, ST_ERR_ARG, "xport_open: no port given");
	if (opt)
		o = *opt;
	if (o.baudrate == 0)
		o.baudrate = XPORT_DEFAULT_BAUD;
	if (o.connect_timeout_ms == 0)
		o.connect_timeout_ms = XPORT_DEFAULT_CONNECT_MS;
	if (o.baudrate < 0 || o.connect_timeout_ms < 0)
		return st_error_set(err, ST_ERR_ARG, "%s: negative baud rate or time-out", spec);
	if (o.backend < XPORT_BACKEND_AUTO || o.backend > XPORT_BACKEND_TCP)
		return st_error_set(err, ST_ERR_ARG, "%s: unknown transport back end %d", spec,
				    (int)o.backend);
	tcp = !strncmp(spec, "tcp://", 6);
	if (tcp != (o.backend == XPORT_BACKEND_TCP) && o.backend != XPORT_BACKEND_AUTO)
		return st_error_set(err, ST_ERR_ARG,
				    "%s: the tcp back end takes only tcp://HOST:PORT specs, and "
				    "tcp:// specs only the tcp back end",
				    spec);

	x = calloc(1, sizeof(*x));
	if (!x)
		return st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", spec);
	x->fd = -1;
	x->baudrate = o.baudrate;
	atomic_init(&x->gone, false);
	x->spec = strdup(spec);
	if (!x->spec) {
		rc = st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", spec);
		goto out_free;
	}
	if (tcp) {
		x->ops = &xport_tcp_ops;
		x->backend = XPORT_BACKEND_TCP;
	} else {
		rc = choose_device(x, o.backend, err);
		if (rc < 0)
			goto out_free;
	}
	rc = x->ops->open(x, &o, err);
	if (rc < 0)
		goto out_free;
	if (tcp)
		snprintf(x->desc, sizeof(x->desc), "%s", x->spec);
	else
		snprintf(x->desc, sizeof(x->desc), "%s (%s, %d baud)", x->spec, x->kind,
			 x->baudrate);
	*out = x;
	return 0;

out_free:
	free(x->path);
	free(x->spec);
	free(x);
	return rc;
}

/* The error for any call on a handle that already saw the hang-up. */
static int gone_error(struct xport *x, struct st_error *err)
{
	atomic_store(&x->gone, true);
	return st_error_set(err, ST_ERR_IO,
			    "%s: port closed by the other end; check the cable, the printer's "
			    "power or the bridge, then reconnect",
			    x->spec);
}

/*
 * Wait until x->fd is ready for events or the deadline passes.
 * Returns 1 ready, 2 when only POLLHUP/POLLERR came (the next step
 * reports why), 0 on time-out, <0 with err filled.
 */
static int wait_fd(struct xport *x, short events, int64_t deadline, struct st_error *err)
{
	for (;;) {
		struct pollfd p = {.fd = x->fd, .events = events};
		/* a simulated clock: look without blocking, then let the time
		 * pass that poll() would have waited */
		bool simulated = x->ops->pause_ms != NULL;
		int n = poll(&p, 1, simulated ? 0 : ms_left(x, deadline));

		if (n == 0 && simulated && ms_left(x, deadline) > 0) {
			x->ops->pause_ms(x, ms_left(x, deadline));
			continue;
		}

		if (n > 0) {
			if (p.revents & POLLNVAL)
				return st_error_set(err, ST_ERR_IO, "%s: descriptor is not open",
						    x->spec);
			if (!(p.revents & events) && (p.revents & (POLLHUP | POLLERR)))
				return 2;
			return 1;
		}
		if (n == 0)
			return 0;
		if (errno != EINTR)
			return st_error_set(err, ST_ERR_IO, "%s: poll failed: %s", x->spec,
					    strerror(errno));
	}
}

/* Common argument checks; returns 0 or ST_ERR_ARG / the hang-up error. */
static int check_call(struct xport *x, const void *buf, size_t len, int timeout_ms,
		      const char *fn, struct st_error *err)
{
	if (!x || (!buf && len) || timeout_ms < 0)
		return st_error_set(err, ST_ERR_ARG,
				    "%s: no handle, no buffer or a negative time-out", fn);
	if (atomic_load(&x->gone))
		return gone_error(x, err);
	return 0;
}

int xport_read(struct xport *x, void *buf, size_t cap, int timeout_ms, struct st_error *err)
{
	int64_t deadline = xport_clock_ms(x) + timeout_ms;
	int rc = check_call(x, buf, cap, timeout_ms, "xport_read", err);

	if (rc < 0)
		return rc;
	if (cap == 0)
		return 0;
	if (cap > INT_MAX)
		cap = INT_MAX;
	for (bool hup = false;;) {
		long n = x->ops->read(x, buf, cap);

		if (n > 0)
			return (int)n;
		/* Hang-up flagged by poll but the read has nothing to say: gone,
		 * rather than spinning on a descriptor that stays "ready". */
		if (n == XPORT_STEP_GONE || (n == XPORT_STEP_AGAIN && hup))
			return gone_error(x, err);
		if (n == XPORT_STEP_ERROR)
			return st_error_set(err, ST_ERR_IO, "%s: read failed: %s", x->spec,
					    strerror(x->sys_errno));
		rc = wait_fd(x, POLLIN, deadline, err);
		if (rc <= 0)
			return rc;
		hup = rc == 2;
	}
}

int xport_write_all(struct xport *x, const void *buf, size_t len, int timeout_ms, size_t *sent,
		    struct st_error *err)
{
	int64_t deadline = xport_clock_ms(x) + timeout_ms;
	const unsigned char *p = buf;
	size_t done = 0;
	int rc = check_call(x, buf, len, timeout_ms, "xport_write_all", err);

	if (sent)
		*sent = 0;
	if (rc < 0)
		return rc;
	while (done < len) {
		long n = x->ops->write(x, p + done, len - done);

		if (n > 0) {
			done += (size_t)n;
			if (sent)
				*sent = done;
			continue;
		}
		if (n == XPORT_STEP_GONE) {
			gone_error(x, err);
			if (err) {
				char tail[64];

				snprintf(tail, sizeof(tail), " (%zu of %zu bytes sent)", done, len);
				if (strlen(err->msg) + strlen(tail) < sizeof(err->msg))
					strcat(err->msg, tail);
			}
			return ST_ERR_IO;
		}
		if (n == XPORT_STEP_ERROR)
			return st_error_set(err, ST_ERR_IO, "%s: write failed after %zu of %zu bytes: %s",
					    x->spec, done, len, strerror(x->sys_errno));
		rc = wait_fd(x, POLLOUT, deadline, err);
		if (rc < 0)
			return rc;
		if (rc == 0)
			return st_error_set(err, ST_ERR_IO,
					    "%s: write timed out after %d ms with %zu of %zu bytes "
					    "sent; the printer is not reading (flow stopped, board "
					    "hung or wrong port?)",
					    x->spec, timeout_ms, done, len);
	}
	return 0;
}

int xport_drain(struct xport *x, int timeout_ms, struct st_error *err)
{
	int64_t deadline = xport_clock_ms(x) + timeout_ms;
	int rc = check_call(x, NULL, 0, timeout_ms, "xport_drain", err);

	if (rc < 0)
		return rc;
	for (;;) {
		long q = x->ops->outq(x);

		if (q <= 0)
			return 0; /* empty, or the back end cannot tell */
		if (ms_left(x, deadline) == 0)
			return st_error_set(err, ST_ERR_IO,
					    "%s: drain timed out after %d ms with %ld bytes still "
					    "queued; the device is not taking data",
					    x->spec, timeout_ms, q);
		xport_pause_ms(x, ms_left(x, deadline) < 2 ? ms_left(x, deadline) : 2);
	}
}

void xport_close(struct xport *x)
{
	if (!x)
		return;
	x->ops->close(x);
	free(x->path);
	free(x->spec);
	free(x);
}

const char *xport_describe(const struct xport *x)
{
	return x ? x->desc : "(no port)";
}

enum xport_backend xport_backend_of(const struct xport *x)
{
	return x ? x->backend : XPORT_BACKEND_AUTO;
}

int xport_fd(const struct xport *x)
{
	return x ? x->fd : -1;
}

bool xport_is_gone(const struct xport *x)
{
	return x && atomic_load(&x->gone);
}

const char *xport_transport_name(enum xport_transport t)
{
	switch (t) {
	case XPORT_TRANSPORT_USB:
		return "usb";
	case XPORT_TRANSPORT_BLUETOOTH:
		return "bluetooth";
	default:
		return "native";
	}
}
