/*
 * region_support.c - the support a G-code file prints, against the model
 * (region.h, region_support_check).
 */
#include "region.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gcwalk.h"
#include "st_grow.h"
#include "toolpath.h"

#define NM SLICE_UNITS_PER_MM
/* A support move belongs to the part's layer whose Z is this close, mm. */
#define SUPPORT_Z_MATCH 1e-4

/* The layer of p printed at z, or p->n when none is. */
static size_t layer_at(const struct region_print *p, double z)
{
	for (size_t i = 0; i < p->n; i++)
		if (fabs(p->layers[i].z - z) < SUPPORT_Z_MATCH)
			return i;
	return p->n;
}

/* Every support move of the file swept into S[layer], as its own bead. */
static int read_support(const char *path, const struct region_print *p,
			const struct region_opts *o, struct clip_paths *S,
			struct region_support_report *r, struct st_error *err)
{
	double fil_area = M_PI * p->filament_diameter * p->filament_diameter / 4.0;
	struct clip_paths *lines = calloc(p->n, sizeof(*lines));
	double **half = calloc(p->n, sizeof(*half));
	size_t *cap = calloc(p->n, sizeof(*cap));
	struct gcwalk *w = NULL;
	struct gcwalk_move m;
	FILE *fp = fopen(path, "rb");
	int rc = 0;

	if (!lines || !half || !cap)
		rc = st_error_set(err, ST_ERR_NOMEM, "region: out of memory for support");
	else if (!fp)
		rc = st_error_set(err, ST_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
	if (!rc)
		rc = gcwalk_new(fp, path, &w, err);
	while (!rc && (rc = gcwalk_next(w, &m, err)) == 1) {
		rc = 0;
		double len = hypot(m.to[0] - m.from[0], m.to[1] - m.from[1]);
		if (!(m.de > 0.0) || len == 0.0 || strncmp(m.type, "Support material", 16))
			continue;
		size_t i = layer_at(p, m.to[2]);
		if (i == p->n) {
			r->stray++;
			continue;
		}
		int64_t seg[4] = {llround(m.from[0] * NM), llround(m.from[1] * NM),
				  llround(m.to[0] * NM), llround(m.to[1] * NM)};
		double wd = region_bead_width(m.de * fil_area / len, p->layers[i].height);
		if (st_grow_at((void **)&half[i], &cap[i], lines[i].n + 1, sizeof(**half)))
			rc = st_error_set(err, ST_ERR_NOMEM, "region: out of memory for support");
		else
			rc = clip_paths_add(&lines[i], seg, 2, err);
		if (!rc)
			half[i][lines[i].n - 1] = wd * NM / 2.0;
		r->beads++;
	}
	if (rc > 0)
		rc = 0;
	for (size_t i = 0; !rc && i < p->n; i++)
		if (lines[i].n)
			rc = clip_sweep(&lines[i], half[i], o->arc_tolerance * NM, &S[i], err);
	gcwalk_free(w);
	if (fp)
		fclose(fp);
	for (size_t i = 0; lines && i < p->n; i++) {
		clip_paths_free(&lines[i]);
		free(half ? half[i] : NULL);
	}
	free(lines);
	free(half);
	free(cap);
	return rc;
}

static int area_of(const struct clip_paths *ps, double *mm2, struct st_error *err)
{
	int rc = clip_paths_area(ps, mm2, err);

	*mm2 /= NM * NM;
	return rc;
}

/* Layer i's overhang (sec: the sections) not within reach of the support
 * under it; adds to r. */
static int check_overhang(const struct region_print *p, size_t i, const struct clip_paths *sec,
			  const struct clip_paths *S, double tan_a, double gap, double reach,
			  struct region_support_report *r, double *worst, struct st_error *err)
{
	const struct region_layer *L = p->layers;
	struct clip_paths O = {0}, held = {0};
	double bottom = L[i].z - L[i].height, a = 0, u = 0;
	int rc = clip_offset(&sec[i - 1], L[i].height / tan_a * NM, CLIP_JOIN_ROUND, 2.0, 1000.0,
			     &O, err);

	if (!rc)
		rc = clip_boolean(CLIP_DIFFERENCE, &sec[i], &O, CLIP_NONZERO, &O, err);
	for (size_t j = i; !rc && O.n && j-- > 0 && bottom - L[j].z <= gap + L[j].height + 1e-6;)
		rc = clip_paths_append(&held, &S[j], err);
	if (!rc && held.n)
		rc = clip_offset(&held, reach * NM, CLIP_JOIN_ROUND, 2.0, 1000.0, &held, err);
	if (!rc && O.n)
		rc = area_of(&O, &a, err);
	if (!rc && O.n)
		rc = clip_boolean(CLIP_DIFFERENCE, &O, &held, CLIP_NONZERO, &O, err);
	if (!rc && O.n)
		rc = area_of(&O, &u, err);
	r->overhang_mm2 += a;
	r->unsupported_mm2 += u;
	if (u > *worst) {
		*worst = u;
		r->worst_z = L[i].z;
	}
	clip_paths_free(&O);
	clip_paths_free(&held);
	return rc;
}

int region_support_check(const char *path, const struct mesh *m, const struct region_print *p,
			 const struct region_opts *o, double threshold_deg, double gap,
			 double reach, struct region_support_report *out, struct st_error *err)
{
	struct region_opts defaults;
	struct clip_paths *S = NULL, *sec = NULL, x = {0};
	double off[3], worst = 0;
	int rc = 0;

	if (!path || !m || !m->nverts || !p || !p->n || !out || !(threshold_deg > 0.0) ||
	    !(threshold_deg < 90.0) || !(gap >= 0.0) || !(reach >= 0.0))
		return st_error_set(err, ST_ERR_ARG,
				    "region: the support check needs a file, a mesh, a print, a "
				    "threshold in (0, 90) degrees and a gap and reach >= 0 mm");
	if (!o) {
		region_opts_init(&defaults);
		o = &defaults;
	}
	memset(out, 0, sizeof(*out));
	S = calloc(p->n, sizeof(*S));
	sec = calloc(p->n, sizeof(*sec));
	if (!S || !sec)
		rc = st_error_set(err, ST_ERR_NOMEM, "region: out of memory");
	if (!rc)
		rc = read_support(path, p, o, S, out, err);
	region_place(m, o, p->min, p->max, off);
	const int64_t d[2] = {llround(off[0] * NM), llround(off[1] * NM)};
	for (size_t i = 0; !rc && i < p->n; i++) {
		const struct region_layer *l = &p->layers[i];
		double in = 0;
		rc = region_section(m, l->z - l->height / 2 - off[2], d[0], d[1], &sec[i], err);
		if (!rc && S[i].n)
			rc = clip_boolean(CLIP_INTERSECTION, &S[i], &sec[i], CLIP_NONZERO, &x, err);
		if (!rc && S[i].n && x.n)
			rc = area_of(&x, &in, err);
		out->inside_mm2 += in;
		if (!rc && i > 0)
			rc = check_overhang(p, i, sec, S, tan(threshold_deg * M_PI / 180.0), gap, reach,
					    out, &worst, err);
	}
	out->layers = p->n;
	for (size_t i = 0; i < p->n && S; i++)
		clip_paths_free(&S[i]);
	for (size_t i = 0; i < p->n && sec; i++)
		clip_paths_free(&sec[i]);
	free(S);
	free(sec);
	clip_paths_free(&x);
	return rc;
}
