/*
 * topology.c - the topology report of an indexed mesh (mesh_analyze).
 *
 * Steps, each over flat uint32_t arrays so a million triangles stay within
 * about 100 bytes each:
 *   1. classify triangles: irregular, degenerate (exact), duplicate; the rest
 *      form the layer (seed 000 Def. 3.1);
 *   2. weld edges with a hash table, count triangles per edge;
 *   3. edge -> corner incidence (CSR), then components, manifold components,
 *      vertex fans, orientation and boundary loops;
 *   4. free all of that, then count self-intersections exactly (CGAL bridge).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "exact.h"
#include "mesh.h"

enum tri_class { TRI_LAYER = 0, TRI_IRREGULAR, TRI_DEGENERATE, TRI_DUPLICATE };

/* Working state; every array is indexed as its comment says. */
struct topo {
	const struct mesh *m;
	uint8_t *tclass;	/* [tri] enum tri_class */
	uint32_t (*tedge)[3];	/* [tri][k] edge of corner k: tris[k] -> tris[k+1] */
	uint32_t (*ev)[2];	/* [edge] its two vertices, smaller first */
	uint32_t *eoff;		/* [edge] start in ecorner; [nedges] = end */
	uint32_t *ecorner;	/* corner ids 3*tri+k incident to each edge */
	size_t nedges;
};

static const struct {
	const char *code;
	const char *text;
} reason_table[MESH_REASON_COUNT] = {
	[MESH_REASON_EMPTY] = {"empty", "no usable triangles"},
	[MESH_REASON_IRREGULAR] = {"irregular", "triangles that repeat a vertex"},
	[MESH_REASON_DEGENERATE] = {"degenerate", "triangles whose corners are collinear"},
	[MESH_REASON_OPEN] = {"open", "holes: edges with an odd number of triangles"},
	[MESH_REASON_SELF_INTERSECTION] = {"self_intersection",
					   "triangles that cross or overlap each other"},
	[MESH_REASON_SEVERAL_PARTS] = {"several_parts",
				       "several separate parts (print them as separate files)"},
	[MESH_REASON_NOT_MANIFOLD_CONNECTED] =
		{"not_manifold_connected",
		 "parts joined only along singular edges or at single vertices"},
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

static uint64_t mix64(uint64_t h)
{
	h ^= h >> 33;
	h *= 0xff51afd7ed558ccdull;
	h ^= h >> 33;
	h *= 0xc4ceb9fe1a85ec53ull;
	h ^= h >> 33;
	return h;
}

static size_t pow2_at_least(size_t n)
{
	size_t p = 16;

	while (p < n)
		p *= 2;
	return p;
}

/* Union-find over uint32_t ids with path halving. */
static uint32_t uf_find(uint32_t *parent, uint32_t x)
{
	while (parent[x] != x) {
		parent[x] = parent[parent[x]];
		x = parent[x];
	}
	return x;
}

static void uf_union(uint32_t *parent, uint32_t a, uint32_t b)
{
	a = uf_find(parent, a);
	b = uf_find(parent, b);
	if (a != b)
		parent[a < b ? b : a] = a < b ? a : b;
}

static void sort3(const uint32_t in[3], uint32_t out[3])
{
	uint32_t a = in[0], b = in[1], c = in[2], t;

	if (a > b) { t = a; a = b; b = t; }
	if (b > c) { t = b; b = c; c = t; }
	if (a > b) { t = a; a = b; b = t; }
	out[0] = a;
	out[1] = b;
	out[2] = c;
}

/* Step 1: irregular, degenerate and duplicate triangles. */
static int classify_triangles(struct topo *tp, struct mesh_report *rep, struct st_error *err)
{
	const struct mesh *m = tp->m;
	size_t nslots = pow2_at_least(m->ntris * 2);
	uint32_t *slots = calloc(nslots, sizeof(*slots)); /* tri + 1, 0 = empty */

	if (!slots)
		return st_error_set(err, ST_ERR_NOMEM, "out of memory classifying %zu triangles",
				    m->ntris);
	for (size_t t = 0; t < m->ntris; t++) {
		const uint32_t *v = m->tris[t];
		uint32_t key[3];
		size_t i;

		if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) {
			tp->tclass[t] = TRI_IRREGULAR;
			rep->irregular++;
			continue;
		}
		if (exact_collinear(m->verts[v[0]], m->verts[v[1]], m->verts[v[2]])) {
			tp->tclass[t] = TRI_DEGENERATE;
			rep->degenerate++;
			continue;
		}
		sort3(v, key);
		i = mix64(((uint64_t)key[0] << 32 | key[1]) ^ mix64(key[2])) & (nslots - 1);
		for (; slots[i]; i = (i + 1) & (nslots - 1)) {
			uint32_t other[3];
			sort3(m->tris[slots[i] - 1], other);
			if (!memcmp(key, other, sizeof(key)))
				break;
		}
		if (slots[i]) {
			tp->tclass[t] = TRI_DUPLICATE;
			rep->duplicates++;
			continue;
		}
		slots[i] = (uint32_t)t + 1;
		tp->tclass[t] = TRI_LAYER;
		rep->triangles++;
	}
	free(slots);
	return 0;
}

/* Step 2: one id per undirected edge of the layer. */
static int weld_edges(struct topo *tp, struct st_error *err)
{
	const struct mesh *m = tp->m;
	size_t nslots = pow2_at_least(m->ntris * 3);
	uint32_t *slots = calloc(nslots, sizeof(*slots)); /* edge + 1 */
	size_t cap = m->ntris * 3 / 2 + 16;
	int rc = 0;

	tp->ev = malloc(cap * sizeof(*tp->ev));
	if (!slots || !tp->ev) {
		rc = st_error_set(err, ST_ERR_NOMEM, "out of memory building edges");
		goto out_free_slots;
	}
	for (size_t t = 0; t < m->ntris; t++) {
		if (tp->tclass[t] != TRI_LAYER)
			continue;
		for (int k = 0; k < 3; k++) {
			uint32_t a = m->tris[t][k], b = m->tris[t][(k + 1) % 3], lo, hi;
			size_t i;

			lo = a < b ? a : b;
			hi = a < b ? b : a;
			i = mix64((uint64_t)lo << 32 | hi) & (nslots - 1);
			for (; slots[i]; i = (i + 1) & (nslots - 1)) {
				const uint32_t *e = tp->ev[slots[i] - 1];
				if (e[0] == lo && e[1] == hi)
					break;
			}
			if (!slots[i]) {
				if (tp->nedges == cap) {
					void *p = realloc(tp->ev, cap * 2 * sizeof(*tp->ev));
					if (!p) {
						rc = st_error_set(err, ST_ERR_NOMEM,
								  "out of memory building edges");
						goto out_free_slots;
					}
					tp->ev = p;
					cap *= 2;
				}
				tp->ev[tp->nedges][0] = lo;
				tp->ev[tp->nedges][1] = hi;
				slots[i] = (uint32_t)++tp->nedges;
			}
			tp->tedge[t][k] = slots[i] - 1;
		}
	}
out_free_slots:
	free(slots);
	return rc;
}

/* Step 3a: edge -> incident corners, as compressed rows. */
static int build_incidence(struct topo *tp, struct st_error *err)
{
	const struct mesh *m = tp->m;

	tp->eoff = calloc(tp->nedges + 1, sizeof(*tp->eoff));
	tp->ecorner = malloc((m->ntris * 3 + 1) * sizeof(*tp->ecorner));
	if (!tp->eoff || !tp->ecorner)
		return st_error_set(err, ST_ERR_NOMEM, "out of memory building edge incidence");
	for (size_t t = 0; t < m->ntris; t++)
		if (tp->tclass[t] == TRI_LAYER)
			for (int k = 0; k < 3; k++)
				tp->eoff[tp->tedge[t][k] + 1]++;
	for (size_t e = 0; e < tp->nedges; e++)
		tp->eoff[e + 1] += tp->eoff[e];
	/* Fill using eoff[e] as a cursor, then shift the offsets back. */
	for (size_t t = 0; t < m->ntris; t++)
		if (tp->tclass[t] == TRI_LAYER)
			for (int k = 0; k < 3; k++)
				tp->ecorner[tp->eoff[tp->tedge[t][k]]++] = (uint32_t)(3 * t + k);
	for (size_t e = tp->nedges; e > 0; e--)
		tp->eoff[e] = tp->eoff[e - 1];
	tp->eoff[0] = 0;
	return 0;
}

static uint32_t edge_count(const struct topo *tp, size_t e)
{
	return tp->eoff[e + 1] - tp->eoff[e];
}

/* Vertex at corner c (3*tri+k) and the corner of the same triangle at vertex v. */
static uint32_t corner_vertex(const struct mesh *m, uint32_t c)
{
	return m->tris[c / 3][c % 3];
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

/* Step 3b: counts per edge class, components and manifold components. */
static int count_edges_and_parts(struct topo *tp, struct mesh_report *rep, struct st_error *err)
{
	const struct mesh *m = tp->m;
	uint32_t *comp = malloc(m->ntris * sizeof(*comp));
	uint32_t *mcomp = malloc(m->ntris * sizeof(*mcomp));
	int rc = 0;

	if (!comp || !mcomp) {
		rc = st_error_set(err, ST_ERR_NOMEM, "out of memory finding components");
		goto out;
	}
	for (size_t t = 0; t < m->ntris; t++)
		comp[t] = mcomp[t] = (uint32_t)t;
	rep->edges = tp->nedges;
	rep->consistently_oriented = true;
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
			uf_union(mcomp, c0 / 3, c1 / 3);
			if (corner_forward(m, c0) == corner_forward(m, c1)) {
				rep->flipped_edges++;
				rep->consistently_oriented = false;
			}
		}
	}
	for (size_t t = 0; t < m->ntris; t++) {
		if (tp->tclass[t] != TRI_LAYER)
			continue;
		rep->components += uf_find(comp, (uint32_t)t) == t;
		rep->manifold_components += uf_find(mcomp, (uint32_t)t) == t;
	}
out:
	free(comp);
	free(mcomp);
	return rc;
}

/*
 * Step 3c: orientability.  Give every triangle a flip bit so that each
 * 2-connected edge is walked both ways; a conflict means the surface is not
 * orientable (a Moebius strip).  Singular edges do not propagate.
 */
static int check_orientable(struct topo *tp, struct mesh_report *rep, struct st_error *err)
{
	const struct mesh *m = tp->m;
	uint8_t *state = calloc(m->ntris, 1); /* 0 unseen, 1 kept, 2 flipped */
	uint32_t *queue = malloc(m->ntris * sizeof(*queue));

	rep->orientable = true;
	if (!state || !queue) {
		free(state);
		free(queue);
		return st_error_set(err, ST_ERR_NOMEM, "out of memory checking orientation");
	}
	for (size_t seed = 0; seed < m->ntris; seed++) {
		size_t head = 0, tail = 0;

		if (tp->tclass[seed] != TRI_LAYER || state[seed])
			continue;
		state[seed] = 1;
		queue[tail++] = (uint32_t)seed;
		while (head < tail) {
			uint32_t t = queue[head++];
			for (uint32_t k = 0; k < 3; k++) {
				uint32_t e = tp->tedge[t][k], c0, c1, other, want;
				bool fwd0, fwd1;

				if (edge_count(tp, e) != 2)
					continue;
				c0 = tp->ecorner[tp->eoff[e]];
				c1 = tp->ecorner[tp->eoff[e] + 1];
				if (c0 / 3 != t) {
					uint32_t tmp = c0;
					c0 = c1;
					c1 = tmp;
				}
				other = c1 / 3;
				fwd0 = corner_forward(m, c0) ^ (state[t] == 2);
				fwd1 = corner_forward(m, c1);
				/* other must end up walking e opposite to t. */
				want = fwd0 == fwd1 ? 2 : 1;
				if (!state[other]) {
					state[other] = (uint8_t)want;
					queue[tail++] = other;
				} else if (state[other] != want) {
					rep->orientable = false;
				}
			}
		}
	}
	free(state);
	free(queue);
	return 0;
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
			vstate[tp->ev[e][0]] |= 2;
			vstate[tp->ev[e][1]] |= 2;
		}
		if (n == 1)
			nb++;
		if (n != 2)
			continue;
		for (int end = 0; end < 2; end++) {
			uint32_t v = tp->ev[e][end];
			uf_union(fan, corner_at(m, tp->ecorner[tp->eoff[e]] / 3, v),
				 corner_at(m, tp->ecorner[tp->eoff[e] + 1] / 3, v));
		}
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
			uint32_t v = tp->ev[e][end];
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

/* Signed volume (divergence theorem, about the bbox centre for precision)
 * and the bounding box of the vertices the layer uses. */
static void measure(const struct topo *tp, struct mesh_report *rep)
{
	const struct mesh *m = tp->m;
	double c[3], vol = 0.0;
	bool first = true;

	for (size_t t = 0; t < m->ntris; t++) {
		if (tp->tclass[t] != TRI_LAYER)
			continue;
		for (int k = 0; k < 3; k++) {
			const double *p = m->verts[m->tris[t][k]];
			for (int i = 0; i < 3; i++) {
				if (first || p[i] < rep->bbox_min[i])
					rep->bbox_min[i] = p[i];
				if (first || p[i] > rep->bbox_max[i])
					rep->bbox_max[i] = p[i];
			}
			first = false;
		}
	}
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
	r[MESH_REASON_OPEN] = rep->odd_edges > 0;
	r[MESH_REASON_SELF_INTERSECTION] = rep->self_intersections > 0;
	r[MESH_REASON_SEVERAL_PARTS] = rep->components > 1;
	r[MESH_REASON_NOT_MANIFOLD_CONNECTED] =
		rep->components <= 1 && rep->manifold_components > 1;
	r[MESH_REASON_DUPLICATE] = rep->duplicates > 0;
	r[MESH_REASON_INCONSISTENT_ORIENTATION] = !rep->consistently_oriented;
	r[MESH_REASON_INSIDE_OUT] = rep->odd_edges == 0 && rep->triangles > 0 &&
				     rep->consistently_oriented && rep->volume < 0;
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
	free(tp->tedge);
	free(tp->ev);
	free(tp->eoff);
	free(tp->ecorner);
	tp->tedge = NULL;
	tp->ev = NULL;
	tp->eoff = tp->ecorner = NULL;
}

int mesh_analyze(const struct mesh *m, int threads, struct mesh_report *rep,
		 struct st_error *err)
{
	struct topo tp = {.m = m};
	int rc;

	memset(rep, 0, sizeof(*rep));
	rep->input_triangles = m->ntris;
	if (m->ntris > UINT32_MAX / 3 - 1)
		return st_error_set(err, ST_ERR_RANGE,
				    "%zu triangles is more than the checker handles", m->ntris);
	tp.tclass = malloc(m->ntris ? m->ntris : 1);
	tp.tedge = malloc((m->ntris ? m->ntris : 1) * sizeof(*tp.tedge));
	if (!tp.tclass || !tp.tedge) {
		rc = st_error_set(err, ST_ERR_NOMEM, "out of memory analysing %zu triangles",
				  m->ntris);
		goto out;
	}
	rc = classify_triangles(&tp, rep, err);
	if (!rc)
		rc = weld_edges(&tp, err);
	if (!rc)
		rc = build_incidence(&tp, err);
	if (!rc)
		rc = count_edges_and_parts(&tp, rep, err);
	if (!rc)
		rc = check_orientable(&tp, rep, err);
	if (!rc)
		rc = check_vertices_and_loops(&tp, rep, err);
	if (rc)
		goto out;
	measure(&tp, rep);
	/* The exact pass needs only the triangle classes: free the rest first. */
	free_topology(&tp);
	rc = exact_count_self_intersections((const double(*)[3])m->verts, m->nverts,
					    (const uint32_t(*)[3])m->tris, m->ntris, tp.tclass,
					    threads, &rep->self_intersections, err);
	if (rc)
		goto out;
	judge(rep);
out:
	free_topology(&tp);
	free(tp.tclass);
	return rc;
}
