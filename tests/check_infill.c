/*
 * check_infill.c - skins, bridges, solid and sparse infill on meshes and
 * stacks built in code, with expectations that follow from the geometry
 * and the flow model: a solid layer deposits the region's volume and
 * covers it, sparse infill at density d deposits d of it, bridges cross
 * the gap from anchor to anchor, shells are as thick as asked.
 */
#include <check.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "clip.h"
#include "fixtures.h"
#include "infill.h"
#include "mesh.h"
#include "patterns.h"
#include "perimeters.h"
#include "section.h"
#include "suites.h"
#include "testutil.h"
#include "toolpath.h"

#define NM SLICE_UNITS_PER_MM
#define ARC 2000.0 /* nm, chord error of the tests' round offsets */

/* A sliced mesh, its regions inside 2 walls, and the infill of every layer. */
struct run {
	struct slice_stack *st;
	struct clip_expolys *inner;
	struct layer_stack *ls;
};

static void run_infill(const struct mesh *m, double h, const struct infill_settings *is,
		       struct run *r)
{
	struct st_error err = {0};
	struct perim_settings ps;
	struct layer_paths walls;

	r->st = NULL;
	ck_assert_msg(slice_mesh(m, h, h, NULL, &r->st, &err) == 0, "slice_mesh: %s", err.msg);
	perim_settings_init(&ps, 0.4);
	r->inner = calloc(r->st->n, sizeof(*r->inner));
	ck_assert_ptr_nonnull(r->inner);
	for (size_t i = 0; i < r->st->n; i++) {
		memset(&walls, 0, sizeof(walls));
		ck_assert_msg(perim_generate(&ps, &r->st->layers[i].regions, h, NULL, &walls,
					     &r->inner[i], NULL, &err) == 0,
			      "perim_generate: %s", err.msg);
		for (size_t k = 0; k < walls.n; k++)
			free(walls.paths[k].pts);
		free(walls.paths);
	}
	r->ls = layer_stack_new(r->st->n, &err);
	ck_assert_ptr_nonnull(r->ls);
	ck_assert_msg(infill_generate(is, r->st, r->inner, r->ls, &err) == 0, "infill: %s",
		      err.msg);
}

static void run_free(struct run *r)
{
	for (size_t i = 0; i < r->st->n; i++)
		clip_expolys_free(&r->inner[i]);
	free(r->inner);
	layer_stack_free(r->ls);
	slice_stack_free(r->st);
}

/*
 * Flow-equivalent area (nm^2) of the paths of role on layer l: length x
 * the bead spacing of their width at height h (perim_spacing), i.e. the
 * deposited volume over h.
 */
static double flow_area(const struct layer_paths *l, enum path_role role, double h)
{
	double a = 0;

	for (size_t i = 0; i < l->n; i++)
		if (l->paths[i].role == role)
			a += tu_path_length(&l->paths[i]) *
			     perim_spacing(l->paths[i].pts[0].width / NM, h) * NM;
	return a;
}

/* Sum of width x length (nm^2) of the paths of role on layer l. */
static double bead_area(const struct layer_paths *l, enum path_role role)
{
	double a = 0;

	for (size_t i = 0; i < l->n; i++)
		if (l->paths[i].role == role)
			a += tu_path_length(&l->paths[i]) * (double)l->paths[i].pts[0].width;
	return a;
}

static double region_area(const struct clip_expolys *ex)
{
	double a = 0;

	ck_assert_int_eq(clip_paths_area(&ex->paths, &a, NULL), 0);
	return a;
}

/*
 * Into all, the beads of the paths of the roles in mask on layer l, each
 * its width (or the given width when > 0) wide with ends as end.
 */
static void beads_of(const struct layer_paths *l, unsigned mask, double width,
		     enum clip_end end, struct clip_paths *all)
{
	struct clip_paths line = {0}, bead = {0};

	for (size_t i = 0; i < l->n; i++) {
		const struct toolpath *p = &l->paths[i];
		if (!(mask & 1u << p->role))
			continue;
		int64_t *xy = malloc(2 * p->n * sizeof(*xy));
		ck_assert_ptr_nonnull(xy);
		for (size_t k = 0; k < p->n; k++) {
			xy[2 * k] = p->pts[k].x;
			xy[2 * k + 1] = p->pts[k].y;
		}
		clip_paths_clear(&line);
		ck_assert_int_eq(clip_paths_add(&line, xy, p->n, NULL), 0);
		free(xy);
		double w = width > 0 ? width : (double)p->pts[0].width;
		ck_assert_int_eq(clip_offset_open(&line, w / 2, CLIP_JOIN_ROUND, end, 2, ARC, &bead,
						  NULL),
				 0);
		ck_assert_int_eq(clip_paths_append(all, &bead, NULL), 0);
	}
	clip_paths_free(&line);
	clip_paths_free(&bead);
}

/* Area (nm^2) of the region ps covered by the beads of beads_of(l, ...). */
static double covered_paths(const struct layer_paths *l, unsigned mask, double width,
			    enum clip_end end, const struct clip_paths *ps)
{
	struct clip_paths all = {0}, in = {0};
	double a = 0;

	beads_of(l, mask, width, end, &all);
	ck_assert_int_eq(clip_boolean(CLIP_INTERSECTION, &all, ps, CLIP_NONZERO, &in, NULL), 0);
	ck_assert_int_eq(clip_paths_area(&in, &a, NULL), 0);
	clip_paths_free(&all);
	clip_paths_free(&in);
	return a;
}

/* Area (nm^2) of region covered by the beads of beads_of(l, ...). */
static double covered(const struct layer_paths *l, unsigned mask, double width,
		      enum clip_end end, const struct clip_expolys *region)
{
	return covered_paths(l, mask, width, end, &region->paths);
}

/* Is (x, y) inside or on the polygon set ps? */
static bool inside(const struct clip_paths *ps, int64_t x, int64_t y)
{
	int parity = 0, where;

	for (size_t i = 0; i < ps->n; i++) {
		ck_assert_int_eq(clip_point_in_polygon(x, y, clip_path_xy(ps, i),
						       clip_path_len(ps, i), &where, NULL),
				 0);
		if (where < 0)
			return true;
		parity ^= where;
	}
	return parity != 0;
}

/* Every point of every path of layer l lies in region grown by d nm. */
static void assert_inside(const struct layer_paths *l, const struct clip_expolys *region, double d)
{
	struct clip_paths g = {0};

	ck_assert_int_eq(clip_offset(&region->paths, d, CLIP_JOIN_ROUND, 0, ARC, &g, NULL), 0);
	for (size_t i = 0; i < l->n; i++)
		for (size_t k = 0; k < l->paths[i].n; k++)
			ck_assert_msg(inside(&g, l->paths[i].pts[k].x, l->paths[i].pts[k].y),
				      "path %zu point %zu (%g, %g) mm outside the region", i, k,
				      l->paths[i].pts[k].x / NM, l->paths[i].pts[k].y / NM);
	clip_paths_free(&g);
}

#define ROLE(r) (1u << (r))
#define SOLID_ROLES                                                                        \
	(ROLE(PATH_BOTTOM_SKIN) | ROLE(PATH_TOP_SKIN) | ROLE(PATH_SOLID_INFILL) |          \
	 ROLE(PATH_GAP_FILL))

/* ---- tests ---- */

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

/* A square column of layers of the given heights, 10 mm wide, walls 1 mm. */
static struct slice_stack *column(const double *heights, size_t n, struct clip_expolys *inner)
{
	struct slice_stack *st = calloc(1, sizeof(*st));
	const int64_t sq[] = {0, 0, 10 * NM, 0, 10 * NM, 10 * NM, 0, 10 * NM};
	struct clip_paths p = {0};
	double z = 0;

	ck_assert_ptr_nonnull(st);
	st->layers = calloc(n, sizeof(*st->layers));
	ck_assert_ptr_nonnull(st->layers);
	st->n = n;
	ck_assert_int_eq(clip_paths_add(&p, sq, 4, NULL), 0);
	for (size_t i = 0; i < n; i++) {
		z += heights[i];
		st->layers[i].z = z;
		st->layers[i].height = heights[i];
		st->layers[i].slice_z = z - heights[i] / 2;
		ck_assert_int_eq(clip_boolean_ex(CLIP_UNION, &p, NULL, CLIP_NONZERO,
						 &st->layers[i].regions, NULL),
				 0);
		ck_assert_int_eq(clip_offset_ex(&p, -1 * NM, CLIP_JOIN_MITER, 2, 0, &inner[i], NULL),
				 0);
	}
	clip_paths_free(&p);
	return st;
}

/* Layers (bottom, top) whose infill has the bottom / top skin role. */
static void skin_layers(const struct infill_settings *is, const double *heights, size_t n,
			size_t *nbottom, size_t *ntop)
{
	struct clip_expolys inner[40];

	memset(inner, 0, sizeof(inner));
	struct slice_stack *st;
	struct layer_stack *ls = layer_stack_new(n, NULL);
	struct st_error err = {0};

	ck_assert(n <= 40 && ls);
	st = column(heights, n, inner);
	ck_assert_msg(infill_generate(is, st, inner, ls, &err) == 0, "infill: %s", err.msg);
	*nbottom = *ntop = 0;
	for (size_t i = 0; i < n; i++) {
		*nbottom += tu_count_role(&ls->layers[i], PATH_BOTTOM_SKIN) > 0;
		*ntop += tu_count_role(&ls->layers[i], PATH_TOP_SKIN) > 0;
		/* A layer is one class: all solid or all sparse here. */
		ck_assert(tu_count_role(&ls->layers[i], PATH_SPARSE_INFILL) == 0 ||
			  tu_count_role(&ls->layers[i], PATH_SPARSE_INFILL) == ls->layers[i].n);
		clip_expolys_free(&inner[i]);
	}
	layer_stack_free(ls);
	slice_stack_free(st);
}

START_TEST(shells_by_thickness)
{
	struct infill_settings is;
	double hs[30];
	size_t nb, nt;

	/* 12 layers of 0.1 mm, then 10 of 0.3 mm. */
	for (size_t i = 0; i < 22; i++)
		hs[i] = i < 12 ? 0.1 : 0.3;
	infill_settings_init(&is, 0.4);
	/* Reference 0.2 mm: 3 layers = 0.6 mm = 6 thin layers at the bottom, 2 thick on top. */
	is.layer_height = 0.2;
	skin_layers(&is, hs, 22, &nb, &nt);
	ck_assert_uint_eq(nb, 6);
	ck_assert_uint_eq(nt, 2);
	/* Default reference: the most common height, 0.1 mm: 0.3 mm shells. */
	is.layer_height = 0;
	skin_layers(&is, hs, 22, &nb, &nt);
	ck_assert_uint_eq(nb, 3);
	ck_assert_uint_eq(nt, 1);
	/* A minimum thickness wins over the count. */
	is.top_solid_min_thickness = 0.9;
	is.bottom_solid_min_thickness = 0.55;
	skin_layers(&is, hs, 22, &nb, &nt);
	ck_assert_uint_eq(nb, 6);
	ck_assert_uint_eq(nt, 3);
	/* No shells asked: no skins, sparse up to the top. */
	is.top_solid_min_thickness = is.bottom_solid_min_thickness = 0;
	is.top_solid_layers = is.bottom_solid_layers = 0;
	skin_layers(&is, hs, 22, &nb, &nt);
	ck_assert_uint_eq(nb, 1); /* layer 0 always rests on the bed */
	ck_assert_uint_eq(nt, 0);
}
END_TEST

START_TEST(small_and_full_density_are_solid)
{
	struct infill_settings is;
	double hs[10];
	struct clip_expolys inner[10];

	memset(inner, 0, sizeof(inner));
	struct st_error err = {0};

	for (size_t i = 0; i < 10; i++)
		hs[i] = 0.2;
	for (int pass = 0; pass < 2; pass++) {
		struct slice_stack *st = column(hs, 10, inner);
		struct layer_stack *ls = layer_stack_new(10, NULL);
		infill_settings_init(&is, 0.4);
		if (pass == 0)
			is.fill_density = 100; /* then: an 8 x 8 mm island < 70 mm^2 */
		is.solid_infill_below_area = pass == 0 ? 0 : 70;
		ck_assert_int_eq(infill_generate(&is, st, inner, ls, &err), 0);
		const struct layer_paths *l = &ls->layers[5];
		ck_assert_uint_eq(tu_count_role(l, PATH_SPARSE_INFILL), 0);
		ck_assert_uint_gt(tu_count_role(l, PATH_SOLID_INFILL), 0);
		double A = region_area(&inner[5]);
		ck_assert(covered(l, SOLID_ROLES, 0, CLIP_END_ROUND, &inner[5]) / A >= 0.99);
		for (size_t i = 0; i < 10; i++)
			clip_expolys_free(&inner[i]);
		layer_stack_free(ls);
		slice_stack_free(st);
	}
}
END_TEST

/*
 * A strip 0.33 mm wide given to infill (the walls take such a strip up
 * inside a 2 mm wall, perimeters.h; a region split by the infill classes
 * can still leave one), narrower than a solid line's spacing: one
 * centre-line bead fills it, where lines across it left dashes with voids
 * between.
 */
START_TEST(narrow_strip_gets_one_bead)
{
	struct mesh *m = fx_box(0, 0, 0, 20, 0.33, 10);
	struct infill_settings is;
	struct st_error err = {0};
	struct run r;
	const double h = 0.2;

	infill_settings_init(&is, 0.4);
	ck_assert_msg(slice_mesh(m, h, h, NULL, &r.st, &err) == 0, "slice_mesh: %s", err.msg);
	r.inner = calloc(r.st->n, sizeof(*r.inner));
	ck_assert_ptr_nonnull(r.inner);
	for (size_t i = 0; i < r.st->n; i++)
		ck_assert_int_eq(clip_boolean_ex(CLIP_UNION, &r.st->layers[i].regions.paths, NULL,
						 CLIP_NONZERO, &r.inner[i], &err),
				 0);
	r.ls = layer_stack_new(r.st->n, &err);
	ck_assert_ptr_nonnull(r.ls);
	ck_assert_msg(infill_generate(&is, r.st, r.inner, r.ls, &err) == 0, "infill: %s", err.msg);
	for (size_t i = 5; i < 45; i++) {
		const struct layer_paths *l = &r.ls->layers[i];
		double A = region_area(&r.inner[i]);
		size_t lines = 0, beads = 0;
		ck_assert_msg(A > 0.3 * 18 * NM * NM && A < 0.4 * 19 * NM * NM,
			      "layer %zu: %g mm2 inside the walls", i, A / NM / NM);
		for (size_t k = 0; k < l->n; k++) {
			lines += l->paths[k].role == PATH_SOLID_INFILL;
			beads += l->paths[k].role == PATH_GAP_FILL;
		}
		ck_assert_msg(lines == 0 && beads >= 1, "layer %zu: %zu solid lines, %zu beads", i,
			      lines, beads);
		double cov = covered(l, SOLID_ROLES, 0, CLIP_END_ROUND, &r.inner[i]) / A;
		ck_assert_msg(cov > 0.99, "layer %zu: %.4f of the strip covered", i, cov);
	}
	run_free(&r);
	mesh_free(m);
}
END_TEST

/* Distance (nm) from bed point (X, Y) at height Z (nm) to the gyroid
 * section at scale k, to first order: |f| / |grad f| in the plane; a
 * negative value where the gradient nearly vanishes (branches meet). */
static double gyroid_distance(double k, double X, double Y, double Z)
{
	double x = k * X, y = k * Y, z = k * Z;
	double f = sin(x) * cos(y) + sin(y) * cos(z) + sin(z) * cos(x);
	double fx = cos(x) * cos(y) - sin(z) * sin(x), fy = -sin(x) * sin(y) + cos(y) * cos(z);
	double g = hypot(fx, fy);
	return g < 0.3 ? -1 : fabs(f) / g / k;
}

/* (X, Y) moved onto the gyroid section at height Z (nm, scale k) by two
 * Newton steps along the gradient in the plane. */
static void gyroid_project(double k, double *X, double *Y, double Z)
{
	for (int it = 0; it < 2; it++) {
		double x = k * *X, y = k * *Y, z = k * Z;
		double f = sin(x) * cos(y) + sin(y) * cos(z) + sin(z) * cos(x);
		double fx = cos(x) * cos(y) - sin(z) * sin(x), fy = -sin(x) * sin(y) + cos(y) * cos(z);
		double g2 = fx * fx + fy * fy;
		*X -= f * fx / g2 / k;
		*Y -= f * fy / g2 / k;
	}
}

/*
 * The gyroid's chords stay within PAT_GYROID_TOLERANCE_NM of the curve,
 * and use most of it: sampled finer than sparse infill needs (10 um), the
 * gyroid was written in 1.7 times PrusaSlicer's moves.  They are as long
 * as the curve (measured along it, 16 points a chord projected onto it):
 * their ends moved across it (simplify_balance), where chords with their
 * ends on the curve are shorter, and at 75 um the sparse infill printed
 * that much less line (docs/benchmarks.md, the region check's voids).
 */
START_TEST(gyroid_chords_within_tolerance)
{
	struct st_error err = {0};
	const double k = 0.2 / (0.45e6 * PAT_GYROID_LENGTH); /* 20 %, 0.45 mm lines */
	struct pat_box box = {0, 0, 20000000, 20000000};
	double worst = 0, length = 0, curve = 0;
	size_t chords = 0;
	for (int layer = 0; layer < 12; layer++) {
		double z = 0.2e6 * (layer * 7 + 1);
		struct clip_paths lines = {0};
		ck_assert_int_eq(pat_gyroid(k, z, &box, &lines, &err), 0);
		for (size_t p = 0; p < lines.n; p++) {
			const int64_t *xy = lines.xy + 2 * lines.start[p];
			size_t n = lines.start[p + 1] - lines.start[p];
			double px = NAN, py = NAN;
			for (size_t i = 0; i + 1 < n; i++, chords++) {
				double dx = (double)(xy[2 * i + 2] - xy[2 * i]);
				double dy = (double)(xy[2 * i + 3] - xy[2 * i + 1]);
				length += hypot(dx, dy);
				for (int j = 0; j <= 16; j++) {
					double X = xy[2 * i] + dx * j / 16.0, Y = xy[2 * i + 1] + dy * j / 16.0;
					if (j % 2 == 0 && j > 0 && j < 16) /* the chord's eighths */
						worst = fmax(worst, gyroid_distance(k, X, Y, z));
					gyroid_project(k, &X, &Y, z);
					if (j && !isnan(px))
						curve += hypot(X - px, Y - py);
					px = X;
					py = Y;
				}
			}
		}
		clip_paths_free(&lines);
	}
	/* first order, and the 48 samples a period: a few per cent over */
	ck_assert_msg(worst <= 1.05 * PAT_GYROID_TOLERANCE_NM, "a chord %.0f nm off the curve",
		      worst);
	ck_assert_msg(worst > 0.5 * PAT_GYROID_TOLERANCE_NM, "chords at most %.0f nm off: finer "
		      "than the tolerance asks", worst);
	/* 0.95 mm at 75 um, 0.66 mm at 50 um; 10 um gave half that, twice
	 * the moves */
	ck_assert_msg(length / (double)chords > 0.8e6, "mean chord %.3f mm",
		      length / (double)chords / 1e6);
	/* 1.0026 across the curve; 0.9925 with their ends on it */
	ck_assert_msg(fabs(length / curve - 1) < 0.004, "chords %.4f times the curve's length",
		      length / curve);
}
END_TEST

START_TEST(bad_settings_refused)
{
	struct infill_settings is;
	struct st_error err = {0};
	enum infill_pattern p = INFILL_GRID;
	double hs[4] = {0.2, 0.2, 0.2, 0.2};
	struct clip_expolys inner[4];

	memset(inner, 0, sizeof(inner));

	infill_settings_init(&is, 0.4);
	ck_assert_int_eq(infill_settings_check(&is, &err), 0);
	ck_assert(fabs(is.infill_extrusion_width - 0.45) < 1e-15);
	is.fill_density = 101;
	ck_assert_int_eq(infill_settings_check(&is, &err), ST_ERR_RANGE);
	ck_assert_ptr_nonnull(strstr(err.msg, "fill_density 101"));
	ck_assert_ptr_nonnull(strstr(err.msg, "0 to 100"));
	is.fill_density = -5;
	ck_assert_int_eq(infill_settings_check(&is, &err), ST_ERR_RANGE);
	ck_assert_ptr_nonnull(strstr(err.msg, "fill_density -5"));
	is.fill_density = NAN;
	ck_assert_int_eq(infill_settings_check(&is, &err), ST_ERR_RANGE);
	infill_settings_init(&is, 0.4);
	is.top_solid_layers = -1;
	ck_assert_int_eq(infill_settings_check(&is, &err), ST_ERR_RANGE);
	ck_assert_ptr_nonnull(strstr(err.msg, "top_solid_layers -1"));
	infill_settings_init(&is, 0.4);
	is.bottom_solid_min_thickness = -0.1;
	ck_assert_int_eq(infill_settings_check(&is, &err), ST_ERR_RANGE);
	infill_settings_init(&is, 0.4);
	is.infill_extrusion_width = 0;
	ck_assert_int_eq(infill_settings_check(&is, &err), ST_ERR_RANGE);
	ck_assert_ptr_nonnull(strstr(err.msg, "infill_extrusion_width"));
	infill_settings_init(&is, 0.4);
	is.fill_pattern = INFILL_PATTERNS;
	ck_assert_int_eq(infill_settings_check(&is, &err), ST_ERR_ARG);
	/* Names: PrusaSlicer's, three printed, the others refused as unsupported. */
	ck_assert_int_eq(infill_pattern_parse("gyroid", &p, &err), 0);
	ck_assert_int_eq(p, INFILL_GYROID);
	ck_assert_int_eq(infill_pattern_parse("rectilinear", &p, &err), 0);
	ck_assert_int_eq(p, INFILL_RECTILINEAR);
	ck_assert_str_eq(infill_pattern_name(INFILL_GRID), "grid");
	ck_assert_int_eq(infill_pattern_parse("stars", &p, &err), 0);
	ck_assert_int_eq(p, INFILL_STARS);
	ck_assert_int_eq(infill_pattern_parse("honeycomb", &p, &err), 0);
	ck_assert_int_eq(p, INFILL_HONEYCOMB);
	ck_assert_int_eq(infill_pattern_parse("line", &p, &err), 0);
	ck_assert_int_eq(p, INFILL_LINE);
	ck_assert_int_eq(infill_pattern_parse("concentric", &p, &err), 0);
	ck_assert_int_eq(p, INFILL_CONCENTRIC);
	ck_assert_int_eq(infill_pattern_parse("3dhoneycomb", &p, &err), ST_ERR_UNSUPPORTED);
	ck_assert_ptr_nonnull(strstr(err.msg, "\"3dhoneycomb\" is not supported"));
	ck_assert_ptr_nonnull(strstr(err.msg, "stars, cubic, line, concentric or honeycomb"));
	p = INFILL_RECTILINEAR;
	ck_assert_int_eq(infill_pattern_parse("spaghetti", &p, &err), ST_ERR_ARG);
	ck_assert_ptr_nonnull(strstr(err.msg, "\"spaghetti\" is unknown"));
	ck_assert_int_eq(p, INFILL_RECTILINEAR); /* untouched on error */
	/* infill_generate refuses too, and adds nothing. */
	struct slice_stack *st = column(hs, 4, inner);
	struct layer_stack *ls = layer_stack_new(4, NULL);
	infill_settings_init(&is, 0.4);
	is.fill_density = 150;
	ck_assert_int_eq(infill_generate(&is, st, inner, ls, &err), ST_ERR_RANGE);
	for (size_t i = 0; i < 4; i++)
		ck_assert_uint_eq(ls->layers[i].n, 0);
	infill_settings_init(&is, 0.4);
	st->layers[2].height = 0.5;
	ck_assert_int_eq(infill_generate(&is, st, inner, ls, &err), ST_ERR_RANGE);
	ck_assert_ptr_nonnull(strstr(err.msg, "layer 2"));
	layer_stack_free(ls);
	ls = layer_stack_new(3, NULL);
	st->layers[2].height = 0.2;
	ck_assert_int_eq(infill_generate(&is, st, inner, ls, &err), ST_ERR_ARG);
	for (size_t i = 0; i < 4; i++)
		clip_expolys_free(&inner[i]);
	layer_stack_free(ls);
	slice_stack_free(st);
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
	tcase_add_test(tc, shells_by_thickness);
	tcase_add_test(tc, small_and_full_density_are_solid);
	tcase_add_test(tc, narrow_strip_gets_one_bead);
	tcase_add_test(tc, bad_settings_refused);
	tcase_add_test(tc, gyroid_chords_within_tolerance);
	suite_add_tcase(s, tc);
	infill_shell_tcases(s);
	return s;
}
