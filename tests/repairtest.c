/*
 * repairtest.c - the helpers of repairtest.h: running the repair, comparing
 * triangle sets, distances to the input, and judge, which writes each part
 * as the file a printer would get, reads it back and checks it.
 */
#include <check.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mesh.h"
#include "meshio.h"
#include "repair.h"
#include "repairtest.h"
#include "testutil.h"

/* Run repair_mesh with opt; it must succeed and report consistently. */
struct fixed repair_with(const struct mesh *in, const struct repair_options *opt)
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
struct fixed repair_eps(const struct mesh *in, double eps)
{
	struct repair_options opt;

	repair_options_init(&opt);
	opt.epsilon = eps;
	return repair_with(in, &opt);
}

void fixed_free(struct fixed *f)
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
void assert_same_triangles(const struct mesh *got, const struct mesh *want, const char *what)
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
int has_triangle(const struct mesh *m, const double p0[3], const double p1[3],
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
void assert_near_input(const struct fixed *f, const struct mesh *in)
{
	double d = max_vertex_distance(f->out, in);

	ck_assert_msg(d <= EPS / 2 + 1e-3,
		      "an output vertex is %.6g mm from the input, more than epsilon/2 = %g", d,
		      EPS / 2);
}

/* The triangles of m whose component is c, as a mesh of their own. */
struct mesh *part_mesh(const struct mesh *m, const uint32_t *comp, uint32_t c)
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
struct mesh_report judge(const struct fixed *f, enum repair_precision prec, const char *name)
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

