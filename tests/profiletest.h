/*
 * profiletest.h - what the profile suite's files share (check_profile.c,
 * check_profile_cli.c): profiles loaded from text or from printers/, the
 * refusals' messages checked, scratch printer folders.
 */
#ifndef STRATUM_TESTS_PROFILETEST_H
#define STRATUM_TESTS_PROFILETEST_H

#include "profile.h"

/* Load text as "test.ini"; the test fails with the loader's message on error. */
struct profile *load_ok(const char *text);
/*
 * Load text and expect class code; the message must contain every string of
 * the NULL-terminated list that follows.
 */
void load_bad(const char *text, int code, ...);
/* Load the shipped printers/ID.ini (run from the source tree). */
struct profile *load_shipped(const char *id);
/* got equals want within 1e-9. */
void assert_close(double got, double want);
/* Make a scratch directory for STRATUM_PRINTERS_DIR and return its path. */
const char *scratch_dir(const char *name);
/* Write text to the file named file in dir. */
void write_in(const char *dir, const char *file, const char *text);
/* The file line that set key (0: not set), as the loader's messages name it. */
int key_line(const struct profile *p, const char *key);

#endif
