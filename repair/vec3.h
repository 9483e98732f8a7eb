/*
 * vec3.h - private to repair/: double-precision 3-D helpers for figures that
 * decide nothing exactly (distances and areas for reports and tolerances,
 * and proximity tests with a wide margin).
 */
#ifndef STRATUM_REPAIR_VEC3_H
#define STRATUM_REPAIR_VEC3_H

#include <math.h>
#include <stddef.h>

/* Euclidean distance between a and b. */
static inline double vec3_dist(const double a[3], const double b[3])
{
	const double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];

	return sqrt(dx * dx + dy * dy + dz * dz);
}

/* n = (b - a) x (c - a): normal of triangle abc by the right-hand rule,
 * twice its area long. */
static inline void vec3_area_normal(const double a[3], const double b[3], const double c[3],
				    double n[3])
{
	const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
	const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};

	n[0] = u[1] * v[2] - u[2] * v[1];
	n[1] = u[2] * v[0] - u[0] * v[2];
	n[2] = u[0] * v[1] - u[1] * v[0];
}

/* Area of triangle abc. */
static inline double vec3_tri_area(const double a[3], const double b[3], const double c[3])
{
	double n[3];

	vec3_area_normal(a, b, c, n);
	return 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

/* Distance from p to the closed triangle abc (NaN when abc has no area). */
static inline double vec3_point_triangle_distance(const double p[3], const double a[3],
						   const double b[3], const double c[3])
{
	const double ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
	const double ac[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
	const double ap[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
	const double n[3] = {ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2],
			     ab[0] * ac[1] - ab[1] * ac[0]};
	const double nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
	const double h = (ap[0] * n[0] + ap[1] * n[1] + ap[2] * n[2]) / nn;
	const double q[3] = {p[0] - h * n[0], p[1] - h * n[1], p[2] - h * n[2]};
	const double *v[3] = {a, b, c};
	double best = HUGE_VAL;
	bool inside = true;

	/* q is p's foot in the plane; inside when on the inner side of
	 * every edge, else the nearest point is on an edge. */
	for (int k = 0; k < 3; k++) {
		const double *u = v[k], *w = v[(k + 1) % 3];
		const double e[3] = {w[0] - u[0], w[1] - u[1], w[2] - u[2]};
		const double uq[3] = {q[0] - u[0], q[1] - u[1], q[2] - u[2]};
		const double x[3] = {e[1] * uq[2] - e[2] * uq[1], e[2] * uq[0] - e[0] * uq[2],
				     e[0] * uq[1] - e[1] * uq[0]};
		if (x[0] * n[0] + x[1] * n[1] + x[2] * n[2] < 0)
			inside = false;
		const double up[3] = {p[0] - u[0], p[1] - u[1], p[2] - u[2]};
		double t = (up[0] * e[0] + up[1] * e[1] + up[2] * e[2]) /
			   (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
		t = t < 0 ? 0 : t > 1 ? 1 : t;
		const double f[3] = {u[0] + t * e[0], u[1] + t * e[1], u[2] + t * e[2]};
		best = fmin(best, vec3_dist(p, f));
	}
	return inside ? fabs(h) * sqrt(nn) : best;
}


/* Distance between the segments pq and rs (Ericson, Real-Time Collision
 * Detection, 5.1.9), robust for segments of length 0. */
static inline double vec3_segment_distance(const double p[3], const double q[3], const double r[3],
					   const double s[3])
{
	const double d1[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
	const double d2[3] = {s[0] - r[0], s[1] - r[1], s[2] - r[2]};
	const double w[3] = {p[0] - r[0], p[1] - r[1], p[2] - r[2]};
	const double a = d1[0] * d1[0] + d1[1] * d1[1] + d1[2] * d1[2];
	const double e = d2[0] * d2[0] + d2[1] * d2[1] + d2[2] * d2[2];
	const double f = d2[0] * w[0] + d2[1] * w[1] + d2[2] * w[2];
	double sc = 0, tc = 0;

	if (a == 0 && e == 0)
		return vec3_dist(p, r);
	if (a == 0) {
		tc = fmin(fmax(f / e, 0), 1);
	} else {
		const double c = d1[0] * w[0] + d1[1] * w[1] + d1[2] * w[2];
		if (e == 0) {
			sc = fmin(fmax(-c / a, 0), 1);
		} else {
			const double b = d1[0] * d2[0] + d1[1] * d2[1] + d1[2] * d2[2];
			const double den = a * e - b * b;
			sc = den > 0 ? fmin(fmax((b * f - c * e) / den, 0), 1) : 0;
			tc = (b * sc + f) / e;
			if (tc < 0) {
				tc = 0;
				sc = fmin(fmax(-c / a, 0), 1);
			} else if (tc > 1) {
				tc = 1;
				sc = fmin(fmax((b - c) / a, 0), 1);
			}
		}
	}
	const double x[3] = {p[0] + sc * d1[0], p[1] + sc * d1[1], p[2] + sc * d1[2]};
	const double y[3] = {r[0] + tc * d2[0], r[1] + tc * d2[1], r[2] + tc * d2[2]};
	return vec3_dist(x, y);
}

/*
 * A unit in the last place, with mantissa_bits bits (24: float32, 53:
 * double), at the largest |coordinate| of the nv points (0 when all are 0):
 * points closer than this are one point once written at that precision.
 */
static inline double vec3_ulp(const double (*verts)[3], size_t nv, int mantissa_bits)
{
	double big = 0;
	int e;

	for (size_t v = 0; v < nv; v++)
		for (int k = 0; k < 3; k++)
			big = fmax(big, fabs(verts[v][k]));
	if (big == 0)
		return 0;
	frexp(big, &e); /* big < 2^e */
	return ldexp(1.0, e - mantissa_bits);
}

#endif /* STRATUM_REPAIR_VEC3_H */
