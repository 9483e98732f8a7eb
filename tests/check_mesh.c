/*
 * check_mesh.c - welding and the topology report, one generated fixture per
 * defect class with counts that follow from how the fixture is built.
 */
#include <check.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "fixtures.h"
#include "mesh.h"
#include "suites.h"

static struct mesh_report analyze(const struct mesh *m)
{
	struct mesh_report r;
	struct st_error err = {0};

	ck_assert_msg(mesh_analyze(m, 2, &r, &err) == 0, "mesh_analyze: %s", err.msg);
	return r;
}

/* Reasons present, as a bit set, to compare with what a fixture expects. */
static unsigned reasons(const struct mesh_report *r)
{
	unsigned bits = 0;

	for (int i = 0; i < MESH_REASON_COUNT; i++)
		if (r->reasons[i])
			bits |= 1u << i;
	return bits;
}

#define BIT(r) (1u << (r))

START_TEST(weld_is_exact)
{
	struct mesh_builder *b = mesh_builder_new(0);
	const double p[3] = {1.0, 2.0, 3.0}, q[3] = {1.0, 2.0, nextafter(3.0, 4.0)};
	const double z[3] = {0.0, 0.0, 0.0}, nz[3] = {-0.0, 0.0, -0.0};
	uint32_t a, c, d, e, f;
	struct mesh *m;

	ck_assert_ptr_nonnull(b);
	ck_assert_int_eq(mesh_builder_vertex(b, p, &a, NULL), 0);
	ck_assert_int_eq(mesh_builder_vertex(b, q, &c, NULL), 0);
	ck_assert_int_eq(mesh_builder_vertex(b, p, &d, NULL), 0);
	ck_assert_int_eq(mesh_builder_vertex(b, z, &e, NULL), 0);
	ck_assert_int_eq(mesh_builder_vertex(b, nz, &f, NULL), 0);
	ck_assert_uint_eq(a, d);	/* bit-identical: one vertex */
	ck_assert_uint_ne(a, c);	/* one ulp apart: two vertices */
	ck_assert_uint_eq(e, f);	/* -0.0 is the same point as +0.0 */
	ck_assert_int_eq(mesh_builder_triangle(b, a, c, 7, NULL), ST_ERR_ARG);
	m = mesh_builder_finish(b);
	ck_assert_uint_eq(m->nverts, 3);
	mesh_free(m);
}
END_TEST

START_TEST(weld_many_vertices_grows_table)
{
	struct mesh_builder *b = mesh_builder_new(0);
	struct mesh *m;

	for (int round = 0; round < 2; round++) {
		for (int i = 0; i < 50000; i++) {
			const double p[3] = {i * 0.1, -i * 0.25, 1.0 / (i + 1)};
			uint32_t idx;
			ck_assert_int_eq(mesh_builder_vertex(b, p, &idx, NULL), 0);
			ck_assert_uint_eq(idx, (uint32_t)i);
		}
	}
	m = mesh_builder_finish(b);
	ck_assert_uint_eq(m->nverts, 50000);
	mesh_free(m);
}
END_TEST

/* Corners for mesh_weld_read from an array, failing from facet fail_at on. */
struct corner_feed {
	const float (*corner)[3];
	size_t fail_at;
};

static bool feed_corners(void *ctx, size_t first, size_t count, float (*corner)[3])
{
	const struct corner_feed *f = ctx;

	if (first + count > f->fail_at)
		return false;
	memcpy(corner, f->corner + 3 * first, 3 * count * sizeof(*corner));
	return true;
}

/* The welds of a corner array (mesh_weld_corners, and mesh_weld_read
 * when read), checked against the builder's mesh. */
static void check_welds(const float (*corner)[3], size_t ntris, int parts, bool read,
			const struct mesh *want)
{
	struct corner_feed feed = {corner, SIZE_MAX};

	for (int how = 0; how < 1 + read; how++) {
		struct mesh *got = NULL;
		struct st_error err = {0};

		ck_assert_int_eq(how ? mesh_weld_read(feed_corners, &feed, ntris, parts, &got, &err)
				     : mesh_weld_corners(corner, ntris, parts, &got, &err),
				 0);
		ck_assert_uint_eq(got->nverts, want->nverts);
		ck_assert_uint_eq(got->ntris, want->ntris);
		ck_assert_int_eq(memcmp(got->verts, want->verts, want->nverts * sizeof(*want->verts)),
				 0);
		ck_assert_int_eq(memcmp(got->tris, want->tris, want->ntris * sizeof(*want->tris)), 0);
		mesh_free(got);
	}
}

/*
 * mesh_weld_corners must make the builder's mesh index for index, whatever
 * the number of parts: corners drawn from a small grid (so most repeat,
 * many first seen late), with -0.0 and +0.0 mixed, and sizes that make
 * the parts' tables grow.  A wrong merge of the parts numbers the
 * vertices out of first-use order; a lost -0.0 fold makes extra ones.
 */
START_TEST(weld_corners_matches_builder)
{
	const size_t sizes[] = {1, 7, 3000, 40000};

	for (size_t n = 0; n < sizeof(sizes) / sizeof(sizes[0]); n++) {
		const size_t ntris = sizes[n];
		float(*corner)[3] = malloc(3 * ntris * sizeof(*corner));
		struct mesh_builder *b = mesh_builder_new(0);
		uint32_t seed = 12345;
		struct mesh *want;

		ck_assert_ptr_nonnull(corner);
		for (size_t c = 0; c < 3 * ntris; c++) {
			for (int k = 0; k < 3; k++) {
				seed = seed * 1103515245u + 12345u;
				/* Grid steps of 0.5 from -20 to 20: -0.0 for half the zeros. */
				int step = (int)((seed >> 8) % 81) - 40;
				corner[c][k] = step == 0 && (seed & 0x10000) ? -0.0f : 0.5f * (float)step;
			}
			/* Late in the file, points the start never had. */
			if (c > 2 * ntris)
				corner[c][2] += 100.0f;
		}
		for (size_t t = 0; t < ntris; t++) {
			uint32_t w[3];
			for (int k = 0; k < 3; k++) {
				const double p[3] = {corner[3 * t + k][0], corner[3 * t + k][1],
						     corner[3 * t + k][2]};
				ck_assert_int_eq(mesh_builder_vertex(b, p, &w[k], NULL), 0);
			}
			ck_assert_int_eq(mesh_builder_triangle(b, w[0], w[1], w[2], NULL), 0);
		}
		want = mesh_builder_finish(b);
		/* The read shares the weld and its merge: one and two parts. */
		for (int parts = 1; parts <= 9; parts += 2)
			check_welds((const float(*)[3])corner, ntris, parts, parts == 1, want);
		check_welds((const float(*)[3])corner, ntris, 2, true, want);
		mesh_free(want);
		free(corner);
	}
}
END_TEST

/* A facet that does not read stops mesh_weld_read with ST_ERR_PARSE and
 * no mesh, on one part and on several, wherever the run it falls in. */
START_TEST(weld_read_stops_at_unread_facet)
{
	const size_t ntris = 5000, fails[] = {0, 1023, 1024, 4999};
	float(*corner)[3] = calloc(3 * ntris, sizeof(*corner));

	ck_assert_ptr_nonnull(corner);
	for (size_t c = 0; c < 3 * ntris; c++)
		corner[c][0] = (float)c;
	for (size_t i = 0; i < sizeof(fails) / sizeof(fails[0]); i++)
		for (int parts = 1; parts <= 3; parts++) {
			struct corner_feed feed = {(const float(*)[3])corner, fails[i]};
			struct mesh *got = NULL;
			struct st_error err = {0};

			ck_assert_int_eq(
			    mesh_weld_read(feed_corners, &feed, ntris, parts, &got, &err),
			    ST_ERR_PARSE);
			ck_assert_ptr_null(got);
		}
	free(corner);
}
END_TEST

START_TEST(cube_is_printable)
{
	struct mesh *m = fx_box(0, 0, 0, 10, 10, 10);
	struct mesh_report r = analyze(m);

	ck_assert_uint_eq(r.vertices, 8);
	ck_assert_uint_eq(r.edges, 18);
	ck_assert_uint_eq(r.triangles, 12);
	ck_assert_uint_eq(r.boundary_edges, 0);
	ck_assert_uint_eq(r.singular_edges, 0);
	ck_assert_uint_eq(r.nonmanifold_vertices, 0);
	ck_assert_uint_eq(r.components, 1);
	ck_assert_uint_eq(r.boundary_loops, 0);
	ck_assert_int_eq(r.euler, 2);
	ck_assert(r.genus_defined);
	ck_assert_int_eq(r.genus, 0);
	ck_assert_uint_eq(r.self_intersections, 0);
	ck_assert(r.orientable && r.consistently_oriented);
	ck_assert_double_eq_tol(r.volume, 1000.0, 1e-9);
	ck_assert_double_eq(r.bbox_max[2], 10.0);
	ck_assert(r.printable);
	ck_assert_uint_eq(reasons(&r), 0);
	mesh_free(m);
}
END_TEST

START_TEST(sphere_genus_0)
{
	struct mesh *m = fx_sphere(0, 0, 0, 10, 8, 12);
	struct mesh_report r = analyze(m);

	ck_assert_uint_eq(r.vertices, 2 + 7 * 12);
	ck_assert_uint_eq(r.triangles, 2 * 12 + 2 * 12 * 6);
	ck_assert_uint_eq(r.edges, r.triangles * 3 / 2);
	ck_assert_int_eq(r.euler, 2);
	ck_assert(r.genus_defined);
	ck_assert_int_eq(r.genus, 0);
	ck_assert_uint_eq(r.self_intersections, 0);
	ck_assert(r.volume > 0 && r.volume < 4.0 / 3.0 * M_PI * 1000.0);
	ck_assert(r.printable);
	mesh_free(m);
}
END_TEST

START_TEST(torus_genus_1)
{
	struct mesh *m = fx_torus(10, 3, 24, 12);
	struct mesh_report r = analyze(m);

	ck_assert_uint_eq(r.vertices, 24 * 12);
	ck_assert_uint_eq(r.triangles, 24 * 12 * 2);
	ck_assert_uint_eq(r.edges, 24 * 12 * 3);
	ck_assert_int_eq(r.euler, 0);
	ck_assert(r.genus_defined);
	ck_assert_int_eq(r.genus, 1);
	ck_assert_uint_eq(r.self_intersections, 0);
	ck_assert(r.printable);
	mesh_free(m);
}
END_TEST

START_TEST(two_tori_genus_2)
{
	struct mesh *a = fx_torus(10, 3, 24, 12), *b = fx_torus(10, 3, 24, 12);
	struct mesh *m;
	struct mesh_report r;

	for (size_t v = 0; v < b->nverts; v++)
		b->verts[v][0] += 40.0;
	m = fx_concat(a, b);
	r = analyze(m);
	ck_assert_uint_eq(r.components, 2);
	ck_assert_int_eq(r.euler, 0);
	ck_assert(r.genus_defined);
	ck_assert_int_eq(r.genus, 2);
	/* Two parts side by side print as they are (docs/check.md). */
	ck_assert(r.printable);
	ck_assert_uint_eq(r.parts, 2);
	ck_assert_uint_eq(r.cavities, 0);
	ck_assert_uint_eq(reasons(&r), BIT(MESH_REASON_SEVERAL_PARTS));
	mesh_free(a);
	mesh_free(b);
	mesh_free(m);
}
END_TEST

/* A copy of m with every triangle reversed: a shell facing inwards. */
static struct mesh *inward(const struct mesh *m)
{
	struct mesh *r = fx_concat(m, m);

	/* fx_concat welds the copy onto the same vertices; keep one copy. */
	r->ntris = m->ntris;
	for (size_t t = 0; t < r->ntris; t++)
		fx_flip(r, t);
	return r;
}

/*
 * Proves that a closed shell facing inwards inside a solid is a cavity:
 * printable, one part with one cavity, volume outer minus inner; the same
 * inner shell facing outwards is a solid inside a solid, which no layer of
 * a printable file holds (misnested), and so is a lone inward cube beside
 * an outward one.
 */
START_TEST(nested_shells_cavity_or_misnested)
{
	struct mesh *outer = fx_box(0, 0, 0, 10, 10, 10), *box = fx_box(3, 3, 3, 7, 7, 7);
	struct mesh *hole = inward(box), *beside = fx_box(20, 0, 0, 24, 4, 4);
	struct mesh *hollow = fx_concat(outer, hole), *nested = fx_concat(outer, box);
	struct mesh *away = inward(beside), *pair = fx_concat(outer, away);
	struct mesh_report r = analyze(hollow);

	ck_assert(r.printable);
	ck_assert_uint_eq(r.parts, 1);
	ck_assert_uint_eq(r.cavities, 1);
	ck_assert_uint_eq(r.manifold_components, 2);
	ck_assert_double_eq_tol(r.volume, 1000.0 - 64.0, 1e-9);
	ck_assert_uint_eq(reasons(&r), 0);

	r = analyze(nested);
	ck_assert(!r.printable);
	ck_assert_uint_eq(r.misnested_shells, 1);
	ck_assert_uint_eq(reasons(&r), BIT(MESH_REASON_MISNESTED) | BIT(MESH_REASON_SEVERAL_PARTS));

	r = analyze(pair);
	ck_assert(!r.printable);
	ck_assert_uint_eq(r.misnested_shells, 1);
	ck_assert(r.reasons[MESH_REASON_MISNESTED]);
	mesh_free(outer);
	mesh_free(box);
	mesh_free(hole);
	mesh_free(beside);
	mesh_free(hollow);
	mesh_free(nested);
	mesh_free(away);
	mesh_free(pair);
}
END_TEST

/*
 * Proves that many parts in the box of a big shell are told apart: a
 * hollow sphere (an inward sphere inside it, a cavity), eight cubes
 * standing in the cavity and eight beside the sphere in the corners of its
 * box.  Every cube asks both spheres whether they hold it, so the spheres
 * are filed for repeated ray tests (repair/parts.c); the answers must be
 * the plain scan's: 17 parts, one cavity, printable.
 */
START_TEST(many_parts_in_one_box)
{
	struct mesh *outer = fx_sphere(0, 0, 0, 10, 16, 32), *in = fx_sphere(0, 0, 0, 6, 16, 32);
	struct mesh *hole = inward(in), *all = fx_concat(outer, hole);
	struct mesh_report r;

	for (int c = 0; c < 16; c++) {
		const double d = c < 8 ? 2 : 8.5; /* in the cavity, or beside the sphere */
		const double x = c & 1 ? d : -d, y = c & 2 ? d : -d, z = c & 4 ? d : -d;
		struct mesh *cube = fx_box(x, y, z, x + 0.5, y + 0.5, z + 0.5), *next;

		next = fx_concat(all, cube);
		mesh_free(all);
		mesh_free(cube);
		all = next;
	}
	r = analyze(all);
	ck_assert(r.printable);
	ck_assert_uint_eq(r.parts, 17);
	ck_assert_uint_eq(r.cavities, 1);
	ck_assert_uint_eq(r.misnested_shells, 0);
	mesh_free(outer);
	mesh_free(in);
	mesh_free(hole);
	mesh_free(all);
}
END_TEST

/* A tetrahedron p q r s facing outwards: each face has the fourth corner behind it. */
static struct mesh *tetra(const double p[3], const double q[3], const double r[3],
			  const double s[3])
{
	const double *v[4] = {p, q, r, s};
	static const int face[4][4] = {{0, 1, 2, 3}, {0, 1, 3, 2}, {0, 2, 3, 1}, {1, 2, 3, 0}};
	struct mesh *m = NULL;

	for (int f = 0; f < 4; f++) {
		const double *a = v[face[f][0]], *b = v[face[f][1]], *c = v[face[f][2]];
		const double *d = v[face[f][3]];
		double u[3], w[3], x[3], det;
		struct mesh *t, *all;

		for (int k = 0; k < 3; k++) {
			u[k] = b[k] - a[k];
			w[k] = c[k] - a[k];
			x[k] = d[k] - a[k];
		}
		det = x[0] * (u[1] * w[2] - u[2] * w[1]) - x[1] * (u[0] * w[2] - u[2] * w[0]) +
		      x[2] * (u[0] * w[1] - u[1] * w[0]);
		t = det < 0 ? fx_triangle(a, b, c) : fx_triangle(a, c, b);
		all = m ? fx_concat(m, t) : t;
		if (m) {
			mesh_free(m);
			mesh_free(t);
		}
		m = all;
	}
	return m;
}

/*
 * Proves that a cavity touching the outer wall along an edge stays part
 * of its solid: a tetrahedral cavity whose edge is the diagonal of the
 * box's bottom face.  The four triangles at that singular edge pair up
 * through the material, so the file is one part and printable, volume box
 * minus tetrahedron.  The same tetrahedron facing outwards is a solid
 * inside the solid and is not printable.  A part standing in a cavity
 * and touching its floor along an edge (a tetrahedron on the floor
 * diagonal of an inward box [2,8]^3) is in the void: two parts, one
 * cavity, printable.
 */
START_TEST(cavity_touching_the_wall)
{
	const double p[3] = {0, 0, 0}, q[3] = {10, 10, 0}, r[3] = {2, 6, 3}, s[3] = {6, 2, 3};
	struct mesh *outer = fx_box(0, 0, 0, 10, 10, 10), *tet = tetra(p, q, r, s);
	struct mesh *hole = inward(tet);
	struct mesh *m = fx_concat(outer, hole), *bad = fx_concat(outer, tet);
	struct mesh_report rep, tr = analyze(tet);

	rep = analyze(m);
	ck_assert_uint_eq(rep.singular_edges, 1);
	ck_assert_uint_eq(rep.self_intersections, 0);
	ck_assert_msg(rep.printable, "odd %zu unpaired %zu misnested %zu", rep.odd_edges,
		      rep.open_singular_edges, rep.misnested_shells);
	ck_assert_uint_eq(rep.parts, 1);
	ck_assert_double_eq_tol(rep.volume, 1000.0 - tr.volume, 1e-9);
	rep = analyze(bad);
	ck_assert(!rep.printable);
	{
		const double a[3] = {2, 2, 2}, b[3] = {8, 8, 2}, c[3] = {3, 5, 4}, d[3] = {5, 3, 4};
		struct mesh *box = fx_box(2, 2, 2, 8, 8, 8), *cav = inward(box);
		struct mesh *island = tetra(a, b, c, d), *hollow = fx_concat(outer, cav);
		struct mesh *all = fx_concat(hollow, island);

		rep = analyze(all);
		ck_assert_uint_eq(rep.singular_edges, 1);
		ck_assert_msg(rep.printable, "unpaired %zu misnested %zu", rep.open_singular_edges,
			      rep.misnested_shells);
		ck_assert_uint_eq(rep.parts, 2);
		ck_assert_uint_eq(rep.cavities, 1);
		mesh_free(box);
		mesh_free(cav);
		mesh_free(island);
		mesh_free(hollow);
		mesh_free(all);
	}
	mesh_free(outer);
	mesh_free(tet);
	mesh_free(hole);
	mesh_free(m);
	mesh_free(bad);
}
END_TEST

START_TEST(cube_missing_one_triangle)
{
	struct mesh *m = fx_box(0, 0, 0, 10, 10, 10);
	struct mesh_report r;

	fx_drop(m, 5);
	r = analyze(m);
	ck_assert_uint_eq(r.triangles, 11);
	ck_assert_uint_eq(r.edges, 18);
	ck_assert_uint_eq(r.boundary_edges, 3);
	ck_assert_uint_eq(r.boundary_loops, 1);
	ck_assert_int_eq(r.euler, 1);
	ck_assert(!r.genus_defined);
	ck_assert(!r.printable);
	ck_assert_uint_eq(reasons(&r), BIT(MESH_REASON_OPEN));
	mesh_free(m);
}
END_TEST

START_TEST(cubes_sharing_an_edge)
{
	struct mesh *a = fx_box(0, 0, 0, 1, 1, 1), *b = fx_box(1, 1, 0, 2, 2, 1);
	struct mesh *m = fx_concat(a, b);
	struct mesh_report r = analyze(m);

	ck_assert_uint_eq(r.vertices, 14);
	ck_assert_uint_eq(r.edges, 35);
	ck_assert_uint_eq(r.singular_edges, 1);
	ck_assert_uint_eq(r.boundary_edges, 0);
	ck_assert_uint_eq(r.nonmanifold_vertices, 2);
	ck_assert_uint_eq(r.components, 1);
	ck_assert_uint_eq(r.manifold_components, 2);
	ck_assert_int_eq(r.euler, 3);
	ck_assert(!r.genus_defined);
	ck_assert_uint_eq(r.self_intersections, 0);
	/* Two closed parts touching along an edge: printable, two parts. */
	ck_assert(r.printable);
	ck_assert_uint_eq(r.parts, 2);
	ck_assert_uint_eq(r.open_singular_edges, 0);
	ck_assert_uint_eq(reasons(&r), BIT(MESH_REASON_NOT_MANIFOLD_CONNECTED) |
					       BIT(MESH_REASON_SEVERAL_PARTS));
	mesh_free(a);
	mesh_free(b);
	mesh_free(m);
}
END_TEST

START_TEST(cubes_sharing_a_vertex)
{
	struct mesh *a = fx_box(0, 0, 0, 1, 1, 1), *b = fx_box(1, 1, 1, 2, 2, 2);
	struct mesh *m = fx_concat(a, b);
	struct mesh_report r = analyze(m);

	ck_assert_uint_eq(r.vertices, 15);
	ck_assert_uint_eq(r.singular_edges, 0);
	ck_assert_uint_eq(r.nonmanifold_vertices, 1);
	ck_assert_uint_eq(r.components, 2);
	ck_assert_uint_eq(r.self_intersections, 0);
	ck_assert(!r.genus_defined);
	ck_assert(r.printable);
	ck_assert_uint_eq(r.parts, 2);
	ck_assert_uint_eq(reasons(&r), BIT(MESH_REASON_SEVERAL_PARTS));
	mesh_free(a);
	mesh_free(b);
	mesh_free(m);
}
END_TEST

/* A box of zero height: the sides collapse to irregular triangles and the
 * top duplicates the bottom, leaving one open square. */
START_TEST(flat_cube)
{
	struct mesh *m = fx_box(0, 0, 0, 10, 10, 0);
	struct mesh_report r = analyze(m);

	ck_assert_uint_eq(r.input_triangles, 12);
	ck_assert_uint_eq(r.irregular, 8);
	ck_assert_uint_eq(r.duplicates, 2);
	ck_assert_uint_eq(r.degenerate, 0);
	ck_assert_uint_eq(r.triangles, 2);
	ck_assert_uint_eq(r.vertices, 4);
	ck_assert_uint_eq(r.edges, 5);
	ck_assert_uint_eq(r.boundary_edges, 4);
	ck_assert_uint_eq(r.boundary_loops, 1);
	ck_assert_double_eq(r.volume, 0.0);
	ck_assert(!r.printable);
	ck_assert_uint_eq(reasons(&r), BIT(MESH_REASON_IRREGULAR) | BIT(MESH_REASON_OPEN) |
					       BIT(MESH_REASON_DUPLICATE));
	mesh_free(m);
}
END_TEST

START_TEST(collinear_triangle_is_degenerate)
{
	struct mesh *cube = fx_box(0, 0, 0, 10, 10, 10);
	struct mesh_builder *b = mesh_builder_new(0);
	const double p[3][3] = {{0, 0, 0}, {3.3, 3.3, 3.3}, {10, 10, 10}};
	uint32_t v[3];
	struct mesh *needle, *m;
	struct mesh_report r;

	for (int k = 0; k < 3; k++)
		ck_assert_int_eq(mesh_builder_vertex(b, p[k], &v[k], NULL), 0);
	ck_assert_int_eq(mesh_builder_triangle(b, v[0], v[1], v[2], NULL), 0);
	needle = mesh_builder_finish(b);
	m = fx_concat(cube, needle);
	r = analyze(m);
	ck_assert_uint_eq(r.degenerate, 1);
	ck_assert_uint_eq(r.triangles, 12);
	ck_assert_uint_eq(r.vertices, 8);
	ck_assert(!r.printable);
	ck_assert_uint_eq(reasons(&r), BIT(MESH_REASON_DEGENERATE));
	mesh_free(cube);
	mesh_free(needle);
	mesh_free(m);
}
END_TEST

START_TEST(duplicated_triangles)
{
	struct mesh *m = fx_box(0, 0, 0, 10, 10, 10);
	struct mesh_report r;

	fx_duplicate(m, 0, 0);
	fx_duplicate(m, 3, 1);
	fx_duplicate(m, 3, 0);
	r = analyze(m);
	ck_assert_uint_eq(r.duplicates, 3);
	ck_assert_uint_eq(r.triangles, 12);
	ck_assert_uint_eq(r.edges, 18);
	ck_assert_uint_eq(r.singular_edges, 0);
	ck_assert(r.printable); /* a layer drops equivalent triangles (Def. 3.1) */
	ck_assert_uint_eq(reasons(&r), BIT(MESH_REASON_DUPLICATE));
	mesh_free(m);
}
END_TEST

START_TEST(flipped_triangle)
{
	struct mesh *m = fx_box(0, 0, 0, 10, 10, 10);
	struct mesh_report r;

	fx_flip(m, 4);
	r = analyze(m);
	ck_assert(!r.consistently_oriented);
	ck_assert(r.orientable);
	ck_assert_uint_eq(r.flipped_edges, 3);
	ck_assert(r.printable); /* normals are not reliable information (seed 000 §3) */
	ck_assert_uint_eq(reasons(&r), BIT(MESH_REASON_INCONSISTENT_ORIENTATION));
	mesh_free(m);
}
END_TEST

START_TEST(inside_out_cube)
{
	struct mesh *m = fx_box(0, 0, 0, 10, 10, 10);
	struct mesh_report r;

	for (size_t t = 0; t < m->ntris; t++)
		fx_flip(m, t);
	r = analyze(m);
	ck_assert(r.consistently_oriented);
	ck_assert_double_eq_tol(r.volume, -1000.0, 1e-9);
	ck_assert(r.printable);
	ck_assert_uint_eq(reasons(&r), BIT(MESH_REASON_INSIDE_OUT));
	mesh_free(m);
}
END_TEST

START_TEST(overlapping_cubes)
{
	struct mesh *a = fx_box(0, 0, 0, 10, 10, 10), *b = fx_box(5, 5, 5, 15, 15, 15);
	struct mesh *m = fx_concat(a, b);
	struct mesh_report r = analyze(m);

	ck_assert_uint_eq(r.components, 2);
	ck_assert(r.self_intersections > 0);
	ck_assert(!r.printable);
	ck_assert_uint_eq(reasons(&r), BIT(MESH_REASON_SELF_INTERSECTION) |
					       BIT(MESH_REASON_SEVERAL_PARTS));
	mesh_free(a);
	mesh_free(b);
	mesh_free(m);
}
END_TEST

/* A Moebius strip of n quads: one boundary loop of 2n edges, unorientable. */
START_TEST(moebius_strip)
{
	const int n = 12;
	struct mesh_builder *b = mesh_builder_new(0);
	uint32_t top[12], bottom[12];
	struct mesh *m;
	struct mesh_report r;

	for (int i = 0; i < n; i++) {
		double u = 2 * M_PI * i / n, w = u / 2;
		const double p[3] = {(10 + 2 * cos(w)) * cos(u), (10 + 2 * cos(w)) * sin(u),
				     2 * sin(w)};
		const double q[3] = {(10 - 2 * cos(w)) * cos(u), (10 - 2 * cos(w)) * sin(u),
				     -2 * sin(w)};
		ck_assert_int_eq(mesh_builder_vertex(b, p, &top[i], NULL), 0);
		ck_assert_int_eq(mesh_builder_vertex(b, q, &bottom[i], NULL), 0);
	}
	for (int i = 0; i < n; i++) {
		/* The half twist: the last quad joins top to bottom. */
		uint32_t t1 = i + 1 < n ? top[i + 1] : bottom[0];
		uint32_t b1 = i + 1 < n ? bottom[i + 1] : top[0];
		ck_assert_int_eq(mesh_builder_triangle(b, top[i], t1, b1, NULL), 0);
		ck_assert_int_eq(mesh_builder_triangle(b, top[i], b1, bottom[i], NULL), 0);
	}
	m = mesh_builder_finish(b);
	r = analyze(m);
	ck_assert(!r.orientable);
	ck_assert_uint_eq(r.boundary_edges, 2 * n);
	ck_assert_uint_eq(r.boundary_loops, 1);
	ck_assert_int_eq(r.euler, 0);
	ck_assert(!r.genus_defined);
	ck_assert(!r.printable);
	mesh_free(m);
}
END_TEST

START_TEST(empty_mesh)
{
	struct mesh_builder *b = mesh_builder_new(0);
	struct mesh *m = mesh_builder_finish(b);
	struct mesh_report r = analyze(m);

	ck_assert_uint_eq(r.triangles, 0);
	ck_assert(!r.printable);
	ck_assert(r.reasons[MESH_REASON_EMPTY]);
	ck_assert_str_eq(mesh_reason_code(MESH_REASON_EMPTY), "empty");
	mesh_free(m);
}
END_TEST

Suite *mesh_suite(void)
{
	Suite *s = suite_create("mesh");
	TCase *weld = tcase_create("weld"), *topo = tcase_create("topology");

	tcase_add_test(weld, weld_is_exact);
	tcase_add_test(weld, weld_many_vertices_grows_table);
	tcase_add_test(weld, weld_corners_matches_builder);
	tcase_add_test(weld, weld_read_stops_at_unread_facet);
	suite_add_tcase(s, weld);
	tcase_add_test(topo, cube_is_printable);
	tcase_add_test(topo, sphere_genus_0);
	tcase_add_test(topo, torus_genus_1);
	tcase_add_test(topo, two_tori_genus_2);
	tcase_add_test(topo, cube_missing_one_triangle);
	tcase_add_test(topo, cubes_sharing_an_edge);
	tcase_add_test(topo, cubes_sharing_a_vertex);
	tcase_add_test(topo, nested_shells_cavity_or_misnested);
	tcase_add_test(topo, cavity_touching_the_wall);
	tcase_add_test(topo, many_parts_in_one_box);
	tcase_add_test(topo, flat_cube);
	tcase_add_test(topo, collinear_triangle_is_degenerate);
	tcase_add_test(topo, duplicated_triangles);
	tcase_add_test(topo, flipped_triangle);
	tcase_add_test(topo, inside_out_cube);
	tcase_add_test(topo, overlapping_cubes);
	tcase_add_test(topo, moebius_strip);
	tcase_add_test(topo, empty_mesh);
	suite_add_tcase(s, topo);
	return s;
}
