/*
 * check_batch.c - the repair of independent groups one by one
 * (repair/batch.h, docs/repair.md "Independent groups"): which triangles
 * form a group, that groups repaired apart give what the whole gives, and
 * that an enclosure the groups could not see sends the repair back to the
 * whole mesh.
 */
#include <check.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "batch.h"
#include "fixtures.h"
#include "mesh.h"
#include "repair.h"
#include "suites.h"

#define EPS 0.4 /* mm */

/* Sphere of 4680 triangles, more than one batch holds, pole at cz + r. */
static struct mesh *big_sphere(double cx, double cy, double cz, double r)
{
	return fx_sphere(cx, cy, cz, r, 40, 60);
}

static struct mesh *concat3(const struct mesh *a, const struct mesh *b, const struct mesh *c)
{
	struct mesh *ab = fx_concat(a, b), *abc = fx_concat(ab, c);

	mesh_free(ab);
	return abc;
}

static size_t count_batches(const struct mesh *m, double reach)
{
	struct batches bs;
	struct st_error err = {0};
	size_t n;

	ck_assert_int_eq(batches_find(m, reach, &bs, &err), 0);
	n = bs.n;
	/* Every triangle in exactly one batch, in input order within it. */
	ck_assert_uint_eq(bs.start[bs.n], m->ntris);
	for (size_t b = 0; b < bs.n; b++)
		for (size_t i = bs.start[b] + 1; i < bs.start[b + 1]; i++)
			ck_assert_uint_lt(bs.tri[i - 1], bs.tri[i]);
	batches_free(&bs);
	return n;
}

/*
 * Proves the reach decides the groups: two spheres whose poles are a
 * gap apart are one group below the reach and two above it.
 */
START_TEST(groups_follow_the_reach)
{
	const double reach = BATCH_REACH * EPS;
	const double gaps[] = {0.9 * reach, 1.1 * reach};
	const size_t expect[] = {1, 2};

	for (int i = 0; i < 2; i++) {
		struct mesh *a = big_sphere(0, 0, 0, 10), *b = big_sphere(0, 0, 20 + gaps[i], 10);
		struct mesh *m = fx_concat(a, b);
		ck_assert_msg(count_batches(m, reach) == expect[i], "gap %g mm: %zu batches",
			      gaps[i], count_batches(m, reach));
		mesh_free(a);
		mesh_free(b);
		mesh_free(m);
	}
}
END_TEST

static struct mesh *repair_ok(const struct mesh *in, struct repair_report *rep)
{
	struct repair_options opt;
	struct st_error err = {0};
	struct mesh *out = NULL;

	repair_options_init(&opt);
	opt.epsilon = EPS;
	ck_assert_msg(repair_mesh(in, &opt, &out, NULL, rep, &err) == 0, "%s", err.msg);
	ck_assert_msg(rep->printable, "not printable: %s", rep->why);
	return out;
}

/* The volume `stratum check` measures. */
static double volume(const struct mesh *m)
{
	struct mesh_report r;
	struct st_error err = {0};

	ck_assert_msg(mesh_analyze(m, 0, &r, &err) == 0, "%s", err.msg);
	return r.volume;
}

/* Triangle t of a and triangle u of b have the same corners, in order. */
static bool same_triangle(const struct mesh *a, size_t t, const struct mesh *b, size_t u)
{
	for (int k = 0; k < 3; k++)
		if (memcmp(a->verts[a->tris[t][k]], b->verts[b->tris[u][k]], sizeof(double[3])))
			return false;
	return true;
}

/*
 * Proves that groups repaired apart give what each gives alone: two
 * overlapping spheres (one group, cut and merged), and a copy of them
 * 100 mm away.  The first half of the result is the pair's own repair,
 * triangle for triangle; the whole has twice its triangles and volume.
 */
START_TEST(apart_groups_match_their_own_repair)
{
	struct mesh *s1 = big_sphere(0, 0, 0, 10), *s2 = big_sphere(6, 0, 0, 10);
	struct mesh *pair = fx_concat(s1, s2);
	struct mesh *t1 = big_sphere(100, 0, 0, 10), *t2 = big_sphere(106, 0, 0, 10);
	struct mesh *copy = fx_concat(t1, t2), *both = fx_concat(pair, copy);
	struct repair_report rp, rb;
	struct mesh *op = repair_ok(pair, &rp), *ob = repair_ok(both, &rb);

	ck_assert_uint_eq(rp.batches, 1);
	ck_assert_uint_eq(rb.batches, 2);
	ck_assert(!rb.batch_fallback);
	ck_assert_uint_gt(rp.intersecting_pairs, 0);
	ck_assert_uint_eq(rb.intersecting_pairs, 2 * rp.intersecting_pairs);
	ck_assert_uint_eq(rb.components, 2);
	ck_assert_uint_eq(ob->ntris, 2 * op->ntris);
	for (size_t t = 0; t < op->ntris; t++)
		ck_assert_msg(same_triangle(op, t, ob, t), "triangle %zu differs", t);
	ck_assert_double_eq_tol(volume(ob), 2 * volume(op), 1e-6 * volume(op));
	mesh_free(op);
	mesh_free(ob);
	mesh_free(both);
	mesh_free(copy);
	mesh_free(pair);
	mesh_free(t1);
	mesh_free(t2);
	mesh_free(s1);
	mesh_free(s2);
}
END_TEST

/*
 * Six crossing plates, each a square 1 mm wider than the box they close
 * around [0,10]^3: open sheets, yet together a closed box.
 */
static struct mesh *plate_box(void)
{
	struct mesh *m = NULL;

	for (int axis = 0; axis < 3; axis++)
		for (int side = 0; side < 2; side++) {
			double o[3], u[3] = {0, 0, 0}, v[3] = {0, 0, 0};
			const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
			o[axis] = side ? 10 : 0;
			o[a1] = o[a2] = -1;
			u[a1] = 12;
			v[a2] = 12;
			struct mesh *p = fx_grid(o, u, v, 1, 1);
			if (m) {
				struct mesh *joined = fx_concat(m, p);
				mesh_free(m);
				mesh_free(p);
				p = joined;
			}
			m = p;
		}
	return m;
}

/*
 * Proves an enclosure by open sheets, which the groups cannot see, sends
 * the repair back to the whole mesh: a cube inside a box of crossing
 * plates (separate groups, the cube first, a big sphere between them so
 * they fall into different batches) comes out as the plates and the
 * sphere alone give, the cube deleted inside the box.
 */
START_TEST(open_enclosure_repaired_whole)
{
	struct mesh *cube = fx_box(4, 4, 4, 6, 6, 6), *sphere = big_sphere(100, 0, 0, 10);
	struct mesh *plates = plate_box();
	struct mesh *with = concat3(cube, sphere, plates), *without = fx_concat(sphere, plates);
	struct repair_report rw, ro;
	struct mesh *ow = repair_ok(with, &rw), *oo = repair_ok(without, &ro);

	ck_assert(rw.batch_fallback);
	ck_assert_uint_eq(rw.batches, 1);
	ck_assert_uint_eq(rw.components, ro.components);
	ck_assert_uint_eq(ow->ntris, oo->ntris);
	ck_assert_double_eq_tol(volume(ow), volume(oo), 1e-9 * volume(oo));
	mesh_free(ow);
	mesh_free(oo);
	mesh_free(with);
	mesh_free(without);
	mesh_free(plates);
	mesh_free(sphere);
	mesh_free(cube);
}
END_TEST

/* fx_box facing inwards. */
static struct mesh *inward_box(double x0, double y0, double z0, double x1, double y1, double z1)
{
	struct mesh *m = fx_box(x0, y0, z0, x1, y1, z1);

	for (size_t t = 0; t < m->ntris; t++)
		fx_flip(m, t);
	return m;
}

/*
 * Proves a closed part's inner wall and what lies in its cavity stay with
 * it (no second repair needed): a hollow box with a core in its cavity,
 * listed as outer wall, a big sphere, inner wall and core (so that, apart,
 * they would fall into three batches), gives three parts and one cavity,
 * repaired in two batches.
 */
START_TEST(hollow_part_stays_one_group)
{
	struct mesh *outer = fx_box(0, 0, 0, 10, 10, 10), *cavity = inward_box(2, 2, 2, 8, 8, 8);
	struct mesh *core = fx_box(4, 4, 4, 6, 6, 6), *sphere = big_sphere(100, 0, 0, 10);
	struct mesh *hollow = concat3(outer, sphere, cavity), *in = fx_concat(hollow, core);
	struct repair_report r;
	struct mesh *out = repair_ok(in, &r);

	ck_assert_uint_eq(r.batches, 2);
	ck_assert(!r.batch_fallback);
	ck_assert_uint_eq(r.components, 3);
	ck_assert_uint_eq(r.cavities, 1);
	mesh_free(out);
	mesh_free(in);
	mesh_free(hollow);
	mesh_free(outer);
	mesh_free(cavity);
	mesh_free(core);
	mesh_free(sphere);
}
END_TEST

Suite *batch_suite(void)
{
	Suite *s = suite_create("batch");
	TCase *groups = tcase_create("groups");
	TCase *repair = tcase_create("repair");

	tcase_add_test(groups, groups_follow_the_reach);
	tcase_add_test(repair, apart_groups_match_their_own_repair);
	tcase_add_test(repair, open_enclosure_repaired_whole);
	tcase_add_test(repair, hollow_part_stays_one_group);
	tcase_set_timeout(repair, 120);
	suite_add_tcase(s, groups);
	suite_add_tcase(s, repair);
	return s;
}
