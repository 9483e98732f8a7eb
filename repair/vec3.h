/*
 * vec3.h - private to repair/: double-precision 3-D helpers for figures that
 * decide nothing (distances and areas for reports and tolerances).
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

/* Area of triangle abc. */
static inline double vec3_tri_area(const double a[3], const double b[3], const double c[3])
{
	const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
	const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
	const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
			     u[0] * v[1] - u[1] * v[0]};

	return 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
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
