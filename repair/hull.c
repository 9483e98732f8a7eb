/*
 * hull.c - outer hull by non-manifold region growing (seed 000 §4.2.1,
 * Algorithms 1 and 2) over an exact mesh without self-intersections.
 *
 * Edges come from vertex stars as compressed rows (edge -> corners), so a
 * million triangles need no hash table.  The radial order of the fan around
 * an edge is never stored: the upward continuation is the triangle at the
 * smallest positive angle, found with exact orientation tests on the fly.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "exact.h"
#include "hull.h"
#include "ids.h"
#include "st_grow.h"

/* Edge incidence as compressed rows; corner c = 3*tri+k is edge (k, k+1). */
struct edges {
	uint32_t *voff, *vtri;	 /* vertex stars */
	uint32_t *eoff;		 /* [edge] first corner in ecorner, [nedges] end */
	uint32_t *ecorner;	 /* corners grouped by edge */
	uint32_t *corner_edge;	 /* [corner] its edge */
	size_t nedges;
};

static void edges_free(struct edges *e)
{
	free(e->voff);
	free(e->vtri);
	free(e->eoff);
	free(e->ecorner);
	free(e->corner_edge);
	memset(e, 0, sizeof(*e));
}

struct pending {
	uint32_t other;	 /* the edge's higher vertex */
	uint32_t corner;
};

static int compare_pending(const void *a, const void *b)
{
	const struct pending *x = a, *y = b;

	if (x->other != y->other)
		return x->other < y->other ? -1 : 1;
	return x->corner < y->corner ? -1 : x->corner > y->corner;
}

/* Build the edges of every triangle; 0 or ST_ERR_NOMEM. */
static int edges_build(const uint32_t (*tris)[3], size_t ntris, size_t nverts, struct edges *e,
		       struct st_error *err)
{
	struct pending *buf = NULL;
	size_t cap = 0, ne = 0;

	memset(e, 0, sizeof(*e));
	e->voff = calloc(nverts + 1, sizeof(*e->voff));
	e->vtri = malloc((3 * ntris + 1) * sizeof(*e->vtri));
	e->eoff = malloc((3 * ntris + 1) * sizeof(*e->eoff));
	e->ecorner = malloc((3 * ntris + 1) * sizeof(*e->ecorner));
	e->corner_edge = malloc((3 * ntris + 1) * sizeof(*e->corner_edge));
	if (!e->voff || !e->vtri || !e->eoff || !e->ecorner || !e->corner_edge)
		goto out_nomem;
	for (size_t t = 0; t < ntris; t++)
		for (int k = 0; k < 3; k++)
			e->voff[tris[t][k] + 1]++;
	for (size_t v = 0; v < nverts; v++)
		e->voff[v + 1] += e->voff[v];
	for (size_t t = 0; t < ntris; t++)
		for (int k = 0; k < 3; k++)
			e->vtri[e->voff[tris[t][k]]++] = (uint32_t)t;
	for (size_t v = nverts; v > 0; v--)
		e->voff[v] = e->voff[v - 1];
	e->voff[0] = 0;

	/* Each edge is collected at its lower vertex from that vertex's star. */
	size_t pos = 0;
	for (size_t v = 0; v < nverts; v++) {
		size_t n = 0;

		for (uint32_t i = e->voff[v]; i < e->voff[v + 1]; i++) {
			const uint32_t t = e->vtri[i];
			for (int k = 0; k < 3; k++) {
				const uint32_t a = tris[t][k], b = tris[t][(k + 1) % 3];
				if ((a == v && b > v) || (b == v && a > v)) {
					struct pending *nb = st_grow(buf, &cap, n + 1, sizeof(*nb));
					if (!nb)
						goto out_nomem;
					buf = nb;
					buf[n].other = a == v ? b : a;
					buf[n].corner = 3 * t + (uint32_t)k;
					n++;
				}
			}
		}
		if (n > 1)
			qsort(buf, n, sizeof(*buf), compare_pending);
		for (size_t i = 0; i < n; i++) {
			if (i == 0 || buf[i].other != buf[i - 1].other)
				e->eoff[ne++] = (uint32_t)pos;
			e->ecorner[pos++] = buf[i].corner;
			e->corner_edge[buf[i].corner] = (uint32_t)(ne - 1);
		}
	}
	e->eoff[ne] = (uint32_t)pos;
	e->nedges = ne;
	free(buf);
	return 0;

out_nomem:
	free(buf);
	edges_free(e);
	return st_error_set(err, ST_ERR_NOMEM, "out of memory building the edges of %zu triangles",
			    ntris);
}

/* Side s of triangle t: its corners as stored (s = 0) or reversed. */
static void oriented(const uint32_t (*tris)[3], uint32_t t, uint8_t s, uint32_t v[3])
{
	v[0] = tris[t][0];
	v[1] = s ? tris[t][2] : tris[t][1];
	v[2] = s ? tris[t][1] : tris[t][2];
}

/* The corner of t (original order) that is not u or w. */
static uint32_t third_vertex(const uint32_t (*tris)[3], uint32_t t, uint32_t u, uint32_t w)
{
	for (int k = 0; k < 3; k++)
		if (tris[t][k] != u && tris[t][k] != w)
			return tris[t][k];
	return tris[t][0];
}

/*
 * Rotation order around the directed axis a->b starting from the half-plane
 * of c: 0 for angles in (0, pi), 1 for pi, 2 for (pi, 2 pi).  Positive
 * rotation is towards the normal of (a, b, c).
 */
static int half_turn(const struct exact_mesh *em, uint32_t a, uint32_t b, uint32_t c, uint32_t x)
{
	const int s = exact_mesh_orient3d(em, a, b, c, x);

	return s > 0 ? 0 : s == 0 ? 1 : 2;
}

/*
 * The upward continuation (Def. 4.1, 4.2) of triangle ti, oriented
 * (a, b, c), at its edge a->b: the first triangle met when turning the
 * half-plane of ti about a->b towards ti's normal.  ti itself on a boundary.
 */
static uint32_t continuation(const struct exact_mesh *em, const uint32_t (*tris)[3],
			     const struct edges *e, uint32_t edge, uint32_t ti, uint32_t a,
			     uint32_t b, uint32_t c)
{
	uint32_t best = ti, bx = 0;
	int bh = 3;

	/* Across a manifold edge the one other triangle is the continuation
	 * whatever the angle: no predicate (pieces of one split triangle are
	 * coplanar, so their orientation would need exact arithmetic). */
	if (e->eoff[edge + 1] - e->eoff[edge] == 2) {
		const uint32_t t0 = e->ecorner[e->eoff[edge]] / 3;
		return t0 != ti ? t0 : e->ecorner[e->eoff[edge] + 1] / 3;
	}
	for (uint32_t i = e->eoff[edge]; i < e->eoff[edge + 1]; i++) {
		const uint32_t t = e->ecorner[i] / 3;
		if (t == ti)
			continue;
		const uint32_t x = third_vertex(tris, t, a, b);
		/* A piece of ti's own triangle lies straight through: the
		 * half turn, known without the (exact, costly) zero. */
		const int h = exact_mesh_same_plane(em, ti, t) ? 1 : half_turn(em, a, b, c, x);
		/* Within one half turn, x comes first when bx lies further
		 * along, i.e. on the positive side of the plane (a, b, x). */
		if (h < bh || (h == bh && h != 1 && exact_mesh_orient3d(em, a, b, x, bx) > 0)) {
			best = t;
			bx = x;
			bh = h;
		}
	}
	return best;
}

/* Whether t as stored runs along its edge from u to w. */
static bool runs_from(const uint32_t (*tris)[3], uint32_t t, uint32_t u, uint32_t w)
{
	uint32_t v[3];

	oriented(tris, t, 0, v);
	for (int k = 0; k < 3; k++)
		if (v[k] == u && v[(k + 1) % 3] == w)
			return true;
	return false;
}

/*
 * A FIFO of sides to walk from: the border B of Algorithm 1.  An item is
 * 6*t + 2*k + s: edge slot k of triangle t seen from side s (0: as stored,
 * 1: reversed).  The side travels with the item, so walking one side of a
 * triangle never depends on when its other side is reached.
 */
struct border {
	uint64_t *items;
	size_t head, tail, cap;
};

static int border_push_all(struct border *q, uint32_t t, uint32_t side, struct st_error *err)
{
	if (q->tail + 3 > q->cap) {
		/* Compact, then grow. */
		if (q->head > 0)
			memmove(q->items, q->items + q->head,
				(q->tail - q->head) * sizeof(*q->items));
		q->tail -= q->head;
		q->head = 0;
		uint64_t *ni = st_grow(q->items, &q->cap, q->tail + 3, sizeof(*ni));
		if (!ni)
			return st_error_set(err, ST_ERR_NOMEM, "out of memory growing the outer hull");
		q->items = ni;
	}
	for (uint32_t k = 0; k < 3; k++)
		q->items[q->tail++] = 6 * (uint64_t)t + 2 * k + side;
	return 0;
}

/*
 * Algorithm 1 on the component whose triangles are listed in comp, over
 * triangle sides: side s of t is reached once, and a triangle whose two
 * sides are both reached is double-sided (tag outer and inner).  Keeping
 * the side in each border item matters: with one orientation bit per
 * triangle, the edges a triangle queued for one side were walked from the
 * other once that was reached too, so a face in the middle of a sheet
 * could be left single-sided, a hole in M_solid that the second pass then
 * found as a sheet again.  side_seen: per triangle, bit s when side s was
 * reached; first: the side reached first.
 */
static int grow(const struct exact_mesh *em, const uint32_t (*tris)[3], const struct edges *e,
		const uint32_t *comp, size_t n, uint8_t *side_seen, uint8_t *first,
		struct st_error *err)
{
	struct border q = {0};
	uint32_t seed;
	bool seed_flip;
	int rc;

	rc = exact_mesh_seed(em, comp, n, &seed, &seed_flip, err);
	if (rc)
		return rc;
	side_seen[seed] = (uint8_t)(1u << seed_flip);
	first[seed] = seed_flip;
	rc = border_push_all(&q, seed, seed_flip, err);
	while (!rc && q.head < q.tail) {
		const uint64_t item = q.items[q.head++];
		const uint32_t ti = (uint32_t)(item / 6), k = (uint32_t)(item / 2 % 3);
		const uint8_t s = (uint8_t)(item % 2);
		uint32_t v[3];

		/* The edge as side s of ti runs along it: a -> b, third c. */
		oriented(tris, ti, s, v);
		const uint32_t a = v[k], b = v[(k + 1) % 3], c = v[(k + 2) % 3];
		/* k indexes that orientation; the edge id is the same for
		 * either, found from the original corners. */
		uint32_t corner = 0;
		for (uint32_t j = 0; j < 3; j++) {
			const uint32_t p = tris[ti][j], r = tris[ti][(j + 1) % 3];
			if ((p == a && r == b) || (p == b && r == a))
				corner = 3 * ti + j;
		}
		const uint32_t tnew = continuation(em, tris, e, e->corner_edge[corner], ti, a, b, c);
		/* The side of tnew facing the same way runs the edge b -> a;
		 * on a boundary (tnew == ti) that is ti's other side. */
		const uint8_t snew = tnew == ti ? (uint8_t)!s : !runs_from(tris, tnew, b, a);
		if (side_seen[tnew] & (1u << snew))
			continue;
		if (!side_seen[tnew])
			first[tnew] = snew;
		side_seen[tnew] |= (uint8_t)(1u << snew);
		rc = border_push_all(&q, tnew, snew, err);
	}
	free(q.items);
	return rc;
}

/* Bounding box of the listed triangles' vertices (double approximations). */
static void list_bbox(const double (*verts)[3], const uint32_t (*tris)[3], const uint32_t *list,
		      size_t n, double lo[3], double hi[3])
{
	for (int k = 0; k < 3; k++) {
		lo[k] = HUGE_VAL;
		hi[k] = -HUGE_VAL;
	}
	for (size_t i = 0; i < n; i++)
		for (int c = 0; c < 3; c++)
			for (int k = 0; k < 3; k++) {
				const double x = verts[tris[list[i]][c]][k];
				lo[k] = x < lo[k] ? x : lo[k];
				hi[k] = x > hi[k] ? x : hi[k];
			}
}

/*
 * Group triangles into components: those with member[t] set, joined
 * across edges where both sides are members.  Writes the lists as rows
 * (off has ncomp+1 entries) and returns the count, or -1 on OOM.
 */
static long components(const struct edges *e, size_t ntris, const uint8_t *member,
		       uint32_t **off_out, uint32_t **list_out)
{
	uint32_t *parent = malloc((ntris + 1) * sizeof(*parent));
	uint32_t *root_id = malloc((ntris + 1) * sizeof(*root_id));
	uint32_t *off = NULL, *list = NULL;
	long nc = 0;

	if (!parent || !root_id)
		goto out_nomem;
	for (size_t t = 0; t < ntris; t++)
		parent[t] = (uint32_t)t;
	for (size_t ed = 0; ed < e->nedges; ed++) {
		uint32_t first = UINT32_MAX;
		for (uint32_t i = e->eoff[ed]; i < e->eoff[ed + 1]; i++) {
			const uint32_t t = e->ecorner[i] / 3;
			if (!member[t])
				continue;
			if (first == UINT32_MAX)
				first = t;
			else
				uf_union(parent, first, t);
		}
	}
	for (size_t t = 0; t < ntris; t++)
		root_id[t] = UINT32_MAX;
	for (size_t t = 0; t < ntris; t++)
		if (member[t]) {
			const uint32_t r = uf_find(parent, (uint32_t)t);
			if (root_id[r] == UINT32_MAX)
				root_id[r] = (uint32_t)nc++;
		}
	off = calloc((size_t)nc + 2, sizeof(*off));
	list = malloc((ntris + 1) * sizeof(*list));
	if (!off || !list)
		goto out_nomem;
	for (size_t t = 0; t < ntris; t++)
		if (member[t])
			off[root_id[uf_find(parent, (uint32_t)t)] + 1]++;
	for (long c = 0; c < nc; c++)
		off[c + 1] += off[c];
	for (size_t t = 0; t < ntris; t++)
		if (member[t])
			list[off[root_id[uf_find(parent, (uint32_t)t)]]++] = (uint32_t)t;
	for (long c = nc; c > 0; c--)
		off[c] = off[c - 1];
	off[0] = 0;
	free(parent);
	free(root_id);
	*off_out = off;
	*list_out = list;
	return nc;

out_nomem:
	free(parent);
	free(root_id);
	free(off);
	free(list);
	return -1;
}

/* A component C of M_solid and M_sheet inside the space bounded by D, a
 * component of M_solid (by index into the two component lists). */
struct containment {
	uint32_t c, d;
};

/* What the nesting pass decided for a component. */
enum nest_fate { NEST_SOLID, NEST_CAVITY, NEST_DELETED };

/*
 * Whether component C (its triangles in cl) is a cavity as the input drew
 * it: a closed M_solid shell every triangle of which the input oriented
 * towards the inside of C, i.e. the growing from outside C had to flip
 * all of them.  Pieces keep their input triangle's orientation
 * (exact_mesh_refine), so the stored orientation is the input's and the
 * comparison with the exact flip decides exactly.  A shell with mixed
 * orientation is unreliable and stays an enclosed component, as seed 000
 * §5.3 warns.
 */
static bool input_faces_inward(const uint8_t *tag, const uint8_t *flip, const uint32_t *cl,
			       size_t cn)
{
	for (size_t i = 0; i < cn; i++)
		if (tag[cl[i]] != HULL_OUTER || !flip[cl[i]])
			return false;
	return cn > 0;
}

/*
 * Algorithm 2, lines 4-10, extended to designed cavities (docs/repair.md,
 * "Cavities").  The nc components of M_solid and M_sheet (rows off/list)
 * are tested exactly against the ns components of M_solid (soff/slist).
 * Going outwards in, a component is in material when the kept shells
 * around it wind round it once more outwards than inwards (an outward
 * solid +1, a cavity -1).  There it is kept as a cavity when the input
 * faced it inwards (its triangles keep the input orientation, facing into
 * the void) and deleted otherwise (seed 000); a component in empty space,
 * such as a part inside a cavity, is kept as a solid.
 */
static int nest_components(const struct exact_mesh *em, long nc, const uint32_t *off,
			   const uint32_t *list, long ns, const uint32_t *soff,
			   const uint32_t *slist, uint8_t *tag, uint8_t *flip,
			   struct hull_stats *st, struct st_error *err)
{
	const size_t ntris = exact_mesh_ntris(em);
	const uint32_t (*tris)[3] = exact_mesh_tris(em);
	const double (*verts)[3] = exact_mesh_verts(em);
	uint32_t *owner = malloc((size_t)ns * sizeof(*owner));	  /* D -> its C */
	uint32_t *comp_of = malloc((ntris + 1) * sizeof(*comp_of)); /* tri -> C */
	double (*slo)[3] = malloc((size_t)ns * sizeof(*slo));
	double (*shi)[3] = malloc((size_t)ns * sizeof(*shi));
	struct id_depth *order = calloc((size_t)nc, sizeof(*order));
	uint8_t *fate = calloc((size_t)nc, 1);
	struct containment *pairs = NULL;
	uint32_t *prow = NULL; /* [c] first pair of c; pairs come grouped by c */
	size_t npairs = 0, cap = 0;
	int rc = 0;

	if (!owner || !comp_of || !slo || !shi || !order || !fate)
		goto out_nomem;
	for (long c = 0; c < nc; c++)
		for (uint32_t i = off[c]; i < off[c + 1]; i++)
			comp_of[list[i]] = (uint32_t)c;
	for (long d = 0; d < ns; d++) {
		owner[d] = comp_of[slist[soff[d]]];
		list_bbox(verts, tris, slist + soff[d], soff[d + 1] - soff[d], slo[d], shi[d]);
	}
	for (long c = 0; c < nc && !rc; c++) {
		const uint32_t *cl = list + off[c];
		double lo[3], hi[3];

		order[c].id = (uint32_t)c;
		list_bbox(verts, tris, cl, off[c + 1] - off[c], lo, hi);
		for (long d = 0; d < ns && !rc; d++) {
			bool inside = false, boxed = true;

			if (owner[d] == (uint32_t)c)
				continue; /* a solid part of C itself does not count */
			/* Cheap reject: C's box must lie in D's box. */
			for (int k = 0; k < 3; k++)
				boxed = boxed && lo[k] >= slo[d][k] && hi[k] <= shi[d][k];
			if (!boxed)
				continue;
			rc = exact_mesh_inside(em, slist + soff[d], soff[d + 1] - soff[d], cl[0],
					       &inside, err);
			if (rc || !inside)
				continue;
			struct containment *np = st_grow(pairs, &cap, npairs + 1, sizeof(*np));
			if (!np)
				goto out_nomem;
			pairs = np;
			pairs[npairs].c = (uint32_t)c;
			pairs[npairs++].d = (uint32_t)d;
			order[c].depth++;
		}
	}
	if (rc)
		goto out;
	prow = calloc((size_t)nc + 1, sizeof(*prow));
	if (!prow)
		goto out_nomem;
	for (size_t i = 0; i < npairs; i++)
		prow[pairs[i].c + 1]++;
	for (long c = 0; c < nc; c++)
		prow[c + 1] += prow[c];
	qsort(order, (size_t)nc, sizeof(*order), id_depth_compare);
	for (long i = 0; i < nc; i++) {
		const uint32_t c = order[i].id;
		const uint32_t *cl = list + off[c];
		const size_t cn = off[c + 1] - off[c];
		long winding = 0;

		/* Containers enclose fewer solids, so their fate is known. */
		for (uint32_t p = prow[c]; p < prow[c + 1]; p++) {
			const uint8_t f = fate[owner[pairs[p].d]];
			winding += f == NEST_SOLID ? 1 : f == NEST_CAVITY ? -1 : 0;
		}
		if (winding <= 0) {
			fate[c] = NEST_SOLID;
		} else if (input_faces_inward(tag, flip, cl, cn)) {
			fate[c] = NEST_CAVITY;
			st->cavities++;
			st->cavity_triangles += cn;
			for (size_t k = 0; k < cn; k++)
				flip[cl[k]] = 0;
		} else {
			fate[c] = NEST_DELETED;
			st->enclosed_components++;
			for (size_t k = 0; k < cn; k++) {
				tag[cl[k]] = 0;
				st->enclosed++;
			}
		}
	}
	goto out;

out_nomem:
	rc = st_error_set(err, ST_ERR_NOMEM, "out of memory testing containment");
out:
	free(owner);
	free(comp_of);
	free(slo);
	free(shi);
	free(order);
	free(fate);
	free(pairs);
	free(prow);
	return rc;
}

int hull_extract(const struct exact_mesh *em, uint8_t *tag, uint8_t *flip,
		 struct hull_stats *st, struct st_error *err)
{
	const size_t ntris = exact_mesh_ntris(em), nverts = exact_mesh_nverts(em);
	const uint32_t (*tris)[3] = exact_mesh_tris(em);
	struct edges e;
	uint8_t *member = NULL;
	uint32_t *off = NULL, *list = NULL, *soff = NULL, *slist = NULL;
	long nc, ns;
	int rc;

	memset(st, 0, sizeof(*st));
	memset(tag, 0, ntris);
	memset(flip, 0, ntris);
	if (ntris == 0)
		return 0;
	rc = edges_build(tris, ntris, nverts, &e, err);
	if (rc)
		return rc;
	member = malloc(ntris);
	if (!member) {
		rc = st_error_set(err, ST_ERR_NOMEM, "out of memory in the outer hull");
		goto out;
	}

	/* Algorithm 2, lines 1-3: grow the outer hull of every
	 * edge-connected component from its own seed. */
	memset(member, 1, ntris);
	nc = components(&e, ntris, member, &off, &list);
	if (nc < 0) {
		rc = st_error_set(err, ST_ERR_NOMEM, "out of memory finding components");
		goto out;
	}
	/* tag holds the sides reached (bit s), flip the first one, until
	 * they become tags: one side outer, both sides a sheet. */
	for (long c = 0; c < nc && !rc; c++)
		rc = grow(em, tris, &e, list + off[c], off[c + 1] - off[c], tag, flip, err);
	if (rc)
		goto out;
	for (size_t t = 0; t < ntris; t++) {
		const uint8_t seen = tag[t];
		tag[t] = seen == 3 ? HULL_OUTER | HULL_INNER : seen ? HULL_OUTER : 0;
		if (seen == 1 || seen == 2)
			flip[t] = seen == 2;
	}
	for (size_t t = 0; t < ntris; t++)
		if (!(tag[t] & HULL_OUTER))
			st->interior++;
	free(off);
	free(list);
	off = list = NULL;

	/* Lines 4-10: a component of M_solid and M_sheet that lies in the
	 * space bounded by a component of M_solid is deleted, unless it is a
	 * cavity or lies in one (nest_components). */
	for (size_t t = 0; t < ntris; t++)
		member[t] = (tag[t] & HULL_OUTER) != 0;
	nc = components(&e, ntris, member, &off, &list);
	for (size_t t = 0; t < ntris; t++)
		member[t] = tag[t] == HULL_OUTER;
	ns = nc < 0 ? -1 : components(&e, ntris, member, &soff, &slist);
	if (nc < 0 || ns < 0) {
		rc = st_error_set(err, ST_ERR_NOMEM, "out of memory finding components");
		goto out;
	}
	if (ns > 0 && nc > 1) {
		rc = nest_components(em, nc, off, list, ns, soff, slist, tag, flip, st, err);
		if (rc)
			goto out;
	}
	for (size_t t = 0; t < ntris; t++) {
		if (tag[t] == HULL_OUTER)
			st->solid++;
		else if (tag[t] == (HULL_OUTER | HULL_INNER))
			st->sheet++;
	}
	/* Sheets as their own edge-connected parts. */
	for (size_t t = 0; t < ntris; t++)
		member[t] = tag[t] == (HULL_OUTER | HULL_INNER);
	free(soff);
	free(slist);
	soff = slist = NULL;
	ns = components(&e, ntris, member, &soff, &slist);
	if (ns < 0) {
		rc = st_error_set(err, ST_ERR_NOMEM, "out of memory finding components");
		goto out;
	}
	st->sheet_components = (size_t)ns;
out:
	free(member);
	free(off);
	free(list);
	free(soff);
	free(slist);
	edges_free(&e);
	return rc;
}

long hull_manifold_components(const struct exact_mesh *em, uint32_t *component,
			      size_t *unpaired, struct st_error *err)
{
	const size_t ntris = exact_mesh_ntris(em), nverts = exact_mesh_nverts(em);
	const uint32_t (*tris)[3] = exact_mesh_tris(em);
	struct edges e;
	uint32_t *parent;
	long nc = 0;

	*unpaired = 0;
	if (ntris == 0)
		return 0;
	if (edges_build(tris, ntris, nverts, &e, err))
		return -1;
	parent = malloc((ntris + 1) * sizeof(*parent));
	if (!parent) {
		edges_free(&e);
		st_error_set(err, ST_ERR_NOMEM, "out of memory splitting components");
		return -1;
	}
	for (size_t t = 0; t < ntris; t++)
		parent[t] = (uint32_t)t;
	/*
	 * The manifold decomposition (Def. 3.10, Hui et al.): across an edge
	 * with two triangles they join; around a singular edge each triangle
	 * joins the one it faces through the solid, the first met turning
	 * away from its outward normal.  Two cubes sharing an edge stay two
	 * parts; a solid pinched along an edge (Fig. 2d) stays one, closed.
	 */
	*unpaired = 0;
	for (size_t ed = 0; ed < e.nedges; ed++) {
		const uint32_t first = e.eoff[ed], count = e.eoff[ed + 1] - first;
		bool mutual = true;
		if (count == 2) {
			uf_union(parent, e.ecorner[first] / 3, e.ecorner[first + 1] / 3);
			continue;
		}
		for (uint32_t i = first; i < e.eoff[ed + 1]; i++) {
			const uint32_t t = e.ecorner[i] / 3, k = e.ecorner[i] % 3;
			const uint32_t a = tris[t][k], b = tris[t][(k + 1) % 3],
				       c = tris[t][(k + 2) % 3];
			/* Away from (a, b, c)'s normal is towards (b, a, c)'s. */
			const uint32_t mate = continuation(em, tris, &e, (uint32_t)ed, t, b, a, c);
			/* Around a solid's edge the material between two
			 * triangles is theirs alone: each is the other's mate,
			 * and the two walk the edge opposite ways. */
			const uint32_t back = continuation(em, tris, &e, (uint32_t)ed, mate,
							   runs_from(tris, mate, a, b) ? b : a,
							   runs_from(tris, mate, a, b) ? a : b,
							   third_vertex(tris, mate, a, b));
			if (back != t || runs_from(tris, mate, a, b))
				mutual = false;
			uf_union(parent, t, mate);
		}
		*unpaired += !mutual;
	}
	for (size_t t = 0; t < ntris; t++)
		component[t] = UINT32_MAX;
	for (size_t t = 0; t < ntris; t++) {
		const uint32_t r = uf_find(parent, (uint32_t)t);
		if (component[r] == UINT32_MAX)
			component[r] = (uint32_t)nc++;
		component[t] = component[r];
	}
	free(parent);
	edges_free(&e);
	return nc;
}
