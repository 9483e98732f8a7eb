/*
 * refine.c - the rounds of the refinement (refine.h): measure every
 * facet's chordal error both ways (deviation.h), split an edge of each
 * facet over the tolerance (every edge in uniform mode), move the new
 * vertices onto the reference (refine_place.c), refuse the moves the
 * exact checks reject, and again until every facet is within the
 * tolerance.
 *
 * A split edge is split on both of its facets, so each facet keeps 0 to 3
 * of its edges whole and is cut by the fixed patterns of red-green
 * refinement: one split edge bisects it, two cut off a corner and halve the
 * rest along its shorter diagonal, three make four.
 */
#include "refine.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "deviation.h"
#include "exact.h"
#include "planar_cdt.h"
#include "refine_impl.h"
#include "st_grow.h"
#include "surfdist.h"
#include "vec3.h"

#define ROUNDS_MAX 64	   /* a hard stop; the cylinder takes a handful */
#define STALL_ROUNDS 4	   /* rounds without progress (below): give up */
#define AREA_PROGRESS 0.9  /* progress: the area over the tolerance down to this share */
/* A new triangle may turn up to 120 degrees from the facet it was cut from:
 * on a scan a small facet follows a bump's steep side, and what a fold would
 * really break, a crossing, the exact test finds; beyond, it is refused as
 * turned over. */
#define TURN_COS (-0.5)
/* A facet's error comes from an edge when that edge's midpoint moves by a
 * quarter of it; edges within this share of the largest move tie, and the
 * shortest of them is split (on a cylinder's side the rim before the
 * diagonal, which the cap's facet shares cheaply).  When no edge carries
 * the error the longest is split (longest-edge bisection keeps shapes). */
#define EDGE_SHARE 0.25
#define TIE_SHARE 0.8

void refine_options_init(struct refine_options *opt)
{
	opt->tolerance = 0.01;
	opt->feature_angle = REFINE_FEATURE_ANGLE_DEFAULT;
	opt->samples = DEVIATION_SAMPLES_DEFAULT;
	opt->max_triangles = REFINE_MAX_TRIANGLES_DEFAULT;
	opt->uniform = false;
	opt->move_vertices = false;
	opt->threads = 0;
}

size_t refine_stl_bytes(size_t ntris)
{
	return 84 + 50 * ntris; /* header, count, 50 bytes a triangle */
}

void refine_report_free(struct refine_report *rep)
{
	free(rep->facet_error);
	rep->facet_error = NULL;
}

/* x as float32 stores it; false when it does not fit. */
static bool to_float(double x, double *out)
{
	if (!(fabs(x) <= FLT_MAX))
		return false;
	*out = (float)x;
	return true;
}

/* coarse on the float32 grid, welded again: what an STL of it holds. */
static int rounded_copy(const struct mesh *in, struct mesh **out, struct st_error *err)
{
	struct mesh_builder *b = mesh_builder_new(in->ntris);
	int rc = b ? 0 : st_error_set(err, ST_ERR_NOMEM, "refine: out of memory");

	for (size_t t = 0; !rc && t < in->ntris; t++) {
		uint32_t v[3];
		for (int k = 0; !rc && k < 3; k++) {
			double p[3];
			const double *q = in->verts[in->tris[t][k]];
			if (!to_float(q[0], &p[0]) || !to_float(q[1], &p[1]) || !to_float(q[2], &p[2]))
				rc = st_error_set(err, ST_ERR_RANGE,
						  "a vertex lies beyond "
						  "float32's range, which STL stores");
			else
				rc = mesh_builder_vertex(b, p, &v[k], err);
		}
		if (!rc)
			rc = mesh_builder_triangle(b, v[0], v[1], v[2], err);
	}
	if (!rc && !(*out = mesh_builder_finish(b)))
		return st_error_set(err, ST_ERR_NOMEM, "refine: out of memory");
	if (rc)
		mesh_builder_free(b);
	return rc;
}

/* ST_ERR_UNSUPPORTED naming the first reason m is not printable; else 0. */
static int require_printable(const struct mesh *m, int threads, struct st_error *err)
{
	struct mesh_report rep;
	int rc = mesh_analyze(m, threads, &rep, err);

	if (rc)
		return rc;
	for (int r = 0; r < MESH_REASON_FIRST_WARNING; r++)
		if (rep.reasons[r])
			return st_error_set(err, ST_ERR_UNSUPPORTED,
					    "not printable (%s); `stratum repair` it first",
					    mesh_reason_text((enum mesh_reason)r));
	return 0;
}

/* Every facet's chordal error, as `compare --reference` measures it. */
static int measure(const struct mesh *m, const struct mesh *ref, const struct refine_options *o,
		   float **facet, double *max, size_t *over, double *over_area,
		   struct st_error *err)
{
	struct chordal_report c;
	int rc = chordal_measure(m, ref, o->samples, o->tolerance, &c, err);

	if (rc)
		return rc;
	free(*facet);
	*facet = c.facet;
	c.facet = NULL;
	*max = c.max;
	*over = c.nover;
	*over_area = c.over_area;
	chordal_report_free(&c);
	return 0;
}

/* One round's work on the edges. */
struct round {
	struct refine_edges e;
	uint32_t *cand;	      /* the edges placed */
	size_t ncand;
	uint32_t *slot;	      /* per edge: its index in cand, or REFINE_NONE */
	double (*pos)[3];     /* per candidate */
	uint8_t *kind;
	uint32_t *newv;	      /* per edge: its new vertex, or REFINE_NONE */
	/* per vertex of the mesh: */
	double (*home)[3];    /* where a refused move puts it back */
	double (*want)[3];    /* where it is moving to (on the reference) */
	uint8_t *step;	      /* 0 at home; 1 at want, 2, 3 that share of the way */
	size_t first_new;     /* index of the first vertex added this round */
};

/* Vertices whose move was refused or cut short in an earlier round, tried
 * again each round: their neighbours have been split since, and a move that
 * flipped a thin triangle may pass beside smaller ones. */
struct pending {
	double (*want)[3]; /* per vertex: its place on the reference */
	uint8_t *short_of; /* per vertex: not there yet */
	size_t n, cap_want, cap_short;
};

static void round_free(struct round *r)
{
	refine_edges_free(&r->e);
	free(r->cand), free(r->slot), free(r->pos), free(r->kind), free(r->newv);
	free(r->home), free(r->want), free(r->step);
}

/* home, want and step for nv vertices, each at home. */
static int moves_alloc(struct round *r, struct mesh *m, size_t nv, struct st_error *err)
{
	r->home = malloc((nv ? nv : 1) * sizeof(*r->home));
	r->want = malloc((nv ? nv : 1) * sizeof(*r->want));
	r->step = calloc(nv ? nv : 1, 1);
	if (!r->home || !r->want || !r->step)
		return st_error_set(err, ST_ERR_NOMEM, "refine: out of memory");
	for (size_t v = 0; v < m->nverts && v < nv; v++) {
		memcpy(r->home[v], m->verts[v], sizeof(r->home[v]));
		memcpy(r->want[v], m->verts[v], sizeof(r->want[v]));
	}
	return 0;
}

/* The candidate edges: all (uniform), or those of the facets over. */
static int pick_candidates(const struct mesh *m, const float *facet,
			   const struct refine_options *o, struct round *r, struct st_error *err)
{
	size_t ne = r->e.n ? r->e.n : 1;

	r->cand = malloc(ne * sizeof(*r->cand));
	r->slot = malloc(ne * sizeof(*r->slot));
	r->newv = malloc(ne * sizeof(*r->newv));
	r->pos = malloc(ne * sizeof(*r->pos));
	r->kind = malloc(ne);
	if (!r->cand || !r->slot || !r->newv || !r->pos || !r->kind)
		return st_error_set(err, ST_ERR_NOMEM, "refine: out of memory");
	for (size_t i = 0; i < r->e.n; i++)
		r->slot[i] = r->newv[i] = REFINE_NONE;
	for (size_t t = 0; t < m->ntris; t++) {
		if (!o->uniform && !(facet[t] > o->tolerance))
			continue;
		for (int k = 0; k < 3; k++) {
			uint32_t ed = r->e.of_tri[t][k];
			if (r->slot[ed] == REFINE_NONE) {
				r->slot[ed] = (uint32_t)r->ncand;
				r->cand[r->ncand++] = ed;
			}
		}
	}
	return 0;
}

/* The edge of facet t to split: the one whose new vertex moves farthest
 * from its midpoint (the error is there), the shortest among near ties;
 * the longest when no edge carries the facet's error (a bump inside). */
static uint32_t edge_to_split(const struct mesh *m, const struct round *r, uint32_t t,
			      double error)
{
	double dev[3], len[3], maxdev = 0, best = -1;
	uint32_t pick = r->e.of_tri[t][0];

	for (int k = 0; k < 3; k++) {
		uint32_t ed = r->e.of_tri[t][k];
		double mid[3];
		refine_midpoint(m, &r->e, ed, mid);
		dev[k] = vec3_dist(mid, r->pos[r->slot[ed]]);
		len[k] = vec3_dist(m->verts[r->e.ends[ed][0]], m->verts[r->e.ends[ed][1]]);
		maxdev = fmax(maxdev, dev[k]);
	}
	/* an edge that stays near the surface runs along a straight line of it
	 * (a cylinder's height): the surface curves one way here, and splitting
	 * across that way is enough; where every edge strays, it curves both
	 * ways (a torus, a scan) and long slivers would flip when their new
	 * vertices move: longest-edge bisection keeps the shapes */
	double mindev = fmin(dev[0], fmin(dev[1], dev[2]));
	bool carried = maxdev >= EDGE_SHARE * error && mindev < EDGE_SHARE * maxdev;
	for (int k = 0; k < 3; k++) {
		bool better = best < 0 || (carried ? len[k] < best : len[k] > best);
		if ((!carried || dev[k] >= TIE_SHARE * maxdev) && better) {
			best = len[k];
			pick = r->e.of_tri[t][k];
		}
	}
	return pick;
}

/* New vertices for the marked edges (newv[e] == 0 marks them on entry). */
static int add_vertices(struct mesh *m, struct round *r, size_t nmarked, struct st_error *err)
{
	double (*v)[3] = st_grow(m->verts, &m->cap_verts, m->nverts + nmarked, sizeof(*v));
	int rc;

	if (!v)
		return st_error_set(err, ST_ERR_NOMEM, "refine: out of memory");
	m->verts = v;
	if ((rc = moves_alloc(r, m, m->nverts + nmarked, err)))
		return rc;
	r->first_new = m->nverts;
	for (size_t ed = 0; ed < r->e.n; ed++) {
		if (r->newv[ed] != 0)
			continue;
		const double *p = r->pos[r->slot[ed]];
		size_t j = m->nverts;
		double mid[3];
		refine_midpoint(m, &r->e, ed, mid);
		if (!to_float(p[0], &v[m->nverts][0]) || !to_float(p[1], &v[m->nverts][1]) ||
		    !to_float(p[2], &v[m->nverts][2]))
			return st_error_set(err, ST_ERR_RANGE,
					    "a new vertex lies beyond float32's range");
		for (int k = 0; k < 3; k++)
			r->home[j][k] = (float)mid[k];
		memcpy(r->want[j], v[j], sizeof(r->want[j]));
		r->step[j] = r->kind[r->slot[ed]] != PLACE_ON_EDGE;
		r->newv[ed] = (uint32_t)m->nverts++;
	}
	return 0;
}

/* The steps of a refused move: all the way, half, a quarter, then home (a
 * new vertex's edge midpoint, rounded as stored; an old one's place). */
#define STEP_LAST 3

/* Vertex w a step back towards home. */
static void step_back(struct mesh *m, struct round *r, uint32_t w)
{
	r->step[w] = r->step[w] >= STEP_LAST ? 0 : r->step[w] + 1;
	double f = r->step[w] ? ldexp(1, 1 - r->step[w]) : 0;
	for (int k = 0; k < 3; k++)
		m->verts[w][k] = (float)(r->home[w][k] + f * (r->want[w][k] - r->home[w][k]));
}

/* Facet (a, b, c) with new vertices ab, bc, ca (REFINE_NONE: edge whole)
 * into out; returns how many triangles. */
static size_t cut(const struct mesh *m, const uint32_t c[3], const uint32_t mid[3],
		  uint32_t (*out)[3])
{
	int nsplit = (mid[0] != REFINE_NONE) + (mid[1] != REFINE_NONE) + (mid[2] != REFINE_NONE);
	int k = 0;

	if (nsplit == 0) {
		memcpy(out[0], c, sizeof(out[0]));
		return 1;
	}
	if (nsplit == 3) {
		uint32_t t[4][3] = {{c[0], mid[0], mid[2]}, {mid[0], c[1], mid[1]},
				    {mid[2], mid[1], c[2]}, {mid[0], mid[1], mid[2]}};
		memcpy(out, t, sizeof(t));
		return 4;
	}
	if (nsplit == 1) {
		while (mid[k] == REFINE_NONE)
			k++;
		uint32_t a = c[k], b = c[(k + 1) % 3], d = c[(k + 2) % 3], x = mid[k];
		uint32_t t[2][3] = {{a, x, d}, {x, b, d}};
		memcpy(out, t, sizeof(t));
		return 2;
	}
	/* two: k the whole edge, from corner k to k + 1; the corner opposite
	 * it, k + 2, is cut off */
	while (mid[k] != REFINE_NONE)
		k++;
	uint32_t a = c[(k + 1) % 3], b = c[(k + 2) % 3], d = c[k];
	uint32_t x = mid[(k + 1) % 3], y = mid[(k + 2) % 3]; /* on ab, on bd */
	out[0][0] = x, out[0][1] = b, out[0][2] = y;
	if (vec3_dist(m->verts[a], m->verts[y]) <= vec3_dist(m->verts[x], m->verts[d])) {
		uint32_t t[2][3] = {{a, x, y}, {a, y, d}};
		memcpy(out + 1, t, sizeof(t));
	} else {
		uint32_t t[2][3] = {{a, x, d}, {x, y, d}};
		memcpy(out + 1, t, sizeof(t));
	}
	return 3;
}

/* A vertex's position and index, for finding equal positions by sorting. */
struct placed {
	double p[3];
	uint32_t v;
};

static int cmp_placed(const void *x, const void *y)
{
	const double *a = ((const struct placed *)x)->p, *b = ((const struct placed *)y)->p;

	for (int k = 0; k < 3; k++)
		if (a[k] != b[k])
			return a[k] < b[k] ? -1 : 1;
	return 0;
}

/* Moved new vertices that landed on another vertex go back to their edge;
 * a vertex on its edge that does so is an error. */
static int separate_equal(struct mesh *m, struct round *r, bool *changed, struct st_error *err)
{
	struct placed *all = malloc((m->nverts ? m->nverts : 1) * sizeof(*all));

	if (!all)
		return st_error_set(err, ST_ERR_NOMEM, "refine: out of memory");
	for (size_t i = 0; i < m->nverts; i++) {
		memcpy(all[i].p, m->verts[i], sizeof(all[i].p));
		all[i].v = (uint32_t)i;
	}
	qsort(all, m->nverts, sizeof(*all), cmp_placed);
	for (size_t i = 1; i < m->nverts; i++) {
		if (cmp_placed(&all[i - 1], &all[i]))
			continue;
		uint32_t hi = all[i].v > all[i - 1].v ? all[i].v : all[i - 1].v;
		uint32_t w = r->step[hi] ? hi : all[i].v ^ all[i - 1].v ^ hi;
		if (!r->step[w]) {
			free(all);
			return st_error_set(err, ST_ERR_INTERNAL,
					    "refine: a new vertex on its edge falls on another vertex");
		}
		step_back(m, r, w);
		*changed = true;
	}
	free(all);
	return 0;
}

/* Steps back the moving corners of triangle t; false when it has none. */
static bool step_back_corners(struct mesh *m, struct round *r, const uint32_t c[3])
{
	bool any = false;

	for (int k = 0; k < 3; k++)
		if (r->step[c[k]]) {
			step_back(m, r, c[k]);
			any = true;
		}
	return any;
}

/*
 * The checks on the new triangles (fresh), until they pass: one that
 * collapses (collinear corners, exact), turns over against the facet it
 * was cut from, or crosses another triangle (exact) gets its moving vertices
 * stepped back towards home, the last step onto their edges, where they make
 * a flat copy of the facet.
 */
static int check_moves(struct mesh *m, struct round *r, const uint32_t *parent,
		       const double (*pnormal)[3], const uint8_t *fresh, struct st_error *err)
{
	uint8_t *hit = malloc(m->ntris ? m->ntris : 1);
	int rc = hit ? 0 : st_error_set(err, ST_ERR_NOMEM, "refine: out of memory");

	for (bool changed = true; !rc && changed;) {
		changed = false;
		if ((rc = separate_equal(m, r, &changed, err)))
			break;
		for (size_t t = 0; t < m->ntris && !rc; t++) {
			const uint32_t *c = m->tris[t];
			double n[3];
			if (!fresh[t])
				continue;
			refine_unit_normal(m, (uint32_t)t, n);
			if (!exact_collinear(m->verts[c[0]], m->verts[c[1]], m->verts[c[2]]) &&
			    n[0] * pnormal[parent[t]][0] + n[1] * pnormal[parent[t]][1] +
				    n[2] * pnormal[parent[t]][2] > TURN_COS)
				continue;
			if (!step_back_corners(m, r, c))
				rc = st_error_set(err, ST_ERR_INTERNAL,
						  "refine: a split facet collapses with its new "
						  "vertices on their edges");
			changed = true;
		}
		if (rc || changed)
			continue;
		rc = planar_cdt_crossings((const double (*)[3])m->verts, m->nverts,
					  (const uint32_t (*)[3])m->tris, m->ntris, fresh, hit, err);
		bool crossed = false;
		for (size_t t = 0; !rc && t < m->ntris; t++) {
			crossed |= hit[t] != 0;
			/* of two new triangles that cross, one may be flat already */
			changed |= hit[t] && step_back_corners(m, r, m->tris[t]);
		}
		if (!rc && crossed && !changed)
			rc = st_error_set(err, ST_ERR_INTERNAL,
					  "refine: a split facet crosses another with its new "
					  "vertices on their edges");
	}
	free(hit);
	return rc;
}

/* The facets cut by the marked edges into new triangles; parent, fresh and
 * the old facets' normals for the checks. */
static int cut_all(struct mesh *m, struct round *r, size_t ntris_new, uint32_t **parent,
		   uint8_t **fresh, double (**pnormal)[3], struct st_error *err)
{
	uint32_t (*tris)[3] = malloc((ntris_new ? ntris_new : 1) * sizeof(*tris));
	size_t n = 0;

	*parent = malloc((ntris_new ? ntris_new : 1) * sizeof(**parent));
	*fresh = malloc(ntris_new ? ntris_new : 1);
	*pnormal = malloc((m->ntris ? m->ntris : 1) * sizeof(**pnormal));
	if (!tris || !*parent || !*fresh || !*pnormal) {
		free(tris);
		return st_error_set(err, ST_ERR_NOMEM, "refine: out of memory");
	}
	for (size_t t = 0; t < m->ntris; t++) {
		uint32_t mid[3];
		for (int k = 0; k < 3; k++)
			mid[k] = r->newv[r->e.of_tri[t][k]];
		refine_unit_normal(m, (uint32_t)t, (*pnormal)[t]);
		size_t got = cut(m, m->tris[t], mid, tris + n);
		for (size_t i = n; i < n + got; i++) {
			(*parent)[i] = (uint32_t)t;
			(*fresh)[i] = got > 1;
		}
		n += got;
	}
	free(m->tris);
	m->tris = tris;
	m->ntris = m->cap_tris = n;
	return 0;
}

/* The pending vertices (earlier rounds') move again, from where they are
 * to their place, and their triangles are checked (fresh, against their
 * normal before the move). */
static void retry_pending(struct mesh *m, struct round *r, const struct pending *pd,
			  uint8_t *fresh)
{
	for (size_t v = 0; v < r->first_new && v < pd->n; v++)
		if (pd->short_of[v]) {
			memcpy(r->want[v], pd->want[v], sizeof(r->want[v]));
			memcpy(m->verts[v], pd->want[v], sizeof(m->verts[v]));
			r->step[v] = 1;
		}
	for (size_t t = 0; t < m->ntris; t++)
		for (int k = 0; k < 3; k++)
			fresh[t] |= m->tris[t][k] < r->first_new && r->step[m->tris[t][k]];
}

/* After the checks: which vertices that were to move fell short (counted
 * in *refused), to be tried again next round. */
static int pending_update(struct pending *pd, const struct mesh *m, const struct round *r,
			  size_t *refused, struct st_error *err)
{
	if (st_grow_at((void **)&pd->want, &pd->cap_want, m->nverts, sizeof(*pd->want)) ||
	    st_grow_at((void **)&pd->short_of, &pd->cap_short, m->nverts, 1))
		return st_error_set(err, ST_ERR_NOMEM, "refine: out of memory");
	for (size_t v = 0; v < m->nverts; v++) {
		bool to_move = memcmp(r->want[v], r->home[v], sizeof(r->want[v])) != 0;
		bool is_short = to_move && r->step[v] != 1;
		if (v >= pd->n || to_move)
			memcpy(pd->want[v], r->want[v], sizeof(pd->want[v]));
		pd->short_of[v] = is_short;
		*refused += is_short;
	}
	pd->n = m->nverts;
	return 0;
}

/* Whether a corner of the facet is short of its place: its error is that
 * corner's to mend (by the retry); split, it would only give vertices that
 * must move as far beside ever smaller triangles, and be refused in turn. */
static bool has_short_corner(const struct pending *pd, const uint32_t c[3])
{
	for (int k = 0; k < 3; k++)
		if (c[k] < pd->n && pd->short_of[c[k]])
			return true;
	return false;
}

/*
 * One round: split edges of the facets over the tolerance (all edges when
 * uniform), place and check the new vertices.  *stop when the round would
 * pass max_triangles (m unchanged).
 */
static int split_round(struct mesh *m, const float *facet, const struct refine_options *o,
		       const struct refine_target *tg, struct pending *pd,
		       struct refine_report *rep, bool *stop, struct st_error *err)
{
	struct round r = {0};
	uint32_t *parent = NULL;
	uint8_t *fresh = NULL;
	double (*pnormal)[3] = NULL;
	size_t nmarked = 0, ntris_new = m->ntris;
	int rc = refine_edges_build(m, &r.e, err);

	if (!rc)
		rc = pick_candidates(m, facet, o, &r, err);
	if (!rc)
		rc = refine_place(m, &r.e, r.cand, r.ncand, tg, r.pos, r.kind, err);
	/* mark: newv 0 until add_vertices numbers them */
	for (size_t t = 0; !rc && t < m->ntris; t++) {
		if (o->uniform)
			for (int k = 0; k < 3; k++)
				r.newv[r.e.of_tri[t][k]] = 0;
		else if (facet[t] > o->tolerance && !has_short_corner(pd, m->tris[t]))
			r.newv[edge_to_split(m, &r, (uint32_t)t, facet[t])] = 0;
	}
	for (size_t ed = 0; !rc && ed < r.e.n; ed++)
		nmarked += r.newv[ed] == 0;
	for (size_t t = 0; !rc && t < m->ntris; t++)
		for (int k = 0; k < 3; k++)
			ntris_new += r.newv[r.e.of_tri[t][k]] == 0;
	*stop = !rc && (ntris_new > o->max_triangles || !nmarked);
	if (!rc && !*stop)
		rc = add_vertices(m, &r, nmarked, err);
	if (!rc && !*stop)
		rc = cut_all(m, &r, ntris_new, &parent, &fresh, &pnormal, err);
	if (!rc && !*stop) {
		retry_pending(m, &r, pd, fresh);
		rc = check_moves(m, &r, parent, (const double (*)[3])pnormal, fresh, err);
		if (!rc)
			rc = pending_update(pd, m, &r, &rep->refused, err);
		rep->vertices_added += nmarked;
		for (size_t ed = 0; !rc && ed < r.e.n; ed++)
			rep->on_creases += r.newv[ed] != REFINE_NONE && r.step[r.newv[ed]] == 1 &&
					   r.kind[r.slot[ed]] == PLACE_ON_CREASE;
	}
	free(parent);
	free(fresh);
	free(pnormal);
	round_free(&r);
	return rc;
}

/* move_vertices: m's own vertices onto their nearest point of the
 * reference, each move kept where the checks of a split pass too (those
 * that fall short are tried again in the rounds, as pending). */
static int move_input_vertices(struct mesh *m, const struct refine_target *tg,
			       struct pending *pd, struct refine_report *rep, struct st_error *err)
{
	struct round r = {0};
	size_t nv = m->nverts ? m->nverts : 1, nt = m->ntris ? m->ntris : 1;
	double (*near)[3] = malloc(nv * sizeof(*near)), (*pnormal)[3] = malloc(nt * sizeof(*pnormal));
	uint32_t *parent = malloc(nt * sizeof(*parent));
	uint8_t *fresh = calloc(nt, 1);
	int rc = moves_alloc(&r, m, m->nverts, err);

	if (!rc && (!near || !pnormal || !parent || !fresh))
		rc = st_error_set(err, ST_ERR_NOMEM, "refine: out of memory");
	if (rc)
		goto done;
	if ((rc = surfdist_closest(tg->tree, (const double (*)[3])m->verts, m->nverts, near, NULL,
				   err)))
		goto done;
	for (size_t t = 0; t < m->ntris; t++) {
		refine_unit_normal(m, (uint32_t)t, pnormal[t]);
		parent[t] = (uint32_t)t;
	}
	for (size_t v = 0; v < m->nverts; v++) {
		for (int k = 0; k < 3; k++)
			m->verts[v][k] = r.want[v][k] = (float)near[v][k]; /* as refine_mesh
									  * rounded its copy */
		r.step[v] = memcmp(r.want[v], r.home[v], sizeof(r.home[v])) != 0;
	}
	for (size_t t = 0; t < m->ntris; t++)
		for (int k = 0; k < 3; k++)
			fresh[t] |= r.step[m->tris[t][k]];
	rc = check_moves(m, &r, parent, (const double (*)[3])pnormal, fresh, err);
	if (!rc)
		rc = pending_update(pd, m, &r, &rep->refused, err);
	for (size_t v = 0; !rc && v < m->nverts; v++)
		rep->vertices_moved += r.step[v] == 1;
done:
	free(near), free(pnormal), free(parent), free(fresh);
	round_free(&r);
	return rc;
}

/* The farthest vertex of m from the reference. */
static int vertex_error(const struct mesh *m, const struct surfdist *tree, double *max,
			struct st_error *err)
{
	double *d = malloc((m->nverts ? m->nverts : 1) * sizeof(*d));
	int rc = d ? surfdist_nearest(tree, (const double (*)[3])m->verts, m->nverts, d, NULL, err)
		   : st_error_set(err, ST_ERR_NOMEM, "refine: out of memory");

	*max = 0;
	for (size_t i = 0; !rc && i < m->nverts; i++)
		*max = fmax(*max, d[i]);
	free(d);
	return rc;
}

static int check_options(const struct refine_options *o, struct st_error *err)
{
	if (!(o->tolerance > 0) || !(o->feature_angle >= 0 && o->feature_angle <= 180) ||
	    !o->samples || !o->max_triangles)
		return st_error_set(err, ST_ERR_ARG,
				    "refine: tolerance must be above 0, the feature angle 0 to 180 "
				    "degrees, samples and the triangle limit above 0");
	return 0;
}

/* The rounds on m until the tolerance, a stall or the triangle limit. */
static int run_rounds(struct mesh *m, const struct mesh *ref, const struct refine_options *o,
		      const struct refine_target *tg, struct pending *pd,
		      struct refine_report *rep, struct st_error *err)
{
	double best, area = 0, best_area = 0;
	size_t stalled = 0;
	bool stop = false;
	int rc = measure(m, ref, o, &rep->facet_error, &rep->error_before, &rep->facets_over,
			 &best_area, err);

	rep->error_after = best = rep->error_before;
	/* an input vertex off the reference: new vertices cannot mend it (one
	 * that move_vertices left short is tried again) */
	while (!rc && rep->facets_over && (rep->vertex_error <= o->tolerance || o->move_vertices) &&
	       rep->rounds < ROUNDS_MAX && stalled < STALL_ROUNDS) {
		if ((rc = split_round(m, rep->facet_error, o, tg, pd, rep, &stop, err)) || stop)
			break;
		rep->rounds++;
		rc = measure(m, ref, o, &rep->facet_error, &rep->error_after, &rep->facets_over,
			     &area, err);
		/* progress: a smaller largest error, or a tenth less area over
		 * the tolerance (a bumpy scan's worst facet may take a few rounds;
		 * facets beside a surface the reference crosses only shrink) */
		stalled = rep->error_after < best || area < AREA_PROGRESS * best_area ? 0
										    : stalled + 1;
		best = fmin(best, rep->error_after);
		best_area = fmin(best_area, area);
	}
	return rc;
}

int refine_mesh(const struct mesh *coarse, const struct mesh *ref,
		const struct refine_options *opt, struct mesh **out, struct refine_report *rep,
		struct st_error *err)
{
	struct surfdist *tree = NULL;
	struct mesh *m = NULL;
	struct pending pd = {0};
	struct refine_target tg = {ref, NULL, cos(opt->feature_angle * M_PI / 180)};
	int rc;

	memset(rep, 0, sizeof(*rep));
	*out = NULL;
	if ((rc = check_options(opt, err)) || (rc = rounded_copy(coarse, &m, err)) ||
	    (rc = require_printable(m, opt->threads, err)))
		goto done;
	rc = surfdist_new((const double (*)[3])ref->verts, ref->nverts,
			  (const uint32_t (*)[3])ref->tris, ref->ntris, &tree, err);
	tg.tree = tree;
	if (!rc && opt->move_vertices)
		rc = move_input_vertices(m, &tg, &pd, rep, err);
	if (!rc)
		rc = vertex_error(m, tree, &rep->vertex_error, err);
	rep->triangles_before = m->ntris;
	if (!rc)
		rc = run_rounds(m, ref, opt, &tg, &pd, rep, err);
	if (rc)
		goto done;
	rep->triangles_after = m->ntris;
	rep->reached = rep->facets_over == 0;
	/* what the splits promise, proved on the result as the check sees it */
	if ((rc = require_printable(m, opt->threads, err))) {
		if (rc == ST_ERR_UNSUPPORTED)
			rc = st_error_set(err, ST_ERR_INTERNAL,
					  "refine: the refined mesh is not printable (a bug)");
		goto done;
	}
	*out = m;
	m = NULL;
done:
	free(pd.want);
	free(pd.short_of);
	surfdist_free(tree);
	mesh_free(m);
	if (rc)
		refine_report_free(rep);
	return rc;
}
