/*
 * check_stfile.c - include/st_file.h, the atomic file writer: an output is
 * the old file or the whole new one, never half of it, and no temporary
 * file is left beside it, whether the write is committed, given up or
 * fails at any step.
 */
#include <check.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include "st_file.h"
#include "suites.h"
#include "testutil.h"

/* A fresh empty directory in the scratch area; its path in a static buffer. */
static const char *fresh_dir(const char *name)
{
	static char dir[512];

	snprintf(dir, sizeof(dir), "%s", tu_path(name));
	ck_assert_msg(mkdir(dir, 0755) == 0, "mkdir %s: %s", dir, strerror(errno));
	return dir;
}

static void expect_content(const char *path, const char *text)
{
	size_t len;
	char *got = tu_slurp(path, &len);

	ck_assert_uint_eq(len, strlen(text));
	ck_assert_str_eq(got, text);
	free(got);
}

/* An existing output is replaced in one step: until the commit readers see
 * the old file whole, after it the new one; its mode is kept. */
START_TEST(replaces_atomically)
{
	const char *dir = fresh_dir("stf-replace");
	char path[600];
	struct st_file_out o;
	struct st_error err = {0};
	struct stat sb;

	snprintf(path, sizeof(path), "%s/out.txt", dir);
	tu_write_str(path, "old content\n");
	ck_assert(chmod(path, 0640) == 0);
	ck_assert_msg(st_file_begin(&o, path, &err) == 0, "%s", err.msg);
	ck_assert(fputs("new content, longer than the old\n", o.f) != EOF);
	ck_assert(fflush(o.f) == 0);
	expect_content(path, "old content\n");
	ck_assert_int_eq(tu_dir_entries(dir), 2); /* the output and the temporary file */
	ck_assert_msg(st_file_commit(&o, &err) == 0, "%s", err.msg);
	expect_content(path, "new content, longer than the old\n");
	ck_assert_int_eq(tu_dir_entries(dir), 1);
	ck_assert(stat(path, &sb) == 0);
	ck_assert_uint_eq(sb.st_mode & 07777, 0640);
}
END_TEST

/* An output that is a pipe or a device (-o /dev/null, -o /dev/stdout) is
 * written in place: a rename would have replaced it with a plain file (it
 * once turned the machine's /dev/null into one). */
START_TEST(pipe_written_in_place)
{
	const char *dir = fresh_dir("stf-fifo");
	char path[600], got[64] = "";
	struct st_file_out o;
	struct st_error err = {0};
	struct stat sb;

	snprintf(path, sizeof(path), "%s/pipe", dir);
	ck_assert(mkfifo(path, 0600) == 0);
	const int rd = open(path, O_RDONLY | O_NONBLOCK); /* so the writer's open returns */
	ck_assert(rd >= 0);
	ck_assert_msg(st_file_begin(&o, path, &err) == 0, "%s", err.msg);
	ck_assert(fputs("through the pipe\n", o.f) != EOF);
	ck_assert_msg(st_file_commit(&o, &err) == 0, "%s", err.msg);
	ck_assert_int_eq(read(rd, got, sizeof(got) - 1), 17);
	ck_assert_str_eq(got, "through the pipe\n");
	close(rd);
	ck_assert(stat(path, &sb) == 0 && S_ISFIFO(sb.st_mode));
	ck_assert_int_eq(tu_dir_entries(dir), 1); /* no temporary file beside it */
	/* A directory is refused, naming it. */
	ck_assert_int_eq(st_file_begin(&o, dir, &err), ST_ERR_IO);
	ck_assert_msg(strstr(err.msg, "is a directory"), "%s", err.msg);
}
END_TEST

/* A new output gets 0666 less the umask, not mkstemp's 0600. */
START_TEST(new_file_mode_follows_umask)
{
	const char *dir = fresh_dir("stf-new");
	char path[600];
	struct st_file_out o;
	struct st_error err = {0};
	struct stat sb;
	mode_t old = umask(027);

	snprintf(path, sizeof(path), "%s/new.txt", dir);
	ck_assert_msg(st_file_begin(&o, path, &err) == 0, "%s", err.msg);
	fputs("x\n", o.f);
	ck_assert_msg(st_file_commit(&o, &err) == 0, "%s", err.msg);
	umask(old);
	ck_assert(stat(path, &sb) == 0);
	ck_assert_uint_eq(sb.st_mode & 07777, 0640);
	expect_content(path, "x\n");
}
END_TEST

/* Giving up leaves the old output and nothing else. */
START_TEST(abort_leaves_the_old_file)
{
	const char *dir = fresh_dir("stf-abort");
	char path[600];
	struct st_file_out o;
	struct st_error err = {0};

	snprintf(path, sizeof(path), "%s/out.txt", dir);
	tu_write_str(path, "old\n");
	ck_assert_msg(st_file_begin(&o, path, &err) == 0, "%s", err.msg);
	fputs("half of it", o.f);
	st_file_abort(&o);
	st_file_abort(&o); /* twice is harmless */
	expect_content(path, "old\n");
	ck_assert_int_eq(tu_dir_entries(dir), 1);
}
END_TEST

/* The disk refuses the data (here a file size limit, as a full disk would):
 * the commit names the output and the cause; no half file, no temporary. */
START_TEST(write_failure_leaves_nothing_half_written)
{
	const char *dir = fresh_dir("stf-full");
	char path[600], block[4096];
	struct st_file_out o;
	struct st_error err = {0};
	struct rlimit rl = {.rlim_cur = 8192, .rlim_max = RLIM_INFINITY};
	int rc = 0;

	snprintf(path, sizeof(path), "%s/out.bin", dir);
	tu_write_str(path, "old\n");
	signal(SIGXFSZ, SIG_IGN); /* the write fails with EFBIG instead */
	ck_assert(setrlimit(RLIMIT_FSIZE, &rl) == 0);
	memset(block, 'x', sizeof(block));
	ck_assert_msg(st_file_begin(&o, path, &err) == 0, "%s", err.msg);
	for (int i = 0; i < 8 && rc == 0; i++)
		if (fwrite(block, 1, sizeof(block), o.f) != sizeof(block))
			rc = st_file_fail(&o, &err);
	if (rc == 0)
		rc = st_file_commit(&o, &err);
	ck_assert_int_eq(rc, ST_ERR_IO);
	ck_assert_msg(strstr(err.msg, path) && strstr(err.msg, "cannot write") &&
		      strstr(err.msg, "left unchanged"), "%s", err.msg);
	expect_content(path, "old\n");
	ck_assert_int_eq(tu_dir_entries(dir), 1);
}
END_TEST

/* The rename is refused (a directory appeared where the file should go;
 * one there already is refused by st_file_begin). */
START_TEST(rename_failure_removes_the_temporary_file)
{
	const char *dir = fresh_dir("stf-rename");
	char path[600];
	struct st_file_out o;
	struct st_error err = {0};

	snprintf(path, sizeof(path), "%s/out", dir);
	ck_assert_msg(st_file_begin(&o, path, &err) == 0, "%s", err.msg);
	ck_assert(mkdir(path, 0755) == 0);
	fputs("content\n", o.f);
	ck_assert_int_eq(st_file_commit(&o, &err), ST_ERR_IO);
	ck_assert_msg(strstr(err.msg, path) && strstr(err.msg, "cannot replace the file"), "%s",
		      err.msg);
	ck_assert_int_eq(tu_dir_entries(dir), 1);
	ck_assert_int_eq(tu_dir_entries(path), 0);
}
END_TEST

/* No directory to put the temporary file in: named, nothing created. */
/* An output named after its data (the node's uploads): the temporary file
 * is made in a directory of its own, stays readable once finished, and is
 * published under its name; a publish that fails leaves nothing behind. */
START_TEST(temp_then_publish)
{
	const char *tmpdir = fresh_dir("stf-temp");
	char tdir[600], path[700], bad[700];
	struct st_file_out o;
	struct st_error err = {0};

	snprintf(tdir, sizeof(tdir), "%s", tmpdir);
	snprintf(path, sizeof(path), "%s/named.gcode", fresh_dir("stf-files"));
	ck_assert_msg(st_file_begin_temp(&o, tdir, "upload", &err) == 0, "%s", err.msg);
	ck_assert(strncmp(o.tmp, tdir, strlen(tdir)) == 0);
	ck_assert(fputs("G28\n", o.f) != EOF);
	ck_assert_msg(st_file_finish(&o, &err) == 0, "%s", err.msg);
	ck_assert_ptr_null(o.f);
	expect_content(o.tmp, "G28\n"); /* a check may read it before it has a name */
	ck_assert_msg(st_file_publish(&o, path, &err) == 0, "%s", err.msg);
	expect_content(path, "G28\n");
	ck_assert_int_eq(tu_dir_entries(tdir), 0);

	ck_assert_int_eq(st_file_begin_temp(&o, tdir, "upload", &err), 0);
	ck_assert_int_eq(st_file_finish(&o, &err), 0);
	snprintf(bad, sizeof(bad), "%s/no-such-folder/x.gcode", tdir);
	errno = 0;
	ck_assert_int_eq(st_file_publish(&o, bad, &err), ST_ERR_IO);
	ck_assert_int_eq(errno, ENOENT); /* kept for the caller's message */
	ck_assert_msg(strstr(err.msg, bad), "%s", err.msg);
	ck_assert_int_eq(tu_dir_entries(tdir), 0);
}
END_TEST

START_TEST(missing_directory_is_named)
{
	struct st_file_out o;
	struct st_error err = {0};

	ck_assert_int_eq(st_file_begin(&o, "/nonexistent-stratum/out.gcode", &err), ST_ERR_IO);
	ck_assert_msg(strstr(err.msg, "/nonexistent-stratum/out.gcode: cannot create a "
				      "temporary file beside it"), "%s", err.msg);
	ck_assert_ptr_null(o.f);
	ck_assert_ptr_null(o.tmp);
	ck_assert_int_eq(st_file_begin(&o, "", &err), ST_ERR_ARG);
}
END_TEST

Suite *stfile_suite(void)
{
	Suite *s = suite_create("stfile");
	TCase *tc = tcase_create("writer");

	tcase_add_test(tc, replaces_atomically);
	tcase_add_test(tc, new_file_mode_follows_umask);
	tcase_add_test(tc, abort_leaves_the_old_file);
	tcase_add_test(tc, write_failure_leaves_nothing_half_written);
	tcase_add_test(tc, rename_failure_removes_the_temporary_file);
	tcase_add_test(tc, missing_directory_is_named);
	tcase_add_test(tc, pipe_written_in_place);
	tcase_add_test(tc, temp_then_publish);
	suite_add_tcase(s, tc);
	return s;
}
