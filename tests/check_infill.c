/*
 * check_infill.c - skins, bridges, solid and sparse infill on meshes and
 * stacks built in code, with expectations that follow from the geometry
 * and the flow model: a solid layer deposits the region's volume and
 * covers it, sparse infill at density d deposits d of it, bridges cross
 * the gap from anchor to anchor (shells, small regions, narrow strips,
 * gyroid chords and bad settings: check_infill_solid.c).
 */
#include <check.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "clip.h"
#include "fixtures.h"
#include "infill.h"
#include "infilltest.h"
#include "mesh.h"
#include "patterns.h"
#include "perimeters.h"
#include "section.h"
#include "suites.h"
#include "testutil.h"
#include "toolpath.h"

START_TEST(cube_skins_and_sparse)
{
	struct mesh *m = fx_box(0, 0, 0, 20, 20, 20);
	struct infill_settings is;
	struct run r;
	const double h = 0.2, d = 0.2;

	infill_settings_init(&is, 0.4);
	is.fill_pattern = INFILL_RECTILINEAR;
	run_infill(m, h, &is, &r);
	ck_assert_uint_eq(r.st->n, 100);
	double worst_solid = 0, worst_sparse = 0, worst_cover = 1, worst_bead = 0;
	for (size_t i = 0; i < r.st->n; i++) {
		const struct layer_paths *l = &r.ls->layers[i];
		double A = region_area(&r.inner[i]);
		enum path_role want = i < 3 ? PATH_BOTTOM_SKIN : i >= 97 ? PATH_TOP_SKIN
									: PATH_SPARSE_INFILL;
		ck_assert_msg(l->n > 0, "layer %zu has no infill", i);
		for (size_t k = 0; k < l->n; k++)
			ck_assert_msg(l->paths[k].role == want || l->paths[k].role == PATH_GAP_FILL,
				      "layer %zu path %zu is %s", i, k,
				      path_role_name(l->paths[k].role));
		ck_assert_uint_eq(tu_count_role(l, PATH_BRIDGE), 0);
		double fa = flow_area(l, want, h) + flow_area(l, PATH_GAP_FILL, h);
		if (want == PATH_SPARSE_INFILL) {
			/* Lines at spacing / d: d of the region's volume, beads d w / s of it. */
			worst_sparse = fmax(worst_sparse, fabs(fa / (d * A) - 1));
			double ws = 0.45 / perim_spacing(0.45, h);
			worst_bead = fmax(worst_bead, fabs(bead_area(l, want) / (d * ws * A) - 1));
		} else {
			worst_solid = fmax(worst_solid, fabs(fa / A - 1));
			worst_cover =
				fmin(worst_cover, covered(l, SOLID_ROLES, 0, CLIP_END_ROUND, &r.inner[i]) / A);
		}
	}
	ck_assert_msg(worst_solid < 0.03, "solid layer volume off by %.2f %%", 100 * worst_solid);
	ck_assert_msg(worst_sparse < 0.05, "sparse volume off by %.2f %%", 100 * worst_sparse);
	ck_assert_msg(worst_bead < 0.05, "sparse width x length off by %.2f %%", 100 * worst_bead);
	ck_assert_msg(worst_cover >= 0.99, "a solid layer covers %.2f %%", 100 * worst_cover);
	/* Sparse beads of the flow spacing cover d of the region. */
	const struct layer_paths *mid = &r.ls->layers[50];
	double A = region_area(&r.inner[50]);
	double cov = covered(mid, ROLE(PATH_SPARSE_INFILL), perim_spacing(0.45, h) * NM,
			     CLIP_END_BUTT, &r.inner[50]) / A;
	ck_assert_msg(fabs(cov / d - 1) < 0.05, "sparse covers %.2f %% of the region", 100 * cov);
	/* Solid layers alternate 90 degrees; sparse lines repeat every other layer. */
	const struct toolpath *p3 = &r.ls->layers[50].paths[0], *p4 = &r.ls->layers[51].paths[0];
	double a3 = atan2((double)(p3->pts[1].y - p3->pts[0].y), (double)(p3->pts[1].x - p3->pts[0].x));
	double a4 = atan2((double)(p4->pts[1].y - p4->pts[0].y), (double)(p4->pts[1].x - p4->pts[0].x));
	ck_assert_msg(fabs(cos(a3 - a4)) < 1e-3, "layers 50, 51 not crossed");
	ck_assert_msg(fabs(fabs(cos(a3)) - sqrt(0.5)) < 1e-3, "sparse not at 45 degrees");
	ck_assert_uint_eq(r.ls->layers[50].n, r.ls->layers[52].n);
	for (size_t k = 0; k < r.ls->layers[50].n; k++) {
		const struct toolpath *p = &r.ls->layers[50].paths[k];
		bool found = false;
		for (size_t j = 0; j < r.ls->layers[52].n && !found; j++) {
			const struct toolpath *q = &r.ls->layers[52].paths[j];
			found = (q->pts[0].x == p->pts[0].x && q->pts[0].y == p->pts[0].y) ||
				(q->pts[q->n - 1].x == p->pts[0].x && q->pts[q->n - 1].y == p->pts[0].y);
		}
		ck_assert_msg(found, "sparse line %zu of layer 50 not on layer 52", k);
	}
	run_free(&r);
	mesh_free(m);
}
END_TEST

START_TEST(patterns_stay_inside)
{
	struct mesh *m = fx_box(0, 0, 0, 20, 20, 4);
	struct infill_settings is;
	const enum infill_pattern pats[] = {INFILL_GRID,      INFILL_GYROID, INFILL_RECTILINEAR,
					    INFILL_TRIANGLES, INFILL_STARS,  INFILL_CUBIC};
	const double h = 0.2;

	for (size_t p = 0; p < sizeof(pats) / sizeof(pats[0]); p++) {
		for (double d = 0.15; d < 0.5; d += 0.25) {
			struct run r;
			infill_settings_init(&is, 0.4);
			is.fill_pattern = pats[p];
			is.fill_density = 100 * d;
			run_infill(m, h, &is, &r);
			double overlap = 0.25 * 0.45 * NM;
			double worst = 0, mean = 0;
			for (size_t i = 0; i < r.st->n; i++) {
				assert_inside(&r.ls->layers[i], &r.inner[i], overlap + 1000);
				if (i < 3 || i + 3 >= r.st->n)
					continue;
				double A = region_area(&r.inner[i]);
				double fa = flow_area(&r.ls->layers[i], PATH_SPARSE_INFILL, h);
				ck_assert_uint_eq(tu_count_role(&r.ls->layers[i], PATH_SPARSE_INFILL),
						  r.ls->layers[i].n);
				worst = fmax(worst, fabs(fa / (d * A) - 1));
				mean += fa / (d * A) / (double)(r.st->n - 6);
			}
			/*
			 * The gyroid's section length per area varies with z and,
			 * over a few periods, with where the region lies: per layer
			 * within 20 %, on average within 5 %.
			 */
			double tol = pats[p] == INFILL_GYROID ? 0.2 : 0.06;
			ck_assert_msg(worst < tol, "%s at %g: a layer's volume off by %.1f %%",
				      infill_pattern_name(pats[p]), d, 100 * worst);
			ck_assert_msg(fabs(mean - 1) < 0.05, "%s at %g: volume off by %.1f %%",
				      infill_pattern_name(pats[p]), d, 100 * (mean - 1));
			run_free(&r);
		}
	}
	mesh_free(m);
}
END_TEST

/* Sparse segments of layer l whose direction (mod 180) is deg degrees. */
static size_t segments_at(const struct layer_paths *l, double deg)
{
	size_t n = 0;

	for (size_t k = 0; k < l->n; k++)
		for (size_t j = 0; j + 1 < l->paths[k].n; j++) {
			const struct path_point *a = &l->paths[k].pts[j], *b = a + 1;
			double t = atan2((double)(b->y - a->y), (double)(b->x - a->x)) * 180 / M_PI;
			double d = fmod(fmod(t - deg, 180) + 180, 180);

			n += d < 0.5 || d > 179.5;
		}
	return n;
}

/* A segment with its ends in order, for comparing layers whatever the
 * printing order and direction. */
struct seg4 {
	int64_t v[4];
};

static int seg4_cmp(const void *a, const void *b)
{
	const int64_t *p = ((const struct seg4 *)a)->v, *q = ((const struct seg4 *)b)->v;

	for (int i = 0; i < 4; i++)
		if (p[i] != q[i])
			return p[i] < q[i] ? -1 : 1;
	return 0;
}

/* The segments of l, sorted; *n of them (free the array). */
static struct seg4 *layer_segments(const struct layer_paths *l, size_t *n)
{
	size_t cap = 0, k = 0;
	struct seg4 *s;

	for (size_t i = 0; i < l->n; i++)
		cap += l->paths[i].n - 1;
	s = calloc(cap + 1, sizeof(*s));
	ck_assert_ptr_nonnull(s);
	for (size_t i = 0; i < l->n; i++)
		for (size_t j = 0; j + 1 < l->paths[i].n; j++, k++) {
			const struct path_point *a = &l->paths[i].pts[j], *b = a + 1;
			bool swap = a->x > b->x || (a->x == b->x && a->y > b->y);
			const struct path_point *lo = swap ? b : a, *hi = swap ? a : b;
			s[k] = (struct seg4){{lo->x, lo->y, hi->x, hi->y}};
		}
	qsort(s, k, sizeof(*s), seg4_cmp);
	*n = k;
	return s;
}

/* The same segments, whatever their order and direction. */
static bool same_layer(const struct layer_paths *a, const struct layer_paths *b)
{
	size_t na, nb;
	struct seg4 *sa = layer_segments(a, &na), *sb = layer_segments(b, &nb);
	bool same = na == nb && !memcmp(sa, sb, na * sizeof(*sa));

	free(sa);
	free(sb);
	return same;
}

/* Triangles, stars and cubic: three line sets at the fill angle + 0, 60,
 * 120 degrees on every layer; triangles and stars repeat layer after layer,
 * stars differs from triangles, cubic moves with z. */
START_TEST(three_line_set_patterns)
{
	struct mesh *m = fx_box(0, 0, 0, 20, 20, 4);
	const enum infill_pattern pats[] = {INFILL_TRIANGLES, INFILL_STARS, INFILL_CUBIC};
	struct infill_settings is;
	struct run r[3];

	for (size_t p = 0; p < 3; p++) {
		infill_settings_init(&is, 0.4);
		is.fill_pattern = pats[p];
		run_infill(m, 0.2, &is, &r[p]);
		const struct layer_paths *l = &r[p].ls->layers[8];
		size_t total = 0;
		for (size_t k = 0; k < l->n; k++)
			total += l->paths[k].n - 1;
		size_t a = segments_at(l, 45), b = segments_at(l, 105), c = segments_at(l, 165);
		ck_assert_msg(a && b && c && a + b + c == total, "%s: %zu + %zu + %zu of %zu",
			      infill_pattern_name(pats[p]), a, b, c, total);
		ck_assert(same_layer(l, &r[p].ls->layers[9]) == (pats[p] != INFILL_CUBIC));
	}
	ck_assert(!same_layer(&r[0].ls->layers[8], &r[1].ls->layers[8]));
	for (size_t p = 0; p < 3; p++)
		run_free(&r[p]);
	mesh_free(m);
}
END_TEST

/* Length (nm) of the sparse paths of layer l, closing segments included. */
static double sparse_length(const struct layer_paths *l)
{
	double len = 0;

	for (size_t k = 0; k < l->n; k++) {
		const struct toolpath *p = &l->paths[k];
		if (p->role != PATH_SPARSE_INFILL)
			continue;
		len += tu_path_length(p);
		if (p->closed)
			len += hypot((double)(p->pts[p->n - 1].x - p->pts[0].x),
				     (double)(p->pts[p->n - 1].y - p->pts[0].y));
	}
	return len;
}

/* Sparse length of layers 3 .. n - 4 (between the shells) of a run. */
static double sparse_total(const struct run *r)
{
	double len = 0;

	for (size_t i = 3; i + 3 < r->st->n; i++)
		len += sparse_length(&r->ls->layers[i]);
	return len;
}

/*
 * Line, concentric and honeycomb: as much line as rectilinear at the same
 * density, inside the region, and each its own shape: line paths are
 * single straight segments alternating 90 degrees, every other one tilted;
 * concentric paths closed loops; honeycomb zig-zags turned 60 degrees a
 * layer, repeating every 3 layers, their walls stacking.
 */
START_TEST(line_concentric_honeycomb)
{
	struct mesh *m = fx_box(0, 0, 0, 20, 20, 4), *ring = fx_box(30, 0, 0, 50, 20, 4);
	struct mesh *hole = fx_box(36, 6, 0, 44, 14, 4), *both = fx_concat(m, ring);
	const enum infill_pattern pats[] = {INFILL_LINE, INFILL_CONCENTRIC, INFILL_HONEYCOMB};
	const double overlap = 0.25 * 0.45 * NM;
	struct infill_settings is;

	/* the second box gets a square hole: the inner walls are reversed */
	for (size_t i = 0; i < hole->ntris; i++)
		fx_flip(hole, i);
	struct mesh *shape = fx_concat(both, hole);
	for (double d = 15; d < 50; d += 20) {
		struct run rect;
		infill_settings_init(&is, 0.4);
		is.fill_pattern = INFILL_RECTILINEAR;
		is.fill_density = d;
		run_infill(shape, 0.2, &is, &rect);
		double want = sparse_total(&rect);
		for (size_t p = 0; p < 3; p++) {
			struct run r;
			is.fill_pattern = pats[p];
			run_infill(shape, 0.2, &is, &r);
			double got = sparse_total(&r);
			ck_assert_msg(fabs(got / want - 1) < 0.15, "%s at %g %%: %.1f mm, rectilinear %.1f",
				      infill_pattern_name(pats[p]), d, got / NM, want / NM);
			for (size_t i = 0; i < r.st->n; i++) {
				const struct layer_paths *l = &r.ls->layers[i];
				assert_inside(l, &r.inner[i], overlap + 1000);
				for (size_t k = 0; i >= 3 && i + 3 < r.st->n && k < l->n; k++) {
					const struct toolpath *t = &l->paths[k];
					ck_assert(t->role == PATH_SPARSE_INFILL);
					if (pats[p] == INFILL_LINE)
						ck_assert_msg(t->n == 2 && !t->closed,
							      "line path of %zu points", t->n);
					else if (pats[p] == INFILL_CONCENTRIC)
						ck_assert_msg(t->closed && t->n >= 3, "concentric path open");
					else
						ck_assert(!t->closed);
				}
			}
			const struct layer_paths *l8 = &r.ls->layers[8], *l9 = &r.ls->layers[9];
			ck_assert_msg(!same_layer(l8, &rect.ls->layers[8]), "%s prints rectilinear",
				      infill_pattern_name(pats[p]));
			if (pats[p] == INFILL_LINE) {
				/* every other line at the fill angle, alternating by layer */
				size_t n8 = segments_at(l8, 45), n9 = segments_at(l9, 135);
				ck_assert_msg(n8 > l8->n / 3 && n8 < l8->n, "%zu of %zu at 45", n8, l8->n);
				ck_assert_msg(n9 > l9->n / 3 && n9 < l9->n, "%zu of %zu at 135", n9, l9->n);
				ck_assert_uint_eq(segments_at(l8, 135), 0);
			}
			if (pats[p] == INFILL_CONCENTRIC) /* no rotation: layers repeat */
				ck_assert(same_layer(l8, l9));
			if (pats[p] == INFILL_HONEYCOMB) {
				ck_assert(!same_layer(l8, l9) && !same_layer(l9, &r.ls->layers[10]));
				ck_assert(same_layer(l8, &r.ls->layers[11]));
				/* turned about a cell centre: the walls stack */
				struct clip_paths b8 = {0}, b9 = {0};
				double a9 = 0, shared;
				beads_of(l8, ROLE(PATH_SPARSE_INFILL), 0, CLIP_END_ROUND, &b8);
				beads_of(l9, ROLE(PATH_SPARSE_INFILL), 0, CLIP_END_ROUND, &b9);
				ck_assert_int_eq(clip_boolean(CLIP_UNION, &b9, NULL, CLIP_NONZERO, &b9,
							      NULL),
						 0);
				ck_assert_int_eq(clip_paths_area(&b9, &a9, NULL), 0);
				shared = covered_paths(l9, ROLE(PATH_SPARSE_INFILL), 0, CLIP_END_ROUND, &b8);
				/* 77 % at 15 and 79 % at 35 %; 16 and 40 % turned
				 * about the origin, inside a cell */
				ck_assert_msg(shared > 0.7 * a9, "%.0f %% of layer 9 on layer 8",
					      100 * shared / a9);
				clip_paths_free(&b8);
				clip_paths_free(&b9);
			}
			run_free(&r);
		}
		run_free(&rect);
	}
	mesh_free(shape);
	mesh_free(both);
	mesh_free(hole);
	mesh_free(ring);
	mesh_free(m);
}
END_TEST

START_TEST(bridge_between_pillars)
{
	struct mesh *a = fx_box(0, 0, 0, 5, 10, 5), *b = fx_box(15, 0, 0, 20, 10, 5);
	struct mesh *ab = fx_concat(a, b), *slab = fx_box(0, 0, 5, 20, 10, 6);
	struct mesh *m = fx_concat(ab, slab);
	struct infill_settings is;
	struct run r;
	const double h = 0.2;

	infill_settings_init(&is, 0.4);
	run_infill(m, h, &is, &r);
	ck_assert_uint_eq(r.st->n, 30);
	for (size_t i = 0; i < 25; i++)
		ck_assert_uint_eq(tu_count_role(&r.ls->layers[i], PATH_BRIDGE), 0);
	/* Layer 25 (z 5.0 .. 5.2) is the first slab layer. */
	const struct layer_paths *l = &r.ls->layers[25];
	double bw = h + M_PI * (0.16 - h * h) / (4 * h);
	size_t nb = 0;
	double across = 0;
	for (size_t k = 0; k < l->n; k++) {
		const struct toolpath *p = &l->paths[k];
		if (p->role != PATH_BRIDGE)
			continue;
		nb++;
		double dx = (double)(p->pts[p->n - 1].x - p->pts[0].x);
		double dy = (double)(p->pts[p->n - 1].y - p->pts[0].y);
		double ang = fabs(atan2(dy, dx)) * 180 / M_PI;
		ang = fmin(ang, 180 - ang);
		ck_assert_msg(ang < 10, "bridge line %zu at %g degrees to the gap", k, ang);
		ck_assert_int_eq(p->pts[0].width, llround(bw * NM));
		/* Both ends on a pillar. */
		double x0 = fmin(p->pts[0].x, p->pts[p->n - 1].x) / NM;
		double x1 = fmax(p->pts[0].x, p->pts[p->n - 1].x) / NM;
		ck_assert_msg(x0 < 5 && x1 > 15, "bridge line %zu from x %g to %g mm", k, x0, x1);
		across += tu_path_length(p);
	}
	ck_assert_msg(nb >= 15, "%zu bridge lines", nb);
	/* The gap (10 x ~8.4 mm inside the walls) is spanned: lines every 0.45 mm. */
	ck_assert_msg(across / NM > 8.0 / 0.45 * 10, "bridge lines total %g mm", across / NM);
	/* Over the bridge: solid infill, then the top shell. */
	ck_assert_uint_gt(tu_count_role(&r.ls->layers[26], PATH_SOLID_INFILL), 0);
	ck_assert_uint_eq(tu_count_role(&r.ls->layers[26], PATH_BRIDGE), 0);
	for (size_t i = 27; i < 30; i++)
		ck_assert_uint_gt(tu_count_role(&r.ls->layers[i], PATH_TOP_SKIN), 0);
	run_free(&r);
	/* A fixed bridge_angle overrides the detection. */
	is.bridge_angle = 90;
	run_infill(m, h, &is, &r);
	l = &r.ls->layers[25];
	ck_assert_uint_gt(tu_count_role(l, PATH_BRIDGE), 0);
	for (size_t k = 0; k < l->n; k++)
		if (l->paths[k].role == PATH_BRIDGE)
			ck_assert_int_eq(l->paths[k].pts[0].x, l->paths[k].pts[1].x);
	run_free(&r);
	mesh_free(a);
	mesh_free(b);
	mesh_free(ab);
	mesh_free(slab);
	mesh_free(m);
}
END_TEST

Suite *infill_suite(void)
{
	Suite *s = suite_create("infill");
	TCase *tc = tcase_create("infill");

	tcase_set_timeout(tc, 120);
	tcase_add_test(tc, cube_skins_and_sparse);
	tcase_add_test(tc, patterns_stay_inside);
	tcase_add_test(tc, three_line_set_patterns);
	tcase_add_test(tc, line_concentric_honeycomb);
	tcase_add_test(tc, bridge_between_pillars);
	infill_solid_tests(tc);
	suite_add_tcase(s, tc);
	infill_shell_tcases(s);
	return s;
}
