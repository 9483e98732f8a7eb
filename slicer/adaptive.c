/*
 * adaptive.c - adaptive layer heights and the cusp of a plan (adaptive.h).
 *
 * The allowed height is kept per cell of ADAPTIVE_CELL_MM along Z: a cell
 * holds the smallest max_cusp / |n_z| of the sloped facets whose Z span
 * reaches into it, so a layer that touches a cell keeps the bound of every
 * facet there whatever part of the cell it covers (a conservative
 * rounding of at most one cell at each end of a layer).
 */
#include "adaptive.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>

/* A facet's Z span and |n_z|; false for a facet with no area. */
static bool facet_slope(const struct mesh *m, size_t t, double zmin, double *lo, double *hi,
			double *nz, double *area)
{
	const double *a = m->verts[m->tris[t][0]], *b = m->verts[m->tris[t][1]],
		     *c = m->verts[m->tris[t][2]];
	double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
	double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
	double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
		       u[0] * v[1] - u[1] * v[0]};
	double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);

	if (!(len > 0.0))
		return false;
	*lo = fmin(a[2], fmin(b[2], c[2])) - zmin;
	*hi = fmax(a[2], fmax(b[2], c[2])) - zmin;
	*nz = fabs(n[2]) / len;
	*area = len / 2;
	return true;
}

struct facet_limit {
	double lo, hi;	/* mm above the lowest point */
	double allowed; /* mm, max_cusp / |n_z| */
};

static int by_allowed(const void *pa, const void *pb)
{
	const struct facet_limit *a = pa, *b = pb;

	return (a->allowed > b->allowed) - (a->allowed < b->allowed);
}

/* First cell at or after k not yet given a limit (path halving). */
static size_t next_free(size_t *next, size_t k)
{
	while (next[k] != k) {
		next[k] = next[next[k]];
		k = next[k];
	}
	return k;
}

/*
 * Each cell's allowed height: facets in increasing order of their limit,
 * each filling the cells of its span still free, so every cell is written
 * once.  Cells no sloped facet reaches stay INFINITY.
 */
static int cell_limits(const struct mesh *m, double zmin, double cusp, double cell, double *limit,
		       size_t ncells, struct st_error *err)
{
	struct facet_limit *f = malloc((m->ntris ? m->ntris : 1) * sizeof(*f));
	size_t *next = malloc((ncells + 1) * sizeof(*next)), nf = 0;

	if (!f || !next) {
		free(f);
		free(next);
		return st_error_set(err, ST_ERR_NOMEM,
				    "adaptive layers: out of memory for %zu "
				    "triangles",
				    m->ntris);
	}
	for (size_t t = 0; t < m->ntris; t++) {
		double lo, hi, nz, area;

		if (facet_slope(m, t, zmin, &lo, &hi, &nz, &area) && hi > lo && nz > 0.0)
			f[nf++] = (struct facet_limit){lo, hi, cusp / nz};
	}
	qsort(f, nf, sizeof(*f), by_allowed);
	for (size_t k = 0; k <= ncells; k++)
		next[k] = k;
	for (size_t k = 0; k < ncells; k++)
		limit[k] = INFINITY;
	for (size_t i = 0; i < nf; i++) {
		size_t first = (size_t)floor(f[i].lo / cell), end = (size_t)ceil(f[i].hi / cell);

		if (end > ncells)
			end = ncells;
		for (size_t k = next_free(next, first < ncells ? first : ncells); k < end;
		     k = next_free(next, k)) {
			limit[k] = f[i].allowed;
			next[k] = k + 1;
		}
	}
	free(f);
	free(next);
	return 0;
}

/* The largest function under limit with slope at most ADAPTIVE_SMOOTHING. */
static void smooth_limits(double *limit, size_t ncells, double cell)
{
	double step = ADAPTIVE_SMOOTHING * cell;

	for (size_t k = 1; k < ncells; k++)
		limit[k] = fmin(limit[k], limit[k - 1] + step);
	for (size_t k = ncells - 1; k-- > 0;)
		limit[k] = fmin(limit[k], limit[k + 1] + step);
}

static int check_settings(const struct adaptive_settings *s, struct st_error *err)
{
	if (!(s->min_height >= ADAPTIVE_STEP_MM))
		return st_error_set(err, ST_ERR_RANGE,
				    "adaptive layers: min_layer_height = %g mm; it must be at "
				    "least %g mm",
				    s->min_height, ADAPTIVE_STEP_MM);
	if (!(s->max_height >= s->min_height))
		return st_error_set(err, ST_ERR_RANGE,
				    "adaptive layers: the largest layer height %g mm is below "
				    "min_layer_height %g mm",
				    s->max_height, s->min_height);
	if (!(s->max_cusp > 0.0 && isfinite(s->max_cusp)))
		return st_error_set(err, ST_ERR_RANGE,
				    "adaptive layers: the cusp bound %g mm must be more than 0",
				    s->max_cusp);
	if (!(s->first_height > 0.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "adaptive layers: first layer height %g mm must be more than 0",
				    s->first_height);
	return 0;
}

/* h in whole ADAPTIVE_STEP_MM, rounded down or up (a rounding error's
 * worth of slack either way). */
static double steps_down(double h)
{
	return floor(h / ADAPTIVE_STEP_MM + 1e-6) * ADAPTIVE_STEP_MM;
}

static double steps_up(double h)
{
	return ceil(h / ADAPTIVE_STEP_MM - 1e-6) * ADAPTIVE_STEP_MM;
}

/* The settings with heights in whole steps, never above the largest given,
 * and the most layers a mesh height mm tall can take (*cap); what names
 * the plan in the message of a mesh needing too many. */
static int whole_step_bounds(const struct adaptive_settings *given, double height,
			     const char *what, struct adaptive_settings *s, size_t *cap,
			     struct st_error *err)
{
	*s = *given;
	s->max_height = steps_down(given->max_height);
	s->min_height = fmin(steps_up(given->min_height), s->max_height);
	if (height / s->min_height > SLICE_MAX_LAYERS)
		return st_error_set(err, ST_ERR_RANGE,
				    "%s: a %g mm tall mesh in layers down to %g mm needs more than "
				    "%u layers; raise min_layer_height",
				    what, height, s->min_height, SLICE_MAX_LAYERS);
	*cap = (size_t)ceil(height / s->min_height) + 2;
	return 0;
}

/* The height of the layer starting at z: the smallest limit of the cells it touches. */
static double layer_height_at(const double *limit, size_t ncells, double cell, double z,
			      const struct adaptive_settings *s)
{
	double h = s->max_height;

	for (size_t k = (size_t)floor(z / cell); k < ncells && (double)k * cell < z + h; k++)
		h = fmin(h, limit[k]);
	return fmax(h, s->min_height);
}

int adaptive_plan(const struct mesh *m, const struct adaptive_settings *given,
		  struct layer_span **plan, size_t *n, struct st_error *err)
{
	/* the heights in whole steps, never above the largest given */
	struct adaptive_settings q = *given, *s = &q;
	double lo[3], hi[3], height, cell = ADAPTIVE_CELL_MM, z;
	struct layer_span *out = NULL;
	size_t ncells, count = 0, cap;
	double *limit;
	int rc;

	*plan = NULL;
	*n = 0;
	rc = check_settings(given, err);
	if (rc)
		return rc;
	if (!m || !m->ntris)
		return st_error_set(err, ST_ERR_ARG, "adaptive layers: the mesh is empty");
	mesh_bbox(m, lo, hi);
	height = hi[2] - lo[2];
	if (!isfinite(height))
		return st_error_set(
		    err, ST_ERR_ARG,
		    "adaptive layers: the mesh has coordinates that are not finite");
	rc = whole_step_bounds(given, height, "adaptive layers", &q, &cap, err);
	if (rc)
		return rc;
	if (height / cell > ADAPTIVE_MAX_CELLS)
		cell = height / ADAPTIVE_MAX_CELLS;
	ncells = (size_t)ceil(height / cell) + 1;
	limit = malloc(ncells * sizeof(*limit));
	out = malloc(cap * sizeof(*out));
	if (!limit || !out) {
		rc = st_error_set(err, ST_ERR_NOMEM, "adaptive layers: out of memory");
		goto out_free;
	}
	rc = cell_limits(m, lo[2], s->max_cusp, cell, limit, ncells, err);
	if (rc)
		goto out_free;
	for (size_t k = 0; k < ncells; k++) /* below the minimum the layer is the minimum */
		limit[k] = fmax(limit[k], s->min_height);
	smooth_limits(limit, ncells, cell);
	for (z = 0.0; z < height && count < cap;) {
		double h = count ? layer_height_at(limit, ncells, cell, z, s) : s->first_height;

		if (count > 0 && z + h > height) { /* the last layer, up to the top */
			h = fmin(fmax(steps_up(height - z), s->min_height), s->max_height);
		} else if (count > 0) {
			double rest = height - (z + h);

			/* a rest thinner than the minimum: this layer leaves the
			 * last one the minimum, rather than a sliver above the top */
			if (rest > 0 && rest < s->min_height &&
			    h - (s->min_height - rest) >= s->min_height)
				h -= s->min_height - rest;
			h = fmax(steps_down(h), s->min_height);
		}
		if (!(z + h / 2 < height))
			break;
		z = count ? out[0].z + (double)llround((z + h - out[0].z) / ADAPTIVE_STEP_MM) *
					   ADAPTIVE_STEP_MM
			  : h;
		out[count++] = (struct layer_span){.z = z, .height = h};
	}
out_free:
	free(limit);
	if (rc) {
		free(out);
		return rc;
	}
	*plan = out;
	*n = count;
	return 0;
}

/* The profile's height at z: linear between the pairs around it, the first
 * below them and the last above; *k is the pair to start from (rises). */
static double profile_height_at(const double *zh, size_t pairs, size_t *k, double z)
{
	double z1, z2;

	while (*k + 1 < pairs && zh[2 * (*k + 1)] <= z)
		(*k)++;
	if (z < zh[0] || *k + 1 == pairs)
		return zh[2 * *k + 1];
	z1 = zh[2 * *k];
	z2 = zh[2 * (*k + 1)];
	if (!(z2 > z1))
		return zh[2 * *k + 3];
	return zh[2 * *k + 1] + (zh[2 * *k + 3] - zh[2 * *k + 1]) * (z - z1) / (z2 - z1);
}

int adaptive_plan_profile(double height, const struct adaptive_settings *given, const double *zh,
			  size_t pairs, struct layer_span **plan, size_t *n, size_t *clamped,
			  struct st_error *err)
{
	struct adaptive_settings s;
	struct layer_span *out;
	size_t count = 0, cap, k = 0, outside = 0;
	int rc;

	*plan = NULL;
	*n = 0;
	if (clamped)
		*clamped = 0;
	rc = check_settings(given, err);
	if (rc)
		return rc;
	if (!zh || !pairs)
		return st_error_set(err, ST_ERR_ARG, "layer height profile: it is empty");
	for (size_t i = 0; i < 2 * pairs; i++)
		if (!isfinite(zh[i]))
			return st_error_set(err, ST_ERR_ARG,
					    "layer height profile: value %zu is not finite", i + 1);
	if (!(height > 0) || !isfinite(height))
		return st_error_set(err, ST_ERR_ARG, "layer height profile: the mesh is %g mm tall",
				    height);
	rc = whole_step_bounds(given, height, "layer height profile", &s, &cap, err);
	if (rc)
		return rc;
	out = malloc(cap * sizeof(*out));
	if (!out)
		return st_error_set(err, ST_ERR_NOMEM, "layer height profile: out of memory");
	for (double z = 0.0; count < cap;) {
		double h = s.first_height;
		bool held = false; /* the profile's height lay outside the bounds */

		if (count) {
			h = profile_height_at(zh, pairs, &k, z + s.min_height / 2);
			held = h < s.min_height - 1e-9 || h > s.max_height + 1e-9;
			h = fmin(fmax(h, s.min_height), s.max_height);
		}
		if (!(z + h / 2 < height))
			break;
		outside += held;
		if (count) { /* the top in whole steps; rounding, not truncating, so
			      * the layers do not drift below the profile */
			double top = out[0].z + (double)llround((z + h - out[0].z) /
								ADAPTIVE_STEP_MM) *
						    ADAPTIVE_STEP_MM;

			h = top - z;
			z = top;
		} else {
			z = h;
		}
		out[count++] = (struct layer_span){.z = z, .height = h};
	}
	*plan = out;
	*n = count;
	if (clamped)
		*clamped = outside;
	return 0;
}

/* First layer whose top lies above z (tops rise with the index). */
static size_t first_top_above(const struct layer_span *plan, size_t n, double z)
{
	size_t lo = 0, hi = n;

	while (lo < hi) {
		size_t mid = lo + (hi - lo) / 2;

		if (plan[mid].z > z)
			hi = mid;
		else
			lo = mid + 1;
	}
	return lo;
}

int adaptive_measure(const struct mesh *m, const struct layer_span *plan, size_t n,
		     double *layer_cusp, struct adaptive_cusp *out, struct st_error *err)
{
	double lo3[3], hi3[3], sum = 0.0, weight = 0.0;

	if (!m || !out || (n && !plan))
		return st_error_set(err, ST_ERR_ARG, "adaptive layers: no mesh or plan to measure");
	*out = (struct adaptive_cusp){0};
	if (layer_cusp)
		for (size_t i = 0; i < n; i++)
			layer_cusp[i] = 0.0;
	if (!m->ntris)
		return 0;
	mesh_bbox(m, lo3, hi3);
	for (size_t t = 0; t < m->ntris; t++) {
		double lo, hi, nz, area;

		if (!facet_slope(m, t, lo3[2], &lo, &hi, &nz, &area) || !(hi > lo))
			continue;
		for (size_t i = first_top_above(plan, n, lo);
		     i < n && plan[i].z - plan[i].height < hi; i++) {
			double c = plan[i].height * nz;
			double part = fmin(hi, plan[i].z) - fmax(lo, plan[i].z - plan[i].height);

			if (!(part > 0.0))
				continue;
			sum += c * area * part / (hi - lo);
			weight += area * part / (hi - lo);
			if (layer_cusp && c > layer_cusp[i])
				layer_cusp[i] = c;
			if (c > out->max) {
				out->max = c;
				out->worst_layer = i;
			}
		}
	}
	out->mean = weight > 0.0 ? sum / weight : 0.0;
	return 0;
}
