/*
 * thicken.c - seed 000 §4.2.1: turn M_sheet into thin closed solids.
 *
 * The slab of a sheet S is the boundary of S x [-half, half]: a copy of S
 * offset by half along the vertex normals on each side (C and its inverted
 * copy C'), stitched by a wall along every edge where S ends.  That surface
 * is closed by construction, whatever S looks like, because S is first cut
 * into a surface the construction applies to:
 *  - an edge joins two sheet triangles only if it has exactly two (or, at
 *    an edge with more, the two that continue each other straight through)
 *    and they bend by less than CREASE_DEGREES; every other edge is cut and
 *    gets a wall on each side;
 *  - where the sheet cannot be oriented (a Moebius strip, a Klein bottle),
 *    the copy above one triangle continues below its neighbour, which keeps
 *    the copies closed without an orientation;
 *  - a vertex's fan (its triangles joined around it) shares one normal; a
 *    fan whose normal leans more than FAN_DEGREES from one of its triangles
 *    has its edges at that vertex cut, so every offset stays on its own
 *    side of the sheet.  At worst every edge is cut and each triangle is a
 *    prism of its own.
 * Slabs of cut neighbours overlap near their common edge; the repair's
 * second pass unites them exactly like any other touching solids, so the
 * result is closed and M_sheet is empty there (docs/repair.md).  Every
 * vertex of a slab is its sheet vertex itself or a copy exactly half away
 * from it, so every point lies within half of the sheet.  Doubles only:
 * nothing here decides anything.
 */
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "ids.h"
#include "thicken.h"
#include "vec3.h"

/* Bends sharper than this cut the sheet: each side keeps its own slab. */
#define CREASE_DEGREES 30.0

/* A fan normal may lean at most this far from each triangle of the fan. */
#define FAN_DEGREES 60.0

struct sheet_edge {
	uint32_t lo, hi;	/* vertex ids, lo < hi */
	uint32_t corner;	/* 3*i+k: edge k of listed triangle i */
};

static int compare_sheet_edge(const void *a, const void *b)
{
	const struct sheet_edge *x = a, *y = b;

	if (x->lo != y->lo)
		return x->lo < y->lo ? -1 : 1;
	if (x->hi != y->hi)
		return x->hi < y->hi ? -1 : 1;
	return x->corner < y->corner ? -1 : x->corner > y->corner;
}

/*
 * Union-find over corners with a parity bit: par[x] says whether x's side
 * is reversed relative to its parent.  Where a sheet cannot be oriented,
 * the copies above one triangle continue below its neighbour.
 */
static uint32_t find(uint32_t *parent, uint8_t *par, uint32_t x, uint8_t *parity)
{
	uint32_t r = x;
	uint8_t p = 0;

	while (parent[r] != r) {
		p ^= par[r];
		r = parent[r];
	}
	/* Point every corner on the path at the root with its own parity. */
	uint8_t px = p;
	while (parent[x] != x) {
		const uint32_t next = parent[x];
		const uint8_t own = par[x];
		parent[x] = r;
		par[x] = px;
		px ^= own;
		x = next;
	}
	*parity = p;
	return r;
}

static void join(uint32_t *parent, uint8_t *par, uint32_t a, uint32_t b, uint8_t flip)
{
	uint8_t pa, pb;

	a = find(parent, par, a, &pa);
	b = find(parent, par, b, &pb);
	if (a == b)
		return;
	if (a > b) {
		const uint32_t t = a;
		a = b;
		b = t;
	}
	parent[b] = a;
	par[b] = pa ^ pb ^ flip;
}

/* Position in the oriented triangle of original corner k. */
static int oriented_slot(const uint8_t *flip, uint32_t i, int k)
{
	static const int rev[3] = {0, 2, 1};

	return flip[i] ? rev[k] : k;
}

/* Oriented unit normal of listed triangle i with flip f; false if none. */
static bool unit_normal(const double (*verts)[3], const uint32_t (*tris)[3], const uint32_t *list,
			uint32_t i, uint8_t f, double nn[3])
{
	const uint32_t *t = tris[list[i]];
	const double *a = verts[t[0]], *b = verts[f ? t[2] : t[1]], *c = verts[f ? t[1] : t[2]];
	const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
	const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};

	nn[0] = u[1] * v[2] - u[2] * v[1];
	nn[1] = u[2] * v[0] - u[0] * v[2];
	nn[2] = u[0] * v[1] - u[1] * v[0];
	const double l = sqrt(nn[0] * nn[0] + nn[1] * nn[1] + nn[2] * nn[2]);
	if (!(l > 0))
		return false;
	for (int k = 0; k < 3; k++)
		nn[k] /= l;
	return true;
}

/*
 * Whether the sheet bends more than CREASE_DEGREES between triangles i and
 * j (j oriented by fj).  Vertex normals are not shared across a crease:
 * offsetting along an averaged normal would thin the slab by the cosine of
 * half the bend (a cube's corner normal leaves its faces 0.58 epsilon
 * thick), so each side gets its own copies and wedges fill the gap.
 */
static bool is_crease(const double (*verts)[3], const uint32_t (*tris)[3], const uint32_t *list,
		      const uint8_t *flip, uint32_t i, uint32_t j, uint8_t fj)
{
	double a[3], b[3];

	if (!unit_normal(verts, tris, list, i, flip[i], a) ||
	    !unit_normal(verts, tris, list, j, fj, b))
		return true;
	return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] < cos(CREASE_DEGREES * M_PI / 180);
}

/* The corner of listed triangle i opposite edge corner c (c = 3i+k). */
static const double *apex(const double (*verts)[3], const uint32_t (*tris)[3],
			  const uint32_t *list, uint32_t c)
{
	return verts[tris[list[c / 3]][(c % 3 + 2) % 3]];
}

/*
 * At an edge shared by more than two sheet triangles (sheets crossing or
 * meeting), mate the pairs that continue each other straight through: apexes
 * on opposite sides, planes within CREASE_DEGREES, best pairs first.  The
 * others end there and get walls.
 */
static void pair_straight(const double (*verts)[3], const uint32_t (*tris)[3],
			  const uint32_t *list, const struct sheet_edge *e, size_t k,
			  uint32_t *mate)
{
	const double *a = verts[e[0].lo], *b = verts[e[0].hi];
	double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
	const double dl = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);

	for (int j = 0; j < 3; j++)
		d[j] /= dl;
	for (;;) {
		double best = cos(CREASE_DEGREES * M_PI / 180);
		size_t bi = k, bj = k;
		for (size_t i = 0; i < k; i++)
			for (size_t j = i + 1; j < k; j++) {
				const uint32_t ci = e[i].corner, cj = e[j].corner;
				if (mate[ci] != UINT32_MAX || mate[cj] != UINT32_MAX)
					continue;
				/* Directions from the edge to each apex, at right
				 * angles to it: straight means opposite. */
				double u[3], w[3], lu = 0, lw = 0, dot = 0;
				const double *p = apex(verts, tris, list, ci);
				const double *q = apex(verts, tris, list, cj);
				double pu = 0, qw = 0;
				for (int t = 0; t < 3; t++) {
					pu += (p[t] - a[t]) * d[t];
					qw += (q[t] - a[t]) * d[t];
				}
				for (int t = 0; t < 3; t++) {
					u[t] = p[t] - a[t] - pu * d[t];
					w[t] = q[t] - a[t] - qw * d[t];
					lu += u[t] * u[t];
					lw += w[t] * w[t];
				}
				for (int t = 0; t < 3; t++)
					dot += u[t] * w[t];
				if (!(lu > 0) || !(lw > 0))
					continue;
				const double c = -dot / sqrt(lu * lw);
				if (c > best) {
					best = c;
					bi = i;
					bj = j;
				}
			}
		if (bi == k)
			return;
		mate[e[bi].corner] = e[bj].corner;
		mate[e[bj].corner] = e[bi].corner;
	}
}

static int compare_u32(const void *a, const void *b)
{
	const uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;

	return x < y ? -1 : x > y;
}

/*
 * The slab's own copy of sheet vertex v (on the walls), made once: uv is
 * the sorted list of the sheet's vertices (nu of them), sidx their slab
 * vertex or UINT32_MAX.
 */
static size_t sheet_index(const uint32_t *uv, size_t nu, uint32_t v)
{
	const uint32_t *hit = bsearch(&v, uv, nu, sizeof(*uv), compare_u32);

	return (size_t)(hit - uv);
}

static uint32_t sheet_vertex(struct thick_out *out, const uint32_t *uv, size_t nu, uint32_t *sidx,
			     const double (*verts)[3], uint32_t v)
{
	const size_t i = sheet_index(uv, nu, v);

	if (sidx[i] == UINT32_MAX) {
		memcpy(out->verts[out->nverts], verts[v], sizeof(out->verts[0]));
		out->sheet_ref[out->nverts] = v;
		sidx[i] = (uint32_t)out->nverts++;
	}
	return sidx[i];
}

struct x_order {
	uint32_t v;
	double x;
};

static int compare_x_order(const void *a, const void *b)
{
	const struct x_order *p = a, *q = b;

	return p->x < q->x ? -1 : p->x > q->x;
}

/*
 * Make vertex copies closer than tol (in every coordinate) exactly equal.
 * Copies of one sheet vertex in different fans that face the same way (or
 * opposite ways) land within rounding of each other; left distinct, they
 * are clusters of points a float cannot tell apart, and the exact pass
 * turns them into slivers that rounding to the output precision flips.
 * Equal, they are one point, which the exact mesh welds.
 */
static int weld_close(struct thick_out *out, double tol, struct st_error *err)
{
	struct x_order *o = malloc((out->nverts + 1) * sizeof(*o));
	uint32_t *rep = malloc((out->nverts + 1) * sizeof(*rep));

	if (!o || !rep) {
		free(o);
		free(rep);
		return st_error_set(err, ST_ERR_NOMEM, "out of memory welding slab vertices");
	}
	size_t no = 0;
	for (uint32_t v = 0; v < out->nverts; v++) {
		rep[v] = v;
		if (out->sheet_ref[v] != UINT32_MAX)
			continue; /* the sheet's own point: exact, never moved */
		o[no].v = v;
		o[no++].x = out->verts[v][0];
	}
	qsort(o, no, sizeof(*o), compare_x_order);
	for (size_t i = 0; i < no; i++)
		for (size_t j = i + 1; j < no && o[j].x - o[i].x <= tol; j++) {
			const double *a = out->verts[o[i].v], *b = out->verts[o[j].v];
			if (fabs(a[1] - b[1]) <= tol && fabs(a[2] - b[2]) <= tol)
				uf_union(rep, o[i].v, o[j].v);
		}
	for (uint32_t v = 0; v < out->nverts; v++) {
		const uint32_t r = uf_find(rep, v);
		if (r != v)
			memcpy(out->verts[v], out->verts[r], sizeof(out->verts[v]));
	}
	free(o);
	free(rep);
	return 0;
}

/* The working state of one thickening: the sheet as a cut surface. */
struct sheet {
	const double (*verts)[3];
	const uint32_t (*tris)[3];
	const uint32_t *list;
	const uint8_t *free_edges; /* [triangle] bit k: edge k touches nothing; may be NULL */
	size_t n;
	uint32_t *mate;		/* [corner] the corner across its edge, or UINT32_MAX */
	uint8_t *flip;		/* [triangle] reversed to orient the sheet */
	uint8_t *joined;	/* [corner] its edge joins it to mate (not cut) */
	uint32_t *group;	/* [corner] union-find over corners of one fan */
	uint8_t *gpar;		/* [corner] parity against the parent (side swap) */
	uint32_t *gid;		/* [corner] its fan, 0..ng-1 */
	uint8_t *side;		/* [corner] its side against its fan's normal */
	double (*gnorm)[3];	/* [fan] angle-weighted normal (not unit) */
	size_t ng;
};

/*
 * Pair the corners across each edge: two triangles at an edge pair up, at
 * an edge with more the straight continuations do (pair_straight).
 */
static void pair_edges(struct sheet *s, struct sheet_edge *edges)
{
	const size_t nc = 3 * s->n;

	for (uint32_t i = 0; i < s->n; i++)
		for (int k = 0; k < 3; k++) {
			const uint32_t a = s->tris[s->list[i]][k], b = s->tris[s->list[i]][(k + 1) % 3];
			edges[3 * i + k].lo = a < b ? a : b;
			edges[3 * i + k].hi = a < b ? b : a;
			edges[3 * i + k].corner = 3 * i + (uint32_t)k;
		}
	qsort(edges, nc, sizeof(*edges), compare_sheet_edge);
	for (size_t c = 0; c < nc; c++)
		s->mate[c] = UINT32_MAX;
	for (size_t e = 0; e < nc;) {
		size_t f = e + 1;
		while (f < nc && edges[f].lo == edges[e].lo && edges[f].hi == edges[e].hi)
			f++;
		if (f - e == 2) {
			s->mate[edges[e].corner] = edges[e + 1].corner;
			s->mate[edges[e + 1].corner] = edges[e].corner;
		} else if (f - e > 2) {
			pair_straight(s->verts, s->tris, s->list, edges + e, f - e, s->mate);
		}
		e = f;
	}
}

/*
 * Orient by breadth-first search across paired edges and join the pairs
 * that bend less than CREASE_DEGREES.  Where two joined triangles disagree
 * once oriented (no orientation exists) the join swaps sides instead.
 */
static void orient_and_join(struct sheet *s, uint32_t *queue, uint8_t *seen)
{
	for (uint32_t t = 0; t < s->n; t++) {
		size_t head = 0, tail = 0;
		if (seen[t])
			continue;
		seen[t] = 1;
		queue[tail++] = t;
		while (head < tail) {
			const uint32_t i = queue[head++];
			for (int k = 0; k < 3; k++) {
				const uint32_t m = s->mate[3 * i + (uint32_t)k];
				if (m == UINT32_MAX)
					continue;
				const uint32_t j = m / 3;
				/* Same direction along the edge in the original
				 * order means opposite orientations. */
				const bool same = s->tris[s->list[i]][k] == s->tris[s->list[j]][m % 3];
				const uint8_t want = (uint8_t)(s->flip[i] ^ same);
				if (!seen[j]) {
					seen[j] = 1;
					s->flip[j] = want;
					queue[tail++] = j;
				}
				if (!is_crease(s->verts, s->tris, s->list, s->flip, i, j, want)) {
					s->joined[3 * i + (uint32_t)k] = 1;
					s->joined[m] = 1;
				}
			}
		}
	}
}

/* Oriented unit normal of listed triangle i, or false when it has none. */
static bool oriented_normal(const struct sheet *s, uint32_t i, double nn[3])
{
	return unit_normal(s->verts, s->tris, s->list, i, s->flip[i], nn);
}

/*
 * Fans: corners of one vertex joined across joined edges share a fan, so a
 * cut or non-manifold vertex has one per side of the cut.  Then each fan's
 * angle-weighted normal, with the side parity of each corner.
 */
static void group_fans(struct sheet *s)
{
	const uint32_t nc = (uint32_t)(3 * s->n);

	for (uint32_t c = 0; c < nc; c++) {
		s->group[c] = c;
		s->gpar[c] = 0;
	}
	for (uint32_t c = 0; c < nc; c++) {
		if (!s->joined[c])
			continue;
		const uint32_t i = c / 3, k = c % 3, m = s->mate[c], j = m / 3, l = m % 3;
		const uint32_t a = s->tris[s->list[i]][k], b = s->tris[s->list[i]][(k + 1) % 3];
		/* Corner of j holding a, and the one holding b. */
		const uint32_t ja = s->tris[s->list[j]][l] == a ? l : (l + 1) % 3;
		const uint32_t jb = s->tris[s->list[j]][l] == b ? l : (l + 1) % 3;
		const uint8_t rev = s->flip[i] ^ s->flip[j] ^
				    (uint8_t)(s->tris[s->list[i]][k] == s->tris[s->list[j]][l]);
		join(s->group, s->gpar, 3 * i + k, 3 * j + ja, rev);
		join(s->group, s->gpar, 3 * i + (k + 1) % 3, 3 * j + jb, rev);
	}
	s->ng = 0;
	for (uint32_t c = 0; c < nc; c++)
		s->gid[c] = UINT32_MAX;
	for (uint32_t c = 0; c < nc; c++) {
		uint8_t p;
		const uint32_t r = find(s->group, s->gpar, c, &p);
		if (s->gid[r] == UINT32_MAX)
			s->gid[r] = (uint32_t)s->ng++;
		s->gid[c] = s->gid[r];
		s->side[c] = p;
	}
	memset(s->gnorm, 0, s->ng * sizeof(*s->gnorm));
	for (uint32_t i = 0; i < s->n; i++) {
		double nn[3];
		if (!oriented_normal(s, i, nn))
			continue;
		for (int k = 0; k < 3; k++) {
			const double *o = s->verts[s->tris[s->list[i]][k]];
			const double *a = s->verts[s->tris[s->list[i]][(k + 1) % 3]];
			const double *b = s->verts[s->tris[s->list[i]][(k + 2) % 3]];
			const double e1[3] = {a[0] - o[0], a[1] - o[1], a[2] - o[2]};
			const double e2[3] = {b[0] - o[0], b[1] - o[1], b[2] - o[2]};
			const double d = e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2];
			const double l1 = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
			const double l2 = sqrt(e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2]);
			double cosv = d / (l1 * l2);
			cosv = cosv > 1 ? 1 : cosv < -1 ? -1 : cosv;
			const double w = acos(cosv);
			const double sign = s->side[3 * i + (uint32_t)k] ? -1 : 1;
			for (int j = 0; j < 3; j++)
				s->gnorm[s->gid[3 * i + (uint32_t)k]][j] += sign * w * nn[j];
		}
	}
}

/* Cut both edges of listed triangle i at its corner k (both sides). */
static void cut_corner(struct sheet *s, uint32_t i, int k)
{
	const uint32_t out = 3 * i + (uint32_t)k, in = 3 * i + (uint32_t)(k + 2) % 3;

	if (s->joined[out]) {
		s->joined[out] = 0;
		s->joined[s->mate[out]] = 0;
	}
	if (s->joined[in]) {
		s->joined[in] = 0;
		s->joined[s->mate[in]] = 0;
	}
}

/* A fan's unit normal into u; false (u = +z) for a fan without direction. */
static bool fan_unit_normal(const struct sheet *s, uint32_t g, double u[3])
{
	const double *f = s->gnorm[g];
	const double l = sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);

	if (!(l > 0)) {
		u[0] = u[1] = 0;
		u[2] = 1;
		return false;
	}
	for (int k = 0; k < 3; k++)
		u[k] = f[k] / l;
	return true;
}

/*
 * Cut the edges around every fan whose normal leans more than FAN_DEGREES
 * from one of its triangles (or has no direction).  Returns how many fans
 * were cut; a fan of one corner is never cut (its normal is its own).
 */
static size_t cut_leaning_fans(struct sheet *s, uint8_t *bad)
{
	const double min_cos = cos(FAN_DEGREES * M_PI / 180);
	size_t nbad = 0;

	memset(bad, 0, s->ng);
	for (uint32_t i = 0; i < s->n; i++) {
		double nn[3];
		const bool has = oriented_normal(s, i, nn);
		for (int k = 0; k < 3; k++) {
			const uint32_t c = 3 * i + (uint32_t)k, g = s->gid[c];
			double u[3];
			const bool dir = fan_unit_normal(s, g, u);
			const double sign = s->side[c] ? -1 : 1;
			const double d =
				has && dir ? sign * (u[0] * nn[0] + u[1] * nn[1] + u[2] * nn[2]) : -1;
			if (!(d >= min_cos))
				bad[g] = 1;
		}
	}
	for (uint32_t i = 0; i < s->n; i++)
		for (int k = 0; k < 3; k++) {
			const uint32_t c = 3 * i + (uint32_t)k;
			if (!bad[s->gid[c]])
				continue;
			cut_corner(s, i, k);
			nbad++;
		}
	return nbad;
}

/*
 * Write the slab: per fan a copy on each side (2g on the normal's side,
 * 2g+1 on the other), per triangle its two offset copies, per cut or
 * boundary edge a wall through the sheet's own edge.
 */
static int emit_slab(const struct sheet *s, double half, struct thick_out *out,
		     struct st_error *err)
{
	const size_t n = s->n;
	uint32_t *uv = malloc((3 * n + 1) * sizeof(*uv));
	uint32_t *sidx = malloc((3 * n + 1) * sizeof(*sidx));
	uint8_t *through = calloc(3 * n + 1, 1);
	size_t nu = 0;

	/* Copies: two per fan, plus the sheet's own vertices on the walls;
	 * triangles: two per triangle, four per wall (at most one a corner). */
	out->verts = malloc((2 * s->ng + 3 * n + 1) * sizeof(*out->verts));
	out->sheet_ref = malloc((2 * s->ng + 3 * n + 1) * sizeof(*out->sheet_ref));
	out->tris = malloc((14 * n + 1) * sizeof(*out->tris));
	if (!out->verts || !out->sheet_ref || !out->tris || !uv || !sidx || !through) {
		free(uv);
		free(sidx);
		free(through);
		return st_error_set(err, ST_ERR_NOMEM, "out of memory thickening %zu sheet triangles",
				    n);
	}
	for (uint32_t c = 0; c < 3 * n; c++) {
		const uint32_t g = s->gid[c];
		const double *p = s->verts[s->tris[s->list[c / 3]][c % 3]];
		double u[3];
		fan_unit_normal(s, g, u);
		for (int j = 0; j < 3; j++) {
			out->verts[2 * g][j] = p[j] + half * u[j];
			out->verts[2 * g + 1][j] = p[j] - half * u[j];
		}
	}
	out->nverts = 2 * s->ng;
	for (size_t v = 0; v < out->nverts; v++)
		out->sheet_ref[v] = UINT32_MAX;
	for (uint32_t c = 0; c < 3 * n; c++)
		uv[c] = s->tris[s->list[c / 3]][c % 3];
	qsort(uv, 3 * n, sizeof(*uv), compare_u32);
	for (size_t c = 0; c < 3 * n; c++)
		if (nu == 0 || uv[nu - 1] != uv[c])
			uv[nu++] = uv[c];
	for (size_t i = 0; i < nu; i++)
		sidx[i] = UINT32_MAX;
	/* Sheet vertices where some wall must hold the sheet's own edge. */
	for (uint32_t c = 0; c < 3 * n; c++) {
		const uint32_t i = c / 3, k = c % 3;
		if (s->joined[c] || (s->free_edges && (s->free_edges[i] >> k & 1)))
			continue;
		through[sheet_index(uv, nu, s->tris[s->list[i]][k])] = 1;
		through[sheet_index(uv, nu, s->tris[s->list[i]][(k + 1) % 3])] = 1;
	}
	/* copy(c, 0) lies on the side triangle c/3's normal points to (as
	 * oriented), copy(c, 1) on the other: parity maps that to the fan's
	 * own two copies. */
#define COPY(c, sd) (2 * s->gid[(c)] + (uint32_t)(s->side[(c)] ^ (sd)))
	for (uint32_t i = 0; i < n; i++) {
		uint32_t cs[3]; /* corner ids by oriented slot */
		for (int k = 0; k < 3; k++)
			cs[oriented_slot(s->flip, i, k)] = 3 * i + (uint32_t)k;
		const uint32_t top[3] = {COPY(cs[0], 0), COPY(cs[1], 0), COPY(cs[2], 0)};
		const uint32_t bot[3] = {COPY(cs[0], 1), COPY(cs[2], 1), COPY(cs[1], 1)};
		memcpy(out->tris[out->ntris++], top, sizeof(top));
		memcpy(out->tris[out->ntris++], bot, sizeof(bot));
		for (int k = 0; k < 3; k++) {
			if (s->joined[3 * i + (uint32_t)k])
				continue;
			const int s0 = oriented_slot(s->flip, i, k);
			const int s1 = oriented_slot(s->flip, i, (k + 1) % 3);
			/* As oriented the edge runs a -> b. */
			uint32_t a = cs[s0], b = cs[s1];
			if ((s0 + 1) % 3 != s1) {
				const uint32_t t = a;
				a = b;
				b = t;
			}
			/* The wall holds the sheet's own edge a b: walls of
			 * several fans meet exactly there instead of crossing
			 * each other within rounding of it, and where the
			 * sheet meets other triangles, the wall meets them
			 * exactly too.  At a vertex whose walls all run along
			 * edges that touch nothing, it goes straight from one
			 * copy to the other (every wall at that vertex alike,
			 * so their upright edges still match). */
			const uint32_t va = s->tris[s->list[a / 3]][a % 3];
			const uint32_t vb = s->tris[s->list[b / 3]][b % 3];
			const bool ta = through[sheet_index(uv, nu, va)];
			const bool tb = through[sheet_index(uv, nu, vb)];
			const uint32_t a0 = COPY(a, 0), a1 = COPY(a, 1), b0 = COPY(b, 0),
				       b1 = COPY(b, 1);
			const uint32_t pa = ta ? sheet_vertex(out, uv, nu, sidx, s->verts, va) : 0;
			const uint32_t pb = tb ? sheet_vertex(out, uv, nu, sidx, s->verts, vb) : 0;
			if (ta && tb) {
				const uint32_t w[4][3] = {
				    {b0, a0, pa}, {b0, pa, pb}, {pb, pa, a1}, {pb, a1, b1}};
				memcpy(out->tris[out->ntris], w, sizeof(w));
				out->ntris += 4;
			} else if (ta) {
				const uint32_t w[3][3] = {{b0, a0, pa}, {b0, pa, a1}, {b0, a1, b1}};
				memcpy(out->tris[out->ntris], w, sizeof(w));
				out->ntris += 3;
			} else if (tb) {
				/* Fanned from a0, off the line b0 pb b1. */
				const uint32_t w[3][3] = {{a0, a1, b1}, {a0, b1, pb}, {a0, pb, b0}};
				memcpy(out->tris[out->ntris], w, sizeof(w));
				out->ntris += 3;
			} else {
				const uint32_t w[2][3] = {{b0, a0, a1}, {b0, a1, b1}};
				memcpy(out->tris[out->ntris], w, sizeof(w));
				out->ntris += 2;
			}
		}
	}
#undef COPY
	free(uv);
	free(sidx);
	free(through);
	return 0;
}

int thicken_sheets(const double (*verts)[3], const uint32_t (*tris)[3], const uint32_t *list,
		   const uint8_t *free_edges, size_t n, double half, double weld,
		   struct thick_out *out, struct st_error *err)
{
	struct sheet s = {.verts = verts, .tris = tris, .list = list, .free_edges = free_edges,
			  .n = n};
	struct sheet_edge *edges = malloc((3 * n + 1) * sizeof(*edges));
	uint8_t *seen = calloc(n + 1, 1), *bad = malloc(3 * n + 1);
	uint32_t *queue = malloc((n + 1) * sizeof(*queue));
	int rc = 0;

	memset(out, 0, sizeof(*out));
	s.flip = calloc(n + 1, 1);
	s.joined = calloc(3 * n + 1, 1);
	s.mate = malloc((3 * n + 1) * sizeof(*s.mate));
	s.group = malloc((3 * n + 1) * sizeof(*s.group));
	s.gpar = malloc(3 * n + 1);
	s.gid = malloc((3 * n + 1) * sizeof(*s.gid));
	s.side = malloc(3 * n + 1);
	s.gnorm = malloc((3 * n + 1) * sizeof(*s.gnorm));
	if (!edges || !seen || !bad || !queue || !s.flip || !s.joined || !s.mate || !s.group ||
	    !s.gpar || !s.gid || !s.side || !s.gnorm) {
		rc = st_error_set(err, ST_ERR_NOMEM, "out of memory thickening %zu sheet triangles",
				  n);
		goto out;
	}
	pair_edges(&s, edges);
	orient_and_join(&s, queue, seen);
	/* Each round cuts at least one joined edge, so this ends (at worst
	 * with every triangle a prism of its own). */
	do
		group_fans(&s);
	while (cut_leaning_fans(&s, bad));
	rc = emit_slab(&s, half, out, err);
	if (!rc)
		rc = weld_close(out, weld, err);
	if (rc)
		goto out;
	/* Every copy is exactly half from its vertex (up to rounding). */
	for (uint32_t c = 0; c < 3 * n; c++) {
		const double *p = verts[tris[list[c / 3]][c % 3]];
		for (int sd = 0; sd < 2; sd++) {
			const double *q = out->verts[2 * s.gid[c] + (uint32_t)sd];
			out->deviation = fmax(out->deviation, vec3_dist(p, q));
		}
	}
	for (uint32_t c = 0; c < 3 * n; c++)
		out->cut_edges += !s.joined[c] && s.mate[c] != UINT32_MAX;
	out->cut_edges /= 2;
out:
	if (rc) {
		free(out->verts);
		free(out->sheet_ref);
		free(out->tris);
		memset(out, 0, sizeof(*out));
	}
	free(edges);
	free(seen);
	free(bad);
	free(queue);
	free(s.flip);
	free(s.joined);
	free(s.mate);
	free(s.group);
	free(s.gpar);
	free(s.gid);
	free(s.side);
	free(s.gnorm);
	return rc;
}
