/* fixtures.c - generated test meshes (see fixtures.h). */
#include "fixtures.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static void die(const char *what)
{
	fprintf(stderr, "fixtures: %s\n", what);
	abort();
}

static uint32_t vert(struct mesh_builder *b, double x, double y, double z)
{
	const double p[3] = {x, y, z};
	uint32_t i;

	if (mesh_builder_vertex(b, p, &i, NULL))
		die("out of memory");
	return i;
}

static void tri(struct mesh_builder *b, uint32_t a, uint32_t c, uint32_t d)
{
	if (mesh_builder_triangle(b, a, c, d, NULL))
		die("out of memory");
}

/* Quad a-b-c-d, counter-clockwise from outside, as two triangles. */
static void quad(struct mesh_builder *b, uint32_t a, uint32_t c, uint32_t d, uint32_t e)
{
	tri(b, a, c, d);
	tri(b, a, d, e);
}

static struct mesh *finish(struct mesh_builder *b)
{
	struct mesh *m = mesh_builder_finish(b);

	if (!m)
		die("out of memory");
	return m;
}

struct mesh *fx_box(double x0, double y0, double z0, double x1, double y1, double z1)
{
	struct mesh_builder *b = mesh_builder_new(12);
	uint32_t v[8];

	if (!b)
		die("out of memory");
	/* Vertex i has x from bit 0, y from bit 1, z from bit 2. */
	for (int i = 0; i < 8; i++)
		v[i] = vert(b, i & 1 ? x1 : x0, i & 2 ? y1 : y0, i & 4 ? z1 : z0);
	quad(b, v[0], v[2], v[3], v[1]); /* z = z0 */
	quad(b, v[4], v[5], v[7], v[6]); /* z = z1 */
	quad(b, v[0], v[1], v[5], v[4]); /* y = y0 */
	quad(b, v[2], v[6], v[7], v[3]); /* y = y1 */
	quad(b, v[0], v[4], v[6], v[2]); /* x = x0 */
	quad(b, v[1], v[3], v[7], v[5]); /* x = x1 */
	return finish(b);
}

struct mesh *fx_torus(double R, double r, int nu, int nv)
{
	struct mesh_builder *b = mesh_builder_new((size_t)nu * nv * 2);
	uint32_t *idx = malloc((size_t)nu * nv * sizeof(*idx));

	if (!b || !idx)
		die("out of memory");
	for (int i = 0; i < nu; i++) {
		double u = 2 * M_PI * i / nu;
		for (int j = 0; j < nv; j++) {
			double w = 2 * M_PI * j / nv;
			idx[i * nv + j] = vert(b, (R + r * cos(w)) * cos(u), (R + r * cos(w)) * sin(u),
					       r * sin(w));
		}
	}
	for (int i = 0; i < nu; i++) {
		int i1 = (i + 1) % nu;
		for (int j = 0; j < nv; j++) {
			int j1 = (j + 1) % nv;
			quad(b, idx[i * nv + j], idx[i1 * nv + j], idx[i1 * nv + j1], idx[i * nv + j1]);
		}
	}
	free(idx);
	return finish(b);
}

struct mesh *fx_sphere(double cx, double cy, double cz, double r, int nlat, int nlon)
{
	struct mesh_builder *b = mesh_builder_new((size_t)nlat * nlon * 2);
	uint32_t *ring = malloc((size_t)(nlat + 1) * nlon * sizeof(*ring));
	uint32_t north, south;

	if (!b || !ring)
		die("out of memory");
	north = vert(b, cx, cy, cz + r);
	south = vert(b, cx, cy, cz - r);
	for (int k = 1; k < nlat; k++) {
		double th = M_PI * k / nlat;
		for (int j = 0; j < nlon; j++) {
			double ph = 2 * M_PI * j / nlon;
			ring[k * nlon + j] = vert(b, cx + r * sin(th) * cos(ph),
						  cy + r * sin(th) * sin(ph), cz + r * cos(th));
		}
	}
	for (int j = 0; j < nlon; j++) {
		int j1 = (j + 1) % nlon;
		tri(b, north, ring[nlon + j], ring[nlon + j1]);
		for (int k = 1; k + 1 < nlat; k++)
			quad(b, ring[k * nlon + j], ring[(k + 1) * nlon + j],
			     ring[(k + 1) * nlon + j1], ring[k * nlon + j1]);
		tri(b, south, ring[(nlat - 1) * nlon + j1], ring[(nlat - 1) * nlon + j]);
	}
	free(ring);
	return finish(b);
}

struct mesh *fx_concat(const struct mesh *a, const struct mesh *c)
{
	struct mesh_builder *b = mesh_builder_new(a->ntris + c->ntris);
	const struct mesh *parts[2] = {a, c};

	if (!b)
		die("out of memory");
	for (int p = 0; p < 2; p++) {
		for (size_t t = 0; t < parts[p]->ntris; t++) {
			uint32_t v[3];
			for (int k = 0; k < 3; k++) {
				const double *q = parts[p]->verts[parts[p]->tris[t][k]];
				v[k] = vert(b, q[0], q[1], q[2]);
			}
			tri(b, v[0], v[1], v[2]);
		}
	}
	return finish(b);
}

void fx_drop(struct mesh *m, size_t i)
{
	for (size_t t = i; t + 1 < m->ntris; t++)
		for (int k = 0; k < 3; k++)
			m->tris[t][k] = m->tris[t + 1][k];
	m->ntris--;
}

void fx_flip(struct mesh *m, size_t i)
{
	uint32_t tmp = m->tris[i][1];

	m->tris[i][1] = m->tris[i][2];
	m->tris[i][2] = tmp;
}

void fx_duplicate(struct mesh *m, size_t i, int flipped)
{
	if (m->ntris == m->cap_tris) {
		size_t cap = m->cap_tris ? m->cap_tris * 2 : 16;
		void *p = realloc(m->tris, cap * sizeof(*m->tris));
		if (!p)
			die("out of memory");
		m->tris = p;
		m->cap_tris = cap;
	}
	for (int k = 0; k < 3; k++)
		m->tris[m->ntris][k] = m->tris[i][k];
	m->ntris++;
	if (flipped)
		fx_flip(m, m->ntris - 1);
}

/*
 * Round to the nearest float.  The volatile is needed: GCC 12.2 at -O2
 * (SLP vectorizer) drops the narrowing in {(float)q[0], (float)q[1], ...}
 * for the first two of three coordinates and passes the doubles through.
 */
static double nearest_float(double x)
{
	volatile float f = (float)x;

	return f;
}

struct mesh *fx_to_float(const struct mesh *m)
{
	struct mesh_builder *b = mesh_builder_new(m->ntris);

	if (!b)
		die("out of memory");
	for (size_t t = 0; t < m->ntris; t++) {
		uint32_t v[3];
		for (int k = 0; k < 3; k++) {
			const double *q = m->verts[m->tris[t][k]];
			v[k] = vert(b, nearest_float(q[0]), nearest_float(q[1]), nearest_float(q[2]));
		}
		tri(b, v[0], v[1], v[2]);
	}
	return finish(b);
}

struct mesh *fx_grid(const double o[3], const double u[3], const double v[3], int nu, int nv)
{
	struct mesh_builder *b = mesh_builder_new((size_t)nu * nv * 2);
	uint32_t *idx = malloc((size_t)(nu + 1) * (nv + 1) * sizeof(*idx));

	if (!b || !idx)
		die("out of memory");
	for (int i = 0; i <= nu; i++) {
		double s = (double)i / nu;
		for (int j = 0; j <= nv; j++) {
			double t = (double)j / nv;
			idx[i * (nv + 1) + j] = vert(b, o[0] + s * u[0] + t * v[0],
						     o[1] + s * u[1] + t * v[1],
						     o[2] + s * u[2] + t * v[2]);
		}
	}
	for (int i = 0; i < nu; i++)
		for (int j = 0; j < nv; j++)
			quad(b, idx[i * (nv + 1) + j], idx[(i + 1) * (nv + 1) + j],
			     idx[(i + 1) * (nv + 1) + j + 1], idx[i * (nv + 1) + j + 1]);
	free(idx);
	return finish(b);
}

struct mesh *fx_triangle(const double a[3], const double c[3], const double d[3])
{
	struct mesh_builder *b = mesh_builder_new(1);
	uint32_t v0, v1, v2;

	if (!b)
		die("out of memory");
	v0 = vert(b, a[0], a[1], a[2]);
	v1 = vert(b, c[0], c[1], c[2]);
	v2 = vert(b, d[0], d[1], d[2]);
	tri(b, v0, v1, v2);
	return finish(b);
}

/* splitmix64: a fixed, portable generator, so seeds mean the same everywhere. */
static uint64_t fx_next(uint64_t *state)
{
	uint64_t z = (*state += 0x9e3779b97f4a7c15u);

	z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9u;
	z = (z ^ (z >> 27)) * 0x94d049bb133111ebu;
	return z ^ (z >> 31);
}

struct mesh *fx_random_triangles(unsigned seed, int n, double size)
{
	struct mesh_builder *b = mesh_builder_new((size_t)n);
	uint64_t state = seed;

	if (!b)
		die("out of memory");
	for (int t = 0; t < n; t++) {
		uint32_t v[3];
		for (int k = 0; k < 3; k++) {
			double p[3];
			for (int a = 0; a < 3; a++) /* 53 random bits in [0,1) */
				p[a] = size * (double)(fx_next(&state) >> 11) * 0x1p-53;
			v[k] = vert(b, p[0], p[1], p[2]);
		}
		tri(b, v[0], v[1], v[2]);
	}
	return finish(b);
}

struct mesh *fx_klein_bottle(double R, double scale, int nu, int nv)
{
	struct mesh_builder *b = mesh_builder_new((size_t)nu * nv * 2);
	uint32_t *idx = malloc((size_t)nu * nv * sizeof(*idx));

	if (!b || !idx)
		die("out of memory");
	for (int i = 0; i < nu; i++) {
		double u = 2 * M_PI * i / nu;
		for (int j = 0; j < nv; j++) {
			double v = 2 * M_PI * (j + 0.5) / nv;
			double r = R + cos(u / 2) * sin(v) - sin(u / 2) * sin(2 * v);
			double z = sin(u / 2) * sin(v) + cos(u / 2) * sin(2 * v);
			idx[i * nv + j] = vert(b, scale * r * cos(u), scale * r * sin(u), scale * z);
		}
	}
	/*
	 * Point (u + 2pi, v) is point (u, -v); with rows at v_j = 2pi(j+1/2)/nv,
	 * -v_j is row nv-1-j.  So past the last column the strip continues on
	 * column 0 with its rows reversed.
	 */
	for (int i = 0; i < nu; i++) {
		for (int j = 0; j < nv; j++) {
			int j1 = (j + 1) % nv;
			uint32_t a = idx[i * nv + j], d = idx[i * nv + j1], c, e;
			if (i + 1 < nu) {
				c = idx[(i + 1) * nv + j];
				e = idx[(i + 1) * nv + j1];
			} else {
				c = idx[nv - 1 - j];
				e = idx[nv - 1 - j1];
			}
			quad(b, a, c, e, d);
		}
	}
	free(idx);
	return finish(b);
}
