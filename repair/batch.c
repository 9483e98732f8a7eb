/*
 * batch.c - independent groups of a mesh and the threads that repair them
 * (batch.h).
 *
 * Groups are the vertex-connected parts, joined where a triangle of one
 * comes within reach of a triangle of another, then to a closed part whose
 * box holds theirs.  Candidate pairs come from a uniform grid of cubes
 * about the size of a typical triangle's box: each box, grown by
 * half the reach, goes into the cells it covers (hashed into buckets by a
 * counting sort), and each overlapping pair is tested in one cell only.
 */
#include <math.h>
#include <pthread.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "batch.h"
#include "ids.h"
#include "vec3.h"

/* Cell entries allowed per triangle, beyond a fixed allowance, before the
 * cells are made coarser. */
#define ENTRIES_PER_TRIANGLE 8
#define ENTRIES_FIXED ((size_t)1 << 20)

/* Vertex-connected parts up to which only the triangles near another
 * part's box are put on the grid. */
#define MAX_FILTERED_PARTS 64

/* Pairs of groups tried for enclosure before that test is left out. */
#define MAX_ENCLOSURE_PAIRS 1e8

/* Bits of each cell index in a cell key. */
#define CELL_BITS 21

#define NO_ID UINT32_MAX

struct box {
	double lo[3], hi[3];
};

/* A triangle in one grid cell. */
struct entry {
	uint64_t cell;
	uint32_t tri;
};

static int double_compare(const void *pa, const void *pb)
{
	const double a = *(const double *)pa, b = *(const double *)pb;

	return a < b ? -1 : a > b;
}

static bool boxes_overlap(const struct box *a, const struct box *b)
{
	for (int k = 0; k < 3; k++)
		if (a->hi[k] < b->lo[k] || b->hi[k] < a->lo[k])
			return false;
	return true;
}

/* Grid cell range of box on axis k: [*first, *last]. */
static void cell_range(const struct box *box, const double origin[3], double h, int k,
		       uint64_t *first, uint64_t *last)
{
	*first = (uint64_t)floor((box->lo[k] - origin[k]) / h);
	*last = (uint64_t)floor((box->hi[k] - origin[k]) / h);
}

/*
 * Whether triangles t and u of m may come within `reach` of each other:
 * true when they cross or when any vertex-face or edge-edge distance is
 * at most reach; NaN (a triangle without area) counts as near.  Doubles
 * suffice: the caller's reach is twice what the repair needs.
 */
static bool triangles_near(const struct mesh *m, uint32_t t, uint32_t u, double reach)
{
	const double *p[3], *q[3];
	double d = INFINITY;

	for (int k = 0; k < 3; k++) {
		p[k] = m->verts[m->tris[t][k]];
		q[k] = m->verts[m->tris[u][k]];
	}
	for (int k = 0; k < 3; k++) {
		d = fmin(d, vec3_point_triangle_distance(p[k], q[0], q[1], q[2]));
		d = fmin(d, vec3_point_triangle_distance(q[k], p[0], p[1], p[2]));
		for (int j = 0; j < 3; j++)
			d = fmin(d, vec3_segment_distance(p[k], p[(k + 1) % 3], q[j], q[(j + 1) % 3]));
	}
	/* fmin drops NaN: test each call's NaN by the area instead. */
	if (!(vec3_tri_area(p[0], p[1], p[2]) > 0) || !(vec3_tri_area(q[0], q[1], q[2]) > 0))
		return true;
	if (d <= reach)
		return true;
	/* Apart at every vertex and edge but crossing: an edge of one
	 * pierces the other, at a point in the other's plane whose distance
	 * to it is then 0. */
	for (int side = 0; side < 2; side++) {
		const double *const *a = side ? q : p, *const *b = side ? p : q;
		const double e1[3] = {b[1][0] - b[0][0], b[1][1] - b[0][1], b[1][2] - b[0][2]};
		const double e2[3] = {b[2][0] - b[0][0], b[2][1] - b[0][1], b[2][2] - b[0][2]};
		const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
				     e1[0] * e2[1] - e1[1] * e2[0]};
		double h[3];
		for (int k = 0; k < 3; k++)
			h[k] = (a[k][0] - b[0][0]) * n[0] + (a[k][1] - b[0][1]) * n[1] +
			       (a[k][2] - b[0][2]) * n[2];
		for (int k = 0; k < 3; k++) {
			const double *e0 = a[k], *e9 = a[(k + 1) % 3];
			const double h0 = h[k], h9 = h[(k + 1) % 3];
			if (!((h0 < 0 && h9 > 0) || (h0 > 0 && h9 < 0)))
				continue;
			const double f = h0 / (h0 - h9);
			const double x[3] = {e0[0] + f * (e9[0] - e0[0]), e0[1] + f * (e9[1] - e0[1]),
					     e0[2] + f * (e9[2] - e0[2])};
			if (!(vec3_point_triangle_distance(x, b[0], b[1], b[2]) > reach))
				return true;
		}
	}
	return false;
}

/* Scratch of the grouping. */
struct groups {
	const struct mesh *m;
	double reach;
	uint32_t *parent;	/* union-find over vertices */
	struct box *box;	/* per triangle, grown by half the reach */
	double *extent;		/* scratch: box sizes */
	uint32_t *cand;		/* the triangles that may come near another part */
	size_t ncand;
	double origin[3], h;	/* the grid: low corner, cell size */
	int bits;		/* 2^bits buckets of cells */
	size_t left;		/* groups left (SIZE_MAX: not counted) */
	size_t *start;		/* bucket b: entries[start[b] .. start[b + 1]) */
	struct entry *entries;
};

/* Cell entries for cells of size h, or SIZE_MAX when over limit. */
static size_t count_entries(const struct groups *g, const double origin[3], double h,
			    size_t limit)
{
	size_t n = 0;

	for (size_t i = 0; i < g->ncand; i++) {
		size_t cells = 1;
		for (int k = 0; k < 3; k++) {
			uint64_t first, last;
			cell_range(&g->box[g->cand[i]], origin, h, k, &first, &last);
			cells *= (size_t)(last - first + 1);
			if (cells > limit)
				return SIZE_MAX;
		}
		n += cells;
		if (n > limit)
			return SIZE_MAX;
	}
	return n;
}

/* The bucket of a cell key among 2^bits (Fibonacci hashing). */
static size_t bucket_of(uint64_t cell, int bits)
{
	return bits ? (size_t)((cell * 0x9e3779b97f4a7c15ull) >> (64 - bits)) : 0;
}

/*
 * Put every candidate into the grid cells its box covers: g->entries,
 * *n of them, grouped by bucket (a hash of the cell, counting sort) with
 * bucket b at g->start[b] .. g->start[b + 1]; cells of size g->h from
 * g->origin.  Returns 0, 1 when the boxes are too tangled for a grid, or
 * ST_ERR_NOMEM.
 */
static int fill_cells(struct groups *g, size_t *n)
{
	const size_t nt = g->ncand, limit = ENTRIES_PER_TRIANGLE * nt + ENTRIES_FIXED;
	struct box all;
	double span = 0;
	size_t nb;

	*n = SIZE_MAX;
	for (int k = 0; k < 3; k++) {
		all.lo[k] = INFINITY;
		all.hi[k] = -INFINITY;
	}
	for (size_t i = 0; i < nt; i++) {
		const struct box *b = &g->box[g->cand[i]];
		g->extent[i] = 0;
		for (int k = 0; k < 3; k++) {
			g->extent[i] = fmax(g->extent[i], b->hi[k] - b->lo[k]);
			all.lo[k] = fmin(all.lo[k], b->lo[k]);
			all.hi[k] = fmax(all.hi[k], b->hi[k]);
		}
	}
	qsort(g->extent, nt, sizeof(*g->extent), double_compare);
	for (int k = 0; k < 3; k++)
		span = fmax(span, all.hi[k] - all.lo[k]);
	memcpy(g->origin, all.lo, sizeof(g->origin));
	/* A typical box, but never so small that an index overflows its bits. */
	g->h = fmax(g->extent[nt / 2], span / ldexp(1.0, CELL_BITS - 1));
	for (int tries = 0; tries < 64 && *n == SIZE_MAX; tries++, g->h *= 2)
		*n = count_entries(g, g->origin, g->h, limit);
	g->h /= 2;
	if (*n == SIZE_MAX)
		return 1;
	for (g->bits = 0; ((size_t)1 << g->bits) < *n; g->bits++)
		;
	nb = (size_t)1 << g->bits;
	g->entries = malloc((*n + 1) * sizeof(*g->entries));
	g->start = calloc(nb + 2, sizeof(*g->start));
	if (!g->entries || !g->start)
		return ST_ERR_NOMEM;
	/* Two passes over the cells: count per bucket, then place. */
	for (int pass = 0; pass < 2; pass++) {
		for (size_t i = 0; i < nt; i++) {
			const uint32_t t = g->cand[i];
			uint64_t f[3], l[3];
			for (int k = 0; k < 3; k++)
				cell_range(&g->box[t], g->origin, g->h, k, &f[k], &l[k]);
			for (uint64_t x = f[0]; x <= l[0]; x++)
				for (uint64_t y = f[1]; y <= l[1]; y++)
					for (uint64_t z = f[2]; z <= l[2]; z++) {
						const uint64_t cell = (x << CELL_BITS | y) << CELL_BITS | z;
						const size_t b = bucket_of(cell, g->bits);
						if (pass == 0)
							g->start[b + 2]++;
						else
							g->entries[g->start[b + 1]++] = (struct entry){cell, t};
					}
		}
		for (size_t b = 2; pass == 0 && b < nb + 2; b++)
			g->start[b] += g->start[b - 1];
	}
	return 0;
}

/* The cell of the low corner of the overlap of boxes a and b. */
static uint64_t overlap_cell(const struct groups *g, const struct box *a, const struct box *b)
{
	struct box low;
	uint64_t c[3], unused;

	for (int k = 0; k < 3; k++)
		low.lo[k] = low.hi[k] = fmax(a->lo[k], b->lo[k]);
	for (int k = 0; k < 3; k++)
		cell_range(&low, g->origin, g->h, k, &c[k], &unused);
	return (c[0] << CELL_BITS | c[1]) << CELL_BITS | c[2];
}

/*
 * Join the groups of triangles that come within reach of each other.
 * Every pair whose grown boxes overlap shares the cell of the low corner
 * of their overlap, and is tested there only.  Returns 0, 1 when the
 * boxes are too tangled for a grid, or ST_ERR_NOMEM.
 */
static int join_near_triangles(struct groups *g)
{
	const struct mesh *m = g->m;
	size_t e;
	int rc = fill_cells(g, &e);

	if (rc)
		return rc;
	for (size_t bk = 0; bk < ((size_t)1 << g->bits) && g->left > 1; bk++) {
		const struct entry *c = g->entries;
		for (size_t i = g->start[bk]; i < g->start[bk + 1]; i++) {
			const uint32_t t = c[i].tri;
			for (size_t j = i + 1; j < g->start[bk + 1]; j++) {
				const uint32_t u = c[j].tri;
				if (c[j].cell != c[i].cell)
					continue;
				/* Cheapest first: most pairs are in one group already. */
				const uint32_t a = uf_find(g->parent, m->tris[t][0]);
				const uint32_t b = uf_find(g->parent, m->tris[u][0]);
				if (a != b && boxes_overlap(&g->box[t], &g->box[u]) &&
				    overlap_cell(g, &g->box[t], &g->box[u]) == c[i].cell &&
				    triangles_near(m, t, u, g->reach)) {
					uf_union(g->parent, a, b);
					g->left--;
				}
			}
		}
	}
	return 0;
}

/* An edge of the mesh (its two vertices, packed) and its triangle's group. */
struct edge_key {
	uint64_t key;
	uint32_t group;
};

static int edge_compare(const void *pa, const void *pb)
{
	const struct edge_key *a = pa, *b = pb;

	return a->key < b->key ? -1 : a->key > b->key;
}

/*
 * Join each group to a closed group whose box holds its box.  A closed
 * group so placed most likely encloses it (a hollow part's inner wall, a
 * part in a box), and repairing the two apart would only be undone by the
 * check of the results; an open group (sheets) rarely encloses anything,
 * so it is left to that check.  Skipped (returns 0) when the pairs to try
 * would be too many; ST_ERR_NOMEM when out of memory.
 */
static int join_enclosed(struct groups *g)
{
	const struct mesh *m = g->m;
	struct edge_key *edges = malloc((3 * m->ntris + 1) * sizeof(*edges));
	uint32_t *list = malloc((2 * m->ntris + 1) * sizeof(*list)), *closed = list + m->ntris;
	uint8_t *open = calloc(m->nverts + 1, 1);
	size_t nlist = 0, nclosed = 0;
	int rc = 0;

	if (!edges || !list || !open) {
		rc = ST_ERR_NOMEM;
		goto out;
	}
	/* Groups by root vertex, their boxes in g->box[root]. */
	for (size_t t = 0; t < m->ntris; t++) {
		const uint32_t r = uf_find(g->parent, m->tris[t][0]);
		for (int c = 0; c < 3; c++) {
			uint32_t a = m->tris[t][c], b = m->tris[t][(c + 1) % 3];
			if (a > b) {
				const uint32_t x = a;
				a = b;
				b = x;
			}
			edges[3 * t + c] = (struct edge_key){(uint64_t)a << 32 | b, r};
		}
	}
	qsort(edges, 3 * m->ntris, sizeof(*edges), edge_compare);
	for (size_t i = 0, j; i < 3 * m->ntris; i = j) {
		for (j = i + 1; j < 3 * m->ntris && edges[j].key == edges[i].key; j++)
			;
		if ((j - i) % 2)
			open[edges[i].group] = 1; /* a boundary edge */
	}
	for (size_t v = 0; v < m->nverts; v++)
		if (g->parent[v] == v) {
			for (int k = 0; k < 3; k++) {
				g->box[v].lo[k] = INFINITY;
				g->box[v].hi[k] = -INFINITY;
			}
		}
	for (size_t t = 0; t < m->ntris; t++) {
		const uint32_t r = uf_find(g->parent, m->tris[t][0]);
		struct box *b = &g->box[r];
		if (b->lo[0] == INFINITY && b->hi[0] == -INFINITY) {
			list[nlist++] = r;
			if (!open[r])
				closed[nclosed++] = r;
		}
		for (int c = 0; c < 3; c++)
			for (int k = 0; k < 3; k++) {
				b->lo[k] = fmin(b->lo[k], m->verts[m->tris[t][c]][k]);
				b->hi[k] = fmax(b->hi[k], m->verts[m->tris[t][c]][k]);
			}
	}
	if ((double)nlist * (double)nclosed > MAX_ENCLOSURE_PAIRS)
		goto out;
	for (size_t i = 0; i < nlist; i++)
		for (size_t j = 0; j < nclosed; j++) {
			const struct box *a = &g->box[list[i]], *b = &g->box[closed[j]];
			bool within = list[i] != closed[j];
			for (int k = 0; k < 3 && within; k++)
				within = a->lo[k] >= b->lo[k] && a->hi[k] <= b->hi[k];
			if (within)
				uf_union(g->parent, list[i], closed[j]);
		}
out:
	free(edges);
	free(list);
	free(open);
	return rc;
}

/*
 * g->cand: the triangles whose grown box overlaps the grown box of another
 * vertex-connected part, the only ones that can join two parts (every
 * triangle when there are more than MAX_FILTERED_PARTS parts); *nparts:
 * the parts (1, or 2 for "more than one" when not counted).  Returns 0 or
 * ST_ERR_NOMEM.
 */
static int pick_candidates(struct groups *g, size_t *nparts)
{
	const struct mesh *m = g->m;
	uint32_t *slot = malloc((m->nverts + 1) * sizeof(*slot));
	struct box part[MAX_FILTERED_PARTS];
	size_t np = 0;
	bool counted = true;

	if (!slot)
		return ST_ERR_NOMEM;
	for (size_t t = 0; t < m->ntris; t++)
		slot[uf_find(g->parent, m->tris[t][0])] = NO_ID;
	for (size_t t = 0; t < m->ntris && counted; t++) {
		const uint32_t r = uf_find(g->parent, m->tris[t][0]);
		if (slot[r] == NO_ID) {
			if (np == MAX_FILTERED_PARTS) {
				counted = false;
				break;
			}
			part[np] = g->box[t];
			slot[r] = (uint32_t)np++;
		}
		for (int k = 0; k < 3; k++) {
			part[slot[r]].lo[k] = fmin(part[slot[r]].lo[k], g->box[t].lo[k]);
			part[slot[r]].hi[k] = fmax(part[slot[r]].hi[k], g->box[t].hi[k]);
		}
	}
	g->ncand = 0;
	for (size_t t = 0; t < m->ntris; t++) {
		const uint32_t own = counted ? slot[uf_find(g->parent, m->tris[t][0])] : NO_ID;
		bool near = !counted;
		for (size_t q = 0; q < np && !near; q++)
			near = q != own && boxes_overlap(&g->box[t], &part[q]);
		if (near)
			g->cand[g->ncand++] = (uint32_t)t;
	}
	*nparts = counted ? np : 2;
	g->left = counted ? np : SIZE_MAX;
	free(slot);
	return 0;
}

/* How many groups g->parent holds (2 for "more than one"). */
static size_t count_groups(const struct groups *g)
{
	const struct mesh *m = g->m;

	for (size_t t = 1; t < m->ntris; t++)
		if (uf_find(g->parent, m->tris[t][0]) != uf_find(g->parent, m->tris[0][0]))
			return 2;
	return m->ntris > 0;
}

/* Every triangle's box, grown by half the reach. */
static void triangle_boxes(struct groups *g)
{
	const struct mesh *m = g->m;

	for (size_t t = 0; t < m->ntris; t++) {
		struct box *b = &g->box[t];
		for (int k = 0; k < 3; k++) {
			b->lo[k] = INFINITY;
			b->hi[k] = -INFINITY;
			for (int c = 0; c < 3; c++) {
				b->lo[k] = fmin(b->lo[k], m->verts[m->tris[t][c]][k]);
				b->hi[k] = fmax(b->hi[k], m->verts[m->tris[t][c]][k]);
			}
			b->lo[k] -= g->reach / 2;
			b->hi[k] += g->reach / 2;
		}
	}
}

/* The batches of groups found in g->parent (one batch when single). */
static int gather(const struct mesh *m, uint32_t *parent, bool single, struct batches *out)
{
	uint32_t *gid = malloc((m->nverts + 1) * sizeof(*gid));
	uint32_t *batch_of = malloc((m->ntris + 1) * sizeof(*batch_of));
	size_t *gsize = calloc(m->ntris + 1, sizeof(*gsize));
	size_t ngroups = 0;
	int rc = ST_ERR_NOMEM;

	if (!gid || !batch_of || !gsize)
		goto out;
	for (size_t v = 0; v < m->nverts; v++)
		gid[v] = NO_ID;
	/* Groups numbered in the order of their first triangle. */
	for (size_t t = 0; t < m->ntris; t++) {
		uint32_t r = single ? 0 : uf_find(parent, m->tris[t][0]);
		if (gid[r] == NO_ID)
			gid[r] = (uint32_t)ngroups++;
		batch_of[t] = gid[r];
		gsize[gid[r]]++;
	}
	/* Consecutive groups into batches; gsize becomes the batch of a group. */
	size_t nb = 0, filled = 0;
	for (size_t k = 0; k < ngroups; k++) {
		if (filled && filled + gsize[k] > BATCH_TRIANGLES) {
			nb++;
			filled = 0;
		}
		filled += gsize[k];
		gsize[k] = nb;
	}
	nb += ngroups > 0;
	out->n = nb;
	out->start = calloc(nb + 2, sizeof(*out->start));
	out->tri = malloc((m->ntris + 1) * sizeof(*out->tri));
	if (!out->start || !out->tri)
		goto out;
	for (size_t t = 0; t < m->ntris; t++) {
		batch_of[t] = (uint32_t)gsize[batch_of[t]];
		out->start[batch_of[t] + 2]++;
	}
	for (size_t b = 2; b < nb + 2; b++)
		out->start[b] += out->start[b - 1];
	for (size_t t = 0; t < m->ntris; t++)
		out->tri[out->start[batch_of[t] + 1]++] = (uint32_t)t;
	rc = 0;
out:
	free(gid);
	free(batch_of);
	free(gsize);
	return rc;
}

int batches_find(const struct mesh *m, double reach, struct batches *out, struct st_error *err)
{
	struct groups g = {.m = m, .reach = reach};
	bool single = m->ntris <= BATCH_TRIANGLES;
	int rc = 0;

	memset(out, 0, sizeof(*out));
	if (!single) {
		g.parent = malloc((m->nverts + 1) * sizeof(*g.parent));
		/* Per triangle, then (join_enclosed) per group's root vertex. */
		g.box = malloc(((m->ntris > m->nverts ? m->ntris : m->nverts) + 1) * sizeof(*g.box));
		g.extent = malloc((m->ntris + 1) * sizeof(*g.extent));
		g.cand = malloc((m->ntris + 1) * sizeof(*g.cand));
		if (!g.parent || !g.box || !g.extent || !g.cand) {
			rc = ST_ERR_NOMEM;
			goto out;
		}
		for (size_t v = 0; v < m->nverts; v++)
			g.parent[v] = (uint32_t)v;
		for (size_t t = 0; t < m->ntris; t++) {
			uf_union(g.parent, m->tris[t][0], m->tris[t][1]);
			uf_union(g.parent, m->tris[t][0], m->tris[t][2]);
		}
		size_t nparts = 0;
		triangle_boxes(&g);
		rc = pick_candidates(&g, &nparts);
		if (!rc && nparts < 2)
			rc = 1; /* one part: nothing to repair apart */
		if (!rc && g.ncand)
			rc = join_near_triangles(&g);
		if (!rc && count_groups(&g) < 2)
			rc = 1; /* all joined */
		if (!rc)
			rc = join_enclosed(&g);
		if (rc == 1) {
			single = true;
			rc = 0;
		}
	}
	if (!rc)
		rc = gather(m, g.parent, single, out);
out:
	free(g.parent);
	free(g.box);
	free(g.extent);
	free(g.cand);
	free(g.entries);
	free(g.start);
	if (rc) {
		batches_free(out);
		return st_error_set(err, ST_ERR_NOMEM, "out of memory grouping the triangles");
	}
	return 0;
}

void batches_free(struct batches *b)
{
	free(b->start);
	free(b->tri);
	memset(b, 0, sizeof(*b));
}

/* Batch b of m as a mesh of its own; map: nverts entries of NO_ID, left so. */
static struct mesh *sub_mesh(const struct mesh *m, const struct batches *bs, size_t b,
			     uint32_t *map)
{
	const uint32_t *tri = bs->tri + bs->start[b];
	const size_t n = bs->start[b + 1] - bs->start[b];
	struct mesh *s = calloc(1, sizeof(*s));

	if (!s)
		return NULL;
	s->tris = malloc((n + 1) * sizeof(*s->tris));
	s->verts = malloc((3 * n + 1) * sizeof(*s->verts));
	if (!s->tris || !s->verts) {
		mesh_free(s);
		return NULL;
	}
	s->cap_tris = n;
	s->cap_verts = 3 * n;
	for (size_t i = 0; i < n; i++)
		for (int c = 0; c < 3; c++) {
			uint32_t v = m->tris[tri[i]][c];
			if (map[v] == NO_ID) {
				map[v] = (uint32_t)s->nverts;
				memcpy(s->verts[s->nverts++], m->verts[v], sizeof(*s->verts));
			}
			s->tris[i][c] = map[v];
		}
	s->ntris = n;
	for (size_t i = 0; i < n; i++)
		for (int c = 0; c < 3; c++)
			map[m->tris[tri[i]][c]] = NO_ID;
	return s;
}

struct run {
	const struct mesh *m;
	const struct batches *b;
	batch_fn fn;
	void *ctx;
	void (*done)(void *ctx, double fraction);
	pthread_mutex_t lock;
	size_t *order, norder, next;
	size_t tris_done;
	int threads_each;
	int rc;
	struct st_error err;
};

/* Run batches from r->order until none is left or one failed. */
static void *worker(void *arg)
{
	struct run *r = arg;
	uint32_t *map = malloc((r->m->nverts + 1) * sizeof(*map));

	if (map)
		for (size_t v = 0; v < r->m->nverts; v++)
			map[v] = NO_ID;
	for (;;) {
		struct st_error e = {0};
		struct mesh *sub = NULL;
		size_t b;
		int rc;

		pthread_mutex_lock(&r->lock);
		if (r->rc || r->next == r->norder || !map) {
			if (!map && !r->rc) {
				r->rc = st_error_set(&r->err, ST_ERR_NOMEM,
						     "out of memory starting a repair thread");
			}
			pthread_mutex_unlock(&r->lock);
			break;
		}
		b = r->order[r->next++];
		pthread_mutex_unlock(&r->lock);

		sub = sub_mesh(r->m, r->b, b, map);
		rc = sub ? r->fn(r->ctx, b, sub, r->threads_each, &e)
			 : st_error_set(&e, ST_ERR_NOMEM, "out of memory copying a group");
		mesh_free(sub);

		pthread_mutex_lock(&r->lock);
		if (rc && !r->rc) {
			r->rc = rc;
			r->err = e;
		}
		r->tris_done += r->b->start[b + 1] - r->b->start[b];
		if (r->done && !r->rc)
			r->done(r->ctx, (double)r->tris_done / (double)(r->m->ntris + !r->m->ntris));
		pthread_mutex_unlock(&r->lock);
	}
	free(map);
	return NULL;
}

struct sized_batch {
	size_t ntris, index;
};

static int larger_batch_first(const void *x, const void *y)
{
	const struct sized_batch *a = x, *b = y;

	if (a->ntris != b->ntris)
		return a->ntris < b->ntris ? 1 : -1;
	return a->index < b->index ? -1 : a->index > b->index;
}

/*
 * Reorder the n batches listed in order, largest first: a large batch
 * taken last would leave the other cores idle while it runs (soup-200k's
 * groups go up to four times a batch's size).  Left as it is when out of
 * memory: the order changes the time only, never the result.
 */
static void largest_first(const struct batches *b, size_t *order, size_t n)
{
	struct sized_batch *s = malloc((n + 1) * sizeof(*s));

	if (!s)
		return;
	for (size_t i = 0; i < n; i++)
		s[i] = (struct sized_batch){b->start[order[i] + 1] - b->start[order[i]], order[i]};
	qsort(s, n, sizeof(*s), larger_batch_first);
	for (size_t i = 0; i < n; i++)
		order[i] = s[i].index;
	free(s);
}

int batches_run(const struct mesh *m, const struct batches *b, int threads, batch_fn fn,
		void *ctx, void (*done)(void *ctx, double fraction), struct st_error *err)
{
	long cores = threads > 0 ? threads : sysconf(_SC_NPROCESSORS_ONLN);
	size_t big = 0, workers;
	struct run r = {.m = m, .b = b, .fn = fn, .ctx = ctx, .done = done};
	pthread_t *tid = NULL;
	size_t started = 0;

	if (cores < 1)
		cores = 1;
	r.order = malloc((b->n + 1) * sizeof(*r.order));
	if (!r.order)
		return st_error_set(err, ST_ERR_NOMEM, "out of memory ordering the groups");
	pthread_mutex_init(&r.lock, NULL);
	for (size_t k = 1; k < b->n; k++)
		if (b->start[k + 1] - b->start[k] > b->start[big + 1] - b->start[big])
			big = k;
	/* A batch of most of the mesh would hold the others up on one core:
	 * it runs first with all of them. */
	if (b->n && 2 * (b->start[big + 1] - b->start[big]) > m->ntris) {
		r.order[0] = big;
		r.norder = 1;
		r.threads_each = (int)cores;
		worker(&r);
	}
	r.norder = 0;
	r.next = 0;
	for (size_t k = 0; k < b->n; k++)
		if (!(r.threads_each && k == big))
			r.order[r.norder++] = k;
	largest_first(b, r.order, r.norder);
	r.threads_each = 1;
	workers = (size_t)cores < r.norder ? (size_t)cores : r.norder;
	if (workers > 1)
		tid = malloc(workers * sizeof(*tid));
	for (; tid && started + 1 < workers; started++)
		if (pthread_create(&tid[started], NULL, worker, &r))
			break;
	worker(&r); /* this thread is a worker too */
	for (size_t k = 0; k < started; k++)
		pthread_join(tid[k], NULL);
	free(tid);
	free(r.order);
	pthread_mutex_destroy(&r.lock);
	if (r.rc)
		*err = r.err;
	return r.rc;
}
