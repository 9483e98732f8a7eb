/*
 * xport.h - byte transports to a printer: one interface, three back ends.
 *
 *   "fd"          POSIX termios on a file descriptor.  Pseudo-terminals
 *                 (/dev/pts/N, or any path resolving there) always use it,
 *                 because libserialport cannot open ptys; the simulated
 *                 printers and the tests go through here.
 *   "serialport"  libserialport for real devices (/dev/ttyUSB0, /dev/ttyACM0,
 *                 /dev/serial/by-id/...), and port enumeration.
 *   "tcp"         tcp://HOST:PORT for serial-to-network bridges
 *                 (ser2net, ESP-Link, ...).
 *
 * Every call that can wait takes a time-out in milliseconds and never waits
 * longer (poll() against a monotonic deadline, EINTR restarted).  The one
 * exception is host-name resolution for tcp://, which is bounded by the
 * system resolver's own time-out (resolv.conf), not by ours.
 *
 * Link settings: raw 8N1, no flow control, baud rate from the options (ptys
 * accept and ignore it).  Writes loop over partial writes.
 *
 * Hang-up (pty master closed, USB cable pulled, TCP peer closed) is reported
 * as ST_ERR_IO with a message ending "closed by the other end", and from then
 * on xport_is_gone() is true and every read or write fails at once.
 *
 * Thread-safety: a handle may be used by one reading thread and one writing
 * thread at the same time; anything else needs the caller's lock.
 * Different handles are independent.
 */
#ifndef STRATUM_SERIAL_XPORT_H
#define STRATUM_SERIAL_XPORT_H

#include <stdbool.h>
#include <stddef.h>

#include "st_error.h"

/* Opaque transport handle. */
struct xport;

/* Which back end xport_open uses. */
enum xport_backend {
	XPORT_BACKEND_AUTO = 0,	  /* decide from the spec (see xport_open) */
	XPORT_BACKEND_FD,	  /* termios on a plain file descriptor */
	XPORT_BACKEND_SERIALPORT, /* libserialport */
	XPORT_BACKEND_TCP,	  /* tcp://HOST:PORT */
};

/* Default baud rate when xport_options.baudrate is 0. */
#define XPORT_DEFAULT_BAUD 115200
/* Default TCP connect time-out when xport_options.connect_timeout_ms is 0. */
#define XPORT_DEFAULT_CONNECT_MS 5000
/* How long DTR is held low for a reset pulse, ms. */
#define XPORT_RESET_PULSE_MS 100

/*
 * Open options.  A zero-initialised struct (or a NULL pointer) means:
 * 115200 baud, no reset, back end chosen from the spec, 5 s TCP connect.
 */
struct xport_options {
	int baudrate;		    /* bits/s; 0 = XPORT_DEFAULT_BAUD */
	/*
	 * true: after opening, pull DTR low for XPORT_RESET_PULSE_MS and raise
	 * it again, which resets Arduino-style boards (the caller then waits
	 * for the boot banner).  false: DTR and RTS are set asserted and left
	 * alone.  Either way HUPCL is cleared so closing the port does not drop
	 * DTR; note that Linux itself raises DTR when a tty is opened, so a
	 * board whose DTR was low before the open is reset by the open anyway.
	 * Ignored by ptys and TCP.
	 */
	bool dtr_reset;
	enum xport_backend backend; /* XPORT_BACKEND_AUTO = from the spec */
	int connect_timeout_ms;	    /* TCP connect bound; 0 = XPORT_DEFAULT_CONNECT_MS */
};

/*
 * xport_open - open the transport named by spec.
 *
 * spec:  "tcp://HOST:PORT" (HOST may be "[v6addr]", PORT 1..65535) -> tcp;
 *        a path that is, or resolves to, a pty slave (/dev/pts/N or a
 *        character device with major 136..143) -> fd;
 *        any other character device -> serialport.
 *        opt->backend other than AUTO forces a back end (fd or serialport
 *        for paths; tcp only for tcp:// specs).
 * opt:   may be NULL for the defaults.
 * out:   receives the new handle (caller frees with xport_close); NULL on
 *        error.
 * Returns 0, or ST_ERR_ARG (malformed spec, bad option, not a serial
 * device), ST_ERR_IO (the OS refused: missing port, permission, busy,
 * refused connection, time-out), ST_ERR_UNSUPPORTED (baud rate the back end
 * cannot set), ST_ERR_NOMEM; err names the port, what failed and what to do.
 * With dtr_reset the call sleeps XPORT_RESET_PULSE_MS.
 */
int xport_open(const char *spec, const struct xport_options *opt, struct xport **out,
	       struct st_error *err);

/*
 * xport_read - read up to cap bytes (cap is clamped to INT_MAX), waiting at
 * most timeout_ms (>= 0; 0 = only what is already there) for the first byte.
 * Returns the number of bytes read (> 0), 0 on time-out, or ST_ERR_IO
 * (hang-up: xport_is_gone() then true; or another OS error) / ST_ERR_ARG
 * with err filled.
 */
int xport_read(struct xport *x, void *buf, size_t cap, int timeout_ms, struct st_error *err);

/*
 * xport_write_all - write all len bytes, looping over partial writes, within
 * a total of timeout_ms (>= 0).  *sent (may be NULL) receives how many bytes
 * were handed to the OS, also on error.  Returns 0 when all went, or
 * ST_ERR_IO on time-out (the message says how many of len bytes went) or
 * hang-up or another OS error, ST_ERR_ARG on bad arguments.
 */
int xport_write_all(struct xport *x, const void *buf, size_t len, int timeout_ms, size_t *sent,
		    struct st_error *err);

/*
 * xport_drain - wait at most timeout_ms (>= 0) until the bytes written so
 * far have left the OS output queue (ttys: TIOCOUTQ polled, since tcdrain
 * and sp_drain cannot be bounded; ptys and TCP: returns at once).  Returns
 * 0, or ST_ERR_IO on time-out, hang-up or OS error.
 */
int xport_drain(struct xport *x, int timeout_ms, struct st_error *err);

/*
 * xport_close - close and free the handle; NULL is safe.  Never waits: on a
 * tty, output not yet sent is discarded (call xport_drain first to keep it);
 * on TCP the kernel still delivers what was queued.
 */
void xport_close(struct xport *x);

/*
 * xport_describe - one human-readable line for the open transport, e.g.
 * "/dev/pts/3 (pty, 115200 baud)", "/dev/ttyUSB0 (serial, 250000 baud)",
 * "tcp://127.0.0.1:5000".  The string belongs to x and lives until
 * xport_close.  NULL x gives "(no port)".
 */
const char *xport_describe(const struct xport *x);

/* xport_backend_of - the back end x was opened with. */
enum xport_backend xport_backend_of(const struct xport *x);

/*
 * xport_fd - the file descriptor under x, for callers that poll() several
 * sources (readable = xport_read will not wait).  Do not read, write or
 * close it directly.  Returns -1 for NULL x.
 */
int xport_fd(const struct xport *x);

/* xport_is_gone - true once the other end hung up (see the top comment). */
bool xport_is_gone(const struct xport *x);

/*
 * xport_clock_s - the clock x's waits and time-outs run on, in seconds: the
 * monotonic clock (st_clock.h) for every line xport_open makes (and for a
 * NULL x).  Drivers
 * measure their own time-outs with it, so a transport with a simulated
 * clock (tests/fuzz) gets whole runs without real waiting.
 */
double xport_clock_s(struct xport *x);

/* xport_pause_ms - sleep ms milliseconds on x's clock (signals restarted). */
void xport_pause_ms(struct xport *x, int ms);

/* How a listed port is attached. */
enum xport_transport {
	XPORT_TRANSPORT_NATIVE,	   /* on-board UART or unknown */
	XPORT_TRANSPORT_USB,
	XPORT_TRANSPORT_BLUETOOTH,
};

/* One serial port found by xport_list.  Strings are NULL when unknown. */
struct xport_port_info {
	char *name;	       /* device path, e.g. "/dev/ttyUSB0" */
	char *by_id;	       /* stable /dev/serial/by-id/... link to it, or NULL */
	char *description;     /* libserialport's one-line description */
	enum xport_transport transport;
	int usb_vid;	       /* USB vendor id, -1 when not USB */
	int usb_pid;	       /* USB product id, -1 when not USB */
	char *manufacturer;    /* USB strings */
	char *product;
	char *serial;
};

/*
 * xport_list - enumerate the serial ports the OS knows (ptys are not
 * listed), sorted by name.  *out receives an array of *n entries (caller
 * frees with xport_list_free); with no ports, *out is NULL and *n is 0.
 * Returns 0, or ST_ERR_IO / ST_ERR_NOMEM with *out NULL and *n 0.
 */
int xport_list(struct xport_port_info **out, size_t *n, struct st_error *err);

/* xport_list_free - free an xport_list result; NULL is safe. */
void xport_list_free(struct xport_port_info *list, size_t n);

/* xport_transport_name - "native", "usb" or "bluetooth". */
const char *xport_transport_name(enum xport_transport t);

#endif /* STRATUM_SERIAL_XPORT_H */
