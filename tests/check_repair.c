/*
 * check_repair.c - seed 000's repair end to end (repair/repair.h).
 *
 * Every input is generated in code (tests/fixtures.c) so what the answer
 * must be follows from how the input is built.  Every test judges the
 * result the way a printer would get it: each part (a manifold-connected
 * shell with its cavities)
 * of the output is written as a binary STL (ASCII with 17 digits for
 * REPAIR_FLOAT64), read back, and the project's exact checker
 * (mesh_analyze) must call the file printable (Definition 3.11 holds per
 * component; seed 000 §4.2.1 saves each component to its own file).  On
 * top of that each test checks the geometric claim that makes the repair
 * "as exact as possible": what was already solid is not moved, unions have
 * the exact volume, sheets and wires become solids of thickness epsilon.
 */
#include <check.h>
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fixtures.h"
#include "mesh.h"
#include "meshio.h"
#include "repair.h"
#include "suites.h"
#include "testutil.h"

#define EPS 0.4 /* mm, the default nozzle-sized thickness */

/* A repair result and what it reported. */
struct fixed {
	struct mesh *out;
	uint32_t *comp;
	struct repair_report rep;
};

/* Run repair_mesh with opt; it must succeed and report consistently. */
static struct fixed repair_with(const struct mesh *in, const struct repair_options *opt)
{
	struct fixed f;
	struct st_error err = {0};
	int rc;

	memset(&f, 0, sizeof(f));
	rc = repair_mesh(in, opt, &f.out, &f.comp, &f.rep, &err);
	ck_assert_msg(rc == 0, "repair_mesh returned %d: %s", rc, err.msg);
	ck_assert_ptr_nonnull(f.out);
	ck_assert_uint_eq(f.rep.input_triangles, in->ntris);
	ck_assert_uint_eq(f.rep.output_triangles, f.out->ntris);
	ck_assert_uint_eq(f.rep.output_vertices, f.out->nverts);
	if (f.out->ntris > 0) {
		/* Component ids are exactly 0..components-1, each one used. */
		size_t used = 0;
		unsigned char *seen;

		ck_assert_ptr_nonnull(f.comp);
		ck_assert_uint_gt(f.rep.components, 0);
		seen = calloc(f.rep.components, 1);
		ck_assert_ptr_nonnull(seen);
		for (size_t t = 0; t < f.out->ntris; t++) {
			ck_assert_msg(f.comp[t] < f.rep.components,
				      "triangle %zu has component %u of %zu", t, f.comp[t],
				      f.rep.components);
			if (!seen[f.comp[t]]) {
				seen[f.comp[t]] = 1;
				used++;
			}
		}
		ck_assert_msg(used == f.rep.components, "%zu components reported, %zu used",
			      f.rep.components, used);
		free(seen);
	}
	return f;
}

/* Repair with the defaults and the given epsilon. */
static struct fixed repair_eps(const struct mesh *in, double eps)
{
	struct repair_options opt;

	repair_options_init(&opt);
	opt.epsilon = eps;
	return repair_with(in, &opt);
}

static void fixed_free(struct fixed *f)
{
	mesh_free(f->out);
	free(f->comp);
	f->out = NULL;
	f->comp = NULL;
}

static struct mesh_report analyze(const struct mesh *m)
{
	struct mesh_report r;
	struct st_error err = {0};

	ck_assert_msg(mesh_analyze(m, 2, &r, &err) == 0, "mesh_analyze: %s", err.msg);
	return r;
}

/* The reason codes present in r, for failure messages. */
static const char *reason_list(const struct mesh_report *r, char *buf, size_t cap)
{
	size_t n = 0;

	buf[0] = '\0';
	for (int i = 0; i < MESH_REASON_COUNT && n + 1 < cap; i++)
		if (r->reasons[i])
			n += (size_t)snprintf(buf + n, cap - n, "%s%s", n ? "," : "",
					      mesh_reason_code((enum mesh_reason)i));
	return buf;
}

/* ---- comparing triangle sets ---- */

/* A triangle as 9 coordinates, rotated so its smallest corner comes first. */
struct ctri {
	double c[9];
};

static int cmp3(const double *a, const double *b)
{
	for (int k = 0; k < 3; k++) {
		if (a[k] < b[k])
			return -1;
		if (a[k] > b[k])
			return 1;
	}
	return 0;
}

static int ctri_cmp(const void *pa, const void *pb)
{
	const struct ctri *a = pa, *b = pb;

	for (int k = 0; k < 9; k++) {
		if (a->c[k] < b->c[k])
			return -1;
		if (a->c[k] > b->c[k])
			return 1;
	}
	return 0;
}

/* Canonical, sorted triangles of m: equal arrays = same oriented triangles. */
static struct ctri *canon(const struct mesh *m)
{
	struct ctri *c = malloc((m->ntris ? m->ntris : 1) * sizeof(*c));

	ck_assert_ptr_nonnull(c);
	for (size_t t = 0; t < m->ntris; t++) {
		const double *p[3];
		int k0 = 0;

		for (int k = 0; k < 3; k++)
			p[k] = m->verts[m->tris[t][k]];
		for (int k = 1; k < 3; k++)
			if (cmp3(p[k], p[k0]) < 0)
				k0 = k;
		/* Rotation keeps the orientation. */
		for (int i = 0; i < 3; i++)
			memcpy(&c[t].c[3 * i], p[(k0 + i) % 3], 3 * sizeof(double));
	}
	qsort(c, m->ntris, sizeof(*c), ctri_cmp);
	return c;
}

/*
 * got and want hold the same oriented triangles with bit-identical
 * coordinates, in any order and with any vertex numbering: Hausdorff 0.
 */
static void assert_same_triangles(const struct mesh *got, const struct mesh *want,
				  const char *what)
{
	struct ctri *a, *b;

	ck_assert_msg(got->ntris == want->ntris, "%s: %zu triangles, expected %zu", what,
		      got->ntris, want->ntris);
	a = canon(got);
	b = canon(want);
	for (size_t t = 0; t < got->ntris; t++) {
		const double *x = a[t].c, *y = b[t].c;
		ck_assert_msg(ctri_cmp(&a[t], &b[t]) == 0,
			      "%s: sorted triangle %zu is (%.9g,%.9g,%.9g)(%.9g,%.9g,%.9g)"
			      "(%.9g,%.9g,%.9g), expected (%.9g,%.9g,%.9g)(%.9g,%.9g,%.9g)"
			      "(%.9g,%.9g,%.9g)",
			      what, t, x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7], x[8], y[0],
			      y[1], y[2], y[3], y[4], y[5], y[6], y[7], y[8]);
	}
	free(a);
	free(b);
}

/* Does m contain triangle (p0,p1,p2) with this orientation? */
static int has_triangle(const struct mesh *m, const double p0[3], const double p1[3],
			const double p2[3])
{
	const double *want[3] = {p0, p1, p2};

	for (size_t t = 0; t < m->ntris; t++)
		for (int r = 0; r < 3; r++) {
			int k = 0;
			while (k < 3 && cmp3(m->verts[m->tris[t][(r + k) % 3]], want[k]) == 0)
				k++;
			if (k == 3)
				return 1;
		}
	return 0;
}

/* ---- distances ---- */

static double dot3(const double a[3], const double b[3])
{
	return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* Distance from p to segment a-b. */
static double seg_dist(const double p[3], const double a[3], const double b[3])
{
	double ab[3], ap[3], t, len2, d[3];

	for (int k = 0; k < 3; k++) {
		ab[k] = b[k] - a[k];
		ap[k] = p[k] - a[k];
	}
	len2 = dot3(ab, ab);
	t = len2 > 0 ? dot3(ap, ab) / len2 : 0;
	t = t < 0 ? 0 : t > 1 ? 1 : t;
	for (int k = 0; k < 3; k++)
		d[k] = ap[k] - t * ab[k];
	return sqrt(dot3(d, d));
}

/* Distance from p to triangle a-b-c; degenerate triangles count as their edges. */
static double tri_dist(const double p[3], const double a[3], const double b[3],
		       const double c[3])
{
	double ab[3], ac[3], ap[3], n[3], nn, s, t, u, q[3];

	for (int k = 0; k < 3; k++) {
		ab[k] = b[k] - a[k];
		ac[k] = c[k] - a[k];
		ap[k] = p[k] - a[k];
	}
	n[0] = ab[1] * ac[2] - ab[2] * ac[1];
	n[1] = ab[2] * ac[0] - ab[0] * ac[2];
	n[2] = ab[0] * ac[1] - ab[1] * ac[0];
	nn = dot3(n, n);
	if (nn > 1e-24 * dot3(ab, ab) * dot3(ac, ac)) {
		/* Barycentric coordinates of p's projection on the plane. */
		double cx[3];
		cx[0] = ap[1] * ac[2] - ap[2] * ac[1];
		cx[1] = ap[2] * ac[0] - ap[0] * ac[2];
		cx[2] = ap[0] * ac[1] - ap[1] * ac[0];
		s = dot3(cx, n) / nn; /* weight of b */
		cx[0] = ab[1] * ap[2] - ab[2] * ap[1];
		cx[1] = ab[2] * ap[0] - ab[0] * ap[2];
		cx[2] = ab[0] * ap[1] - ab[1] * ap[0];
		t = dot3(cx, n) / nn; /* weight of c */
		u = 1 - s - t;
		if (s >= 0 && t >= 0 && u >= 0) {
			for (int k = 0; k < 3; k++)
				q[k] = ap[k] - s * ab[k] - t * ac[k];
			return sqrt(dot3(q, q));
		}
	}
	s = seg_dist(p, a, b);
	t = seg_dist(p, b, c);
	u = seg_dist(p, c, a);
	return fmin(s, fmin(t, u));
}

/*
 * The largest distance from a vertex of out to the nearest triangle of in
 * (degenerate ones included, as segments): how far the repair strayed from
 * the input.  Sheets and wires thickened to total thickness epsilon stay
 * within epsilon/2; exact solid parts within rounding.
 */
static double max_vertex_distance(const struct mesh *out, const struct mesh *in)
{
	double worst = 0;

	for (size_t v = 0; v < out->nverts; v++) {
		double best = INFINITY;
		for (size_t t = 0; t < in->ntris && best > worst; t++)
			best = fmin(best, tri_dist(out->verts[v], in->verts[in->tris[t][0]],
						   in->verts[in->tris[t][1]],
						   in->verts[in->tris[t][2]]));
		worst = fmax(worst, best);
	}
	return worst;
}

/* Every output vertex within epsilon/2 (+1e-3) of the input surface. */
static void assert_near_input(const struct fixed *f, const struct mesh *in)
{
	double d = max_vertex_distance(f->out, in);

	ck_assert_msg(d <= EPS / 2 + 1e-3,
		      "an output vertex is %.6g mm from the input, more than epsilon/2 = %g", d,
		      EPS / 2);
}

/* The triangles of m whose component is c, as a mesh of their own. */
static struct mesh *part_mesh(const struct mesh *m, const uint32_t *comp, uint32_t c)
{
	struct mesh_builder *b = mesh_builder_new(0);
	struct mesh *part;

	ck_assert_ptr_nonnull(b);
	for (size_t t = 0; t < m->ntris; t++) {
		uint32_t v[3];
		if (comp[t] != c)
			continue;
		for (int k = 0; k < 3; k++)
			ck_assert_int_eq(mesh_builder_vertex(b, m->verts[m->tris[t][k]], &v[k], NULL),
					 0);
		ck_assert_int_eq(mesh_builder_triangle(b, v[0], v[1], v[2], NULL), 0);
	}
	part = mesh_builder_finish(b);
	ck_assert_ptr_nonnull(part);
	return part;
}

/* Write m to the scratch file name in fmt and read it back. */

/*
 * judge - the checks every test makes on a result: the repair calls it
 * printable; with float32 precision every coordinate is a float; the whole
 * output has no self-intersections and no open edges and splits into
 * exactly rep.components manifold-connected parts; each part, written as
 * the file a printer would get and read back, is unchanged by the trip,
 * printable by mesh_analyze and encloses positive volume, and so is the
 * whole output written as one file.  Returns the
 * analysis of the whole output as read back from a file (volume, bbox).
 */
static struct mesh_report judge(const struct fixed *f, enum repair_precision prec,
				const char *name)
{
	enum meshio_format fmt = prec == REPAIR_FLOAT32 ? MESHIO_STL_BINARY : MESHIO_STL_ASCII;
	char why[256], file[128];
	struct mesh_report whole;
	struct mesh *back;

	ck_assert_msg(f->rep.printable, "%s: repair says not printable: %s", name, f->rep.why);
	ck_assert_msg(f->out->ntris > 0, "%s: empty output", name);
	if (prec == REPAIR_FLOAT32)
		for (size_t v = 0; v < f->out->nverts; v++)
			for (int k = 0; k < 3; k++)
				ck_assert_msg((double)(float)f->out->verts[v][k] == f->out->verts[v][k],
					      "%s: vertex %zu coordinate %d = %.17g is not a float",
					      name, v, k, f->out->verts[v][k]);

	whole = analyze(f->out);
	ck_assert_msg(whole.self_intersections == 0, "%s: output has %llu intersecting pairs",
		      name, (unsigned long long)whole.self_intersections);
	ck_assert_msg(whole.odd_edges == 0, "%s: output has %zu odd edges (%zu boundary)", name,
		      whole.odd_edges, whole.boundary_edges);
	ck_assert_msg(whole.parts == f->rep.components,
		      "%s: mesh_analyze finds %zu parts, repair reports %zu", name, whole.parts,
		      f->rep.components);
	ck_assert_msg(whole.cavities == f->rep.cavities,
		      "%s: mesh_analyze finds %zu cavities, repair reports %zu", name,
		      whole.cavities, f->rep.cavities);

	for (uint32_t c = 0; c < f->rep.components; c++) {
		struct mesh *part = part_mesh(f->out, f->comp, c);
		struct mesh_report r;

		snprintf(file, sizeof(file), "%s-part%u.stl", name, c);
		back = tu_round_trip(part, file, fmt);
		assert_same_triangles(back, part, file);
		r = analyze(back);
		ck_assert_msg(r.printable, "%s: component %u of %zu (%zu triangles) not printable: %s",
			      name, c, f->rep.components, part->ntris, reason_list(&r, why, sizeof(why)));
		ck_assert_msg(r.volume > 0, "%s: component %u has volume %g (inside out?)", name, c,
			      r.volume);
		mesh_free(back);
		mesh_free(part);
	}

	snprintf(file, sizeof(file), "%s-all.stl", name);
	back = tu_round_trip(f->out, file, fmt);
	whole = analyze(back);
	/* Several parts and cavities in one file print too (docs/check.md). */
	ck_assert_msg(whole.printable, "%s: written output not printable: %s", name,
		      reason_list(&whole, why, sizeof(why)));
	mesh_free(back);
	return whole;
}

/* Nothing geometric happened: no cuts, no deletions, no sheets, no wires. */
static void assert_untouched_report(const struct repair_report *rep)
{
	ck_assert_uint_eq(rep->intersecting_pairs, 0);
	ck_assert_uint_eq(rep->triangles_split, 0);
	ck_assert_uint_eq(rep->interior_deleted, 0);
	ck_assert_uint_eq(rep->enclosed_deleted, 0);
	ck_assert_uint_eq(rep->sheet_triangles, 0);
	ck_assert_uint_eq(rep->wires, 0);
	ck_assert(!rep->second_pass);
	ck_assert_double_eq(rep->solid_deviation, 0.0);
	ck_assert_uint_eq(rep->components, 1);
}

/* ---- 1. printable inputs come back unchanged ---- */

/* Solid inputs whose coordinates are all floats (what binary STL holds). */
static struct mesh *float_solid(int i)
{
	struct mesh *m, *f;

	switch (i) {
	case 0:
		return fx_box(0, 0, 0, 10, 10, 10);
	case 1: /* float-representable but not integers */
		return fx_box(-1.5, 0.25, 3, 7.75, 9.5, 12.125);
	case 2:
		m = fx_sphere(0, 0, 0, 10, 8, 12);
		break;
	default:
		m = fx_torus(10, 3, 24, 12);
		break;
	}
	f = fx_to_float(m);
	mesh_free(m);
	return f;
}

/*
 * Proves that a mesh that is already printable (box, sphere, torus) is
 * returned with exactly the same triangles, same orientation, same
 * coordinates, both in memory and in the written binary STL: Hausdorff
 * distance 0, and the report shows nothing was cut, deleted or thickened.
 */
START_TEST(solid_float_input_unchanged)
{
	struct mesh *in = float_solid(_i);
	struct fixed f = repair_eps(in, EPS);
	struct mesh *back;

	assert_same_triangles(f.out, in, "output");
	judge(&f, REPAIR_FLOAT32, "unchanged");
	back = tu_round_trip(f.out, "unchanged-file.stl", MESHIO_STL_BINARY);
	assert_same_triangles(back, in, "written file");
	assert_untouched_report(&f.rep);
	ck_assert_double_eq(f.rep.rounding_deviation, 0.0);
	mesh_free(back);
	fixed_free(&f);
	mesh_free(in);
}
END_TEST

/*
 * Proves the same for double coordinates when the output precision is
 * float64 (ASCII STL with 17 digits): not even rounding moves a vertex.
 */
START_TEST(solid_double_input_unchanged_float64)
{
	struct mesh *in = _i == 0 ? fx_sphere(0, 0, 0, 10, 8, 12) : fx_torus(10, 3, 24, 12);
	struct repair_options opt;
	struct fixed f;

	repair_options_init(&opt);
	opt.precision = REPAIR_FLOAT64;
	f = repair_with(in, &opt);
	assert_same_triangles(f.out, in, "output");
	judge(&f, REPAIR_FLOAT64, "unchanged64");
	assert_untouched_report(&f.rep);
	ck_assert_double_eq(f.rep.rounding_deviation, 0.0);
	fixed_free(&f);
	mesh_free(in);
}
END_TEST

/*
 * Proves that with float32 output a printable double-coordinate mesh is
 * only rounded: every vertex goes to its nearest float (the smallest move
 * there is; rounding a sphere or torus this coarse creates no
 * intersection, so no further rounds are needed), and the reported
 * rounding deviation is that move, well under a micrometre.
 */
START_TEST(solid_double_input_rounded_to_nearest_float)
{
	struct mesh *in = _i == 0 ? fx_sphere(0, 0, 0, 10, 8, 12) : fx_torus(10, 3, 24, 12);
	struct mesh *want = fx_to_float(in);
	struct fixed f = repair_eps(in, EPS);

	assert_same_triangles(f.out, want, "output vs input rounded to float");
	judge(&f, REPAIR_FLOAT32, "rounded");
	assert_untouched_report(&f.rep);
	ck_assert_msg(f.rep.rounding_deviation > 0 && f.rep.rounding_deviation < 1e-6,
		      "rounding_deviation %g", f.rep.rounding_deviation);
	fixed_free(&f);
	mesh_free(want);
	mesh_free(in);
}
END_TEST

/* ---- 2. overlapping cubes: the exact union ---- */

/* p is within tol of the closed box lo..hi. */
static int in_box(const double p[3], const double lo[3], const double hi[3], double tol)
{
	for (int k = 0; k < 3; k++)
		if (p[k] < lo[k] - tol || p[k] > hi[k] + tol)
			return 0;
	return 1;
}

/*
 * p lies on the boundary of the union of the closed boxes: it is in the
 * union, and a step of 1e-3 along one of the 26 lattice directions leaves
 * every box.  For axis-aligned boxes the lattice directions find the
 * outside wherever it touches p.
 */
static int on_union_boundary(const double p[3], const double (*lo)[3], const double (*hi)[3],
			     int n)
{
	int inside = 0;

	for (int b = 0; b < n; b++)
		inside |= in_box(p, lo[b], hi[b], 1e-9);
	if (!inside)
		return 0;
	for (int d = 0; d < 27; d++) {
		const double q[3] = {p[0] + 1e-3 * (d % 3 - 1), p[1] + 1e-3 * (d / 3 % 3 - 1),
				     p[2] + 1e-3 * (d / 9 - 1)};
		int out = 1;
		if (d == 13)
			continue;
		for (int b = 0; b < n; b++)
			if (in_box(q, lo[b], hi[b], 0))
				out = 0;
		if (out)
			return 1;
	}
	return 0;
}

/*
 * Proves the exact union of [0,2]^3 and [1,3]^3: one component of volume
 * 8 + 8 - 1 = 15 exactly, made only of triangles that lie in a face plane
 * of the input (x, y or z in {0,1,2,3} at all three corners) and on the
 * union's boundary (the parts of each cube's faces inside the other cube
 * are gone).
 */
START_TEST(overlapping_cubes_union)
{
	struct mesh *a = fx_box(0, 0, 0, 2, 2, 2), *b = fx_box(1, 1, 1, 3, 3, 3);
	struct mesh *in = fx_concat(a, b);
	const double lo[2][3] = {{0, 0, 0}, {1, 1, 1}}, hi[2][3] = {{2, 2, 2}, {3, 3, 3}};
	struct fixed f = repair_eps(in, EPS);
	struct mesh_report r = judge(&f, REPAIR_FLOAT32, "union");

	ck_assert_uint_gt(f.rep.intersecting_pairs, 0);
	ck_assert_uint_gt(f.rep.triangles_split, 0);
	ck_assert_uint_eq(f.rep.components, 1);
	ck_assert_uint_eq(f.rep.sheet_triangles, 0);
	ck_assert(!f.rep.second_pass);
	ck_assert_double_eq(f.rep.solid_deviation, 0.0);
	ck_assert_uint_eq(r.components, 1);
	ck_assert_msg(fabs(r.volume - 15.0) <= 15.0 * 1e-9, "union volume %.17g, expected 15",
		      r.volume);
	for (size_t t = 0; t < f.out->ntris; t++) {
		const double *p[3] = {f.out->verts[f.out->tris[t][0]], f.out->verts[f.out->tris[t][1]],
				      f.out->verts[f.out->tris[t][2]]};
		double g[3];
		int planar = 0;

		for (int k = 0; k < 3; k++) {
			double c = p[0][k];
			g[k] = (p[0][k] + p[1][k] + p[2][k]) / 3;
			if (p[1][k] == c && p[2][k] == c && (c == 0 || c == 1 || c == 2 || c == 3))
				planar = 1;
		}
		ck_assert_msg(planar, "triangle %zu (%g,%g,%g)(%g,%g,%g)(%g,%g,%g) is in no face plane",
			      t, p[0][0], p[0][1], p[0][2], p[1][0], p[1][1], p[1][2], p[2][0],
			      p[2][1], p[2][2]);
		for (int k = 0; k < 3; k++)
			ck_assert_msg(on_union_boundary(p[k], lo, hi, 2),
				      "vertex (%g,%g,%g) of triangle %zu is not on the union's surface",
				      p[k][0], p[k][1], p[k][2], t);
		ck_assert_msg(on_union_boundary(g, lo, hi, 2),
			      "triangle %zu (centroid %g,%g,%g) is not on the union's surface", t,
			      g[0], g[1], g[2]);
	}
	fixed_free(&f);
	mesh_free(in);
	mesh_free(a);
	mesh_free(b);
}
END_TEST

/*
 * Proves the result does not depend on the thread count: one thread and
 * all cores give the same triangles.
 */
START_TEST(threads_do_not_change_result)
{
	struct mesh *a = fx_box(0, 0, 0, 2, 2, 2), *b = fx_box(1, 1, 1, 3, 3, 3);
	struct mesh *in = fx_concat(a, b);
	struct repair_options opt;
	struct fixed f1, f0;

	repair_options_init(&opt);
	opt.threads = 1;
	f1 = repair_with(in, &opt);
	opt.threads = 0;
	f0 = repair_with(in, &opt);
	assert_same_triangles(f0.out, f1.out, "threads 0 vs 1");
	ck_assert_uint_eq(f0.rep.intersecting_pairs, f1.rep.intersecting_pairs);
	fixed_free(&f1);
	fixed_free(&f0);
	mesh_free(in);
	mesh_free(a);
	mesh_free(b);
}
END_TEST

/* ---- 3. a shell inside another is deleted ---- */

/*
 * Proves that a closed component enclosed by another (box [3,7]^3 inside
 * [0,10]^3, both outward) is deleted and the outer box is returned exactly.
 */
START_TEST(nested_shell_deleted)
{
	struct mesh *outer = fx_box(0, 0, 0, 10, 10, 10), *inner = fx_box(3, 3, 3, 7, 7, 7);
	struct mesh *in = fx_concat(outer, inner);
	struct fixed f = repair_eps(in, EPS);
	struct mesh_report r = judge(&f, REPAIR_FLOAT32, "nested");

	assert_same_triangles(f.out, outer, "output vs outer box");
	ck_assert_uint_eq(f.rep.enclosed_deleted, 12);
	ck_assert_uint_eq(f.rep.intersecting_pairs, 0);
	ck_assert_uint_eq(f.rep.sheet_triangles, 0);
	ck_assert_uint_eq(f.rep.components, 1);
	ck_assert_double_eq_tol(r.volume, 1000.0, 1e-9);
	fixed_free(&f);
	mesh_free(in);
	mesh_free(outer);
	mesh_free(inner);
}
END_TEST

/* m with every triangle reversed (a closed shell facing inwards). */
static struct mesh *reversed(const struct mesh *m)
{
	struct mesh *r = fx_concat(m, m);

	r->ntris = m->ntris; /* the copy welded onto the same vertices: keep one */
	for (size_t t = 0; t < r->ntris; t++)
		fx_flip(r, t);
	return r;
}

/*
 * Proves that an enclosed shell the input faces inwards is a designed
 * cavity and is kept (docs/repair.md, "Cavities"): the output is the
 * input, triangle for triangle and orientation for orientation, one part
 * with one cavity, volume 1000 - 64; nothing is counted as enclosed.
 */
START_TEST(nested_inward_shell_is_a_cavity)
{
	struct mesh *outer = fx_box(0, 0, 0, 10, 10, 10), *box = fx_box(3, 3, 3, 7, 7, 7);
	struct mesh *inner = reversed(box), *in = fx_concat(outer, inner);
	struct fixed f = repair_eps(in, EPS);
	struct mesh_report r = judge(&f, REPAIR_FLOAT32, "cavity");

	assert_same_triangles(f.out, in, "output vs input");
	ck_assert_uint_eq(f.rep.enclosed_deleted, 0);
	ck_assert_uint_eq(f.rep.cavities, 1);
	ck_assert_uint_eq(f.rep.components, 1);
	ck_assert_uint_eq(r.cavities, 1);
	ck_assert_double_eq_tol(r.volume, 1000.0 - 64.0, 1e-9);
	fixed_free(&f);
	mesh_free(in);
	mesh_free(outer);
	mesh_free(box);
	mesh_free(inner);
}
END_TEST

/*
 * Proves that a part inside a cavity is in empty space and is kept as a
 * part of its own (a ball in a hollow box): outer box, inward cavity
 * [2,8]^3, outward cube [4,6]^3 in it: two parts, one cavity, volume
 * 1000 - 216 + 8.
 */
START_TEST(part_inside_a_cavity_kept)
{
	struct mesh *outer = fx_box(0, 0, 0, 10, 10, 10), *box = fx_box(2, 2, 2, 8, 8, 8);
	struct mesh *cavity = reversed(box), *core = fx_box(4, 4, 4, 6, 6, 6);
	struct mesh *shell = fx_concat(outer, cavity), *in = fx_concat(shell, core);
	struct fixed f = repair_eps(in, EPS);
	struct mesh_report r = judge(&f, REPAIR_FLOAT32, "ballinbox");

	assert_same_triangles(f.out, in, "output vs input");
	ck_assert_uint_eq(f.rep.components, 2);
	ck_assert_uint_eq(f.rep.cavities, 1);
	ck_assert_double_eq_tol(r.volume, 1000.0 - 216.0 + 8.0, 1e-9);
	fixed_free(&f);
	mesh_free(in);
	mesh_free(shell);
	mesh_free(outer);
	mesh_free(box);
	mesh_free(cavity);
	mesh_free(core);
}
END_TEST

/*
 * Proves that touching cubes come out as one printable file: two 10 mm
 * cubes sharing a face (i = 0: fused into one solid), an edge (i = 1) or
 * a vertex (i = 2) (two parts); 2000 mm^3 either way, the file printable
 * as a whole and part by part.
 */
START_TEST(touching_cubes_printable)
{
	const int i = _i;
	const double off[3][3] = {{10, 0, 0}, {10, 10, 0}, {10, 10, 10}};
	struct mesh *a = fx_box(0, 0, 0, 10, 10, 10);
	struct mesh *b = fx_box(off[i][0], off[i][1], off[i][2], off[i][0] + 10, off[i][1] + 10,
				off[i][2] + 10);
	struct mesh *in = fx_concat(a, b);
	struct fixed f = repair_eps(in, EPS);
	struct mesh_report r = judge(&f, REPAIR_FLOAT32, "touching");

	ck_assert_uint_eq(f.rep.components, i == 0 ? 1 : 2);
	ck_assert_double_eq_tol(r.volume, 2000.0, 1e-9);
	fixed_free(&f);
	mesh_free(in);
	mesh_free(a);
	mesh_free(b);
}
END_TEST

/*
 * Proves that a part smaller than epsilon in every direction is dropped
 * and counted: a 0.1 mm cube beside a 10 mm cube, epsilon 0.4, leaves
 * the 10 mm cube alone (its 12 triangles unchanged); a plate 0.1 mm thin
 * but 10 mm wide is kept.
 */
START_TEST(tiny_part_dropped)
{
	struct mesh *big = fx_box(0, 0, 0, 10, 10, 10), *tiny = fx_box(20, 0, 0, 20.1, 0.1, 0.1);
	struct mesh *plate = fx_box(0, 20, 0, 10, 30, 0.1);
	struct mesh *in = fx_concat(big, tiny), *both = fx_concat(big, plate);
	struct fixed f = repair_eps(in, EPS), g;

	judge(&f, REPAIR_FLOAT32, "tiny");
	assert_same_triangles(f.out, big, "output vs the big cube");
	ck_assert_uint_eq(f.rep.parts_dropped, 1);
	ck_assert_uint_eq(f.rep.dropped_triangles, 12);
	ck_assert_uint_eq(f.rep.components, 1);
	g = repair_eps(both, EPS);
	judge(&g, REPAIR_FLOAT32, "plate");
	ck_assert_uint_eq(g.rep.parts_dropped, 0);
	ck_assert_uint_eq(g.rep.components, 2);
	fixed_free(&f);
	fixed_free(&g);
	mesh_free(in);
	mesh_free(both);
	mesh_free(big);
	mesh_free(tiny);
	mesh_free(plate);
}
END_TEST

/* ---- 4.-6. sheets are thickened ---- */

/* The bounding box of m lies within lo..hi (per axis) with slack tol. */
static void assert_bbox_within(const struct mesh *m, const double lo[3], const double hi[3],
			       double tol)
{
	double mn[3], mx[3];

	mesh_bbox(m, mn, mx);
	for (int k = 0; k < 3; k++)
		ck_assert_msg(mn[k] >= lo[k] - tol && mx[k] <= hi[k] + tol,
			      "axis %d: bbox [%.9g, %.9g] not within [%.9g, %.9g]", k, mn[k], mx[k],
			      lo[k], hi[k]);
}

/*
 * Proves that with --keep-holes an open cube (one triangle missing; by
 * default the hole is filled, tests/check_heal.c) is entirely M_sheet (all
 * 11 triangles double-sided) and becomes a closed thin-walled box: the
 * second pass runs and finds no sheet, the result stays within epsilon of
 * the cube, and its volume is that of a wall of thickness epsilon over the
 * cube's surface (A = 600 mm^2, loose bounds 0.3..1.5 * A * epsilon).
 */
START_TEST(open_cube_thickened)
{
	struct mesh *in = fx_box(0, 0, 0, 10, 10, 10);
	struct repair_options opt;
	const double lo[3] = {-EPS, -EPS, -EPS}, hi[3] = {10 + EPS, 10 + EPS, 10 + EPS};
	struct fixed f;
	struct mesh_report r;

	fx_drop(in, 5);
	repair_options_init(&opt);
	opt.epsilon = EPS;
	opt.keep_holes = true; /* the seed's pipeline: no hole filling */
	f = repair_with(in, &opt);
	r = judge(&f, REPAIR_FLOAT32, "opencube");
	ck_assert_uint_eq(f.rep.sheet_triangles, 11);
	ck_assert(f.rep.second_pass);
	ck_assert_uint_eq(f.rep.second_sheet_triangles, 0);
	ck_assert_uint_gt(f.rep.thickened_triangles, 0);
	assert_near_input(&f, in);
	ck_assert_msg(f.rep.sheet_deviation <= EPS / 2 + 1e-3, "reported sheet_deviation %g",
		      f.rep.sheet_deviation);
	ck_assert_uint_eq(f.rep.components, 1);
	assert_bbox_within(f.out, lo, hi, 1e-6);
	ck_assert_msg(r.volume >= 0.3 * 600 * EPS && r.volume <= 1.5 * 600 * EPS,
		      "thin-walled box volume %g, expected %g..%g", r.volume, 0.3 * 600 * EPS,
		      1.5 * 600 * EPS);
	fixed_free(&f);
	mesh_free(in);
}
END_TEST

/*
 * The output is a slab of thickness epsilon over the square [x0,x1]^2 in
 * z = 0: z extent epsilon (0.9..1.1 epsilon), it covers the square and
 * grows at most epsilon/2 past each edge, volume about area * epsilon.
 */
static void assert_slab(const struct fixed *f, const struct mesh_report *r, double x0, double x1)
{
	double mn[3], mx[3], side = x1 - x0;

	mesh_bbox(f->out, mn, mx);
	ck_assert_msg(mx[2] - mn[2] >= 0.9 * EPS && mx[2] - mn[2] <= 1.1 * EPS + 1e-3,
		      "slab z extent %.9g (z %.9g..%.9g), expected epsilon = %g", mx[2] - mn[2],
		      mn[2], mx[2], EPS);
	ck_assert_msg(mn[2] <= 0 && mx[2] >= 0, "slab z %.9g..%.9g does not contain the sheet",
		      mn[2], mx[2]);
	for (int k = 0; k < 2; k++) {
		ck_assert_msg(mn[k] <= x0 && mx[k] >= x1,
			      "axis %d: slab %.9g..%.9g does not cover the sheet %g..%g", k, mn[k],
			      mx[k], x0, x1);
		ck_assert_msg(mx[k] - mn[k] <= side + EPS + 1e-3, "axis %d: slab extent %.9g > %g",
			      k, mx[k] - mn[k], side + EPS);
	}
	ck_assert_msg(r->volume >= 0.9 * side * side * EPS &&
			      r->volume <= 1.1 * (side + EPS) * (side + EPS) * EPS,
		      "slab volume %g, expected about %g", r->volume, side * side * EPS);
	ck_assert_msg(f->rep.sheet_deviation <= EPS / 2 + 1e-3, "reported sheet_deviation %g",
		      f->rep.sheet_deviation);
	ck_assert(f->rep.second_pass);
	ck_assert_uint_eq(f->rep.second_sheet_triangles, 0);
	ck_assert_uint_eq(f->rep.components, 1);
}

/*
 * Proves that an open 30 x 30 mm square sheet in z = 0 (as two triangles,
 * and as an 8 x 8 grid of 128) becomes one slab of total thickness
 * epsilon around it.
 */
START_TEST(open_square_becomes_slab)
{
	const int n = _i == 0 ? 1 : 8;
	const double o[3] = {0, 0, 0}, u[3] = {30, 0, 0}, v[3] = {0, 30, 0};
	struct mesh *in = fx_grid(o, u, v, n, n);
	struct fixed f = repair_eps(in, EPS);
	struct mesh_report r = judge(&f, REPAIR_FLOAT32, "square");

	ck_assert_uint_eq(f.rep.sheet_triangles, (size_t)2 * n * n);
	ck_assert_uint_eq(f.rep.sheet_components, 1);
	ck_assert_double_eq_tol(f.rep.sheet_area, 900.0, 1e-9);
	ck_assert(f.rep.second_pass);
	ck_assert_uint_eq(f.rep.second_sheet_triangles, 0);
	assert_near_input(&f, in);
	assert_slab(&f, &r, 0, 30);
	fixed_free(&f);
	mesh_free(in);
}
END_TEST

/*
 * Proves that a box of zero height, fx_box(0,0,0,10,10,0) (8 irregular
 * side triangles, the top an equivalent copy of the bottom: one open
 * square, see check_mesh.c flat_cube), becomes a 10 x 10 slab of
 * thickness epsilon.
 */
START_TEST(flat_cube_becomes_slab)
{
	struct mesh *in = fx_box(0, 0, 0, 10, 10, 0);
	struct fixed f = repair_eps(in, EPS);
	struct mesh_report r = judge(&f, REPAIR_FLOAT32, "flat");

	ck_assert_uint_eq(in->ntris, 12);
	ck_assert_uint_eq(f.rep.irregular_removed, 8);
	ck_assert_uint_eq(f.rep.duplicates_removed, 2);
	ck_assert_uint_eq(f.rep.sheet_triangles, 2);
	ck_assert(f.rep.second_pass);
	ck_assert_uint_eq(f.rep.second_sheet_triangles, 0);
	assert_near_input(&f, in);
	assert_slab(&f, &r, 0, 10);
	fixed_free(&f);
	mesh_free(in);
}
END_TEST

/*
 * Proves that a fin (a 10 x 5 mm sheet standing on the top face of the
 * cube [0,10]^3 at x = 5, as 2 triangles and as a 4 x 4 grid) is
 * thickened and fused to the cube: one component, top at z = 15 (plus at
 * most epsilon/2), volume 1000 plus about 50 * epsilon, and the cube's
 * bottom face, which nothing touches, is still there exactly.
 */
START_TEST(fin_fused_to_cube)
{
	const int n = _i == 0 ? 1 : 4;
	const double o[3] = {5, 0, 10}, u[3] = {0, 10, 0}, v[3] = {0, 0, 5};
	const double lo[3] = {0, -EPS / 2, 0}, hi[3] = {10, 10 + EPS / 2, 15 + EPS / 2};
	const double c000[3] = {0, 0, 0}, c100[3] = {10, 0, 0}, c010[3] = {0, 10, 0},
		     c110[3] = {10, 10, 0};
	struct mesh *cube = fx_box(0, 0, 0, 10, 10, 10), *fin = fx_grid(o, u, v, n, n);
	struct mesh *in = fx_concat(cube, fin);
	struct fixed f = repair_eps(in, EPS);
	struct mesh_report r = judge(&f, REPAIR_FLOAT32, "fin");
	double mn[3], mx[3];

	ck_assert_uint_eq(f.rep.components, 1);
	ck_assert_uint_eq(r.components, 1);
	ck_assert_uint_ge(f.rep.sheet_triangles, (size_t)2 * n * n);
	ck_assert(f.rep.second_pass);
	ck_assert_uint_eq(f.rep.second_sheet_triangles, 0);
	mesh_bbox(f.out, mn, mx);
	ck_assert_msg(mx[2] >= 15 && mx[2] <= 15 + EPS / 2 + 1e-3, "top z %.9g, expected 15",
		      mx[2]);
	ck_assert_double_eq(mn[2], 0.0);
	assert_bbox_within(f.out, lo, hi, 1e-3);
	assert_near_input(&f, in);
	ck_assert_msg(r.volume >= 1000 && r.volume <= 1000 + 50 * EPS * 1.5,
		      "cube + fin volume %.9g, expected 1000 + about %g", r.volume, 50 * EPS);
	/* Bottom face, quad v0 v2 v3 v1 of fx_box. */
	ck_assert(has_triangle(f.out, c000, c010, c110));
	ck_assert(has_triangle(f.out, c000, c110, c100));
	fixed_free(&f);
	mesh_free(in);
	mesh_free(cube);
	mesh_free(fin);
}
END_TEST

/* ---- 8. wires ---- */

/*
 * Proves that a degenerate triangle (collinear corners (5,5,10),
 * (5,5,15), (5,5,12.5)) standing on the cube's top face is kept as one
 * wire of length 5, thickened and fused: one component reaching z = 15
 * (within epsilon), and a thin rod adds little volume.
 */
START_TEST(dangling_wire_thickened)
{
	const double a[3] = {5, 5, 10}, b[3] = {5, 5, 15}, c[3] = {5, 5, 12.5};
	const double lo[3] = {0, 0, 0}, hi[3] = {10, 10, 15 + EPS};
	struct mesh *cube = fx_box(0, 0, 0, 10, 10, 10), *wire = fx_triangle(a, b, c);
	struct mesh *in = fx_concat(cube, wire);
	struct fixed f = repair_eps(in, EPS);
	struct mesh_report r = judge(&f, REPAIR_FLOAT32, "wire");
	double mn[3], mx[3];

	ck_assert_uint_eq(f.rep.degenerate_removed, 1);
	ck_assert_uint_eq(f.rep.wires, 1);
	ck_assert_double_eq_tol(f.rep.wire_length, 5.0, 1e-9);
	ck_assert_uint_eq(f.rep.wires_discarded, 0);
	ck_assert(f.rep.second_pass);
	ck_assert_uint_eq(f.rep.second_sheet_triangles, 0);
	ck_assert_uint_eq(f.rep.components, 1);
	mesh_bbox(f.out, mn, mx);
	ck_assert_msg(fabs(mx[2] - 15) <= EPS, "top z %.9g, expected 15 +- %g", mx[2], EPS);
	assert_near_input(&f, in);
	assert_bbox_within(f.out, lo, hi, 1e-6);
	ck_assert_msg(r.volume > 1000 && r.volume <= 1000 + 2 * (5 + EPS) * EPS * EPS,
		      "cube + rod volume %.9g", r.volume);
	fixed_free(&f);
	mesh_free(in);
	mesh_free(cube);
	mesh_free(wire);
}
END_TEST

/*
 * Proves that a wire entirely inside the solid ((2,2,2)-(8,8,8) with a
 * middle corner (5,5,5)) is discarded and the cube comes back exactly.
 */
START_TEST(inner_wire_discarded)
{
	const double a[3] = {2, 2, 2}, b[3] = {8, 8, 8}, c[3] = {5, 5, 5};
	struct mesh *cube = fx_box(0, 0, 0, 10, 10, 10), *wire = fx_triangle(a, b, c);
	struct mesh *in = fx_concat(cube, wire);
	struct fixed f = repair_eps(in, EPS);
	struct mesh_report r = judge(&f, REPAIR_FLOAT32, "innerwire");

	ck_assert_uint_eq(f.rep.degenerate_removed, 1);
	ck_assert_uint_eq(f.rep.wires_discarded, 1);
	assert_same_triangles(f.out, cube, "output vs cube");
	ck_assert_double_eq_tol(r.volume, 1000.0, 1e-9);
	ck_assert_uint_eq(f.rep.components, 1);
	fixed_free(&f);
	mesh_free(in);
	mesh_free(cube);
	mesh_free(wire);
}
END_TEST

/* ---- 9. split into manifold-connected parts ---- */

/* Mean x of m's vertices. */
static double mean_x(const struct mesh *m)
{
	double sum = 0;

	for (size_t v = 0; v < m->nverts; v++)
		sum += m->verts[v][0];
	return m->nverts ? sum / m->nverts : 0;
}

/*
 * Proves that two cubes sharing only an edge ([0,1]^3 and [1,2]x[1,2]x[0,1])
 * are not manifold-connected (Def. 3.10): the output is the input
 * unchanged, split into two components of 12 triangles, each one cube.
 */
START_TEST(edge_touching_cubes_two_components)
{
	struct mesh *a = fx_box(0, 0, 0, 1, 1, 1), *b = fx_box(1, 1, 0, 2, 2, 1);
	struct mesh *in = fx_concat(a, b);
	struct fixed f = repair_eps(in, EPS);
	struct mesh *p0, *p1;

	judge(&f, REPAIR_FLOAT32, "edgecubes");
	ck_assert_uint_eq(f.rep.components, 2);
	ck_assert_uint_eq(f.rep.intersecting_pairs, 0);
	ck_assert_uint_eq(f.rep.sheet_triangles, 0);
	assert_same_triangles(f.out, in, "output vs input");
	p0 = part_mesh(f.out, f.comp, 0);
	p1 = part_mesh(f.out, f.comp, 1);
	ck_assert_uint_eq(p0->ntris, 12);
	ck_assert_uint_eq(p1->ntris, 12);
	/* Each component is one of the cubes; a's vertices average x = 0.5, b's 1.5. */
	if (mean_x(p0) < 1) {
		assert_same_triangles(p0, a, "component 0");
		assert_same_triangles(p1, b, "component 1");
	} else {
		assert_same_triangles(p0, b, "component 0");
		assert_same_triangles(p1, a, "component 1");
	}
	mesh_free(p0);
	mesh_free(p1);
	fixed_free(&f);
	mesh_free(in);
	mesh_free(a);
	mesh_free(b);
}
END_TEST

/* ---- 10.-11. arbitrary soups ---- */

/*
 * Proves the claim of seed 000 §4, any soup in, printable out, on 20
 * random triangles in a 10 mm box (intersecting, open, isolated).  Each
 * component must be printable and the result stays within epsilon of the
 * input's box.  Seed 10 is a soup where plain float32 rounding made new
 * crossings faster than re-cutting removed them; snap rounding places its
 * vertices without any.  (Seeds 14, 18, 20, 30, 36 were such too; they
 * pass as well but cost the suite too much time.)  Its moves stay within two float
 * steps of the exact places (a few micrometres at 10 mm), per rounding
 * round.  The second pass must leave M_sheet empty (a sheet left is an
 * internal error, no third pass): seeds 1 and 10 left 1 and 6 sheet
 * triangles while the hull growing could leave one side of a face in
 * the middle of a sheet unwalked.
 */
static const unsigned random_seeds[] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13};

START_TEST(random_triangles_printable)
{
	struct mesh *in = fx_random_triangles(random_seeds[_i], 20, 10.0);
	struct fixed f = repair_eps(in, EPS);
	double mn[3], mx[3], lo[3], hi[3];
	char name[32];

	snprintf(name, sizeof(name), "random%u", random_seeds[_i]);
	judge(&f, REPAIR_FLOAT32, name);
	ck_assert(f.rep.second_pass);
	ck_assert_uint_eq(f.rep.second_sheet_triangles, 0);
	mesh_bbox(in, mn, mx);
	for (int k = 0; k < 3; k++) {
		lo[k] = mn[k] - EPS;
		hi[k] = mx[k] + EPS;
	}
	assert_bbox_within(f.out, lo, hi, 1e-6);
	assert_near_input(&f, in);
	/* Two float steps at 10 mm (< 1.9e-6 mm per coordinate) a round. */
	ck_assert_msg(f.rep.rounding_deviation < 3.3e-6 * (f.rep.rounding_rounds + 1),
		      "rounding_deviation %g after %d rounds", f.rep.rounding_deviation,
		      f.rep.rounding_rounds);
	fixed_free(&f);
	mesh_free(in);
}
END_TEST

/* Klein bottle resolutions: the 40 x 20 of the plan and others around it. */
static const int klein_grid[][2] = {{40, 20}, {24, 12}, {32, 16}, {48, 24}};

/*
 * Proves that a closed, unorientable, self-intersecting surface (the
 * figure-8 Klein bottle immersion, about 22 mm across, at several grid
 * resolutions) is resolved into printable solids: the intersections are
 * found and cut, and the result stays within the input's box (plus epsilon
 * for any sheet) and within epsilon/2 of the input surface.
 */
START_TEST(klein_bottle_printable)
{
	struct mesh *in = fx_klein_bottle(3, 2.5, klein_grid[_i][0], klein_grid[_i][1]);
	struct fixed f = repair_eps(in, EPS);
	double mn[3], mx[3], lo[3], hi[3];
	struct mesh_report r;

	r = judge(&f, REPAIR_FLOAT32, "klein");
	ck_assert_uint_gt(f.rep.intersecting_pairs, 0);
	ck_assert_uint_gt(f.rep.triangles_split, 0);
	ck_assert_uint_eq(f.rep.second_sheet_triangles, 0);
	ck_assert(r.volume > 0);
	mesh_bbox(in, mn, mx);
	for (int k = 0; k < 3; k++) {
		lo[k] = mn[k] - EPS;
		hi[k] = mx[k] + EPS;
	}
	assert_bbox_within(f.out, lo, hi, 1e-6);
	assert_near_input(&f, in);
	fixed_free(&f);
	mesh_free(in);
}
END_TEST

/* ---- 12. bad input ---- */

/*
 * Proves that a non-positive or NaN epsilon is refused with ST_ERR_ARG, a
 * message, and both output pointers set to NULL (docs/architecture.md convention 3).
 */
START_TEST(bad_epsilon_rejected)
{
	const double bad[] = {0.0, -0.4, NAN};
	struct mesh *in = fx_box(0, 0, 0, 10, 10, 10);
	struct mesh sentinel;
	uint32_t dummy = 0;
	struct repair_options opt;
	struct repair_report rep;
	struct st_error err;
	struct mesh *out = &sentinel;
	uint32_t *comp = &dummy;
	int rc;

	repair_options_init(&opt);
	opt.epsilon = bad[_i];
	memset(&err, 0, sizeof(err));
	rc = repair_mesh(in, &opt, &out, &comp, &rep, &err);
	ck_assert_msg(rc == ST_ERR_ARG, "epsilon %g: returned %d, expected ST_ERR_ARG", bad[_i],
		      rc);
	ck_assert_int_eq(err.code, ST_ERR_ARG);
	ck_assert_msg(err.msg[0] != '\0', "no error message");
	ck_assert_ptr_null(out);
	ck_assert_ptr_null(comp);
	mesh_free(in);
}
END_TEST

/* Proves that the defaults are the documented ones (epsilon 0.4 mm, float32). */
START_TEST(default_options)
{
	struct repair_options opt;

	memset(&opt, 0xff, sizeof(opt));
	repair_options_init(&opt);
	ck_assert_double_eq(opt.epsilon, 0.4);
	ck_assert_int_eq(opt.precision, REPAIR_FLOAT32);
	ck_assert_int_eq(opt.threads, 0);
	ck_assert(opt.progress == NULL);
}
END_TEST

/*
 * Proves that an empty mesh is not an error but not printable either:
 * repair_mesh returns 0, rep.printable false and rep.why says why.
 */
START_TEST(empty_mesh_not_printable)
{
	struct mesh_builder *b = mesh_builder_new(0);
	struct mesh *in = mesh_builder_finish(b);
	struct repair_options opt;
	struct repair_report rep;
	struct st_error err = {0};
	struct mesh *out = NULL;
	uint32_t *comp = NULL;
	int rc;

	repair_options_init(&opt);
	rc = repair_mesh(in, &opt, &out, &comp, &rep, &err);
	ck_assert_msg(rc == 0, "returned %d: %s", rc, err.msg);
	ck_assert(!rep.printable);
	ck_assert_msg(rep.why[0] != '\0', "rep.why is empty");
	ck_assert_uint_eq(rep.input_triangles, 0);
	if (out)
		ck_assert_uint_eq(out->ntris, 0);
	mesh_free(out);
	free(comp);
	mesh_free(in);
}
END_TEST

Suite *repair_suite(void)
{
	Suite *s = suite_create("repair");
	TCase *solid = tcase_create("solid"), *sheet = tcase_create("sheet");
	TCase *soup = tcase_create("soup"), *args = tcase_create("args");

	/* Exact arithmetic under ASan/UBSan is slow; these are small inputs. */
	tcase_set_timeout(solid, 60);
	tcase_set_timeout(sheet, 60);
	tcase_set_timeout(soup, 300); /* random soups re-cut several rounds; slow under ASan */
	tcase_add_loop_test(solid, solid_float_input_unchanged, 0, 4);
	tcase_add_loop_test(solid, solid_double_input_unchanged_float64, 0, 2);
	tcase_add_loop_test(solid, solid_double_input_rounded_to_nearest_float, 0, 2);
	tcase_add_test(solid, overlapping_cubes_union);
	tcase_add_test(solid, threads_do_not_change_result);
	tcase_add_test(solid, nested_shell_deleted);
	tcase_add_test(solid, nested_inward_shell_is_a_cavity);
	tcase_add_test(solid, part_inside_a_cavity_kept);
	tcase_add_loop_test(solid, touching_cubes_printable, 0, 3);
	tcase_add_test(solid, tiny_part_dropped);
	tcase_add_test(solid, inner_wire_discarded);
	tcase_add_test(solid, edge_touching_cubes_two_components);
	suite_add_tcase(s, solid);
	tcase_add_test(sheet, open_cube_thickened);
	tcase_add_loop_test(sheet, open_square_becomes_slab, 0, 2);
	tcase_add_test(sheet, flat_cube_becomes_slab);
	tcase_add_loop_test(sheet, fin_fused_to_cube, 0, 2);
	tcase_add_test(sheet, dangling_wire_thickened);
	suite_add_tcase(s, sheet);
	tcase_add_loop_test(soup, random_triangles_printable, 0,
			    (int)(sizeof(random_seeds) / sizeof(random_seeds[0])));
	tcase_add_loop_test(soup, klein_bottle_printable, 0,
			    (int)(sizeof(klein_grid) / sizeof(klein_grid[0])));
	suite_add_tcase(s, soup);
	tcase_add_loop_test(args, bad_epsilon_rejected, 0, 3);
	tcase_add_test(args, default_options);
	tcase_add_test(args, empty_mesh_not_printable);
	suite_add_tcase(s, args);
	return s;
}
