/*
 * check_profile_shipped.c - every file in printers/ is a profile Stratum can
 * ship: it loads, its header cites its sources, docs/printers.md lists it, and
 * a cube slices with it without a warning (and, for a Sailfish printer,
 * translates to X3G without one).  A profile added to printers/ is checked
 * here without a test of its own; a broken one fails the profile suite.
 * Part of the profile suite.
 */
#include <check.h>
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "fixtures.h"
#include "mesh.h"
#include "meshio.h"
#include "profile.h"
#include "suites.h"
#include "testutil.h"

#define SHIPPED_DIR "printers"
#define MAX_SHIPPED 64

static char out[1 << 16];

/* The NAMEs of SHIPPED_DIR's NAME.ini files, sorted; returns how many. */
static size_t shipped_names(char names[][128])
{
	DIR *d = opendir(SHIPPED_DIR);
	struct dirent *e;
	size_t n = 0;

	ck_assert_msg(d != NULL, "cannot open %s/", SHIPPED_DIR);
	while ((e = readdir(d))) {
		size_t len = strlen(e->d_name);

		if (e->d_name[0] == '.' || len <= 4 || strcmp(e->d_name + len - 4, ".ini"))
			continue;
		ck_assert_uint_lt(n, MAX_SHIPPED);
		ck_assert_uint_lt(len - 4, 128);
		memcpy(names[n], e->d_name, len - 4);
		names[n][len - 4] = '\0';
		n++;
	}
	closedir(d);
	qsort(names, n, sizeof(names[0]), (int (*)(const void *, const void *))strcmp);
	return n;
}

/* A word Stratum's commands print before every warning, in any case. */
static int has_warning(const char *text)
{
	for (const char *p = text; *p; p++)
		if (!strncasecmp(p, "warning", 7))
			return 1;
	return 0;
}

/* The comment lines before the first key must name the sources. */
static void assert_sources_cited(const char *path)
{
	size_t len = 0;
	char *text = tu_slurp(path, &len);
	char *first_key = text;

	while (*first_key == '#' || *first_key == '\n') {
		char *nl = strchr(first_key, '\n');
		if (!nl)
			break;
		first_key = nl + 1;
	}
	*first_key = '\0';
	ck_assert_msg(strstr(text, "Source") != NULL,
		      "%s: its header comment cites no sources (docs/printers.md, Adding a profile)",
		      path);
	free(text);
}

START_TEST(every_shipped_profile_slices)
{
	static char names[MAX_SHIPPED][128];
	size_t n = shipped_names(names), dlen = 0;
	char *docs = tu_slurp("docs/printers.md", &dlen);
	char cube[600], gcode[600], x3g[600];
	struct st_error err = {0};
	struct mesh *m = fx_box(0, 0, 0, 10, 10, 5);

	/* tu_path reuses its buffers after 8 calls: keep copies */
	snprintf(cube, sizeof(cube), "%s", tu_path("shipped-cube.stl"));
	snprintf(gcode, sizeof(gcode), "%s", tu_path("shipped.gcode"));
	snprintf(x3g, sizeof(x3g), "%s", tu_path("shipped.x3g"));
	ck_assert_uint_gt(dlen, 0);
	ck_assert_msg(meshio_write_stl(cube, m, MESHIO_STL_BINARY, &err) == 0, "%s", err.msg);
	mesh_free(m);
	ck_assert_uint_gt(n, 0);
	for (size_t i = 0; i < n; i++) {
		char path[256], row[160];
		struct profile *p = NULL;
		int status;

		snprintf(path, sizeof(path), "%s/%s.ini", SHIPPED_DIR, names[i]);
		ck_assert_msg(profile_load_file(path, &p, &err) == 0, "%s", err.msg);
		assert_sources_cited(path);
		snprintf(row, sizeof(row), "| `%s` |", names[i]);
		ck_assert_msg(strstr(docs, row), "docs/printers.md does not list %s", names[i]);

		status = tu_run(out, sizeof(out), "slice '%s' -o '%s' --printer '%s'", cube, gcode,
				path);
		ck_assert_msg(status == 0, "%s: slice exit %d: %s", names[i], status, out);
		ck_assert_msg(!has_warning(out), "%s: slice warned: %s", names[i], out);
		ck_assert_msg(tu_file_exists(gcode), "%s: no G-code written", names[i]);
		if (p->protocol == PROFILE_PROTOCOL_SAILFISH) {
			status = tu_run(out, sizeof(out), "x3g '%s' -o '%s' --printer '%s'", gcode,
					x3g, path);
			ck_assert_msg(status == 0, "%s: x3g exit %d: %s", names[i], status, out);
			ck_assert_msg(strstr(out, " 0 warnings") && !strstr(out, "warning:"),
				      "%s: x3g warned: %s", names[i], out);
		}
		remove(gcode);
		profile_free(p);
	}
	free(docs);
}
END_TEST

void profile_shipped_tcases(Suite *s)
{
	TCase *tc = tcase_create("every shipped");

	tcase_set_timeout(tc, 120);
	tcase_add_test(tc, every_shipped_profile_slices);
	suite_add_tcase(s, tc);
}
