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

/* Prism over the convex polygon (x[i], y[i]) (counter-clockwise) from z0 to
 * z1, fan-triangulated caps. */
static void add_prism(struct mesh_builder *b, const double *x, const double *y, int n, double z0,
		      double z1)
{
	uint32_t lo[256], hi[256];

	if (n < 3 || n > 256)
		die("prism needs 3 to 256 corners");
	for (int i = 0; i < n; i++) {
		lo[i] = vert(b, x[i], y[i], z0);
		hi[i] = vert(b, x[i], y[i], z1);
	}
	for (int i = 1; i + 1 < n; i++) {
		tri(b, lo[0], lo[i + 1], lo[i]);
		tri(b, hi[0], hi[i], hi[i + 1]);
	}
	for (int i = 0; i < n; i++)
		quad(b, lo[i], lo[(i + 1) % n], hi[(i + 1) % n], hi[i]);
}

/* Regular n-gon of radius r around (cx, cy), vertices on the circle. */
static void ngon(double cx, double cy, double r, int n, double *x, double *y)
{
	for (int i = 0; i < n; i++) {
		x[i] = cx + r * cos(2 * M_PI * i / n);
		y[i] = cy + r * sin(2 * M_PI * i / n);
	}
}

/* The same n-gon as points. */
static void ngon_xy(double cx, double cy, double r, int n, double (*xy)[2])
{
	for (int i = 0; i < n; i++) {
		xy[i][0] = cx + r * cos(2 * M_PI * i / n);
		xy[i][1] = cy + r * sin(2 * M_PI * i / n);
	}
}

struct mesh *fx_cylinder(double cx, double cy, double r, double h, int n)
{
	struct mesh_builder *b = mesh_builder_new(4 * (size_t)n);
	double x[256], y[256];

	if (!b)
		die("out of memory");
	ngon(cx, cy, r, n, x, y);
	add_prism(b, x, y, n, 0, h);
	return finish(b);
}

struct mesh *fx_wedge(double len, double base, double h)
{
	struct mesh_builder *b = mesh_builder_new(6);
	const double x[3] = {0, len, len}, y[3] = {0, -base / 2, base / 2};

	if (!b)
		die("out of memory");
	add_prism(b, x, y, 3, 0, h);
	return finish(b);
}

struct mesh *fx_tube(double R, double r, double h, int n)
{
	struct mesh_builder *b = mesh_builder_new(8 * (size_t)n);
	double ox[256], oy[256], ix[256], iy[256];
	uint32_t o0[256], o1[256], i0[256], i1[256];

	if (!b)
		die("out of memory");
	if (!(r > 0 && r < R))
		die("fx_tube: the inner radius must be in (0, R)");
	ngon(0, 0, R, n, ox, oy);
	ngon(0, 0, r, n, ix, iy);
	for (int k = 0; k < n; k++) {
		o0[k] = vert(b, ox[k], oy[k], 0);
		o1[k] = vert(b, ox[k], oy[k], h);
		i0[k] = vert(b, ix[k], iy[k], 0);
		i1[k] = vert(b, ix[k], iy[k], h);
	}
	for (int k = 0; k < n; k++) {
		int j = (k + 1) % n;
		quad(b, o0[k], o0[j], o1[j], o1[k]); /* outside, facing out */
		quad(b, i0[j], i0[k], i1[k], i1[j]); /* inside, facing the axis */
		quad(b, o1[k], o1[j], i1[j], i1[k]); /* top */
		quad(b, o0[j], o0[k], i0[k], i0[j]); /* bottom */
	}
	return finish(b);
}

/* The square x0..x1, y0..y1 walked counter-clockwise from (x0, y0), a point
 * every step mm; returns the number of points written to xy (at most cap). */
static int square_loop(double x0, double y0, double x1, double y1, double step, double (*xy)[2],
		       int cap)
{
	const double cx[4] = {x0, x1, x1, x0}, cy[4] = {y0, y0, y1, y1};
	int n = 0;

	for (int s = 0; s < 4; s++) {
		double ax = cx[s], ay = cy[s], bx = cx[(s + 1) % 4], by = cy[(s + 1) % 4];
		int k = (int)lround(hypot(bx - ax, by - ay) / step);
		for (int i = 0; i < k; i++, n++) {
			if (n == cap)
				die("square_loop: too many points");
			xy[n][0] = ax + (bx - ax) * i / k;
			xy[n][1] = ay + (by - ay) * i / k;
		}
	}
	return n;
}

/* Angle of (x, y) around (cx, cy) in [0, 2 pi). */
static double angle_of(double x, double y, double cx, double cy)
{
	double a = atan2(y - cy, x - cx);
	return a < 0 ? a + 2 * M_PI : a;
}

/*
 * Triangulate, at height z, the ring between the loop o (n points,
 * counter-clockwise, star-shaped from (cx, cy)) and the convex hole h (m
 * points, counter-clockwise, around (cx, cy)) by zipping the two loops in
 * angular order; up gives the normal +z, else -z.  Both loops must be
 * dense enough that no triangle spans a large angle.
 */
static void zip_ring(struct mesh_builder *b, const double (*o)[2], int n, const double (*h)[2],
		     int m, double cx, double cy, double z, int up)
{
	int os = 0, hs = 0;

	for (int i = 1; i < n; i++)
		if (angle_of(o[i][0], o[i][1], cx, cy) < angle_of(o[os][0], o[os][1], cx, cy))
			os = i;
	for (int j = 1; j < m; j++)
		if (angle_of(h[j][0], h[j][1], cx, cy) < angle_of(h[hs][0], h[hs][1], cx, cy))
			hs = j;
	int i = 0, j = 0;
	while (i < n || j < m) {
		const double *oi = o[(os + i) % n], *oj = o[(os + i + 1) % n];
		const double *hi = h[(hs + j) % m], *hj = h[(hs + j + 1) % m];
		double ao = i < n ? angle_of(oj[0], oj[1], cx, cy) + (i + 1 == n ? 2 * M_PI : 0) : INFINITY;
		double ah = j < m ? angle_of(hj[0], hj[1], cx, cy) + (j + 1 == m ? 2 * M_PI : 0) : INFINITY;
		uint32_t a = vert(b, oi[0], oi[1], z), c, d;
		if (ao <= ah) {
			c = vert(b, oj[0], oj[1], z);
			d = vert(b, hi[0], hi[1], z);
			i++;
		} else {
			c = vert(b, hj[0], hj[1], z);
			d = vert(b, hi[0], hi[1], z);
			j++;
		}
		if (up)
			tri(b, a, c, d);
		else
			tri(b, a, d, c);
	}
}

/* Side walls of the loop xy (n points, counter-clockwise) from z0 to z1;
 * inward (a hole's wall) when hole is set. */
static void loop_walls(struct mesh_builder *b, const double (*xy)[2], int n, double z0, double z1,
		       int hole)
{
	for (int i = 0; i < n; i++) {
		int j = (i + 1) % n;
		uint32_t li = vert(b, xy[i][0], xy[i][1], z0), lj = vert(b, xy[j][0], xy[j][1], z0);
		uint32_t hi = vert(b, xy[i][0], xy[i][1], z1), hj = vert(b, xy[j][0], xy[j][1], z1);
		if (hole)
			quad(b, li, hi, hj, lj);
		else
			quad(b, li, lj, hj, hi);
	}
}

struct mesh *fx_plate_holes(void)
{
	struct mesh_builder *b = mesh_builder_new(0);
	double left[120][2], right[120][2], outer[160][2], sq[64][2], circ[64][2];
	int nl, nr, no, ns;

	if (!b)
		die("out of memory");
	/* Two cells (x 0..20 and 20..40), one hole each, so each cap is a ring
	 * around a convex hole; the cells share the vertices on x = 20. */
	nl = square_loop(0, 0, 20, 40, 1, left, 120);
	nr = square_loop(20, 0, 40, 40, 1, right, 120);
	no = square_loop(0, 0, 40, 40, 1, outer, 160);
	ns = square_loop(8, 16, 16, 24, 0.5, sq, 64);
	ngon_xy(28, 20, 4, 64, circ);
	for (int up = 0; up < 2; up++) {
		zip_ring(b, (const double(*)[2])left, nl, (const double(*)[2])sq, ns, 12, 20,
			 up ? 3 : 0, up);
		zip_ring(b, (const double(*)[2])right, nr, (const double(*)[2])circ, 64, 28, 20,
			 up ? 3 : 0, up);
	}
	loop_walls(b, (const double(*)[2])outer, no, 0, 3, 0);
	loop_walls(b, (const double(*)[2])sq, ns, 0, 3, 1);
	loop_walls(b, (const double(*)[2])circ, 64, 0, 3, 1);
	return finish(b);
}

/*
 * The profile (x[i], z[i]) (counter-clockwise seen from -y, x right, z up)
 * extruded from y = 0 to y = depth; tris (ntri triples of profile indices,
 * counter-clockwise) triangulate the profile for the two caps.
 */
static struct mesh *extrude_y(const double *x, const double *z, int n, const int (*tris)[3],
			      int ntri, double depth)
{
	struct mesh_builder *b = mesh_builder_new(2 * (size_t)(n + ntri));
	uint32_t f[16], k[16];

	if (!b || n > 16)
		die("out of memory");
	for (int i = 0; i < n; i++) {
		f[i] = vert(b, x[i], 0, z[i]);
		k[i] = vert(b, x[i], depth, z[i]);
	}
	for (int t = 0; t < ntri; t++) {
		tri(b, f[tris[t][0]], f[tris[t][1]], f[tris[t][2]]);
		tri(b, k[tris[t][0]], k[tris[t][2]], k[tris[t][1]]);
	}
	for (int i = 0; i < n; i++) {
		int j = (i + 1) % n;
		quad(b, f[i], k[i], k[j], f[j]);
	}
	return finish(b);
}

struct mesh *fx_overhang(void)
{
	static const double x[] = {0, 10, 10, 20, 0}, z[] = {0, 0, 5, 15, 15};
	static const int t[][3] = {{4, 0, 1}, {4, 1, 2}, {4, 2, 3}};

	return extrude_y(x, z, 5, t, 3, 10);
}

struct mesh *fx_bridge(void)
{
	static const double x[] = {0, 5, 5, 15, 15, 20, 20, 0}, z[] = {0, 0, 10, 10, 0, 0, 12, 12};
	static const int t[][3] = {{0, 1, 2}, {0, 2, 7}, {2, 3, 6}, {2, 6, 7}, {3, 4, 5}, {3, 5, 6}};

	return extrude_y(x, z, 8, t, 6, 10);
}

struct mesh *fx_shelf(void)
{
	static const double x[] = {0, 12, 12, 4, 4, 20, 20, 0}, z[] = {0, 0, 2, 2, 9, 9, 10, 10};
	static const int t[][3] = {{0, 1, 2}, {0, 2, 3}, {0, 3, 7}, {3, 4, 7}, {4, 5, 6}, {4, 6, 7}};

	return extrude_y(x, z, 8, t, 6, 10);
}

struct mesh *fx_cube_without(double size, unsigned drop)
{
	struct mesh *m = fx_box(0, 0, 0, size, size, size);

	for (int t = 11; t >= 0; t--)
		if (drop & (1u << t))
			fx_drop(m, (size_t)t);
	return m;
}

struct mesh *fx_jitter(const struct mesh *m, double amount, unsigned seed)
{
	struct mesh_builder *b = mesh_builder_new(m->ntris);
	uint64_t state = seed;

	if (!b)
		die("out of memory");
	for (size_t t = 0; t < m->ntris; t++) {
		uint32_t v[3];
		for (int k = 0; k < 3; k++) {
			const double *p = m->verts[m->tris[t][k]];
			double q[3];
			for (int a = 0; a < 3; a++) /* uniform in [-amount, amount) */
				q[a] = p[a] + amount * (2 * (double)(fx_next(&state) >> 11) * 0x1p-53 - 1);
			v[k] = vert(b, q[0], q[1], q[2]);
		}
		tri(b, v[0], v[1], v[2]);
	}
	return finish(b);
}

struct mesh *fx_split_gap(const struct mesh *m, double z0, double gap)
{
	struct mesh_builder *b = mesh_builder_new(m->ntris);

	if (!b)
		die("out of memory");
	for (size_t t = 0; t < m->ntris; t++) {
		const uint32_t *c = m->tris[t];
		const double zc = (m->verts[c[0]][2] + m->verts[c[1]][2] + m->verts[c[2]][2]) / 3;
		const double dz = zc < z0 ? -gap : 0;
		uint32_t v[3];
		for (int k = 0; k < 3; k++) {
			const double *p = m->verts[c[k]];
			v[k] = vert(b, p[0], p[1], p[2] + dz);
		}
		tri(b, v[0], v[1], v[2]);
	}
	return finish(b);
}

struct mesh *fx_soup(unsigned seed, int n, double box, double size)
{
	struct mesh_builder *b = mesh_builder_new((size_t)n);
	uint64_t state = seed;

	if (!b)
		die("out of memory");
	for (int t = 0; t < n; t++) {
		double c[3];
		uint32_t v[3];
		for (int a = 0; a < 3; a++) /* 53 random bits in [0,1) */
			c[a] = box * (double)(fx_next(&state) >> 11) * 0x1p-53;
		for (int k = 0; k < 3; k++) {
			double p[3];
			for (int a = 0; a < 3; a++)
				p[a] = c[a] + size * ((double)(fx_next(&state) >> 11) * 0x1p-53 - 0.5);
			v[k] = vert(b, p[0], p[1], p[2]);
		}
		tri(b, v[0], v[1], v[2]);
	}
	return finish(b);
}

struct mesh *fx_hemisphere(double r, int nlat, int nlon, int upper, double dz, double turn)
{
	struct mesh_builder *b = mesh_builder_new((size_t)nlat * nlon);
	const int k0 = upper ? 0 : nlat / 2, k1 = upper ? nlat / 2 : nlat;

	if (!b)
		die("out of memory");
	for (int k = k0; k < k1; k++)
		for (int j = 0; j < nlon; j++) {
			uint32_t v[2][2];
			for (int a = 0; a < 2; a++)
				for (int c = 0; c < 2; c++) {
					const double th = M_PI * (k + a) / nlat;
					const double ph = 2 * M_PI * (j + c) / nlon + turn;
					v[a][c] = vert(b, r * sin(th) * cos(ph), r * sin(th) * sin(ph),
						       r * cos(th) + dz);
				}
			if (k > 0) /* no triangle at the north pole's ring of points */
				tri(b, v[0][0], v[1][0], v[0][1]);
			if (k + 1 < nlat)
				tri(b, v[1][0], v[1][1], v[0][1]);
		}
	return finish(b);
}
