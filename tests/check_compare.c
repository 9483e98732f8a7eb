/*
 * check_compare.c - the surface distance and chordal error
 * (repair/deviation.h, on CGAL's AABB tree through repair/exact/surfdist.h)
 * and `stratum compare`.
 *
 * The analytic values:
 * - a mesh against itself: every distance 0;
 * - a sphere of radius r against itself moved by d < r: a point at angle
 *   phi from the direction of the move is | |p - d| - r | from the moved
 *   sphere, largest (d) at phi = 0 and pi; over the sphere's area
 *   (cos phi uniform in -1..1) its mean is exactly d / 2 (the integral of
 *   |s - r| s ds / (2 r d) for s from r - d to r + d is r d^2 / (2 r d)).
 *   The tessellated spheres stray from the round one by up to the sagitta
 *   of their facets, r (1 - cos(pi / 64)) = 0.012 mm here: the bound below.
 * - a 16-sided prism against a 256-sided one on the same circle of radius
 *   r: a side facet's chordal error is the sagitta r (1 - cos(pi / 16)),
 *   at its middle, where a vertex of the fine prism lies (256 = 16 x 16).
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "deviation.h"
#include "fixtures.h"
#include "meshio.h"
#include "suites.h"
#include "testutil.h"

#define R 10.0	       /* mm, sphere and cylinder radius */
#define MOVE 1.0       /* mm, the sphere's translation */
#define SAMPLES 20000  /* per surface: enough for the figures below, fast */
#define SPHERE_SAG (R * (1 - cos(M_PI / 64)))

START_TEST(mesh_against_itself_is_zero)
{
	struct mesh *m = fx_sphere(0, 0, 0, R, 24, 48);
	struct deviation_report d;
	struct st_error err;

	ck_assert_int_eq(deviation_measure(m, m, SAMPLES, &d, &err), 0);
	ck_assert_msg(d.max <= 1e-9 && d.mean <= 1e-9 && d.p95 <= 1e-9, "max %g mean %g p95 %g",
		      d.max, d.mean, d.p95);
	ck_assert_uint_ge(d.a_to_b.samples, SAMPLES / 2);
	double share = 0;
	for (int i = 0; i < DEVIATION_BINS; i++)
		share += d.hist[i];
	ck_assert(fabs(share - 1) < 1e-9); /* the histogram covers the whole area */
	deviation_report_free(&d);
	mesh_free(m);
}
END_TEST

START_TEST(sphere_moved_by_d_is_d_away)
{
	struct mesh *a = fx_sphere(0, 0, 0, R, 64, 128), *b = fx_sphere(MOVE, 0, 0, R, 64, 128);
	struct deviation_report d;
	struct st_error err;

	ck_assert_int_eq(deviation_measure(a, b, SAMPLES, &d, &err), 0);
	ck_assert_msg(fabs(d.max - MOVE) <= SPHERE_SAG, "max %.6f mm, analytic %.6f mm", d.max,
		      MOVE);
	ck_assert_msg(fabs(d.mean - MOVE / 2) <= SPHERE_SAG, "mean %.6f mm, analytic %.6f mm",
		      d.mean, MOVE / 2);
	/* both ways alike, by symmetry */
	ck_assert(fabs(d.a_to_b.max - d.b_to_a.max) <= SPHERE_SAG);
	ck_assert(d.p95 < d.max && d.p95 > d.mean);
	deviation_report_free(&d);
	mesh_free(a);
	mesh_free(b);
}
END_TEST

START_TEST(coarse_cylinder_chordal_error_is_the_sagitta)
{
	struct mesh *coarse = fx_cylinder(0, 0, R, 20, 16), *fine = fx_cylinder(0, 0, R, 20, 256);
	const double sagitta = R * (1 - cos(M_PI / 16));
	struct chordal_report c;
	struct st_error err;
	size_t sides = 0;

	ck_assert_int_eq(chordal_measure(coarse, fine, SAMPLES, 0.01, &c, &err), 0);
	ck_assert_msg(fabs(c.max - sagitta) <= 1e-6 * sagitta, "max %.9f mm, sagitta %.9f mm",
		      c.max, sagitta);
	/* every side facet reaches it; the caps lie in the fine caps' planes */
	for (size_t t = 0; t < coarse->ntris; t++) {
		const double *v0 = coarse->verts[coarse->tris[t][0]];
		const double *v1 = coarse->verts[coarse->tris[t][1]];
		const double *v2 = coarse->verts[coarse->tris[t][2]];
		bool cap = v0[2] == v1[2] && v1[2] == v2[2];
		if (cap)
			ck_assert_msg(c.facet[t] <= 1e-9, "cap facet %zu: %g mm", t, c.facet[t]);
		else
			ck_assert_msg(fabs(c.facet[t] - sagitta) <= 1e-6 * sagitta,
				      "side facet %zu: %.9f mm", t, c.facet[t]), sides++;
	}
	ck_assert_uint_eq(sides, 32);
	ck_assert_uint_eq(c.nover, 32);	 /* seed 003's isolation: the side band */
	ck_assert_uint_eq(c.regions, 1);
	chordal_report_free(&c);
	mesh_free(coarse);
	mesh_free(fine);
}
END_TEST

/* The command: the figures, the picture and the exit statuses. */
START_TEST(cli_reports_draws_and_refuses)
{
	static char out[1 << 16];
	char coarse[256], fine[256], png[256], missing[256];
	struct mesh *c = fx_cylinder(0, 0, R, 20, 16), *f = fx_cylinder(0, 0, R, 20, 256);
	struct st_error err;
	size_t len;
	unsigned char *pic;

	snprintf(coarse, sizeof(coarse), "%s", tu_path("cyl16.stl"));
	snprintf(fine, sizeof(fine), "%s", tu_path("cyl256.stl"));
	snprintf(png, sizeof(png), "%s", tu_path("cyl.png"));
	snprintf(missing, sizeof(missing), "%s", tu_path("no-such-model.stl"));
	ck_assert_int_eq(meshio_write_stl(coarse, c, MESHIO_STL_BINARY, &err), 0);
	ck_assert_int_eq(meshio_write_stl(fine, f, MESHIO_STL_BINARY, &err), 0);
	mesh_free(c);
	mesh_free(f);

	ck_assert_int_eq(tu_run(out, sizeof(out), "compare '%s' '%s' --samples %d", coarse, coarse,
				SAMPLES), 0);
	ck_assert_msg(strstr(out, "max 0.000000 mm, mean 0.000000 mm") != NULL, "%s", out);
	ck_assert_int_eq(tu_run(out, sizeof(out),
				"compare '%s' '%s' --reference '%s' --tolerance 0.1 --samples %d "
				"--png '%s' --json",
				coarse, fine, fine, SAMPLES, png), 0);
	ck_assert_msg(strstr(out, "\"facets_over\": 32") && strstr(out, "\"regions\": 1"), "%s",
		      out);
	pic = tu_slurp(png, &len);
	ck_assert(len > 8 && !memcmp(pic, "\x89PNG", 4));
	free(pic);

	/* 65 naming the file that cannot be read, whichever it is; 2 for usage */
	ck_assert_int_eq(tu_run(out, sizeof(out), "compare '%s' '%s'", coarse, missing), 65);
	ck_assert_msg(strstr(out, missing) != NULL, "%s", out);
	ck_assert_int_eq(tu_run(out, sizeof(out), "compare '%s' --reference '%s'", coarse, missing),
			 65);
	ck_assert_msg(strstr(out, missing) != NULL, "%s", out);
	ck_assert_int_eq(tu_run(out, sizeof(out), "compare '%s'", coarse), 2);
	ck_assert_int_eq(tu_run(out, sizeof(out), "compare '%s' '%s' '%s'", coarse, fine, fine), 2);
	ck_assert_int_eq(tu_run(out, sizeof(out), "compare '%s' '%s' --tolerance -1", coarse, fine),
			 2);
}
END_TEST

/* A disc 0.1 mm thick: every point of a side facet is within 0.05 mm of a
 * cap of the fine disc, nearer than the side (0.19 mm along the normal),
 * so the line along the normal counts only near the cap; the fine side's
 * points, nearest to the coarse side facet, still find the sagitta
 * (chordal_measure, deviation.h). */
START_TEST(chordal_error_beside_a_crease)
{
	struct mesh *coarse = fx_cylinder(0, 0, R, 0.1, 16), *fine = fx_cylinder(0, 0, R, 0.1, 256);
	const double sagitta = R * (1 - cos(M_PI / 16));
	struct chordal_report c;
	struct st_error err;

	ck_assert_int_eq(chordal_measure(coarse, fine, SAMPLES, 0.01, &c, &err), 0);
	ck_assert_msg(fabs(c.max - sagitta) <= 1e-6 * sagitta, "max %.9f mm, sagitta %.9f mm",
		      c.max, sagitta);
	ck_assert_uint_eq(c.nover, 32);
	chordal_report_free(&c);
	mesh_free(coarse);
	mesh_free(fine);
}
END_TEST

Suite *compare_suite(void)
{
	Suite *s = suite_create("compare");
	TCase *tc = tcase_create("deviation");

	tcase_set_timeout(tc, 120); /* ASan makes the queries several times slower */
	tcase_add_test(tc, mesh_against_itself_is_zero);
	tcase_add_test(tc, sphere_moved_by_d_is_d_away);
	tcase_add_test(tc, coarse_cylinder_chordal_error_is_the_sagitta);
	tcase_add_test(tc, chordal_error_beside_a_crease);
	tcase_add_test(tc, cli_reports_draws_and_refuses);
	suite_add_tcase(s, tc);
	return s;
}
