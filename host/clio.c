/*
 * clio.c - "-" for stdin and stdout, and the stderr capture of --json
 * answers (clio.h).
 */
#define _GNU_SOURCE /* fopencookie: a FILE that both shows and keeps stderr */
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "clio.h"
#include "commands.h"
#include "st_error.h"

#define CLIO_LINE_MAX 1024

bool clio_is_std(const char *path)
{
	return path && !strcmp(path, "-");
}

void clio_init(struct clio *c, const char *cmd)
{
	c->cmd = cmd;
	c->in_tmp[0] = c->out_tmp[0] = '\0';
	c->data_fd = -1;
}

/* Remove the temporary file at path (if any) and its directory; path becomes "". */
static void remove_temp(char *path)
{
	char *slash = strrchr(path, '/');

	if (!path[0])
		return;
	unlink(path);
	if (slash) {
		*slash = '\0';
		rmdir(path);
	}
	path[0] = '\0';
}

/* A new empty file WHAT<ext> in a new directory $TMPDIR/stratum-XXXXXX, so
 * that messages naming it read "…/stdin.gcode"; its path into buf, its fd
 * or -1. */
static int temp_file(const char *what, const char *ext, char *buf, size_t cap)
{
	const char *dir = getenv("TMPDIR");
	size_t n;
	int fd;

	if (!dir || !*dir)
		dir = "/tmp";
	n = (size_t)snprintf(buf, cap, "%s/stratum-XXXXXX", dir);
	if (n + strlen(what) + strlen(ext) + 2 > cap) {
		buf[0] = '\0';
		errno = ENAMETOOLONG;
		return -1;
	}
	if (!mkdtemp(buf)) {
		buf[0] = '\0';
		return -1;
	}
	snprintf(buf + n, cap - n, "/%s%s", what, ext);
	fd = open(buf, O_WRONLY | O_CREAT | O_EXCL, 0600);
	if (fd < 0)
		remove_temp(buf);
	return fd;
}

/* Copy all of fd from into fd to; 0 or -1 with errno. */
static int copy_fd(int from, int to)
{
	char buf[1 << 16];
	ssize_t n;

	while ((n = read(from, buf, sizeof(buf))) != 0) {
		if (n < 0) {
			if (errno == EINTR)
				continue;
			return -1;
		}
		for (ssize_t done = 0; done < n;) {
			ssize_t w = write(to, buf + done, (size_t)(n - done));
			if (w < 0) {
				if (errno == EINTR)
					continue;
				return -1;
			}
			done += w;
		}
	}
	return 0;
}

int clio_input(struct clio *c, const char **path, const char *ext)
{
	int fd;

	if (!clio_is_std(*path))
		return 0;
	if (c->in_tmp[0])
		return cmd_fail(c->cmd, ST_EXIT_USAGE,
				"'-' (stdin) is given twice; stdin can be read once");
	if (isatty(STDIN_FILENO))
		return cmd_fail(c->cmd, ST_EXIT_USAGE,
				"'-' reads the input from stdin, which is a terminal; pipe or "
				"redirect a file into it");
	fd = temp_file("stdin", ext, c->in_tmp, sizeof(c->in_tmp));
	if (fd < 0 || copy_fd(STDIN_FILENO, fd) || close(fd)) {
		fprintf(stderr, "%s: cannot read stdin into a temporary file%s%s: %s\n", c->cmd,
			c->in_tmp[0] ? " " : "", c->in_tmp, strerror(errno));
		remove_temp(c->in_tmp);
		return ST_EXIT_FAILURE;
	}
	*path = c->in_tmp;
	return 0;
}

int clio_output(struct clio *c, const char **path, bool binary, const char *ext)
{
	int fd;

	if (!clio_is_std(*path))
		return 0;
	if (binary && isatty(STDOUT_FILENO))
		return cmd_fail(c->cmd, ST_EXIT_USAGE,
				"-o - would write binary data to the terminal; redirect stdout to "
				"a file or a pipe");
	fd = temp_file("stdout", ext, c->out_tmp, sizeof(c->out_tmp));
	if (fd < 0)
		return cmd_fail(c->cmd, ST_EXIT_FAILURE,
				"cannot make a temporary file for -o -: %s", strerror(errno));
	close(fd);
	/* stdout carries the data only: the reports go to stderr meanwhile */
	fflush(stdout);
	c->data_fd = dup(STDOUT_FILENO);
	if (c->data_fd < 0 || dup2(STDERR_FILENO, STDOUT_FILENO) < 0) {
		fprintf(stderr, "%s: cannot set stdout aside: %s\n", c->cmd, strerror(errno));
		remove_temp(c->out_tmp);
		return ST_EXIT_FAILURE;
	}
	*path = c->out_tmp;
	return 0;
}

int clio_finish(struct clio *c, int status)
{
	if (c->data_fd >= 0) {
		fflush(stdout);
		dup2(c->data_fd, STDOUT_FILENO);
		close(c->data_fd);
		c->data_fd = -1;
	}
	if (c->out_tmp[0]) {
		if (status == 0) {
			FILE *f = fopen(c->out_tmp, "rb");
			if (!f || copy_fd(fileno(f), STDOUT_FILENO)) {
				fprintf(stderr, "%s: cannot write the output to stdout: %s\n", c->cmd,
					strerror(errno));
				status = ST_EXIT_FAILURE;
			}
			if (f)
				fclose(f);
		}
	}
	remove_temp(c->out_tmp);
	remove_temp(c->in_tmp);
	return status;
}

int clio_run(const char *cmd, int (*run)(int argc, char **argv, struct clio *io), int argc,
	     char **argv)
{
	struct clio io;

	clio_init(&io, cmd);
	return clio_finish(&io, run(argc, argv, &io));
}

/* -------- the stderr capture -------- */

static struct {
	FILE *real;		      /* stderr before the capture */
	char line[CLIO_LINE_MAX];     /* the line being written */
	size_t n;
	char last[CLIO_LINE_MAX];     /* the last "stratum ..." line */
} cap;

static ssize_t cap_write(void *cookie, const char *buf, size_t len)
{
	(void)cookie;
	fwrite(buf, 1, len, cap.real);
	for (size_t i = 0; i < len; i++) {
		if (buf[i] == '\r') { /* a progress bar redrawn: not a message */
			cap.n = 0;
		} else if (buf[i] != '\n') {
			if (cap.n + 1 < sizeof(cap.line))
				cap.line[cap.n++] = buf[i];
		} else {
			cap.line[cap.n] = '\0';
			if (!strncmp(cap.line, "stratum ", 8))
				memcpy(cap.last, cap.line, cap.n + 1);
			cap.n = 0;
		}
	}
	return (ssize_t)len;
}

void clio_capture_begin(void)
{
	cookie_io_functions_t io = {.write = cap_write};
	FILE *f;

	if (cap.real)
		return;
	cap.n = 0;
	cap.last[0] = '\0';
	f = fopencookie(NULL, "w", io);
	if (!f)
		return; /* no capture: the answer says "see stderr" */
	setvbuf(f, NULL, _IONBF, 0);
	fflush(stderr);
	cap.real = stderr;
	stderr = f;
}

void clio_capture_end(char *msg, size_t cap_len)
{
	const char *colon;

	if (cap.real) {
		FILE *f = stderr;
		stderr = cap.real;
		cap.real = NULL;
		fclose(f);
	}
	colon = strstr(cap.last, ": ");
	snprintf(msg, cap_len, "%s", colon ? colon + 2 : cap.last);
}
