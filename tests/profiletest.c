/*
 * profiletest.c - the helpers of profiletest.h.
 */
#include <check.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#include "profile.h"
#include "profile_int.h"
#include "profiletest.h"
#include "testutil.h"

/* Load text as "test.ini"; the test fails with the loader's message on error. */
struct profile *load_ok(const char *text)
{
	struct profile *p = NULL;
	struct st_error err = {0};
	int rc = profile_load_buffer(text, strlen(text), "test.ini", &p, &err);

	ck_assert_msg(rc == 0, "load failed (%d): %s", rc, err.msg);
	ck_assert_ptr_nonnull(p);
	return p;
}

/*
 * Load text and expect class code; the message must contain every string of
 * the NULL-terminated list that follows.
 */
void load_bad(const char *text, int code, ...)
{
	struct profile *p = (struct profile *)&p; /* must be reset to NULL */
	struct st_error err = {0};
	const char *needle;
	va_list ap;
	int rc = profile_load_buffer(text, strlen(text), "test.ini", &p, &err);

	ck_assert_msg(rc == code, "wanted class %d, got %d (%s) for:\n%s", code, rc, err.msg, text);
	ck_assert_int_eq(err.code, code);
	ck_assert_ptr_null(p);
	ck_assert_msg(!strncmp(err.msg, "test.ini: ", 10), "message lacks the file: %s", err.msg);
	va_start(ap, code);
	while ((needle = va_arg(ap, const char *)))
		ck_assert_msg(strstr(err.msg, needle), "'%s' not in message: %s", needle, err.msg);
	va_end(ap);
}

struct profile *load_shipped(const char *id)
{
	char path[256];
	struct profile *p = NULL;
	struct st_error err = {0};

	snprintf(path, sizeof(path), "printers/%s.ini", id);
	ck_assert_msg(profile_load_file(path, &p, &err) == 0, "%s", err.msg);
	ck_assert_str_eq(p->id, id);
	return p;
}

void assert_close(double got, double want)
{
	ck_assert_msg(fabs(got - want) < 1e-9, "got %.17g, wanted %.17g", got, want);
}

/* Make a scratch directory for STRATUM_PRINTERS_DIR and return its path. */
const char *scratch_dir(const char *name)
{
	static char dir[512];

	snprintf(dir, sizeof(dir), "%s", tu_path(name));
	ck_assert_msg(mkdir(dir, 0755) == 0 || errno == EEXIST, "mkdir %s", dir);
	return dir;
}

void write_in(const char *dir, const char *file, const char *text)
{
	char path[700];

	snprintf(path, sizeof(path), "%s/%s", dir, file);
	tu_write_str(path, text);
}

/* The file line that set key (0: not set), as the loader's messages name it. */
int key_line(const struct profile *p, const char *key)
{
	const struct profile_kv *kv = prof_find_kv(p->keys, key);

	return kv ? kv->line : 0;
}

