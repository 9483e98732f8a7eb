/*
 * cmd_output.c - checks on an output path made before a command does its
 * work (commands.h): the user's input is never overwritten, and a missing
 * or read-only directory is reported at once, not after a long repair;
 * and the one way a command builds and writes its --json answer.
 */
#include <errno.h>
#include <limits.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include <jansson.h>

#include "commands.h"
#include "st_error.h"

bool cmd_has_ext(const char *path, const char *ext)
{
	size_t n = strlen(path), k = strlen(ext);

	return n > k && !strcasecmp(path + n - k, ext);
}

bool cmd_same_file(const char *a, const char *b)
{
	struct stat sa, sb;

	/* stat follows symlinks: a link to the input is the input. */
	if (stat(a, &sa) || stat(b, &sb))
		return false;
	return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

/* The directory part of path ("." when there is none) into dir. */
static void dir_of(const char *path, char *dir, size_t cap)
{
	const char *slash = strrchr(path, '/');

	if (!slash)
		snprintf(dir, cap, ".");
	else if (slash == path)
		snprintf(dir, cap, "/");
	else
		snprintf(dir, cap, "%.*s", (int)(slash - path), path);
}

int cmd_output_check(const char *in, const char *out, char *msg, size_t cap)
{
	char dir[PATH_MAX];
	struct stat st;

	if (in && cmd_same_file(in, out)) {
		snprintf(msg, cap, "%s is the input file %s; name another output so the input "
			 "is kept", out, in);
		return ST_EXIT_USAGE;
	}
	if (stat(out, &st) == 0 && S_ISDIR(st.st_mode)) {
		snprintf(msg, cap, "%s is a directory; name the output file", out);
		return ST_EXIT_USAGE;
	}
	dir_of(out, dir, sizeof(dir));
	if (stat(dir, &st) || !S_ISDIR(st.st_mode)) {
		snprintf(msg, cap, "%s: the directory %s does not exist; create it first", out, dir);
		return ST_EXIT_FAILURE;
	}
	if (access(dir, W_OK | X_OK)) {
		snprintf(msg, cap, "%s: cannot write in the directory %s: %s", out, dir,
			 strerror(errno));
		return ST_EXIT_FAILURE;
	}
	return 0;
}

int cmd_json_out(json_t *o, size_t flags)
{
	int rc;

	if (!o)
		return -1;
	rc = json_dumpf(o, stdout, flags);
	json_decref(o);
	return rc || putchar('\n') == EOF ? -1 : 0;
}

void cmd_json_set(json_t *o, ...)
{
	const char *k;
	va_list ap;

	va_start(ap, o);
	while ((k = va_arg(ap, const char *)) != NULL) {
		json_t *v;

		switch (k[0]) {
		case 'b':
			v = json_boolean(va_arg(ap, int));
			break;
		case 'i':
			v = json_integer(va_arg(ap, int));
			break;
		case 'z':
			v = json_integer((json_int_t)va_arg(ap, size_t));
			break;
		case 'I':
			v = json_integer(va_arg(ap, json_int_t));
			break;
		case 'f':
			v = json_real(va_arg(ap, double));
			break;
		case 's':
			v = json_string(va_arg(ap, const char *));
			break;
		default: /* 'o' */
			v = va_arg(ap, json_t *);
			break;
		}
		json_object_set_new(o, k + 2, v);
	}
	va_end(ap);
}

int cmd_report_end(const char *cmd, const char *what, bool json_failed)
{
	if (json_failed)
		return cmd_fail(cmd, ST_EXIT_SOFTWARE, "cannot write the JSON %s", what);
	if (fflush(stdout) == EOF)
		return cmd_fail(cmd, ST_EXIT_SOFTWARE, "cannot write the %s: %s", what,
				strerror(errno));
	return 0;
}

int cmd_read_mesh(const char *cmd, const char *path, struct mesh **m, enum meshio_format *fmt)
{
	struct st_error err = {0};
	int rc = meshio_read(path, MESHIO_AUTO, m, fmt, &err);

	if (!rc)
		return 0;
	return cmd_fail(cmd, rc == ST_ERR_NOMEM ? ST_EXIT_SOFTWARE : ST_EXIT_DATAERR, "%s", err.msg);
}

int cmd_fail(const char *cmd, int status, const char *fmt, ...)
{
	va_list ap;

	flockfile(stderr); /* one message, whatever other threads write */
	fprintf(stderr, "%s: ", cmd);
	va_start(ap, fmt);
	vfprintf(stderr, fmt, ap);
	va_end(ap);
	fputc('\n', stderr);
	funlockfile(stderr);
	return status;
}
