/*
 * heal.c - welding and stitching before the exact repair, and the driver of
 * the healing steps (heal.h; docs/repair.md, "Healing").
 *
 * Both steps merge vertices: every vertex of a cluster takes the index of
 * the cluster's lowest vertex, whose position is kept exactly, so a mesh
 * with nothing to merge is not touched at all.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "heal.h"
#include "ids.h"
#include "repair_impl.h"
#include "vec3.h"
#include "st_grow.h"

/* Grid coordinates beyond this many cells are not searched (no overflow). */
#define HEAL_MAX_CELLS 4.0e18

/* A point in a uniform grid: its cell and its vertex. */
struct cell_point {
	int64_t c[3];
	uint32_t v;
};

static int compare_cell(const int64_t a[3], const int64_t b[3])
{
	for (int k = 0; k < 3; k++)
		if (a[k] != b[k])
			return a[k] < b[k] ? -1 : 1;
	return 0;
}

static int compare_cell_point(const void *pa, const void *pb)
{
	const struct cell_point *a = pa, *b = pb;
	const int c = compare_cell(a->c, b->c);

	return c ? c : (a->v > b->v) - (a->v < b->v);
}

/* A pair of vertices closer than the search radius. */
struct near_pair {
	double d;
	uint32_t v, u;	/* v < u */
};

static int compare_near_pair(const void *pa, const void *pb)
{
	const struct near_pair *a = pa, *b = pb;

	if (a->d != b->d)
		return a->d < b->d ? -1 : 1;
	if (a->v != b->v)
		return a->v < b->v ? -1 : 1;
	return (a->u > b->u) - (a->u < b->u);
}

/* A growable list of near pairs. */
struct pair_list {
	struct near_pair *p;
	size_t n, cap;
};

static int pair_push(struct pair_list *l, double d, uint32_t v, uint32_t u)
{
	struct near_pair *p = st_grow(l->p, &l->cap, l->n + 1, sizeof(*p));

	if (!p)
		return -1;
	l->p = p;
	l->p[l->n].d = d;
	l->p[l->n].v = v < u ? v : u;
	l->p[l->n].u = v < u ? u : v;
	l->n++;
	return 0;
}

/*
 * Every pair of the n vertices listed in ids closer than r (and not equal
 * indices) into *out, sorted by distance: a uniform grid of cell r, each
 * point looked up in its 27 neighbour cells.  Leaves *out empty when the
 * coordinates are too large for r.  Returns 0 or ST_ERR_NOMEM.
 */
static int near_pairs(const double (*verts)[3], const uint32_t *ids, size_t n, double r,
		      struct pair_list *out, struct st_error *err)
{
	struct cell_point *g = malloc((n + 1) * sizeof(*g));

	out->n = 0;
	if (!g)
		return st_error_set(err, ST_ERR_NOMEM, "heal: out of memory for %zu points", n);
	for (size_t i = 0; i < n; i++) {
		for (int k = 0; k < 3; k++) {
			const double c = floor(verts[ids[i]][k] / r);
			if (!(fabs(c) < HEAL_MAX_CELLS)) {
				free(g);
				return 0;
			}
			g[i].c[k] = (int64_t)c;
		}
		g[i].v = ids[i];
	}
	qsort(g, n, sizeof(*g), compare_cell_point);
	for (size_t i = 0; i < n; i++) {
		for (int dx = -1; dx <= 1; dx++)
			for (int dy = -1; dy <= 1; dy++)
				for (int dz = -1; dz <= 1; dz++) {
					const int64_t want[3] = {g[i].c[0] + dx, g[i].c[1] + dy,
								 g[i].c[2] + dz};
					size_t lo = 0, hi = n;
					/* First point of cell want. */
					while (lo < hi) {
						size_t mid = lo + (hi - lo) / 2;
						if (compare_cell(g[mid].c, want) < 0)
							lo = mid + 1;
						else
							hi = mid;
					}
					for (size_t j = lo; j < n && !compare_cell(g[j].c, want);
					     j++) {
						const uint32_t v = g[i].v, u = g[j].v;
						double d;
						if (u <= v)
							continue; /* each pair once */
						d = vec3_dist(verts[v], verts[u]);
						if (d < r && pair_push(out, d, v, u)) {
							free(g);
							return st_error_set(err, ST_ERR_NOMEM,
									    "heal: out of memory "
									    "for near vertices");
						}
					}
				}
	}
	free(g);
	if (out->n) /* out->p may be NULL: nothing near */
		qsort(out->p, out->n, sizeof(*out->p), compare_near_pair);
	return 0;
}

static int compare_edge(const void *pa, const void *pb)
{
	const struct heal_edge *a = pa, *b = pb;

	if (a->a != b->a)
		return a->a < b->a ? -1 : 1;
	if (a->b != b->b)
		return a->b < b->b ? -1 : 1;
	return (a->t > b->t) - (a->t < b->t);
}

static bool regular(const uint32_t t[3])
{
	return t[0] != t[1] && t[1] != t[2] && t[0] != t[2];
}

int heal_edges(const struct heal_work *w, struct heal_edge **edges, size_t *n,
	       struct st_error *err)
{
	struct heal_edge *e;
	size_t c = 0;

	*edges = NULL;
	*n = 0;
	if (w->ntris > (SIZE_MAX / sizeof(*e) - 1) / 3)
		return st_error_set(err, ST_ERR_NOMEM, "heal: too many triangles for the edges");
	e = malloc((3 * w->ntris + 1) * sizeof(*e));
	if (!e)
		return st_error_set(err, ST_ERR_NOMEM, "heal: out of memory for %zu edges",
				    3 * w->ntris);
	for (size_t t = 0; t < w->ntris; t++) {
		if (!regular(w->tris[t]))
			continue;
		for (int k = 0; k < 3; k++) {
			const uint32_t a = w->tris[t][k], b = w->tris[t][(k + 1) % 3];
			e[c].a = a < b ? a : b;
			e[c].b = a < b ? b : a;
			e[c].t = (uint32_t)t;
			c++;
		}
	}
	qsort(e, c, sizeof(*e), compare_edge);
	*edges = e;
	*n = c;
	return 0;
}

/*
 * Point every triangle at its vertices' cluster roots and drop the
 * triangles that this makes irregular (they were regular before: the
 * irregular ones of the input stay for the cleaning to count).  Returns
 * how many were dropped.
 */
static size_t remap(struct heal_work *w, uint32_t *root)
{
	size_t kept = 0, dropped = 0;

	for (size_t t = 0; t < w->ntris; t++) {
		uint32_t m[3];
		const bool was = regular(w->tris[t]);
		for (int k = 0; k < 3; k++)
			m[k] = uf_find(root, w->tris[t][k]);
		if (was && !regular(m)) {
			dropped++;
			continue;
		}
		memcpy(w->tris[kept++], m, sizeof(m));
	}
	w->ntris = kept;
	return dropped;
}

/* The vertices some triangle uses, ascending, into a new array. */
static uint32_t *used_vertices(const struct heal_work *w, size_t *n)
{
	uint8_t *used = calloc(w->nverts + 1, 1);
	uint32_t *ids = malloc((w->nverts + 1) * sizeof(*ids));
	size_t c = 0;

	if (!used || !ids) {
		free(used);
		free(ids);
		return NULL;
	}
	for (size_t t = 0; t < w->ntris; t++)
		for (int k = 0; k < 3; k++)
			used[w->tris[t][k]] = 1;
	for (size_t v = 0; v < w->nverts; v++)
		if (used[v])
			ids[c++] = (uint32_t)v;
	free(used);
	*n = c;
	return ids;
}

/* A fresh union-find forest over w's vertices, or NULL. */
static uint32_t *new_forest(const struct heal_work *w)
{
	uint32_t *p = malloc((w->nverts + 1) * sizeof(*p));

	if (p)
		for (size_t v = 0; v < w->nverts; v++)
			p[v] = (uint32_t)v;
	return p;
}

/* Step 1: weld vertices closer than tol (chains of them weld as one). */
static int weld(struct heal_work *w, double tol, struct repair_report *rep, struct st_error *err)
{
	struct pair_list pl = {0};
	size_t n = 0;
	uint32_t *ids = used_vertices(w, &n), *root = new_forest(w);
	int rc = 0;

	if (!ids || !root) {
		rc = st_error_set(err, ST_ERR_NOMEM, "heal: out of memory welding");
		goto out;
	}
	rc = near_pairs((const double(*)[3])w->verts, ids, n, tol, &pl, err);
	if (rc)
		goto out;
	for (size_t i = 0; i < pl.n; i++)
		uf_union(root, pl.p[i].v, pl.p[i].u);
	for (size_t i = 0; i < n; i++)
		if (uf_find(root, ids[i]) != ids[i])
			rep->welded_vertices++;
	if (rep->welded_vertices)
		rep->weld_collapsed = remap(w, root);
out:
	free(pl.p);
	free(ids);
	free(root);
	return rc;
}

/*
 * The boundary of w: which vertices lie on a boundary edge (on[v]), which
 * loop of boundary edges they belong to (loop[v], a union-find forest
 * over edge-connected boundary), and each vertex's shortest incident edge
 * (shortest[v], mm).
 */
struct boundary {
	uint8_t *on;
	uint32_t *loop;
	double *shortest;
	uint32_t *ids;	/* the boundary vertices, ascending */
	size_t n;
	struct heal_edge *edges; /* every edge, sorted (heal_edges) */
	size_t nedges;
	/* Boundary neighbours of v: nbr[first[v] .. first[v + 1]). */
	size_t *first;
	uint32_t *nbr;
};

static void boundary_free(struct boundary *b)
{
	free(b->on);
	free(b->loop);
	free(b->shortest);
	free(b->ids);
	free(b->edges);
	free(b->first);
	free(b->nbr);
}

/* Fill b->first and b->nbr from the boundary edges (runs of one in b->edges). */
static int boundary_neighbours(const struct heal_work *w, struct boundary *b,
			       struct st_error *err)
{
	size_t *fill;

	b->first = calloc(w->nverts + 2, sizeof(*b->first));
	b->nbr = malloc((b->nedges + 1) * 2 * sizeof(*b->nbr));
	fill = calloc(w->nverts + 1, sizeof(*fill));
	if (!b->first || !b->nbr || !fill) {
		free(fill);
		return st_error_set(err, ST_ERR_NOMEM, "heal: out of memory finding the boundary");
	}
	for (int pass = 0; pass < 2; pass++) {
		for (size_t i = 0; i < b->nedges;) {
			const struct heal_edge *e = &b->edges[i];
			size_t j = i + 1;
			while (j < b->nedges && b->edges[j].a == e->a && b->edges[j].b == e->b)
				j++;
			if (j == i + 1 && pass == 0) {
				b->first[e->a + 1]++;
				b->first[e->b + 1]++;
			} else if (j == i + 1) {
				b->nbr[b->first[e->a] + fill[e->a]++] = e->b;
				b->nbr[b->first[e->b] + fill[e->b]++] = e->a;
			}
			i = j;
		}
		if (pass == 0)
			for (size_t v = 0; v < w->nverts; v++)
				b->first[v + 1] += b->first[v];
	}
	free(fill);
	return 0;
}

/*
 * Whether boundary vertices v and u (closer than gamma) look like two
 * sides of one gap: a boundary edge at v and one at u whose other ends lie
 * within gamma too (they may be one vertex, where a crack opens).  Lone
 * corners that come near each other, as in a soup, do not.
 */
static bool edge_matched(const struct heal_work *w, const struct boundary *b, uint32_t v,
			 uint32_t u, double gamma)
{
	for (size_t i = b->first[v]; i < b->first[v + 1]; i++)
		for (size_t j = b->first[u]; j < b->first[u + 1]; j++) {
			const uint32_t v2 = b->nbr[i], u2 = b->nbr[j];
			if (v2 != u && u2 != v && vec3_dist(w->verts[v2], w->verts[u2]) < gamma)
				return true;
		}
	return false;
}

static int find_boundary(const struct heal_work *w, struct boundary *b, struct st_error *err)
{
	struct heal_edge *e = NULL;
	size_t ne = 0;
	int rc;

	memset(b, 0, sizeof(*b));
	rc = heal_edges(w, &e, &ne, err);
	if (rc)
		return rc;
	b->on = calloc(w->nverts + 1, 1);
	b->loop = new_forest(w);
	b->shortest = malloc((w->nverts + 1) * sizeof(*b->shortest));
	b->ids = malloc((w->nverts + 1) * sizeof(*b->ids));
	if (!b->on || !b->loop || !b->shortest || !b->ids) {
		b->edges = e;
		boundary_free(b);
		return st_error_set(err, ST_ERR_NOMEM, "heal: out of memory finding the boundary");
	}
	for (size_t v = 0; v < w->nverts; v++)
		b->shortest[v] = HUGE_VAL;
	for (size_t i = 0; i < ne;) {
		size_t j = i + 1;
		const double len = vec3_dist(w->verts[e[i].a], w->verts[e[i].b]);
		while (j < ne && e[j].a == e[i].a && e[j].b == e[i].b)
			j++;
		b->shortest[e[i].a] = fmin(b->shortest[e[i].a], len);
		b->shortest[e[i].b] = fmin(b->shortest[e[i].b], len);
		if (j == i + 1) {
			b->on[e[i].a] = b->on[e[i].b] = 1;
			uf_union(b->loop, e[i].a, e[i].b);
		}
		i = j;
	}
	for (size_t v = 0; v < w->nverts; v++)
		if (b->on[v])
			b->ids[b->n++] = (uint32_t)v;
	b->edges = e;
	b->nedges = ne;
	return boundary_neighbours(w, b, err);
}

/* Whether x and y are the ends of an edge of the mesh. */
static bool adjacent(const struct boundary *b, uint32_t x, uint32_t y)
{
	const uint32_t lo = x < y ? x : y, hi = x < y ? y : x;
	size_t l = 0, h = b->nedges;

	while (l < h) {
		const size_t mid = l + (h - l) / 2;
		const struct heal_edge *e = &b->edges[mid];
		if (e->a < lo || (e->a == lo && e->b < hi))
			l = mid + 1;
		else
			h = mid;
	}
	return l < b->nedges && b->edges[l].a == lo && b->edges[l].b == hi;
}

/* Portion pairs joined by stitching, for counting distinct gaps. */
static int compare_u64(const void *pa, const void *pb)
{
	const uint64_t a = *(const uint64_t *)pa, b = *(const uint64_t *)pb;

	return (a > b) - (a < b);
}

/*
 * Whether clusters with roots ra and rb (member lists through next[]) may
 * merge: no edge may join two vertices of one cluster, or merging would
 * collapse it and the triangles on it.
 */
static bool may_merge(const struct boundary *b, const uint32_t *next, uint32_t ra, uint32_t rb)
{
	for (uint32_t x = ra; x != UINT32_MAX; x = next[x])
		for (uint32_t y = rb; y != UINT32_MAX; y = next[y])
			if (adjacent(b, x, y))
				return false;
	return true;
}

/*
 * Step 2: snap boundary vertices onto other boundary vertices within
 * gamma, nearest pairs first (heal.h says which snaps are allowed).
 */
static int stitch(struct heal_work *w, double gamma, struct repair_report *rep,
		  size_t *n_boundary, struct st_error *err)
{
	struct boundary b;
	struct pair_list pl = {0};
	uint32_t *root = NULL, *next = NULL, *tail = NULL;
	uint64_t *gaps = NULL;
	size_t ngaps = 0;
	int rc = find_boundary(w, &b, err);

	if (rc)
		return rc;
	*n_boundary = b.n;
	if (b.n < 2)
		goto out;
	rc = near_pairs((const double(*)[3])w->verts, b.ids, b.n, gamma, &pl, err);
	if (rc || pl.n == 0)
		goto out;
	root = new_forest(w);
	next = malloc((w->nverts + 1) * sizeof(*next));
	tail = new_forest(w);
	gaps = malloc((w->nverts + 1) * sizeof(*gaps));
	if (!root || !next || !tail || !gaps) {
		rc = st_error_set(err, ST_ERR_NOMEM, "heal: out of memory stitching");
		goto out;
	}
	for (size_t v = 0; v < w->nverts; v++)
		next[v] = UINT32_MAX;
	for (size_t i = 0; i < pl.n; i++) {
		const struct near_pair *p = &pl.p[i];
		uint32_t ra = uf_find(root, p->v), rb = uf_find(root, p->u);
		if (ra == rb)
			continue;
		if (!(p->d < HEAL_STITCH_EDGE * b.shortest[p->v]) ||
		    !(p->d < HEAL_STITCH_EDGE * b.shortest[p->u]) ||
		    !edge_matched(w, &b, p->v, p->u, gamma) || !may_merge(&b, next, ra, rb))
			continue;
		if (rb < ra) {
			const uint32_t t = ra;
			ra = rb;
			rb = t;
		}
		root[rb] = ra; /* the lower index stays the root, as uf_union */
		next[tail[ra]] = rb;
		tail[ra] = tail[rb];
	}
	/* Report: moved vertices, the longest move, distinct loop pairs. */
	for (size_t i = 0; i < b.n; i++) {
		const uint32_t v = b.ids[i], r = uf_find(root, v);
		if (r == v)
			continue;
		rep->stitched_vertices++;
		rep->stitch_max_gap = fmax(rep->stitch_max_gap, vec3_dist(w->verts[v], w->verts[r]));
		uint32_t lv = uf_find(b.loop, v), lr = uf_find(b.loop, r);
		gaps[ngaps++] = lv < lr ? (uint64_t)lv << 32 | lr : (uint64_t)lr << 32 | lv;
	}
	qsort(gaps, ngaps, sizeof(*gaps), compare_u64);
	for (size_t i = 0; i < ngaps; i++)
		if (i == 0 || gaps[i] != gaps[i - 1])
			rep->stitched_gaps++;
	if (rep->stitched_vertices)
		rep->stitch_collapsed = remap(w, root);
out:
	free(pl.p);
	free(root);
	free(next);
	free(tail);
	free(gaps);
	boundary_free(&b);
	return rc;
}

/* w as a new welded mesh. */
static int build(const struct heal_work *w, struct mesh **out, struct st_error *err)
{
	struct mesh_builder *b = mesh_builder_new(w->ntris);
	uint32_t *index = malloc((w->nverts + 1) * sizeof(*index));
	int rc = 0;

	*out = NULL;
	if (!b || !index) {
		rc = st_error_set(err, ST_ERR_NOMEM, "heal: out of memory building the mesh");
		goto out;
	}
	for (size_t v = 0; v < w->nverts; v++)
		index[v] = UINT32_MAX;
	for (size_t t = 0; t < w->ntris && !rc; t++) {
		uint32_t c[3];
		for (int k = 0; k < 3 && !rc; k++) {
			const uint32_t v = w->tris[t][k];
			if (index[v] == UINT32_MAX)
				rc = mesh_builder_vertex(b, w->verts[v], &index[v], err);
			c[k] = index[v];
		}
		if (!rc)
			rc = mesh_builder_triangle(b, c[0], c[1], c[2], err);
	}
	if (!rc) {
		*out = mesh_builder_finish(b);
		b = NULL;
		if (!*out)
			rc = st_error_set(err, ST_ERR_NOMEM, "heal: out of memory building the mesh");
	}
out:
	mesh_builder_free(b);
	free(index);
	return rc;
}

int heal_mesh(const struct mesh *in, const struct repair_options *opt, struct mesh **out,
	      struct repair_report *rep, struct st_error *err)
{
	struct heal_work w = {0};
	size_t n_boundary = 1; /* unknown until stitching looks */
	int rc = 0;

	*out = NULL;
	if (!isfinite(opt->weld) || !isfinite(opt->stitch))
		return st_error_set(err, ST_ERR_ARG,
				    "repair: weld %g mm and stitch %g mm must be finite", opt->weld,
				    opt->stitch);
	/* Default: HEAL_WELD_ULPS float32 ulps of the largest coordinate. */
	rep->weld_tolerance =
		opt->weld < 0 ? HEAL_WELD_ULPS * vec3_ulp((const double(*)[3])in->verts, in->nverts, 24)
			      : opt->weld;
	rep->stitch_tolerance = opt->keep_holes ? 0
				: opt->stitch < 0 ? HEAL_STITCH_FACTOR * opt->epsilon
						  : opt->stitch;
	if (in->ntris == 0 || (rep->weld_tolerance == 0 && opt->keep_holes))
		return 0;

	w.nverts = in->nverts;
	w.ntris = w.cap_tris = in->ntris;
	w.cap_verts = in->nverts + 1;
	w.verts = malloc(w.cap_verts * sizeof(*w.verts));
	w.tris = malloc((in->ntris + 1) * sizeof(*w.tris));
	if (!w.verts || !w.tris) {
		rc = st_error_set(err, ST_ERR_NOMEM, "heal: out of memory copying %zu triangles",
				  in->ntris);
		goto out;
	}
	if (in->nverts)
		memcpy(w.verts, in->verts, in->nverts * sizeof(*w.verts));
	if (in->ntris)
		memcpy(w.tris, in->tris, in->ntris * sizeof(*w.tris));

	if (rep->weld_tolerance > 0) {
		repair_progress(opt, "welding the mesh", 0);
		rc = weld(&w, rep->weld_tolerance, rep, err);
	}
	if (!rc && rep->stitch_tolerance > 0) {
		repair_progress(opt, "stitching the gaps", 0);
		rc = stitch(&w, rep->stitch_tolerance, rep, &n_boundary, err);
	}
	/* A closed mesh has no hole: skip the second walk over its edges. */
	if (!rc && !opt->keep_holes && n_boundary > 0) {
		repair_progress(opt, "filling the holes", 0);
		rc = heal_fill(&w, rep, err);
	}
	if (!rc && (rep->welded_vertices || rep->stitched_vertices || rep->holes_filled))
		rc = build(&w, out, err);
out:
	free(w.verts);
	free(w.tris);
	return rc;
}
