/*
 * check_analyze.c - the cusp-height measurement (repair/cusp_measure.h,
 * seed 004's bounding-box method) and `stratum analyze`.
 *
 * The analytic value: a plane surface whose normal makes the angle theta
 * with Z, printed in layers h thick cut at mid-height, leaves a staircase
 * whose corners stand h / 2 above and below the cutting plane on the
 * wall; a corner lies (h / 2) |cos theta| from the surface along its
 * normal.  For a 45-degree wedge that is h / (2 sqrt 2) = 0.35355 h, in
 * every layer, whether the slope faces up (the normal leads to the wall)
 * or down (an overhang: the reversed normal does).
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cusp_measure.h"
#include "fixtures.h"
#include "meshio.h"
#include "suites.h"
#include "testutil.h"

#define H 0.1	  /* mm, layer height of the wedge tests */
#define SIDE 0.5  /* mm, the wedge's legs: five layers */
#define WIDTH 0.1 /* mm, the wedge along Y */
/* mm between cloud points, as `stratum analyze` spaces them by default:
 * the cloud alone falls 1.1 % short of the analytic value here; each
 * box's best point refined on its facet is within 0.05 % of it */
#define SPACING (H / CUSP_MEASURE_POINTS_PER_LAYER)

/*
 * A wedge: the right triangle (0,0) (SIDE,0) (0,SIDE) of the XZ plane
 * swept along Y over WIDTH; its slope's normal is (1, 0, 1) / sqrt 2.
 * upside_down mirrors it in Z: the slope becomes an overhang.
 */
static struct mesh *wedge(bool upside_down)
{
	const double s = SIDE, w = WIDTH;
	const double v[6][3] = {{0, 0, 0}, {s, 0, 0}, {0, 0, s}, {0, w, 0}, {s, w, 0}, {0, w, s}};
	const int tri[8][3] = {{0, 1, 2}, {3, 5, 4}, {0, 3, 4}, {0, 4, 1},
			       {0, 2, 5}, {0, 5, 3}, {1, 4, 5}, {1, 5, 2}};
	struct mesh_builder *b = mesh_builder_new(8);
	struct st_error err;
	uint32_t id[6];

	ck_assert_ptr_nonnull(b);
	for (int i = 0; i < 6; i++) {
		double p[3] = {v[i][0], v[i][1], upside_down ? s - v[i][2] : v[i][2]};
		ck_assert_int_eq(mesh_builder_vertex(b, p, &id[i], &err), 0);
	}
	for (int t = 0; t < 8; t++) {
		/* mirroring turns the orientation: swap two corners back */
		int c1 = upside_down ? tri[t][2] : tri[t][1], c2 = upside_down ? tri[t][1] : tri[t][2];
		ck_assert_int_eq(mesh_builder_triangle(b, id[tri[t][0]], id[c1], id[c2], &err), 0);
	}
	return mesh_builder_finish(b);
}

START_TEST(wedge_45_matches_the_analytic_cusp)
{
	const double analytic = H / (2 * sqrt(2.0));

	for (int down = 0; down < 2; down++) {
		struct mesh *m = wedge(down);
		struct cusp_report r;
		struct st_error err;

		ck_assert_int_eq(cusp_measure(m, H, SPACING, &r, &err), 0);
		ck_assert_uint_eq(r.nslices, 5);
		ck_assert_msg(fabs(r.max - analytic) <= 0.01 * analytic,
			      "%s: max %.6f mm, analytic %.6f mm", down ? "overhang" : "slope", r.max,
			      analytic);
		for (size_t i = 0; i < r.nslices; i++)
			ck_assert_msg(fabs(r.slices[i].max - analytic) <= 0.01 * analytic,
				      "%s: layer %zu max %.6f mm, analytic %.6f mm",
				      down ? "overhang" : "slope", i, r.slices[i].max, analytic);
		cusp_report_free(&r);
		mesh_free(m);
	}
}
END_TEST

/* A box an exact number of layers tall: vertical walls, no staircase. */
START_TEST(vertical_walls_have_no_cusp)
{
	struct mesh *m = fx_box(0, 0, 0, 2, 1, 1);
	struct cusp_report r;
	struct st_error err;

	ck_assert_int_eq(cusp_measure(m, H, SPACING, &r, &err), 0);
	ck_assert_uint_eq(r.nslices, 10);
	ck_assert_uint_gt(r.nboxes, 0);
	ck_assert_msg(r.max <= 1e-12, "max %g mm", r.max);
	cusp_report_free(&r);
	mesh_free(m);
}
END_TEST

/* The command: the figures, the JSON, the plot and the exit statuses. */
START_TEST(cli_reports_plots_and_refuses)
{
	static char out[1 << 16];
	char stl[256], png[256], missing[256];
	struct mesh *m = wedge(false);
	struct st_error err;
	size_t len;
	unsigned char *pic;
	double max;

	snprintf(stl, sizeof(stl), "%s", tu_path("wedge.stl"));
	snprintf(png, sizeof(png), "%s", tu_path("wedge-cusp.png"));
	snprintf(missing, sizeof(missing), "%s", tu_path("no-such-model.stl"));
	ck_assert_int_eq(meshio_write_stl(stl, m, MESHIO_STL_BINARY, &err), 0);
	mesh_free(m);

	ck_assert_int_eq(tu_run(out, sizeof(out), "analyze '%s' --layer-height %g --json --png '%s'",
				stl, H, png), 0);
	char *at = strstr(out, "\"max\": ");
	ck_assert_msg(at && sscanf(at + 7, "%lf", &max) == 1, "%s", out);
	ck_assert_msg(fabs(max - H / (2 * sqrt(2.0))) <= 0.01 * H / (2 * sqrt(2.0)), "%s", out);
	pic = tu_slurp(png, &len);
	ck_assert(len > 8 && !memcmp(pic, "\x89PNG", 4));
	free(pic);

	/* 65 naming the file; 2 for usage */
	ck_assert_int_eq(tu_run(out, sizeof(out), "analyze '%s' --layer-height 0.2", missing), 65);
	ck_assert_msg(strstr(out, missing) != NULL, "%s", out);
	tu_write_str(missing, "this is no mesh\n");
	ck_assert_int_eq(tu_run(out, sizeof(out), "analyze '%s' --layer-height 0.2", missing), 65);
	ck_assert_msg(strstr(out, missing) != NULL, "%s", out);
	ck_assert_int_eq(tu_run(out, sizeof(out), "analyze '%s'", stl), 2);
	ck_assert_msg(strstr(out, "--layer-height") != NULL, "%s", out);
	ck_assert_int_eq(tu_run(out, sizeof(out), "analyze '%s' --layer-height 0", stl), 2);
}
END_TEST

Suite *analyze_suite(void)
{
	Suite *s = suite_create("analyze");
	TCase *tc = tcase_create("cusp");

	tcase_set_timeout(tc, 30);
	tcase_add_test(tc, wedge_45_matches_the_analytic_cusp);
	tcase_add_test(tc, vertical_walls_have_no_cusp);
	tcase_add_test(tc, cli_reports_plots_and_refuses);
	suite_add_tcase(s, tc);
	return s;
}
