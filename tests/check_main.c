/* check_main.c - run every module's suite; fork mode stays on so a crash
 * fails only its own test. */
#include <stdlib.h>

#include "suites.h"
#include "testutil.h"

int main(void)
{
	Suite *(*const suites[])(void) = {stfile_suite, mesh_suite,  meshio_suite, exact_suite, repair_suite,
					  batch_suite,
					  thicken_suite, heal_suite, corpus_suite,
					  profile_suite, ini_suite, placeholder_suite, gcode_suite,
					  xport_suite, sim_suite, marlin_suite, printer_suite,
					  slicer_suite, gcodewriter_suite, infill_suite, support_suite,
					  slicecli_suite, region_suite, x3g_suite, s3g_suite, serve_suite,
					  preview_suite, portpick_suite, send_suite, guard_suite, print_suite, cli_suite};
	SRunner *sr = srunner_create(NULL);
	int failed;

	tu_scratch_init();
	for (size_t i = 0; i < sizeof(suites) / sizeof(suites[0]); i++)
		srunner_add_suite(sr, suites[i]());
	srunner_run_all(sr, CK_NORMAL);
	failed = srunner_ntests_failed(sr);
	srunner_free(sr);
	tu_scratch_cleanup();
	return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
