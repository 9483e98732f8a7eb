/*
 * topology.c - the topology report of an indexed mesh (mesh_analyze).
 *
 * Steps, each over flat uint32_t arrays so a million triangles stay within
 * about 100 bytes each:
 *   1. classify triangles: irregular, degenerate (exact), duplicate; the rest
 *      form the layer (seed 000 Def. 3.1);
 *   2. edges and edge -> corner incidence (CSR) from the vertex stars;
 *   3. components, manifold components, vertex fans, orientation and
 *      boundary loops;
 *   4. count self-intersections exactly (CGAL bridge), on its own thread
 *      beside steps 2 and 3 and on the same vertex stars, then parts.
 */
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "exact.h"
#include "ids.h"
#include "mesh.h"
#include "parts.h"
#include "st_grow.h"

enum tri_class { TRI_LAYER = 0, TRI_IRREGULAR, TRI_DEGENERATE, TRI_DUPLICATE };

/* Working state; every array is indexed as its comment says. */
struct topo {
	const struct mesh *m;
	uint8_t *tclass;	/* [tri] enum tri_class */
	uint32_t *voff;		/* [vertex] start in vtri; [nverts] = end */
	uint32_t *vtri;		/* layer-candidate triangles around each vertex */
	uint32_t *eoff;		/* [edge] start in ecorner; [nedges] = end */
	uint32_t *ecorner;	/* corner ids 3*tri+k incident to each edge */
	size_t nedges;
	uint32_t *shell;	/* [tri] manifold component (shell), 0.. */
};

static const struct {
	const char *code;
	const char *text;
} reason_table[MESH_REASON_COUNT] = {
	[MESH_REASON_EMPTY] = {"empty", "no usable triangles"},
	[MESH_REASON_IRREGULAR] = {"irregular", "triangles that repeat a vertex"},
	[MESH_REASON_DEGENERATE] = {"degenerate", "triangles whose corners are collinear"},
	[MESH_REASON_OPEN] = {"open", "holes: edges a shell does not close"},
	[MESH_REASON_SELF_INTERSECTION] = {"self_intersection",
					   "triangles that cross or overlap each other"},
	[MESH_REASON_MISNESTED] = {"misnested",
				   "shells facing outwards inside a solid, or inwards outside "
				   "every solid"},
	[MESH_REASON_SEVERAL_PARTS] = {"several_parts",
				       "separate parts, printed side by side (--split in "
				       "stratum repair writes one file each)"},
	[MESH_REASON_NOT_MANIFOLD_CONNECTED] =
		{"not_manifold_connected",
		 "parts or cavities touching along singular edges"},
	[MESH_REASON_DUPLICATE] = {"duplicates", "equivalent (duplicated) triangles"},
	[MESH_REASON_INCONSISTENT_ORIENTATION] =
		{"inconsistent_orientation", "neighbouring triangles face opposite ways"},
	[MESH_REASON_INSIDE_OUT] = {"inside_out", "closed surface oriented inside out"},
};

const char *mesh_reason_code(enum mesh_reason r)
{
	return (unsigned)r < MESH_REASON_COUNT ? reason_table[r].code : "unknown";
}

const char *mesh_reason_text(enum mesh_reason r)
{
	return (unsigned)r < MESH_REASON_COUNT ? reason_table[r].text : "unknown";
}

/*
 * Union-find whose links carry a parity bit: the parity of x relative to its
 * root says whether x must be flipped to match the root's orientation.
 */
static uint32_t pf_find(uint32_t *parent, uint8_t *par, uint32_t x, uint8_t *parity)
{
	uint32_t root = x;
	uint8_t p = 0, px;

	while (parent[root] != root) {
		p ^= par[root];
		root = parent[root];
	}
	/* Point the whole path at the root, keeping each node's parity. */
	for (px = p; parent[x] != root && x != root;) {
		uint32_t next = parent[x];
		uint8_t pnext = px ^ par[x];
		parent[x] = root;
		par[x] = px;
		x = next;
		px = pnext;
	}
	*parity = p;
	return root;
}

/* Join a and b so that their parities differ by flip; false on a conflict. */
static bool pf_union(uint32_t *parent, uint8_t *par, uint32_t a, uint32_t b, uint8_t flip)
{
	uint8_t pa, pb;
	uint32_t ra = pf_find(parent, par, a, &pa), rb = pf_find(parent, par, b, &pb);

	if (ra == rb)
		return (pa ^ pb) == flip;
	if (ra > rb) {
		uint32_t t = ra;
		ra = rb;
		rb = t;
	}
	parent[rb] = ra;
	par[rb] = pa ^ pb ^ flip;
	return true;
}

/* Step 1a: irregular and degenerate triangles; the rest are layer candidates. */
static void classify_triangles(struct topo *tp, struct mesh_report *rep)
{
	const struct mesh *m = tp->m;

	for (size_t t = 0; t < m->ntris; t++) {
		const uint32_t *v = m->tris[t];

		if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) {
			tp->tclass[t] = TRI_IRREGULAR;
			rep->irregular++;
		} else if (exact_collinear(m->verts[v[0]], m->verts[v[1]], m->verts[v[2]])) {
			tp->tclass[t] = TRI_DEGENERATE;
			rep->degenerate++;
		} else {
			tp->tclass[t] = TRI_LAYER;
		}
	}
}

/* Step 1b: the star of every vertex (its layer-candidate triangles), as
 * compressed rows.  Walking stars keeps memory access local where a hash
 * table of edges would jump across the whole mesh. */
static int build_stars(struct topo *tp, struct st_error *err)
{
	const struct mesh *m = tp->m;

	tp->voff = calloc(m->nverts + 1, sizeof(*tp->voff));
	tp->vtri = malloc((m->ntris * 3 + 1) * sizeof(*tp->vtri));
	if (!tp->voff || !tp->vtri)
		return st_error_set(err, ST_ERR_NOMEM, "out of memory building vertex stars");
	for (size_t t = 0; t < m->ntris; t++)
		if (tp->tclass[t] == TRI_LAYER)
			for (int k = 0; k < 3; k++)
				tp->voff[m->tris[t][k] + 1]++;
	for (size_t v = 0; v < m->nverts; v++)
		tp->voff[v + 1] += tp->voff[v];
	for (size_t t = 0; t < m->ntris; t++)
		if (tp->tclass[t] == TRI_LAYER)
			for (int k = 0; k < 3; k++)
				tp->vtri[tp->voff[m->tris[t][k]]++] = (uint32_t)t;
	for (size_t v = m->nverts; v > 0; v--)
		tp->voff[v] = tp->voff[v - 1];
	tp->voff[0] = 0;
	return 0;
}

/* Step 1c: a triangle with the same vertex set as an earlier one (either
 * orientation) is a duplicate; both are in the star of their lowest vertex. */
static void find_duplicates(struct topo *tp, struct mesh_report *rep)
{
	const struct mesh *m = tp->m;

	for (size_t t = 0; t < m->ntris; t++) {
		uint32_t key[3];

		if (tp->tclass[t] != TRI_LAYER)
			continue;
		sort3(m->tris[t], key);
		for (uint32_t i = tp->voff[key[0]]; i < tp->voff[key[0] + 1]; i++) {
			uint32_t other = tp->vtri[i];

			if (other >= t)
				break; /* stars list triangles in increasing order */
			if (tp->tclass[other] != TRI_LAYER)
				continue;
			/* other has key[0] (it is in its star): the same set iff it
			 * has the other two as well. */
			const uint32_t *o = m->tris[other];
			if ((o[0] == key[1] || o[1] == key[1] || o[2] == key[1]) &&
			    (o[0] == key[2] || o[1] == key[2] || o[2] == key[2])) {
				tp->tclass[t] = TRI_DUPLICATE;
				rep->duplicates++;
				break;
			}
		}
		rep->triangles += tp->tclass[t] == TRI_LAYER;
	}
}

/* Step 1d: the stars keep the layer's triangles only, as the exact pass
 * takes them (a file with duplicates; most have none). */
static void drop_duplicates_from_stars(struct topo *tp)
{
	uint32_t kept = 0;

	for (size_t v = 0; v < tp->m->nverts; v++) {
		uint32_t from = tp->voff[v], to = tp->voff[v + 1];

		tp->voff[v] = kept;
		for (uint32_t i = from; i < to; i++)
			if (tp->tclass[tp->vtri[i]] == TRI_LAYER)
				tp->vtri[kept++] = tp->vtri[i];
	}
	tp->voff[tp->m->nverts] = kept;
}

struct half {
	uint32_t hi;	 /* the edge's other (higher) vertex */
	uint32_t corner; /* 3*tri+k */
};

static int compare_half(const void *a, const void *b)
{
	const struct half *x = a, *y = b;

	if (x->hi != y->hi)
		return x->hi < y->hi ? -1 : 1;
	return x->corner < y->corner ? -1 : x->corner > y->corner;
}

/* Sort a vertex's half-edges as compare_half orders them: by insertion
 * for the few of a usual vertex (about three), where qsort's calls
 * through a pointer cost 3 % of checking a 1M-triangle sphere. */
static void sort_halves(struct half *h, size_t n)
{
	if (n > 16) {
		qsort(h, n, sizeof(*h), compare_half);
		return;
	}
	for (size_t i = 1; i < n; i++) {
		struct half x = h[i];
		size_t j = i;

		for (; j > 0 && compare_half(&h[j - 1], &x) > 0; j--)
			h[j] = h[j - 1];
		h[j] = x;
	}
}

/* Start a new edge at position start of ecorner; grows eoff (capacity
 * *cap) as needed, keeping room for the end marker after the last edge. */
static int push_edge(struct topo *tp, size_t *cap, uint32_t start)
{
	uint32_t *p = st_grow(tp->eoff, cap, tp->nedges + 2, sizeof(*tp->eoff));

	if (!p)
		return -1;
	tp->eoff = p;
	tp->eoff[tp->nedges++] = start;
	return 0;
}

/*
 * Step 2: edges and edge -> corner incidence straight from the stars.  Each
 * edge belongs to its lower vertex; gathering that vertex's half-edges and
 * sorting them by the other end groups every edge's corners together.
 */
static int build_edges(struct topo *tp, struct st_error *err)
{
	const struct mesh *m = tp->m;
	size_t cap = m->ntris * 3 / 2 + 17, hcap = 64, pos = 0; /* eoff's */
	struct half *h = malloc(hcap * sizeof(*h));
	int rc = 0;

	tp->eoff = malloc(cap * sizeof(*tp->eoff));
	tp->ecorner = malloc((m->ntris * 3 + 1) * sizeof(*tp->ecorner));
	if (!h || !tp->eoff || !tp->ecorner)
		goto out_nomem;
	for (size_t lo = 0; lo < m->nverts; lo++) {
		size_t nh = 0;
		/* At most two half-edges per triangle of the star. */
		void *p = st_grow(h, &hcap, 2 * (size_t)(tp->voff[lo + 1] - tp->voff[lo]) + 1,
				  sizeof(*h));

		if (!p)
			goto out_nomem;
		h = p;
		for (uint32_t i = tp->voff[lo]; i < tp->voff[lo + 1]; i++) {
			uint32_t t = tp->vtri[i];
			if (tp->tclass[t] != TRI_LAYER)
				continue;
			/* Of a layer triangle's edges (corners distinct), only the
			 * two at lo can start at lo as their lower vertex: the one
			 * leaving lo (corner k) and the one arriving (corner k-1). */
			const uint32_t *v = m->tris[t];
			const uint32_t k = v[0] == lo ? 0 : v[1] == lo ? 1 : 2;
			const uint32_t next = v[k == 2 ? 0 : k + 1], prev = v[k == 0 ? 2 : k - 1];
			if (next > lo) {
				h[nh].hi = next;
				h[nh++].corner = 3 * t + k;
			}
			if (prev > lo) {
				h[nh].hi = prev;
				h[nh++].corner = 3 * t + (k == 0 ? 2 : k - 1);
			}
		}
		sort_halves(h, nh);
		for (size_t i = 0; i < nh; i++) {
			if (i == 0 || h[i].hi != h[i - 1].hi)
				if (push_edge(tp, &cap, (uint32_t)pos))
					goto out_nomem;
			tp->ecorner[pos++] = h[i].corner;
		}
	}
	tp->eoff[tp->nedges] = (uint32_t)pos;
	goto out;
out_nomem:
	rc = st_error_set(err, ST_ERR_NOMEM, "out of memory building edges");
out:
	free(h);
	return rc;
}

static uint32_t edge_count(const struct topo *tp, size_t e)
{
	return tp->eoff[e + 1] - tp->eoff[e];
}

/* Vertex end (0 or 1) of edge e, read off its first corner. */
static uint32_t edge_vertex(const struct topo *tp, size_t e, int end)
{
	uint32_t c = tp->ecorner[tp->eoff[e]];

	return tp->m->tris[c / 3][(c % 3 + (uint32_t)end) % 3];
}

/* Vertex at corner c (3*tri+k) and the corner of the same triangle at vertex v. */
static uint32_t corner_vertex(const struct mesh *m, uint32_t c)
{
	return m->tris[c / 3][c % 3];
}

/* The next corner of the same triangle. */
static uint32_t next_corner(uint32_t c)
{
	return c % 3 == 2 ? c - 2 : c + 1;
}

static uint32_t corner_at(const struct mesh *m, uint32_t tri, uint32_t v)
{
	for (uint32_t k = 0; k < 3; k++)
		if (m->tris[tri][k] == v)
			return 3 * tri + k;
	return 3 * tri; /* not reached: v is a vertex of tri */
}

/* Does corner c's edge run from the smaller vertex to the larger? */
static bool corner_forward(const struct mesh *m, uint32_t c)
{
	uint32_t t = c / 3, k = c % 3;

	return m->tris[t][k] < m->tris[t][(k + 1) % 3];
}

/*
 * Step 3b: counts per edge class, components, manifold components and
 * orientability.  Manifold components join triangles across 2-connected
 * edges only; the same joins, with a parity bit saying "flip one to match
 * the other", find a non-orientable surface (a Moebius strip) as a conflict.
 */
static int count_edges_and_parts(struct topo *tp, struct mesh_report *rep, struct st_error *err)
{
	const struct mesh *m = tp->m;
	uint32_t *comp = malloc((m->ntris + 1) * sizeof(*comp));
	uint32_t *mcomp = malloc((m->ntris + 1) * sizeof(*mcomp));
	uint8_t *flip = calloc(m->ntris + 1, 1);
	int rc = 0;

	if (!comp || !mcomp || !flip) {
		rc = st_error_set(err, ST_ERR_NOMEM, "out of memory finding components");
		goto out;
	}
	for (size_t t = 0; t < m->ntris; t++)
		comp[t] = mcomp[t] = (uint32_t)t;
	rep->edges = tp->nedges;
	rep->consistently_oriented = true;
	rep->orientable = true;
	for (size_t e = 0; e < tp->nedges; e++) {
		uint32_t n = edge_count(tp, e), first = tp->ecorner[tp->eoff[e]] / 3;

		if (n == 1)
			rep->boundary_edges++;
		else if (n > 2)
			rep->singular_edges++;
		if (n % 2)
			rep->odd_edges++;
		for (uint32_t i = 1; i < n; i++)
			uf_union(comp, first, tp->ecorner[tp->eoff[e] + i] / 3);
		if (n == 2) {
			uint32_t c0 = tp->ecorner[tp->eoff[e]], c1 = tp->ecorner[tp->eoff[e] + 1];
			/* Walked the same way twice: one of the two is flipped. */
			uint8_t same = corner_forward(m, c0) == corner_forward(m, c1);

			if (same) {
				rep->flipped_edges++;
				rep->consistently_oriented = false;
			}
			if (!pf_union(mcomp, flip, c0 / 3, c1 / 3, same))
				rep->orientable = false;
		}
	}
	for (size_t t = 0; t < m->ntris; t++)
		if (tp->tclass[t] == TRI_LAYER)
			rep->components += uf_find(comp, (uint32_t)t) == t;
	/* comp is done with: it becomes the shell numbers.  Roots come first
	 * in their set (the lower root wins a union). */
	for (size_t t = 0; t < m->ntris; t++) {
		uint8_t parity;

		if (tp->tclass[t] != TRI_LAYER)
			continue;
		if (pf_find(mcomp, flip, (uint32_t)t, &parity) == t)
			comp[t] = (uint32_t)rep->manifold_components++;
		else
			comp[t] = comp[mcomp[t]]; /* pf_find pointed t at its root */
	}
	tp->shell = comp;
	comp = NULL;
out:
	free(comp);
	free(mcomp);
	free(flip);
	return rc;
}

static int compare_end(const void *a, const void *b)
{
	uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;

	return x < y ? -1 : x > y;
}

/*
 * Step 3d: non-manifold vertices and boundary loops, from the fans around
 * each vertex.  Corners at the same vertex are joined across 2-connected
 * edges; a vertex whose corners form more than one fan, or that ends a
 * singular edge, is non-manifold.  Boundary edges that end in the same fan at
 * a vertex continue each other, so loops are the connected groups of
 * boundary edges under that relation.
 */
static int check_vertices_and_loops(struct topo *tp, struct mesh_report *rep,
				    struct st_error *err)
{
	const struct mesh *m = tp->m;
	size_t ncorners = m->ntris * 3, nb = 0;
	uint32_t *fan = malloc(ncorners * sizeof(*fan));
	uint8_t *vstate = calloc(m->nverts, 1); /* bit0 used, bit1 singular, bits2+ fans */
	uint32_t *bedge = NULL;			/* boundary edge ids */
	uint64_t(*ends)[2] = NULL;		/* (vertex<<32 | fan root), boundary index */
	uint32_t *loop = NULL;
	int rc = 0;

	if (!fan || !vstate) {
		rc = st_error_set(err, ST_ERR_NOMEM, "out of memory checking vertices");
		goto out;
	}
	for (size_t c = 0; c < ncorners; c++)
		fan[c] = (uint32_t)c;
	for (size_t e = 0; e < tp->nedges; e++) {
		uint32_t n = edge_count(tp, e);

		if (n > 2) {
			vstate[edge_vertex(tp, e, 0)] |= 2;
			vstate[edge_vertex(tp, e, 1)] |= 2;
		}
		if (n == 1)
			nb++;
		if (n != 2)
			continue;
		/* The corners at each end of the edge: the first corner runs from
		 * end 0 to end 1; the second starts at one of them. */
		const uint32_t c0 = tp->ecorner[tp->eoff[e]], c1 = tp->ecorner[tp->eoff[e] + 1];
		const uint32_t c0_end = next_corner(c0), c1_end = next_corner(c1);
		const bool c1_from_start = corner_vertex(m, c1) == corner_vertex(m, c0);
		uf_union(fan, c0, c1_from_start ? c1 : c1_end);
		uf_union(fan, c0_end, c1_from_start ? c1_end : c1);
	}
	for (size_t c = 0; c < ncorners; c++) {
		uint32_t v;

		if (tp->tclass[c / 3] != TRI_LAYER)
			continue;
		v = corner_vertex(m, (uint32_t)c);
		vstate[v] |= 1;
		if (uf_find(fan, (uint32_t)c) == c && (vstate[v] >> 2) < 2)
			vstate[v] = (uint8_t)(vstate[v] + 4);
	}
	for (size_t v = 0; v < m->nverts; v++) {
		if (!(vstate[v] & 1))
			continue;
		/* The bounding box of the vertices the layer uses, once each. */
		for (int k = 0; k < 3; k++) {
			const double c = m->verts[v][k];
			if (rep->vertices == 0 || c < rep->bbox_min[k])
				rep->bbox_min[k] = c;
			if (rep->vertices == 0 || c > rep->bbox_max[k])
				rep->bbox_max[k] = c;
		}
		rep->vertices++;
		if ((vstate[v] & 2) || (vstate[v] >> 2) > 1)
			rep->nonmanifold_vertices++;
	}

	if (nb == 0)
		goto out;
	bedge = malloc(nb * sizeof(*bedge));
	ends = malloc(nb * 2 * sizeof(*ends));
	loop = malloc(nb * sizeof(*loop));
	if (!bedge || !ends || !loop) {
		rc = st_error_set(err, ST_ERR_NOMEM, "out of memory tracing boundary loops");
		goto out;
	}
	nb = 0;
	for (size_t e = 0; e < tp->nedges; e++) {
		uint32_t t;

		if (edge_count(tp, e) != 1)
			continue;
		t = tp->ecorner[tp->eoff[e]] / 3;
		for (int end = 0; end < 2; end++) {
			uint32_t v = edge_vertex(tp, e, end);
			ends[2 * nb + end][0] = (uint64_t)v << 32 | uf_find(fan, corner_at(m, t, v));
			ends[2 * nb + end][1] = nb;
		}
		loop[nb] = (uint32_t)nb;
		bedge[nb++] = (uint32_t)e;
	}
	/* A fan holds at most two boundary edges: equal keys come in pairs. */
	qsort(ends, nb * 2, sizeof(*ends), compare_end);
	for (size_t i = 0; i + 1 < nb * 2; i++)
		if (ends[i][0] == ends[i + 1][0])
			uf_union(loop, (uint32_t)ends[i][1], (uint32_t)ends[i + 1][1]);
	for (size_t i = 0; i < nb; i++)
		rep->boundary_loops += uf_find(loop, (uint32_t)i) == i;
out:
	free(fan);
	free(vstate);
	free(bedge);
	free(ends);
	free(loop);
	return rc;
}

/* Signed volume (divergence theorem, about the centre of the bounding box
 * check_vertices_and_loops() found, for precision). */
static void measure(const struct topo *tp, struct mesh_report *rep)
{
	const struct mesh *m = tp->m;
	double c[3], vol = 0.0;

	for (int i = 0; i < 3; i++)
		c[i] = 0.5 * (rep->bbox_min[i] + rep->bbox_max[i]);
	for (size_t t = 0; t < m->ntris; t++) {
		const double *p, *q, *r;
		double a[3], b[3], d[3];

		if (tp->tclass[t] != TRI_LAYER)
			continue;
		p = m->verts[m->tris[t][0]];
		q = m->verts[m->tris[t][1]];
		r = m->verts[m->tris[t][2]];
		for (int i = 0; i < 3; i++) {
			a[i] = p[i] - c[i];
			b[i] = q[i] - c[i];
			d[i] = r[i] - c[i];
		}
		vol += a[0] * (b[1] * d[2] - b[2] * d[1]) - a[1] * (b[0] * d[2] - b[2] * d[0]) +
		       a[2] * (b[0] * d[1] - b[1] * d[0]);
	}
	rep->volume = vol / 6.0;
}

/*
 * Definition 3.11 of seed 000: some layer of the STL realises a closed,
 * manifold-connected polyhedron that coincides with its outer hull.  The
 * layer is what we analysed; it is a polyhedron when no triangle is
 * degenerate and none intersect; closed when every edge has an even number
 * of triangles.  The outer-hull condition then follows from there being one
 * manifold-connected component: triangles joined across a 2-connected edge
 * face the same two regions of space, so if one of them faces the outside
 * (the extreme one does) all of them do.
 */
static void judge(struct mesh_report *rep)
{
	bool *r = rep->reasons;

	r[MESH_REASON_EMPTY] = rep->triangles == 0;
	r[MESH_REASON_IRREGULAR] = rep->irregular > 0;
	r[MESH_REASON_DEGENERATE] = rep->degenerate > 0;
	r[MESH_REASON_OPEN] = rep->odd_edges > 0 || rep->open_singular_edges > 0;
	r[MESH_REASON_SELF_INTERSECTION] = rep->self_intersections > 0;
	r[MESH_REASON_MISNESTED] = rep->misnested_shells > 0;
	r[MESH_REASON_SEVERAL_PARTS] = rep->parts > 1;
	/* Shells joined into fewer edge-connected components touch along
	 * an edge (a pinch within one shell is not counted). */
	r[MESH_REASON_NOT_MANIFOLD_CONNECTED] = rep->manifold_components > rep->components;
	r[MESH_REASON_DUPLICATE] = rep->duplicates > 0;
	r[MESH_REASON_INCONSISTENT_ORIENTATION] = !rep->consistently_oriented;
	r[MESH_REASON_INSIDE_OUT] = rep->odd_edges == 0 && rep->triangles > 0 &&
				     rep->consistently_oriented && rep->volume < 0 &&
				     rep->manifold_components == 1;
	rep->printable = true;
	for (int i = 0; i < MESH_REASON_FIRST_WARNING; i++)
		if (r[i])
			rep->printable = false;

	rep->euler = (long long)rep->vertices - (long long)rep->edges + (long long)rep->triangles;
	/* Closed orientable 2-manifold components: chi_c = 2 - 2 g_c each. */
	rep->genus_defined = rep->triangles > 0 && rep->boundary_edges == 0 &&
			     rep->singular_edges == 0 && rep->nonmanifold_vertices == 0 &&
			     rep->orientable;
	rep->genus = rep->genus_defined ? (2 * (long long)rep->components - rep->euler) / 2 : 0;
}

static void free_topology(struct topo *tp)
{
	free(tp->eoff);
	free(tp->ecorner);
	tp->eoff = tp->ecorner = NULL;
}

/*
 * Step 5: parts and cavities (parts.c).  Nesting means something only for
 * closed, intersection-free shells; with several shells a side can only
 * be told when they are consistently oriented, so without that they are
 * all counted misnested.
 */
static int find_parts(struct topo *tp, struct mesh_report *rep, uint32_t *part,
		      uint32_t *around, struct st_error *err)
{
	const struct mesh *m = tp->m;
	const bool closed = rep->odd_edges == 0 && rep->open_singular_edges == 0 &&
			    rep->self_intersections == 0 && rep->triangles > 0;
	struct parts_out po;
	uint8_t *in_layer = malloc(m->ntris + 1);
	int rc;

	if (!in_layer)
		return st_error_set(err, ST_ERR_NOMEM, "out of memory finding parts");
	for (size_t t = 0; t < m->ntris; t++)
		in_layer[t] = tp->tclass[t] == TRI_LAYER;
	rc = parts_nest(m, in_layer, tp->shell, &rep->manifold_components,
			closed && rep->consistently_oriented, rep->singular_edges > 0, part, around, &po,
			err);
	free(in_layer);
	if (rc)
		return rc;
	rep->open_singular_edges = po.unpaired;
	rep->parts = po.parts;
	rep->cavities = po.cavities;
	rep->misnested_shells = po.misnested;
	if (closed && !rep->consistently_oriented && rep->manifold_components > 1)
		rep->misnested_shells = rep->manifold_components;
	return 0;
}

/* The exact self-intersection pass, run on its own thread beside the
 * topology passes so the second core is busy during both. */
struct exact_job {
	const struct mesh *m;
	const uint8_t *skip;
	const uint32_t *star_off, *star_tri; /* the layer's stars, shared */
	int threads;
	uint64_t count;
	int rc;
	struct st_error err;
	bool done;	/* the caller already knows the count */
};

static void *exact_job_run(void *arg)
{
	struct exact_job *job = arg;

	job->rc = exact_count_self_intersections_stars(
	    (const double(*)[3])job->m->verts, job->m->nverts, (const uint32_t(*)[3])job->m->tris,
	    job->m->ntris, job->skip, job->star_off, job->star_tri, job->threads, &job->count,
	    &job->err);
	return NULL;
}

int mesh_analyze(const struct mesh *m, int threads, struct mesh_report *rep,
		 struct st_error *err)
{
	return mesh_analyze_known(m, threads, -1, rep, err);
}

int mesh_analyze_known(const struct mesh *m, int threads, long long self_intersections,
		       struct mesh_report *rep, struct st_error *err)
{
	return mesh_analyze_parts(m, threads, self_intersections, rep, NULL, err);
}

int mesh_analyze_parts(const struct mesh *m, int threads, long long self_intersections,
		       struct mesh_report *rep, uint32_t *part, struct st_error *err)
{
	return mesh_analyze_nesting(m, threads, self_intersections, rep, part, NULL, err);
}

int mesh_analyze_nesting(const struct mesh *m, int threads, long long self_intersections,
			 struct mesh_report *rep, uint32_t *part, uint32_t *around,
			 struct st_error *err)
{
	struct topo tp = {.m = m};
	struct exact_job job = {.m = m, .threads = threads};
	pthread_t exact_thread;
	bool exact_running = false;
	int rc;

	memset(rep, 0, sizeof(*rep));
	rep->input_triangles = m->ntris;
	if (m->ntris > UINT32_MAX / 3 - 1)
		return st_error_set(err, ST_ERR_RANGE,
				    "%zu triangles is more than the checker handles", m->ntris);
	tp.tclass = malloc(m->ntris ? m->ntris : 1);
	if (!tp.tclass) {
		rc = st_error_set(err, ST_ERR_NOMEM, "out of memory analysing %zu triangles",
				  m->ntris);
		goto out;
	}
	classify_triangles(&tp, rep);
	rc = build_stars(&tp, err);
	if (rc)
		goto out;
	find_duplicates(&tp, rep);
	if (rep->duplicates)
		drop_duplicates_from_stars(&tp);
	/* From here tclass and the stars are final and only read: the exact
	 * pass can start, on the same stars (every degenerate triangle is
	 * flagged in tclass, as it asks). */
	job.skip = tp.tclass;
	job.star_off = tp.voff;
	job.star_tri = tp.vtri;
	if (self_intersections >= 0)
		job.done = true;
	else if (threads != 1 && pthread_create(&exact_thread, NULL, exact_job_run, &job) == 0)
		exact_running = true;
	rc = build_edges(&tp, err);
	if (!rc)
		rc = count_edges_and_parts(&tp, rep, err);
	if (!rc)
		rc = check_vertices_and_loops(&tp, rep, err);
	if (!rc)
		measure(&tp, rep);
	free_topology(&tp);
	if (exact_running)
		pthread_join(exact_thread, NULL);
	else if (!rc && !job.done)
		exact_job_run(&job); /* one core, or no thread: run it here */
	/* The stars are not needed past this point. */
	free(tp.voff);
	free(tp.vtri);
	tp.voff = tp.vtri = NULL;
	if (job.done)
		job.count = (uint64_t)self_intersections;
	if (rc)
		goto out;
	if (job.rc) {
		rc = job.rc;
		if (err)
			*err = job.err;
		goto out;
	}
	rep->self_intersections = job.count;
	rc = find_parts(&tp, rep, part, around, err);
	if (rc)
		goto out;
	judge(rep);
out:
	free(tp.shell);
	free_topology(&tp);
	free(tp.voff);
	free(tp.vtri);
	free(tp.tclass);
	return rc;
}
