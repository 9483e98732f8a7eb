/*
 * check_xport.c - transports over real pseudo-terminals (openpty) and a
 * loopback TCP listener: round trips, bounded waits, 1 MiB writes through a
 * full pty buffer, write time-outs, hang-up detection, describe strings,
 * spec errors.  libserialport needs hardware, so only enumeration and a
 * non-serial character device are checked there.
 */
#include <arpa/inet.h>
#include <check.h>
#include <errno.h>
#include <netinet/in.h>
#include <poll.h>
#include <pthread.h>
#include <pty.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "suites.h"
#include "xport.h"

/* Pty fixture: master fd kept by the test, slave opened through xport. */
struct pty_fix {
	int master;
	char slave_path[64];
	struct xport *x;
};

static int64_t now_ms(void)
{
	struct timespec ts;

	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (int64_t)ts.tv_sec * 1000 + ts.tv_nsec / 1000000;
}

/* Make a pty pair and open its slave with opt (NULL = defaults). */
static void pty_open(struct pty_fix *f, const struct xport_options *opt)
{
	struct st_error err = {0};
	int slave;

	ck_assert_int_eq(openpty(&f->master, &slave, f->slave_path, NULL, NULL), 0);
	ck_assert_msg(xport_open(f->slave_path, opt, &f->x, &err) == 0, "open: %s", err.msg);
	/* Only xport's descriptor stays open on the slave side. */
	close(slave);
}

static void pty_close(struct pty_fix *f)
{
	xport_close(f->x);
	if (f->master >= 0)
		close(f->master);
}

/* Read exactly len bytes from fd (blocking, test side). */
static void read_exact(int fd, void *buf, size_t len)
{
	size_t got = 0;

	while (got < len) {
		struct pollfd p = {.fd = fd, .events = POLLIN};
		ssize_t n;

		ck_assert_int_eq(poll(&p, 1, 2000), 1);
		n = read(fd, (char *)buf + got, len - got);
		ck_assert_int_gt(n, 0);
		got += (size_t)n;
	}
}

/* Read from x until len bytes arrived, each read bounded. */
static void xread_exact(struct xport *x, void *buf, size_t len)
{
	struct st_error err = {0};
	size_t got = 0;

	while (got < len) {
		int n = xport_read(x, (char *)buf + got, len - got, 2000, &err);

		ck_assert_msg(n > 0, "xport_read gave %d: %s", n, err.msg);
		got += (size_t)n;
	}
}

/* Assert err.msg contains needle. */
static void msg_has(const struct st_error *err, const char *needle)
{
	ck_assert_msg(strstr(err->msg, needle), "'%s' not in message: %s", needle, err->msg);
}

START_TEST(pty_roundtrip)
{
	struct pty_fix f;
	struct st_error err = {0};
	char buf[64];
	const char *cmd = "N1 G28*18\n", *reply = "ok\nstart\n";

	pty_open(&f, NULL);
	ck_assert_int_eq(xport_write_all(f.x, cmd, strlen(cmd), 1000, NULL, &err), 0);
	read_exact(f.master, buf, strlen(cmd));
	ck_assert_mem_eq(buf, cmd, strlen(cmd));

	ck_assert_int_eq(write(f.master, reply, strlen(reply)), (ssize_t)strlen(reply));
	xread_exact(f.x, buf, strlen(reply));
	ck_assert_mem_eq(buf, reply, strlen(reply)); /* raw: no CR/LF mangling */

	/* All 256 byte values pass unchanged in both directions (binary X3G). */
	{
		unsigned char all[256], back[256];

		for (int i = 0; i < 256; i++)
			all[i] = (unsigned char)i;
		ck_assert_int_eq(xport_write_all(f.x, all, sizeof(all), 1000, NULL, &err), 0);
		read_exact(f.master, back, sizeof(back));
		ck_assert_mem_eq(all, back, sizeof(all));
		ck_assert_int_eq(write(f.master, all, sizeof(all)), 256);
		xread_exact(f.x, back, sizeof(back));
		ck_assert_mem_eq(all, back, sizeof(all));
	}
	ck_assert_int_eq(xport_drain(f.x, 500, &err), 0);
	ck_assert(!xport_is_gone(f.x));
	pty_close(&f);
}
END_TEST

START_TEST(pty_read_timeout)
{
	struct pty_fix f;
	struct st_error err = {0};
	char buf[16];
	int64_t t0, dt;
	int n;

	pty_open(&f, NULL);
	t0 = now_ms();
	n = xport_read(f.x, buf, sizeof(buf), 200, &err);
	dt = now_ms() - t0;
	ck_assert_int_eq(n, 0);
	ck_assert_msg(dt >= 199 && dt <= 1200, "200 ms time-out took %lld ms", (long long)dt);

	/* Zero time-out: only what is there, no waiting. */
	t0 = now_ms();
	ck_assert_int_eq(xport_read(f.x, buf, sizeof(buf), 0, &err), 0);
	ck_assert_int_lt(now_ms() - t0, 100);
	ck_assert_int_eq(write(f.master, "x", 1), 1);
	ck_assert_int_eq(poll(&(struct pollfd){.fd = xport_fd(f.x), .events = POLLIN}, 1, 1000), 1);
	ck_assert_int_eq(xport_read(f.x, buf, sizeof(buf), 0, &err), 1);
	ck_assert_int_eq(buf[0], 'x');
	pty_close(&f);
}
END_TEST

#define BIG (1u << 20)

struct drain_arg {
	int fd;
	unsigned char *buf;
	size_t len;
};

/* Thread: read len bytes from the master, slowly at first. */
static void *drain_thread(void *p)
{
	struct drain_arg *a = p;
	size_t got = 0;

	usleep(50000); /* let the writer fill the pty buffer first */
	while (got < a->len) {
		ssize_t n = read(a->fd, a->buf + got, a->len - got);

		if (n <= 0)
			break;
		got += (size_t)n;
	}
	a->len = got;
	return NULL;
}

START_TEST(pty_write_big)
{
	struct pty_fix f;
	struct st_error err = {0};
	unsigned char *out = malloc(BIG), *in = malloc(BIG);
	struct drain_arg a;
	pthread_t th;
	size_t sent = 0;
	uint32_t s = 12345;

	ck_assert(out && in);
	for (size_t i = 0; i < BIG; i++) {
		s = s * 1103515245u + 12345u;
		out[i] = (unsigned char)(s >> 16);
	}
	pty_open(&f, NULL);
	a = (struct drain_arg){.fd = f.master, .buf = in, .len = BIG};
	ck_assert_int_eq(pthread_create(&th, NULL, drain_thread, &a), 0);
	ck_assert_msg(xport_write_all(f.x, out, BIG, 10000, &sent, &err) == 0, "%s", err.msg);
	ck_assert_uint_eq(sent, BIG);
	pthread_join(th, NULL);
	ck_assert_uint_eq(a.len, BIG);
	ck_assert_msg(!memcmp(in, out, BIG), "bytes arrived changed or out of order");
	pty_close(&f);
	free(out);
	free(in);
}
END_TEST

START_TEST(pty_write_timeout)
{
	struct pty_fix f;
	struct st_error err = {0};
	unsigned char *out = calloc(1, BIG);
	size_t sent = 0;
	int64_t t0, dt;
	int rc;
	char want[64];

	ck_assert_ptr_nonnull(out);
	pty_open(&f, NULL);
	t0 = now_ms();
	rc = xport_write_all(f.x, out, BIG, 300, &sent, &err);
	dt = now_ms() - t0;
	ck_assert_int_eq(rc, ST_ERR_IO);
	ck_assert_int_eq(err.code, ST_ERR_IO);
	ck_assert_msg(dt >= 299 && dt <= 1300, "300 ms write bound took %lld ms", (long long)dt);
	ck_assert_uint_gt(sent, 0);
	ck_assert_uint_lt(sent, BIG);
	msg_has(&err, f.slave_path);
	msg_has(&err, "timed out");
	snprintf(want, sizeof(want), "%zu of %u bytes", sent, BIG);
	msg_has(&err, want);
	ck_assert(!xport_is_gone(f.x));
	pty_close(&f);
	free(out);
}
END_TEST

START_TEST(pty_hangup)
{
	struct pty_fix f;
	struct st_error err = {0};
	char buf[16];
	int rc;

	pty_open(&f, NULL);
	close(f.master);
	f.master = -1;
	rc = xport_read(f.x, buf, sizeof(buf), 1000, &err);
	ck_assert_int_eq(rc, ST_ERR_IO);
	ck_assert(xport_is_gone(f.x));
	msg_has(&err, "closed by the other end");
	msg_has(&err, f.slave_path);
	/* Later calls fail at once, the same way. */
	memset(&err, 0, sizeof(err));
	ck_assert_int_eq(xport_write_all(f.x, "M105\n", 5, 1000, NULL, &err), ST_ERR_IO);
	msg_has(&err, "closed by the other end");
	pty_close(&f);
}
END_TEST

/* Thread: close the master fd after a short delay. */
static void *close_later(void *p)
{
	usleep(100000);
	close(*(int *)p);
	return NULL;
}

START_TEST(pty_hangup_while_waiting)
{
	struct pty_fix f;
	struct st_error err = {0};
	char buf[16];
	pthread_t th;
	int64_t t0, dt;
	int rc;

	pty_open(&f, NULL);
	ck_assert_int_eq(pthread_create(&th, NULL, close_later, &f.master), 0);
	t0 = now_ms();
	rc = xport_read(f.x, buf, sizeof(buf), 3000, &err);
	dt = now_ms() - t0;
	pthread_join(th, NULL);
	f.master = -1;
	ck_assert_int_eq(rc, ST_ERR_IO);
	ck_assert(xport_is_gone(f.x));
	ck_assert_msg(dt < 1500, "hang-up noticed only after %lld ms", (long long)dt);
	pty_close(&f);
}
END_TEST

START_TEST(pty_describe)
{
	struct pty_fix f;
	struct xport_options opt = {.baudrate = 250000, .dtr_reset = true};
	char want[192], link[128];
	struct xport *x = NULL;
	struct st_error err = {0};

	pty_open(&f, NULL);
	snprintf(want, sizeof(want), "%s (pty, 115200 baud)", f.slave_path);
	ck_assert_str_eq(xport_describe(f.x), want);
	ck_assert_int_eq(xport_backend_of(f.x), XPORT_BACKEND_FD);
	ck_assert_int_ge(xport_fd(f.x), 0);
	pty_close(&f);

	/* Non-standard rate and DTR reset: ptys accept and ignore both. */
	pty_open(&f, &opt);
	snprintf(want, sizeof(want), "%s (pty, 250000 baud)", f.slave_path);
	ck_assert_str_eq(xport_describe(f.x), want);
	xport_close(f.x);
	f.x = NULL;

	/* A symlink resolving into /dev/pts goes to the fd back end too. */
	snprintf(link, sizeof(link), "/tmp/check_xport_link_%ld", (long)getpid());
	unlink(link);
	ck_assert_int_eq(symlink(f.slave_path, link), 0);
	ck_assert_msg(xport_open(link, NULL, &x, &err) == 0, "%s", err.msg);
	ck_assert_int_eq(xport_backend_of(x), XPORT_BACKEND_FD);
	snprintf(want, sizeof(want), "%s (pty, 115200 baud)", link);
	ck_assert_str_eq(xport_describe(x), want);
	xport_close(x);

	/* libserialport cannot open ptys: forcing it is refused clearly. */
	opt = (struct xport_options){.backend = XPORT_BACKEND_SERIALPORT};
	x = (struct xport *)&x;
	ck_assert_int_eq(xport_open(link, &opt, &x, &err), ST_ERR_ARG);
	ck_assert_ptr_null(x);
	msg_has(&err, "pseudo-terminal");
	unlink(link);
	pty_close(&f);

	ck_assert_str_eq(xport_describe(NULL), "(no port)");
	ck_assert_int_eq(xport_fd(NULL), -1);
	ck_assert(!xport_is_gone(NULL));
	xport_close(NULL);
}
END_TEST

START_TEST(bad_args)
{
	struct pty_fix f;
	struct st_error err = {0};
	char buf[4];

	pty_open(&f, NULL);
	ck_assert_int_eq(xport_read(f.x, buf, sizeof(buf), -1, &err), ST_ERR_ARG);
	ck_assert_int_eq(xport_write_all(f.x, NULL, 3, 100, NULL, &err), ST_ERR_ARG);
	ck_assert_int_eq(xport_drain(f.x, -5, &err), ST_ERR_ARG);
	ck_assert_int_eq(xport_read(NULL, buf, sizeof(buf), 10, &err), ST_ERR_ARG);
	ck_assert_int_eq(xport_read(f.x, buf, 0, 10, &err), 0);
	ck_assert_int_eq(xport_write_all(f.x, buf, 0, 0, NULL, &err), 0);
	pty_close(&f);
}
END_TEST

/* Loopback listener on an ephemeral port; returns the fd, *port set. */
static int listen_loopback(int *port)
{
	struct sockaddr_in sa = {.sin_family = AF_INET};
	socklen_t len = sizeof(sa);
	int fd = socket(AF_INET, SOCK_STREAM, 0);

	ck_assert_int_ge(fd, 0);
	sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
	ck_assert_int_eq(bind(fd, (struct sockaddr *)&sa, sizeof(sa)), 0);
	ck_assert_int_eq(listen(fd, 1), 0);
	ck_assert_int_eq(getsockname(fd, (struct sockaddr *)&sa, &len), 0);
	*port = ntohs(sa.sin_port);
	return fd;
}

START_TEST(tcp_roundtrip_and_close)
{
	struct st_error err = {0};
	struct xport *x = NULL;
	char spec[64], buf[64];
	int port, lfd = listen_loopback(&port), cfd;

	snprintf(spec, sizeof(spec), "tcp://127.0.0.1:%d", port);
	ck_assert_msg(xport_open(spec, NULL, &x, &err) == 0, "%s", err.msg);
	cfd = accept(lfd, NULL, NULL);
	ck_assert_int_ge(cfd, 0);
	ck_assert_str_eq(xport_describe(x), spec);
	ck_assert_int_eq(xport_backend_of(x), XPORT_BACKEND_TCP);

	ck_assert_int_eq(xport_write_all(x, "M115\n", 5, 1000, NULL, &err), 0);
	read_exact(cfd, buf, 5);
	ck_assert_mem_eq(buf, "M115\n", 5);
	ck_assert_int_eq(write(cfd, "ok\n", 3), 3);
	xread_exact(x, buf, 3);
	ck_assert_mem_eq(buf, "ok\n", 3);
	ck_assert_int_eq(xport_drain(x, 100, &err), 0);
	ck_assert_int_eq(xport_read(x, buf, sizeof(buf), 50, &err), 0);

	close(cfd);
	ck_assert_int_eq(xport_read(x, buf, sizeof(buf), 1000, &err), ST_ERR_IO);
	ck_assert(xport_is_gone(x));
	msg_has(&err, "closed by the other end");
	msg_has(&err, spec);
	/* Writing after the peer left is an error, not SIGPIPE. */
	ck_assert_int_eq(xport_write_all(x, "M105\n", 5, 200, NULL, &err), ST_ERR_IO);
	xport_close(x);
	close(lfd);
}
END_TEST

START_TEST(tcp_refused)
{
	struct st_error err = {0};
	struct xport *x = (struct xport *)&x;
	char spec[64];
	int port, lfd = listen_loopback(&port);
	int64_t t0;

	close(lfd); /* nothing listens there now */
	snprintf(spec, sizeof(spec), "tcp://127.0.0.1:%d", port);
	t0 = now_ms();
	ck_assert_int_eq(xport_open(spec, NULL, &x, &err), ST_ERR_IO);
	ck_assert_int_lt(now_ms() - t0, 1000);
	ck_assert_ptr_null(x);
	msg_has(&err, "connection refused");
	msg_has(&err, spec);
}
END_TEST

/* Open spec and expect class code with needle in the message. */
static void open_bad(const char *spec, const struct xport_options *opt, int code,
		     const char *needle)
{
	struct st_error err = {0};
	struct xport *x = (struct xport *)&err;
	int rc = xport_open(spec, opt, &x, &err);

	ck_assert_msg(rc == code, "%s: wanted %d, got %d (%s)", spec ? spec : "(null)", code, rc,
		      err.msg);
	ck_assert_int_eq(err.code, code);
	ck_assert_ptr_null(x);
	msg_has(&err, needle);
	if (spec)
		msg_has(&err, spec);
}

START_TEST(bad_specs)
{
	struct xport_options fd_opt = {.backend = XPORT_BACKEND_FD};
	struct xport_options tcp_opt = {.backend = XPORT_BACKEND_TCP};
	struct xport_options neg = {.baudrate = -9600};
	char path[128];
	FILE *fp;

	open_bad("tcp://nohost", NULL, ST_ERR_ARG, "tcp://HOST:PORT");
	open_bad("tcp://127.0.0.1:99999", NULL, ST_ERR_ARG, "1 to 65535");
	open_bad("tcp://127.0.0.1:0", NULL, ST_ERR_ARG, "1 to 65535");
	open_bad("tcp://127.0.0.1:5x", NULL, ST_ERR_ARG, "1 to 65535");
	open_bad("tcp://:5000", NULL, ST_ERR_ARG, "tcp://HOST:PORT");
	open_bad("tcp://[::1:5000", NULL, ST_ERR_ARG, "tcp://HOST:PORT");
	open_bad("tcp://no-such-host.invalid:23", NULL, ST_ERR_IO, "cannot resolve");
	open_bad("/nonexistent", NULL, ST_ERR_IO, "no such port");
	open_bad("/dev/ttyUSB-not-there", NULL, ST_ERR_IO, "stratum ports");
	open_bad("/dev/null", &tcp_opt, ST_ERR_ARG, "tcp back end");
	open_bad("/dev/pts/0", &neg, ST_ERR_ARG, "negative");

	/* A regular file is not a serial port. */
	snprintf(path, sizeof(path), "/tmp/check_xport_file_%ld", (long)getpid());
	fp = fopen(path, "w");
	ck_assert_ptr_nonnull(fp);
	fclose(fp);
	open_bad(path, NULL, ST_ERR_ARG, "not a character device");
	unlink(path);

	/* /dev/null is a character device but no tty, through either back end. */
	open_bad("/dev/null", NULL, ST_ERR_ARG, "not a serial port");
	open_bad("/dev/null", &fd_opt, ST_ERR_ARG, "not a serial port");

	{
		struct st_error err = {0};
		struct xport *x = (struct xport *)&err;

		ck_assert_int_eq(xport_open(NULL, NULL, &x, &err), ST_ERR_ARG);
		ck_assert_ptr_null(x);
		ck_assert_int_eq(xport_open("", NULL, &x, &err), ST_ERR_ARG);
	}
}
END_TEST

START_TEST(list_ports)
{
	struct st_error err = {0};
	struct xport_port_info *list = (struct xport_port_info *)&err;
	size_t n = 99;

	ck_assert_msg(xport_list(&list, &n, &err) == 0, "%s", err.msg);
	ck_assert(n == 0 ? list == NULL : list != NULL);
	for (size_t i = 0; i < n; i++) {
		ck_assert_ptr_nonnull(list[i].name);
		ck_assert(list[i].transport == XPORT_TRANSPORT_USB ||
			  (list[i].usb_vid == -1 && list[i].usb_pid == -1));
		ck_assert_ptr_nonnull(xport_transport_name(list[i].transport));
		if (i)
			ck_assert_int_le(strcmp(list[i - 1].name, list[i].name), 0);
	}
	xport_list_free(list, n);
	xport_list_free(NULL, 0);
	ck_assert_str_eq(xport_transport_name(XPORT_TRANSPORT_USB), "usb");
	ck_assert_int_eq(xport_list(NULL, &n, &err), ST_ERR_ARG);
}
END_TEST

Suite *xport_suite(void)
{
	Suite *s = suite_create("xport");
	TCase *pty = tcase_create("pty");
	TCase *tcp = tcase_create("tcp");
	TCase *misc = tcase_create("specs");

	tcase_set_timeout(pty, 20);
	tcase_add_test(pty, pty_roundtrip);
	tcase_add_test(pty, pty_read_timeout);
	tcase_add_test(pty, pty_write_big);
	tcase_add_test(pty, pty_write_timeout);
	tcase_add_test(pty, pty_hangup);
	tcase_add_test(pty, pty_hangup_while_waiting);
	tcase_add_test(pty, pty_describe);
	tcase_add_test(pty, bad_args);
	suite_add_tcase(s, pty);

	tcase_set_timeout(tcp, 20);
	tcase_add_test(tcp, tcp_roundtrip_and_close);
	tcase_add_test(tcp, tcp_refused);
	suite_add_tcase(s, tcp);

	tcase_set_timeout(misc, 20);
	tcase_add_test(misc, bad_specs);
	tcase_add_test(misc, list_ports);
	suite_add_tcase(s, misc);
	return s;
}
