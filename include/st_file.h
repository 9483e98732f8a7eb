/*
 * st_file.h - the one atomic file writer, header-only like st_error.h so
 * every layer may use it.  An output is written to a temporary file in its
 * own directory, flushed to disk, then renamed over the output and the
 * directory synced: a reader sees the old file or the whole new one, and a
 * failure leaves neither a half-written output nor the temporary file.
 *
 *	struct st_file_out o;
 *	if (st_file_begin(&o, path, err)) return err->code;
 *	... write to o.f ...
 *	return st_file_commit(&o, err);	   (or st_file_abort(&o) to give up)
 *
 * An output whose name comes after its data (the farm node's uploads)
 * begins with st_file_begin_temp in a directory of the same file system,
 * then st_file_finish (on disk, still readable as o.tmp for a check) and
 * st_file_publish (its name).
 */
#ifndef STRATUM_ST_FILE_H
#define STRATUM_ST_FILE_H

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "st_error.h"

/* An output being written: write to f; tmp is the file beside path. */
struct st_file_out {
	FILE *f;
	char *tmp;
	const char *path; /* the caller's string, kept until commit or abort */
	int direct;	  /* path is a device or pipe, written in place */
};

/* The process umask without changing it (umask() would, for every thread):
 * Linux reports it in /proc/self/status; elsewhere assume the usual 022. */
static inline mode_t st_file_umask(void)
{
	FILE *f = fopen("/proc/self/status", "r");
	char line[256];
	mode_t mask = 022;

	if (!f)
		return mask;
	while (fgets(line, sizeof(line), f)) {
		if (!strncmp(line, "Umask:", 6)) {
			mask = (mode_t)(strtol(line + 6, NULL, 8) & 0777);
			break;
		}
	}
	fclose(f);
	return mask;
}

/* Create the temporary file o->tmp (a mkstemp template, malloc'd; freed on
 * failure) with mode, open as o->f; err names what (the output or dir),
 * errno is kept on failure. */
static inline int st_file_open_temp(struct st_file_out *o, const char *what, mode_t mode,
				    struct st_error *err)
{
	int fd = mkstemp(o->tmp), rc, saved;

	if (fd < 0) {
		saved = errno;
		rc = st_error_set(err, ST_ERR_IO, "%s: cannot create a temporary file beside it: %s",
				  what, strerror(saved));
		free(o->tmp);
		o->tmp = NULL;
		errno = saved;
		return rc;
	}
	if (fchmod(fd, mode) != 0 || !(o->f = fdopen(fd, "wb"))) {
		saved = errno;
		rc = st_error_set(err, ST_ERR_IO, "%s: cannot open the temporary file %s: %s",
				  what, o->tmp, strerror(saved));
		close(fd);
		unlink(o->tmp);
		free(o->tmp);
		o->tmp = NULL;
		errno = saved;
		return rc;
	}
	return 0;
}

/*
 * st_file_begin - open a temporary file "DIR/.NAME.XXXXXX" beside path
 * with the mode the output will need (the old file's when replacing one,
 * else 0666 less the umask).  An existing path that is no regular file
 * (/dev/null, /dev/stdout, a named pipe) is written in place instead: a
 * rename would replace the device with a file.  Returns 0, or ST_ERR_ARG /
 * ST_ERR_NOMEM / ST_ERR_IO with err naming path; nothing is left behind on
 * failure.
 */
static inline int st_file_begin(struct st_file_out *o, const char *path, struct st_error *err)
{
	const char *slash;
	size_t dirlen, len;
	struct stat sb;
	mode_t mode;
	int rc;

	memset(o, 0, sizeof(*o));
	if (!path || !*path)
		return st_error_set(err, ST_ERR_ARG, "no output file name given");
	if (stat(path, &sb) == 0 && S_ISDIR(sb.st_mode))
		return st_error_set(err, ST_ERR_IO, "%s: is a directory, not a file", path);
	if (stat(path, &sb) == 0 && !S_ISREG(sb.st_mode)) {
		if (!(o->f = fopen(path, "wb")))
			return st_error_set(err, ST_ERR_IO, "%s: cannot open: %s", path,
					    strerror(errno));
		o->path = path;
		o->direct = 1;
		return 0;
	}
	slash = strrchr(path, '/');
	dirlen = slash ? (size_t)(slash - path) + 1 : 0;
	len = strlen(path) + sizeof(".") + sizeof(".XXXXXX");
	if (!(o->tmp = malloc(len)))
		return st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", path);
	snprintf(o->tmp, len, "%.*s.%s.XXXXXX", (int)dirlen, path, path + dirlen);
	if (stat(path, &sb) == 0 && S_ISREG(sb.st_mode))
		mode = sb.st_mode & 07777;
	else
		mode = 0666 & ~st_file_umask();
	if ((rc = st_file_open_temp(o, path, mode, err)))
		return rc;
	o->path = path;
	return 0;
}

/*
 * st_file_begin_temp - begin an output whose name is not known yet: the
 * temporary file is "DIR/PREFIX-XXXXXX" (dir on the file system the output
 * will be published to).  Returns 0, or ST_ERR_NOMEM / ST_ERR_IO with err
 * naming dir and errno kept.
 */
static inline int st_file_begin_temp(struct st_file_out *o, const char *dir, const char *prefix,
				     struct st_error *err)
{
	size_t len = strlen(dir) + strlen(prefix) + sizeof("/-XXXXXX");

	memset(o, 0, sizeof(*o));
	if (!(o->tmp = malloc(len)))
		return st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", dir);
	snprintf(o->tmp, len, "%s/%s-XXXXXX", dir, prefix);
	return st_file_open_temp(o, dir, 0666 & ~st_file_umask(), err);
}

/* st_file_abort - give up: the temporary file is removed, the output is
 * as it was.  Safe on a writer that failed to begin or was committed. */
static inline void st_file_abort(struct st_file_out *o)
{
	int saved = errno; /* callers report why the step before failed */

	if (o->f)
		fclose(o->f);
	if (o->tmp) {
		unlink(o->tmp);
		free(o->tmp);
	}
	memset(o, 0, sizeof(*o));
	errno = saved;
}

/* st_file_sync_dir - fsync the directory holding path, so that a rename
 * into it is on disk (best effort: the data itself already is). */
static inline void st_file_sync_dir(const char *path)
{
	const char *slash = strrchr(path, '/');
	char *dir = slash ? strndup(path, slash == path ? 1 : (size_t)(slash - path))
			  : strdup(".");
	int fd;

	if (dir && (fd = open(dir, O_RDONLY | O_DIRECTORY)) >= 0) {
		if (fsync(fd) != 0) {
			/* some file systems refuse to sync a directory */
		}
		close(fd);
	}
	free(dir);
}

/* st_file_fail - writing to f failed (errno says why): abort and return
 * ST_ERR_IO with err naming the output. */
static inline int st_file_fail(struct st_file_out *o, struct st_error *err)
{
	int rc = st_error_set(err, ST_ERR_IO, "%s: cannot write: %s; the file was left unchanged",
			      o->path ? o->path : o->tmp ? o->tmp : "(no file)",
			      strerror(errno ? errno : EIO));

	st_file_abort(o);
	return rc;
}

/*
 * st_file_finish - flush and fsync the temporary file and close it; o->tmp
 * stays on disk, readable, until st_file_publish or st_file_abort.
 * Returns 0, or ST_ERR_IO (then the writer is aborted).
 */
static inline int st_file_finish(struct st_file_out *o, struct st_error *err)
{
	const char *name = o->path ? o->path : o->tmp;
	int rc;

	if (!o->f || !o->tmp)
		return st_error_set(err, ST_ERR_ARG, "st_file_finish: no file being written");
	errno = 0;
	if (fflush(o->f) == EOF || ferror(o->f))
		return st_file_fail(o, err);
	if (fsync(fileno(o->f)) != 0) {
		rc = st_error_set(err, ST_ERR_IO, "%s: cannot sync it to disk: %s; the file was "
				  "left unchanged", name, strerror(errno));
		st_file_abort(o);
		return rc;
	}
	rc = fclose(o->f);
	o->f = NULL;
	if (rc != 0)
		return st_file_fail(o, err);
	return 0;
}

/*
 * st_file_publish - rename the finished temporary file to path and fsync
 * path's directory (the rename itself on disk).  Returns 0, or ST_ERR_IO
 * with err naming path and errno kept; then the temporary file is removed.
 */
static inline int st_file_publish(struct st_file_out *o, const char *path, struct st_error *err)
{
	int rc;

	if (o->f || !o->tmp)
		return st_error_set(err, ST_ERR_ARG, "st_file_publish: no finished file");
	if (rename(o->tmp, path) != 0) {
		rc = st_error_set(err, ST_ERR_IO, "%s: cannot replace the file: %s", path,
				  strerror(errno));
		st_file_abort(o);
		return rc;
	}
	free(o->tmp);
	memset(o, 0, sizeof(*o));
	st_file_sync_dir(path);
	return 0;
}

/*
 * st_file_commit - st_file_finish then st_file_publish over the output
 * (a device or pipe is only flushed and closed).  Returns 0, or ST_ERR_IO
 * with err naming the output and the step that failed; then the temporary
 * file is removed and the output is left unchanged.
 */
static inline int st_file_commit(struct st_file_out *o, struct st_error *err)
{
	const char *path = o->path;
	int rc;

	if (!o->f || (!o->tmp && !o->direct))
		return st_error_set(err, ST_ERR_ARG, "st_file_commit: no file being written");
	if (o->direct) { /* a device or pipe: nothing to sync or rename */
		errno = 0;
		if (fflush(o->f) == EOF || ferror(o->f))
			return st_file_fail(o, err);
		rc = fclose(o->f);
		o->f = NULL;
		if (rc != 0)
			return st_file_fail(o, err);
		memset(o, 0, sizeof(*o));
		return 0;
	}
	if ((rc = st_file_finish(o, err)))
		return rc;
	return st_file_publish(o, path, err);
}

#endif /* STRATUM_ST_FILE_H */
