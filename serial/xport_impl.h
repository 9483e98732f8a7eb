/*
 * xport_impl.h - private to serial/xport*.c: the back-end ops table, the
 * handle layout and helpers shared by the back ends.
 *
 * Back ends only do single non-blocking steps (read once, write once, open,
 * close); all waiting, deadlines and hang-up bookkeeping live in xport.c so
 * every back end gets the same bounds.
 */
#ifndef STRATUM_SERIAL_XPORT_IMPL_H
#define STRATUM_SERIAL_XPORT_IMPL_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "xport.h"

/* Result of one non-blocking step, besides a byte count >= 0. */
enum xport_step {
	XPORT_STEP_AGAIN = -1000, /* nothing possible now: poll and retry */
	XPORT_STEP_GONE = -1001,  /* the other end hung up */
	XPORT_STEP_ERROR = -1002, /* OS error; errno kept in x->sys_errno */
};

struct xport_ops {
	const char *name; /* "fd", "serialport", "tcp" */
	/*
	 * Open x->spec (path already resolved into x->path for devices) and
	 * set x->fd (non-blocking) and x->kind.  Returns 0 or <0 with err
	 * filled; on failure everything it built is undone.
	 */
	int (*open)(struct xport *x, const struct xport_options *opt, struct st_error *err);
	/* Read once: bytes (> 0), or an xport_step (never 0). */
	long (*read)(struct xport *x, void *buf, size_t cap);
	/* Write once: bytes (>= 0), or an xport_step. */
	long (*write)(struct xport *x, const void *buf, size_t len);
	/* Bytes still in the OS output queue (>= 0), or -1 if unknown. */
	long (*outq)(struct xport *x);
	/* Release what open built; x itself is freed by xport_close. */
	void (*close)(struct xport *x);
	/*
	 * Optional, NULL for every real line: the handle's own clock in
	 * microseconds, and a pause on it.  A line whose other end is a
	 * script in this process (the fuzz harness, tests/fuzz/util.c) knows
	 * that waiting changes nothing, so its clock jumps where a wait would
	 * block and the drivers' waits and time-outs take no real time.
	 */
	int64_t (*clock_us)(struct xport *x);
	void (*pause_ms)(struct xport *x, int ms);
};

struct xport {
	const struct xport_ops *ops;
	enum xport_backend backend;
	char *spec;	      /* as given by the caller, for messages */
	char *path;	      /* resolved device path (NULL for TCP) */
	const char *kind;     /* "pty", "tty", "serial", "tcp" for describe */
	bool is_pty;	      /* path is a pty slave (set before open) */
	int fd;		      /* non-blocking; -1 when closed */
	int baudrate;	      /* bits/s actually requested */
	int sys_errno;	      /* errno of the last XPORT_STEP_ERROR */
	atomic_bool gone;     /* set once by whichever thread sees the hang-up */
	void *priv;	      /* back-end data (struct sp_port * for serialport) */
	char desc[320];	      /* xport_describe text */
};

extern const struct xport_ops xport_fd_ops;
extern const struct xport_ops xport_sp_ops;
extern const struct xport_ops xport_tcp_ops;

/* Milliseconds on the monotonic clock. */
int64_t xport_now_ms(void);

/* Milliseconds on x's clock (xport_clock_s). */
int64_t xport_clock_ms(struct xport *x);

/* Sleep ms milliseconds, restarting after signals. */
void xport_sleep_ms(int ms);

/*
 * Fill err with a message for an open()-style failure of errno e on the
 * device spec ("what" names the step, e.g. "cannot open"), including advice
 * for the common cases (missing, permission, busy, not a tty).  Returns
 * ST_ERR_IO (ST_ERR_ARG when the device is not a serial port).
 */
int xport_open_error(const char *spec, const char *what, int e, struct st_error *err);

/* Map a baud rate to a termios speed_t; false when it has no Bxxx constant. */
bool xport_baud_to_speed(int baud, unsigned int *speed);

/*
 * Put the open tty fd in raw 8N1 mode, no flow control, CLOCAL|CREAD,
 * VMIN=1 VTIME=0 (so a non-blocking read with no data gives EAGAIN, never a
 * false end-of-file), HUPCL cleared.  set_speed: also set speed.  Returns 0
 * or an errno value.
 */
int xport_tty_raw(int fd, bool set_speed, unsigned int speed);

/*
 * Set DTR/RTS on a real tty fd: asserted, with an optional reset pulse on
 * DTR first.  Returns 0 or an errno value.
 */
int xport_tty_modem(int fd, bool reset);

#endif /* STRATUM_SERIAL_XPORT_IMPL_H */
