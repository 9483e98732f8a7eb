/*
 * xport_fd.c - the "fd" back end: termios on a plain file descriptor.
 *
 * Used for pseudo-terminals (libserialport cannot open them), so the
 * simulated printers and the tests run through here, and for real ttys when
 * the caller forces it.  Speed is set from a Bxxx constant; ptys accept and
 * ignore it, real ttys need a standard rate (the serialport back end handles
 * non-standard rates such as 250000).
 */
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#include "xport_impl.h"

/* Open and configure x->path; sets x->fd and x->kind. */
static int fd_open(struct xport *x, const struct xport_options *opt, struct st_error *err)
{
	unsigned int speed = 0;
	bool have_speed = xport_baud_to_speed(x->baudrate, &speed);
	bool pty = x->is_pty;
	int fd, e, rc;

	/* O_NOCTTY: a pty must never become our controlling terminal, or the
	 * master closing would send us SIGHUP. */
	fd = open(x->path, O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
	if (fd < 0)
		return xport_open_error(x->spec, "cannot open", errno, err);
	if (!isatty(fd)) {
		rc = xport_open_error(x->spec, "cannot use", ENOTTY, err);
		goto out_close_fd;
	}
	if (!pty && !have_speed) {
		rc = st_error_set(err, ST_ERR_UNSUPPORTED,
				  "%s: %d baud has no standard termios constant; use the "
				  "libserialport back end for this rate",
				  x->spec, x->baudrate);
		goto out_close_fd;
	}
	e = xport_tty_raw(fd, have_speed, speed);
	if (e) {
		rc = xport_open_error(x->spec, "cannot set 8N1 raw mode", e, err);
		goto out_close_fd;
	}
	if (!pty) {
		/* Keep other programs from opening the same printer port. */
		if (ioctl(fd, TIOCEXCL) < 0) {
			rc = xport_open_error(x->spec, "cannot lock the port", errno, err);
			goto out_close_fd;
		}
		e = xport_tty_modem(fd, opt->dtr_reset);
		if (e) {
			rc = xport_open_error(x->spec, "cannot set DTR/RTS", e, err);
			goto out_close_fd;
		}
	}
	x->fd = fd;
	x->kind = pty ? "pty" : "tty";
	return 0;

out_close_fd:
	close(fd);
	return rc;
}

/*
 * One non-blocking read.  A pty slave whose master closed reads EIO or 0;
 * an unplugged USB tty reads 0 or EIO/ENODEV: all hang-ups.  (VMIN=1 means
 * "no data" is EAGAIN, never 0.)
 */
static long fd_read(struct xport *x, void *buf, size_t cap)
{
	for (;;) {
		ssize_t n = read(x->fd, buf, cap);

		if (n > 0)
			return (long)n;
		if (n == 0)
			return XPORT_STEP_GONE;
		switch (errno) {
		case EINTR:
			continue;
		case EAGAIN:
			return XPORT_STEP_AGAIN;
		case EIO:
		case ENODEV:
		case ENXIO:
			return XPORT_STEP_GONE;
		default:
			x->sys_errno = errno;
			return XPORT_STEP_ERROR;
		}
	}
}

/* One non-blocking write; EIO after a hang-up. */
static long fd_write(struct xport *x, const void *buf, size_t len)
{
	for (;;) {
		ssize_t n = write(x->fd, buf, len);

		if (n >= 0)
			return (long)n;
		switch (errno) {
		case EINTR:
			continue;
		case EAGAIN:
			return XPORT_STEP_AGAIN;
		case EIO:
		case ENODEV:
		case ENXIO:
		case EPIPE:
			return XPORT_STEP_GONE;
		default:
			x->sys_errno = errno;
			return XPORT_STEP_ERROR;
		}
	}
}

/* Bytes still queued for output; ptys queue nothing of their own. */
static long fd_outq(struct xport *x)
{
	int q = 0;

	if (x->is_pty || ioctl(x->fd, TIOCOUTQ, &q) < 0)
		return -1;
	return q;
}

/*
 * Close without waiting: on a real tty, close() would wait up to the
 * driver's closing_wait (30 s) for stuck output, so unsent output is
 * discarded first (callers that care call xport_drain before closing).
 */
static void fd_close(struct xport *x)
{
	if (x->fd >= 0) {
		if (!x->is_pty)
			tcflush(x->fd, TCOFLUSH);
		close(x->fd);
	}
	x->fd = -1;
}

const struct xport_ops xport_fd_ops = {
	.name = "fd",
	.open = fd_open,
	.read = fd_read,
	.write = fd_write,
	.outq = fd_outq,
	.close = fd_close,
};
