/*
 * check_main.c - run every module's suite; fork mode stays on so a crash
 * fails only its own test.  For make check's lanes (see the Makefile):
 * STRATUM_CHECK_ONLY="name ..." runs only those suites, STRATUM_CHECK_EXCEPT
 * every other one; a name that is no suite is an error.  STRATUM_CHECK_LIST
 * set prints the suites' names, one a line, and runs none: tests/lanes.sh
 * runs each of them once, so its lanes cover every suite by construction.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "suites.h"
#include "testutil.h"

struct suite_entry {
	const char *name; /* as make check's lanes name it */
	Suite *(*make)(void);
};

static const struct suite_entry suites[] = {
	{"stfile", stfile_suite},     {"mesh", mesh_suite},
	{"meshio", meshio_suite},     {"exact", exact_suite},
	{"repair", repair_suite},     {"batch", batch_suite},
	{"thicken", thicken_suite},   {"heal", heal_suite},
	{"corpus", corpus_suite},     {"planar", planar_suite},
	{"profile", profile_suite},   {"ini", ini_suite},
	{"placeholder", placeholder_suite}, {"gcode", gcode_suite},
	{"xport", xport_suite},	      {"sim", sim_suite},
	{"marlin", marlin_suite},     {"printer", printer_suite},
	{"slicer", slicer_suite},     {"gcodewriter", gcodewriter_suite},
	{"infill", infill_suite},     {"support", support_suite},
	{"supportmodel", supportmodel_suite},
	{"raft", raft_suite},	      {"adaptive", adaptive_suite},
	{"slicecli", slicecli_suite}, {"region", region_suite},
	{"multimodel", multimodel_suite}, {"thin", thin_suite},
	{"x3g", x3g_suite},	      {"s3g", s3g_suite},
	{"serve", serve_suite},	      {"octoapi", octoapi_suite},
	{"farm", farm_suite},
	{"preview", preview_suite},
	{"portpick", portpick_suite}, {"send", send_suite},
	{"console", console_suite},
	{"guard", guard_suite},	      {"print", print_suite},
	{"cli", cli_suite},	      {"help", help_suite},
	{"install", install_suite},   {"jobs", jobs_suite},
	{"progress", progress_suite},
	{"analyze", analyze_suite},   {"compare", compare_suite},
	{"refine", refine_suite},
};
#define NSUITES (sizeof(suites) / sizeof(suites[0]))

/* Whether name is a word of the space-separated list. */
static int listed(const char *list, const char *name)
{
	size_t n = strlen(name);

	for (const char *s = list; (s = strstr(s, name)); s += n)
		if ((s == list || s[-1] == ' ') && (s[n] == ' ' || s[n] == '\0'))
			return 1;
	return 0;
}

/* Every word of list names a suite; else say which does not (returns 0). */
static int all_known(const char *var, const char *list)
{
	char word[64];

	for (const char *s = list; *s;) {
		size_t n = strcspn(s, " ");
		int found = 0;

		snprintf(word, sizeof(word), "%.*s", (int)n, s);
		for (size_t i = 0; i < NSUITES && n; i++)
			found |= !strcmp(suites[i].name, word);
		if (n && !found) {
			fprintf(stderr, "%s: '%s' is no suite of tests/check_main.c\n", var, word);
			return 0;
		}
		s += n;
		s += strspn(s, " ");
	}
	return 1;
}

int main(void)
{
	const char *only = getenv("STRATUM_CHECK_ONLY"), *except = getenv("STRATUM_CHECK_EXCEPT");
	SRunner *sr;
	int failed;

	if (getenv("STRATUM_CHECK_LIST")) {
		for (size_t i = 0; i < NSUITES; i++)
			printf("%s\n", suites[i].name);
		return EXIT_SUCCESS;
	}
	if ((only && !all_known("STRATUM_CHECK_ONLY", only)) ||
	    (except && !all_known("STRATUM_CHECK_EXCEPT", except)))
		return EXIT_FAILURE;
	sr = srunner_create(NULL);
	tu_scratch_init();
	for (size_t i = 0; i < NSUITES; i++)
		if ((!only || listed(only, suites[i].name)) &&
		    (!except || !listed(except, suites[i].name)))
			srunner_add_suite(sr, suites[i].make());
	srunner_run_all(sr, CK_NORMAL);
	failed = srunner_ntests_failed(sr);
	srunner_free(sr);
	tu_scratch_cleanup();
	return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
