/*
 * xport_sp.c - the "serialport" back end (libserialport) for real devices,
 * and port enumeration.
 *
 * libserialport opens the port and sets 8N1, the baud rate (non-standard
 * rates such as 250000 included), no flow control and DTR/RTS.  The I/O
 * itself goes through the port's file descriptor (sp_get_port_handle) so the
 * shared poll()-based loops in xport.c bound every wait; libserialport's own
 * sp_drain cannot be bounded, so drain polls TIOCOUTQ instead.
 */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <libserialport.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#include "xport_impl.h"

#define BY_ID_DIR "/dev/serial/by-id"

/* Turn a failed libserialport call into our error, naming the step. */
static int lsp_error(const struct xport *x, const char *what, enum sp_return r,
		    struct st_error *err)
{
	switch (r) {
	case SP_ERR_FAIL:
		return xport_open_error(x->spec, what, sp_last_error_code(), err);
	case SP_ERR_MEM:
		return st_error_set(err, ST_ERR_NOMEM, "%s: %s: out of memory", x->spec, what);
	case SP_ERR_SUPP:
		return st_error_set(err, ST_ERR_UNSUPPORTED,
				    "%s: %s: not supported by this port or OS (baud rate %d?); "
				    "try a standard rate such as 115200",
				    x->spec, what, x->baudrate);
	default:
		return st_error_set(err, ST_ERR_ARG,
				    "%s: %s: not a serial port libserialport can use; give the "
				    "printer's device, e.g. /dev/ttyUSB0, or see `stratum ports`",
				    x->spec, what);
	}
}

/* Build the 8N1 / no-flow-control / DTR+RTS configuration and apply it. */
static enum sp_return lsp_configure(struct sp_port *port, int baud, bool dtr_low)
{
	struct sp_port_config *cfg = NULL;
	enum sp_return r = sp_new_config(&cfg);

	if (r != SP_OK)
		return r;
	/* Flow control first: it may change the DTR/RTS fields set below. */
	if ((r = sp_set_config_flowcontrol(cfg, SP_FLOWCONTROL_NONE)) != SP_OK ||
	    (r = sp_set_config_baudrate(cfg, baud)) != SP_OK ||
	    (r = sp_set_config_bits(cfg, 8)) != SP_OK ||
	    (r = sp_set_config_parity(cfg, SP_PARITY_NONE)) != SP_OK ||
	    (r = sp_set_config_stopbits(cfg, 1)) != SP_OK ||
	    (r = sp_set_config_dtr(cfg, dtr_low ? SP_DTR_OFF : SP_DTR_ON)) != SP_OK ||
	    (r = sp_set_config_rts(cfg, SP_RTS_ON)) != SP_OK)
		goto out_free_config;
	r = sp_set_config(port, cfg);

out_free_config:
	sp_free_config(cfg);
	return r;
}

/*
 * Our termios adjustments on top of libserialport's: VMIN=1/VTIME=0 so a
 * non-blocking read without data is EAGAIN (not a false end-of-file), and
 * HUPCL off so closing does not drop DTR and reset the board.
 */
static int lsp_tune_fd(int fd)
{
	struct termios t;

	if (tcgetattr(fd, &t) < 0)
		return errno;
	t.c_cflag &= ~(tcflag_t)HUPCL;
	t.c_cc[VMIN] = 1;
	t.c_cc[VTIME] = 0;
	if (tcsetattr(fd, TCSANOW, &t) < 0)
		return errno;
	if (fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK) < 0)
		return errno;
	return 0;
}

/* Open x->path through libserialport; sets x->fd, x->kind, x->priv. */
static int lsp_open_port(struct xport *x, const struct xport_options *opt, struct st_error *err)
{
	struct sp_port *port = NULL;
	enum sp_return r;
	int fd = -1, e, rc;

	r = sp_get_port_by_name(x->path, &port);
	if (r != SP_OK)
		return lsp_error(x, "cannot look up the port", r, err);
	r = sp_open(port, SP_MODE_READ_WRITE);
	if (r != SP_OK) {
		rc = lsp_error(x, "cannot open", r, err);
		goto out_free_port;
	}
	r = lsp_configure(port, x->baudrate, opt->dtr_reset);
	if (r != SP_OK) {
		rc = lsp_error(x, "cannot set 8N1 and the baud rate", r, err);
		goto out_close_port;
	}
	r = sp_get_port_handle(port, &fd);
	if (r != SP_OK || fd < 0) {
		rc = lsp_error(x, "cannot get the port's descriptor", r, err);
		goto out_close_port;
	}
	e = lsp_tune_fd(fd);
	if (e) {
		rc = xport_open_error(x->spec, "cannot set raw mode", e, err);
		goto out_close_port;
	}
	/* Keep other programs from opening the same printer port. */
	if (ioctl(fd, TIOCEXCL) < 0) {
		rc = xport_open_error(x->spec, "cannot lock the port", errno, err);
		goto out_close_port;
	}
	if (opt->dtr_reset) {
		/* DTR is low since lsp_configure: finish the reset pulse. */
		xport_sleep_ms(XPORT_RESET_PULSE_MS);
		r = sp_set_dtr(port, SP_DTR_ON);
		if (r != SP_OK) {
			rc = lsp_error(x, "cannot raise DTR after the reset pulse", r, err);
			goto out_close_port;
		}
	}
	x->fd = fd;
	x->kind = "serial";
	x->priv = port;
	return 0;

out_close_port:
	sp_close(port);
out_free_port:
	sp_free_port(port);
	return rc;
}

/* Reads and writes go straight to the descriptor, as in the fd back end. */
static long lsp_read_step(struct xport *x, void *buf, size_t cap)
{
	for (;;) {
		ssize_t n = read(x->fd, buf, cap);

		if (n > 0)
			return (long)n;
		if (n == 0)
			return XPORT_STEP_GONE; /* device gone (VMIN=1: no false EOF) */
		if (errno == EINTR)
			continue;
		if (errno == EAGAIN)
			return XPORT_STEP_AGAIN;
		if (errno == EIO || errno == ENODEV || errno == ENXIO)
			return XPORT_STEP_GONE;
		x->sys_errno = errno;
		return XPORT_STEP_ERROR;
	}
}

static long lsp_write_step(struct xport *x, const void *buf, size_t len)
{
	for (;;) {
		ssize_t n = write(x->fd, buf, len);

		if (n >= 0)
			return (long)n;
		if (errno == EINTR)
			continue;
		if (errno == EAGAIN)
			return XPORT_STEP_AGAIN;
		if (errno == EIO || errno == ENODEV || errno == ENXIO || errno == EPIPE)
			return XPORT_STEP_GONE;
		x->sys_errno = errno;
		return XPORT_STEP_ERROR;
	}
}

/* sp_output_waiting would do, but keep the same answer as the fd back end. */
static long lsp_outq(struct xport *x)
{
	int q = 0;

	if (ioctl(x->fd, TIOCOUTQ, &q) < 0)
		return -1;
	return q;
}

/* Close without waiting: unsent output is discarded first (see fd_close). */
static void lsp_close_port(struct xport *x)
{
	struct sp_port *port = x->priv;

	if (port) {
		tcflush(x->fd, TCOFLUSH);
		sp_close(port);
		sp_free_port(port);
	}
	x->priv = NULL;
	x->fd = -1;
}

const struct xport_ops xport_sp_ops = {
	.name = "serialport",
	.open = lsp_open_port,
	.read = lsp_read_step,
	.write = lsp_write_step,
	.outq = lsp_outq,
	.close = lsp_close_port,
};

/* strdup that maps NULL to NULL; *oom set when a copy fails. */
static char *dup_or_null(const char *s, bool *oom)
{
	char *d;

	if (!s)
		return NULL;
	d = strdup(s);
	if (!d)
		*oom = true;
	return d;
}

/* The /dev/serial/by-id link resolving to device (resolved), or NULL. */
static char *find_by_id(const char *device, bool *oom)
{
	DIR *dir = opendir(BY_ID_DIR);
	struct dirent *de;
	char *found = NULL;

	if (!dir)
		return NULL;
	while (!found && (de = readdir(dir))) {
		char link[PATH_MAX];
		char *target;

		if (de->d_name[0] == '.')
			continue;
		if (snprintf(link, sizeof(link), "%s/%s", BY_ID_DIR, de->d_name) >=
		    (int)sizeof(link))
			continue;
		target = realpath(link, NULL);
		if (target && !strcmp(target, device))
			found = dup_or_null(link, oom);
		free(target);
	}
	closedir(dir);
	return found;
}

/* Fill one entry from a libserialport port; false on OOM. */
static bool fill_info(struct xport_port_info *pi, const struct sp_port *port)
{
	bool oom = false;
	const char *name = sp_get_port_name(port);
	char *real = name ? realpath(name, NULL) : NULL;

	pi->usb_vid = pi->usb_pid = -1;
	pi->name = dup_or_null(name, &oom);
	pi->description = dup_or_null(sp_get_port_description(port), &oom);
	pi->by_id = find_by_id(real ? real : (name ? name : ""), &oom);
	free(real);
	switch (sp_get_port_transport(port)) {
	case SP_TRANSPORT_USB:
		pi->transport = XPORT_TRANSPORT_USB;
		if (sp_get_port_usb_vid_pid(port, &pi->usb_vid, &pi->usb_pid) != SP_OK)
			pi->usb_vid = pi->usb_pid = -1;
		pi->manufacturer = dup_or_null(sp_get_port_usb_manufacturer(port), &oom);
		pi->product = dup_or_null(sp_get_port_usb_product(port), &oom);
		pi->serial = dup_or_null(sp_get_port_usb_serial(port), &oom);
		break;
	case SP_TRANSPORT_BLUETOOTH:
		pi->transport = XPORT_TRANSPORT_BLUETOOTH;
		break;
	default:
		pi->transport = XPORT_TRANSPORT_NATIVE;
		break;
	}
	return !oom && pi->name;
}

/* qsort order: by device name. */
static int cmp_info(const void *a, const void *b)
{
	const struct xport_port_info *pa = a, *pb = b;

	return strcmp(pa->name ? pa->name : "", pb->name ? pb->name : "");
}

int xport_list(struct xport_port_info **out, size_t *n, struct st_error *err)
{
	struct sp_port **ports = NULL;
	struct xport_port_info *list = NULL;
	size_t count = 0, filled = 0;
	enum sp_return r;
	int rc;

	if (out)
		*out = NULL;
	if (n)
		*n = 0;
	if (!out || !n)
		return st_error_set(err, ST_ERR_ARG, "xport_list: no output given");
	r = sp_list_ports(&ports);
	if (r != SP_OK) {
		if (r == SP_ERR_MEM)
			return st_error_set(err, ST_ERR_NOMEM, "listing serial ports: out of memory");
		return st_error_set(err, ST_ERR_IO, "listing serial ports failed: %s",
				    r == SP_ERR_FAIL ? strerror(sp_last_error_code())
						     : "not supported on this system");
	}
	while (ports[count])
		count++;
	if (count == 0) {
		rc = 0;
		goto out_free_ports;
	}
	list = calloc(count, sizeof(*list));
	if (!list) {
		rc = st_error_set(err, ST_ERR_NOMEM, "listing serial ports: out of memory");
		goto out_free_ports;
	}
	for (filled = 0; filled < count; filled++) {
		if (!fill_info(&list[filled], ports[filled])) {
			filled++;
			rc = st_error_set(err, ST_ERR_NOMEM, "listing serial ports: out of memory");
			goto out_free_list;
		}
	}
	qsort(list, count, sizeof(*list), cmp_info);
	*out = list;
	*n = count;
	sp_free_port_list(ports);
	return 0;

out_free_list:
	xport_list_free(list, filled);
out_free_ports:
	sp_free_port_list(ports);
	return rc;
}

void xport_list_free(struct xport_port_info *list, size_t n)
{
	if (!list)
		return;
	for (size_t i = 0; i < n; i++) {
		free(list[i].name);
		free(list[i].by_id);
		free(list[i].description);
		free(list[i].manufacturer);
		free(list[i].product);
		free(list[i].serial);
	}
	free(list);
}
