/*
 * surfsample.c - even samples on triangles (surfsample.h).
 */
#include "surfsample.h"

#include <math.h>

#include "vec3.h"

size_t surfsample_k(const double a[3], const double b[3], const double c[3], double spacing)
{
	double longest = fmax(vec3_dist(a, b), fmax(vec3_dist(b, c), vec3_dist(c, a)));
	double k = ceil(longest / spacing);

	if (!(k >= 1)) /* also NaN */
		return 1;
	return k > SURFSAMPLE_K_MAX ? SURFSAMPLE_K_MAX : (size_t)k;
}

/* a + s (b - a) + t (c - a) */
static void at(const double a[3], const double b[3], const double c[3], double s, double t,
	       double out[3])
{
	for (int d = 0; d < 3; d++)
		out[d] = a[d] + s * (b[d] - a[d]) + t * (c[d] - a[d]);
}

void surfsample_centroids(const double a[3], const double b[3], const double c[3], size_t k,
			  double (*out)[3])
{
	size_t n = 0;
	double step = 1.0 / (double)k;

	for (size_t i = 0; i < k; i++)
		for (size_t j = 0; i + j < k; j++) {
			/* the sub-triangle pointing like abc, then the one upside down */
			at(a, b, c, ((double)i + 1.0 / 3) * step, ((double)j + 1.0 / 3) * step,
			   out[n++]);
			if (i + j + 1 < k)
				at(a, b, c, ((double)i + 2.0 / 3) * step,
				   ((double)j + 2.0 / 3) * step, out[n++]);
		}
}

void surfsample_grid(const double a[3], const double b[3], const double c[3], size_t k,
		     double (*out)[3])
{
	size_t n = 0;

	for (size_t i = 0; i <= k; i++)
		for (size_t j = 0; i + j <= k; j++)
			at(a, b, c, (double)i / (double)k, (double)j / (double)k, out[n++]);
}

bool surfsample_normal(const double a[3], const double b[3], const double c[3], double n[3],
		       double *area)
{
	const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
	const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
	double len;

	n[0] = u[1] * v[2] - u[2] * v[1];
	n[1] = u[2] * v[0] - u[0] * v[2];
	n[2] = u[0] * v[1] - u[1] * v[0];
	len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
	*area = 0.5 * len;
	if (!(len > 0) || !isfinite(len)) {
		n[0] = n[1] = n[2] = 0;
		*area = 0;
		return false;
	}
	for (int d = 0; d < 3; d++)
		n[d] /= len;
	return true;
}

double surfsample_area(const struct mesh *m)
{
	double sum = 0;

	for (size_t t = 0; t < m->ntris; t++)
		sum += vec3_tri_area(m->verts[m->tris[t][0]], m->verts[m->tris[t][1]],
				     m->verts[m->tris[t][2]]);
	return sum;
}

/* (b - a) x (p - a) . n: the side of edge a b that p lies on. */
static double edge_side(const double a[3], const double b[3], const double p[3], const double n[3])
{
	const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
	const double v[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};

	return (u[1] * v[2] - u[2] * v[1]) * n[0] + (u[2] * v[0] - u[0] * v[2]) * n[1] +
	       (u[0] * v[1] - u[1] * v[0]) * n[2];
}

bool surfsample_inside(const double a[3], const double b[3], const double c[3], const double n[3],
		       const double p[3])
{
	return edge_side(a, b, p, n) >= 0 && edge_side(b, c, p, n) >= 0 && edge_side(c, a, p, n) >= 0;
}
