/*
 * gen_mesh.c - write a generated mesh for the benchmarks:
 *   gen_mesh torus NU NV OUT.stl     torus with NU x NV quads (2*NU*NV triangles)
 *   gen_mesh spheres N OUT.stl       N overlapping spheres (self-intersections)
 *   gen_mesh sphere NLAT NLON OUT.stl
 *                                    one UV sphere of radius 50 (2*NLON*(NLAT-1)
 *                                    triangles; "sphere 501 1000" is 1M), poles
 *                                    where NLON thin triangles meet
 *   gen_mesh twospheres NLAT NLON OUT.stl
 *                                    two UV spheres of radius 20 whose centres
 *                                    are 0.6 r apart (one intersection curve)
 *   gen_mesh scan NU NV JITTER OUT.stl
 *                                    "scan-like": a torus whose vertices are moved
 *                                    by pseudo-random offsets of up to JITTER times
 *                                    the smallest grid spacing in each axis, so
 *                                    triangles fold over their neighbours and cut
 *                                    through them (JITTER 0.7 folds many)
 *   gen_mesh box SX SY SZ OUT.stl    an SX x SY x SZ mm box at the origin (mm, may
 *                                    have decimals: "box 20 0.4 10" is a wall of 0.4)
 *   gen_mesh cylinder R H N OUT.stl  a cylinder of radius R, height H mm: a regular
 *                                    N-gon (3..256) prism
 *   gen_mesh wedge L W H OUT.stl     a triangular prism H mm tall, its tip at the
 *                                    origin and W mm wide at x = L (thin walls)
 *   gen_mesh tube R r H N OUT.stl    a tube H mm tall between N-gons (3..256) of
 *                                    radius r and R (a ring-shaped wall)
 *   gen_mesh soup N SIZE SEED OUT.stl
 *                                    N random triangles, each with corners uniform in
 *                                    its own SIZE mm cube, the cubes scattered
 *                                    uniformly at a density of 8 per SIZE^3: a soup
 *                                    whose triangles each cross a few others, as in a
 *                                    broken download (corners everywhere in one cube,
 *                                    fx_random_triangles, would make
 *                                    every triangle cross a fixed share of all others)
 *   gen_mesh convert IN SIZE OUT.stl
 *                                    IN (STL, OBJ or OFF) moved to the origin and
 *                                    scaled so its largest extent is SIZE mm, as
 *                                    seed 000's experiments scale their models
 *   gen_mesh same A B                exit 0 when meshes A and B have the same triangles
 *                                    in the same order over bit-identical corners
 *                                    (normals and headers aside), else 1
 *   gen_mesh plate|overhang|bridge|shelf OUT.stl
 *                                    the slicer's test models (tests/fixtures.h):
 *                                    a plate with a square and a round hole, a 45
 *                                    degree overhang, a 10 mm bridge between pillars,
 *                                    a shelf over a lower step of the same part
 * Every mesh is deterministic: the same arguments give the same file.
 */
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fixtures.h"
#include "meshio.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* splitmix64: a small deterministic generator, so runs are repeatable. */
static uint64_t next_random(uint64_t *state)
{
	uint64_t z = (*state += 0x9e3779b97f4a7c15ull);

	z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
	z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
	return z ^ (z >> 31);
}

/* A uniform double in [-1, 1). */
static double uniform(uint64_t *state)
{
	return (double)(next_random(state) >> 11) * 0x1.0p-52 - 1.0;
}

/* Move every welded vertex of m by up to amp (mm) in each axis. */
static void jitter(struct mesh *m, double amp, uint64_t seed)
{
	for (size_t i = 0; i < m->nverts; i++)
		for (int k = 0; k < 3; k++)
			m->verts[i][k] += amp * uniform(&seed);
}

/* Whole number argument in [lo, hi], or exit with a usage message. */
static int int_arg(const char *s, int lo, int hi)
{
	char *end;
	long v = strtol(s, &end, 10);

	if (end == s || *end || v < lo || v > hi) {
		fprintf(stderr, "gen_mesh: '%s' is not a whole number from %d to %d\n", s, lo, hi);
		exit(2);
	}
	return (int)v;
}

/* Length argument in mm, (0, 10000], or exit with a usage message. */
static double mm_arg(const char *s)
{
	char *end;
	double v = strtod(s, &end);

	if (end == s || *end || !(v > 0 && v <= 10000)) {
		fprintf(stderr, "gen_mesh: '%s' is not a length in mm from 0 to 10000\n", s);
		exit(2);
	}
	return v;
}

/* Move m's bounding box to the origin and scale its largest extent to size. */
static void fit(struct mesh *m, double size)
{
	double lo[3], hi[3], ext = 0;

	mesh_bbox(m, lo, hi);
	for (int k = 0; k < 3; k++)
		ext = fmax(ext, hi[k] - lo[k]);
	for (size_t i = 0; i < m->nverts; i++)
		for (int k = 0; k < 3; k++)
			m->verts[i][k] = ext > 0 ? (m->verts[i][k] - lo[k]) * (size / ext) : 0;
}

/* Whether a and b list the same triangles, in order, over identical corners. */
static bool same_triangles(const struct mesh *a, const struct mesh *b)
{
	if (a->ntris != b->ntris)
		return false;
	for (size_t t = 0; t < a->ntris; t++)
		for (int k = 0; k < 3; k++)
			if (memcmp(a->verts[a->tris[t][k]], b->verts[b->tris[t][k]],
				   sizeof(a->verts[0])))
				return false;
	return true;
}

static void usage(void)
{
	fprintf(stderr, "usage: gen_mesh torus NU NV OUT.stl | gen_mesh spheres N OUT.stl\n"
			"       gen_mesh sphere NLAT NLON OUT.stl\n"
			"       gen_mesh twospheres NLAT NLON OUT.stl | gen_mesh scan NU NV JITTER "
			"OUT.stl\n"
			"       gen_mesh box SX SY SZ OUT.stl | gen_mesh cylinder R H N OUT.stl\n"
			"       gen_mesh wedge L W H OUT.stl | gen_mesh tube R r H N OUT.stl\n"
			"       gen_mesh soup N SIZE SEED OUT.stl | gen_mesh convert IN SIZE OUT.stl\n"
			"       gen_mesh same A B | gen_mesh plate|overhang|bridge|shelf OUT.stl\n");
	exit(2);
}

int main(int argc, char **argv)
{
	struct st_error err = {0};
	struct mesh *m = NULL;

	if (argc == 4 && !strcmp(argv[1], "same")) {
		struct mesh *b = NULL;
		if (meshio_read(argv[2], MESHIO_AUTO, &m, NULL, &err) ||
		    meshio_read(argv[3], MESHIO_AUTO, &b, NULL, &err)) {
			fprintf(stderr, "gen_mesh: %s\n", err.msg);
			mesh_free(m);
			return 2;
		}
		const bool same = same_triangles(m, b);
		mesh_free(m);
		mesh_free(b);
		return same ? 0 : 1;
	}
	if (argc == 5 && !strcmp(argv[1], "torus")) {
		m = fx_torus(60.0, 20.0, int_arg(argv[2], 3, 100000), int_arg(argv[3], 3, 100000));
	} else if (argc == 4 && !strcmp(argv[1], "spheres")) {
		int n = int_arg(argv[2], 1, 1000);
		m = fx_sphere(0, 0, 0, 10, 64, 128);
		for (int i = 1; i < n; i++) {
			struct mesh *s = fx_sphere(i * 7.0, 0, 0, 10, 64, 128), *both;
			both = fx_concat(m, s);
			mesh_free(m);
			mesh_free(s);
			m = both;
		}
	} else if (argc == 5 && !strcmp(argv[1], "sphere")) {
		m = fx_sphere(0, 0, 0, 50, int_arg(argv[2], 3, 100000), int_arg(argv[3], 3, 100000));
	} else if (argc == 5 && !strcmp(argv[1], "twospheres")) {
		int nlat = int_arg(argv[2], 3, 100000), nlon = int_arg(argv[3], 3, 100000);
		/* Off the x axis by a little, so the two grids do not line up. */
		struct mesh *a = fx_sphere(0, 0, 0, 20, nlat, nlon);
		struct mesh *b = fx_sphere(12.0, 0.37, -0.23, 20, nlat, nlon);

		m = fx_concat(a, b);
		mesh_free(a);
		mesh_free(b);
	} else if (argc == 6 && !strcmp(argv[1], "scan")) {
		int nu = int_arg(argv[2], 3, 100000), nv = int_arg(argv[3], 3, 100000);
		char *end;
		double j = strtod(argv[4], &end);
		/* Grid spacing of fx_torus(60, 20): around the hole and around the tube. */
		double du = 2 * M_PI * (60.0 - 20.0) / nu, dv = 2 * M_PI * 20.0 / nv;

		if (end == argv[4] || *end || !(j >= 0 && j <= 10))
			usage();
		m = fx_torus(60.0, 20.0, nu, nv);
		jitter(m, j * (du < dv ? du : dv), 20151215u);
	} else if (argc == 6 && !strcmp(argv[1], "box")) {
		m = fx_box(0, 0, 0, mm_arg(argv[2]), mm_arg(argv[3]), mm_arg(argv[4]));
	} else if (argc == 6 && !strcmp(argv[1], "cylinder")) {
		m = fx_cylinder(0, 0, mm_arg(argv[2]), mm_arg(argv[3]), int_arg(argv[4], 3, 256));
	} else if (argc == 6 && !strcmp(argv[1], "wedge")) {
		m = fx_wedge(mm_arg(argv[2]), mm_arg(argv[3]), mm_arg(argv[4]));
	} else if (argc == 7 && !strcmp(argv[1], "tube")) {
		m = fx_tube(mm_arg(argv[2]), mm_arg(argv[3]), mm_arg(argv[4]), int_arg(argv[5], 3, 256));
	} else if (argc == 6 && !strcmp(argv[1], "soup")) {
		const int n = int_arg(argv[2], 1, 50000000);
		const double size = mm_arg(argv[3]);
		/* Boxes of side size at 8 per size^3 fill a cube of this side. */
		m = fx_soup((unsigned)int_arg(argv[4], 0, 1 << 30), n, size * cbrt((double)n) / 2,
			    size);
	} else if (argc == 5 && !strcmp(argv[1], "convert")) {
		if (meshio_read(argv[2], MESHIO_AUTO, &m, NULL, &err)) {
			fprintf(stderr, "gen_mesh: %s\n", err.msg);
			return 1;
		}
		fit(m, mm_arg(argv[3]));
	} else if (argc == 3 && !strcmp(argv[1], "plate")) {
		m = fx_plate_holes();
	} else if (argc == 3 && !strcmp(argv[1], "overhang")) {
		m = fx_overhang();
	} else if (argc == 3 && !strcmp(argv[1], "bridge")) {
		m = fx_bridge();
	} else if (argc == 3 && !strcmp(argv[1], "shelf")) {
		m = fx_shelf();
	} else {
		usage();
	}
	if (!m) {
		fprintf(stderr, "gen_mesh: out of memory\n");
		return 1;
	}
	if (meshio_write_stl(argv[argc - 1], m, MESHIO_STL_BINARY, &err)) {
		fprintf(stderr, "gen_mesh: %s\n", err.msg);
		mesh_free(m);
		return 1;
	}
	printf("%s: %zu triangles, %zu vertices\n", argv[argc - 1], m->ntris, m->nverts);
	mesh_free(m);
	return 0;
}
