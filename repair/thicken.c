/*
 * thicken.c - seed 000 §4.2.1: turn M_sheet into thin closed solids.
 *
 * As the paper does: orient each sheet (cutting it where it cannot be
 * oriented), make a copy on each side at distance half = epsilon/2 along
 * the vertex normals, and stitch the two copies along every boundary and
 * cut with a wall.  Where sheets cross (edges with more than two sheet
 * triangles) each sheet is continued straight through; where a sheet bends
 * sharply the two sides keep their own copies, joined by a bevel, and the
 * small holes left at such corners are closed by fans.  Every point of the result is a convex combination of points at
 * distance half from a point of the sheet, so it lies within half of the
 * sheet: the deviation bound holds by construction.  Folds and overlaps
 * the offset makes are resolved exactly by the repair's second pass, which
 * treats the slabs like any other input.  Doubles only: nothing here
 * decides anything.
 */
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "ids.h"
#include "thicken.h"

/* Bends sharper than this keep separate vertex copies on each side. */
#define CREASE_DEGREES 30.0

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

/* Corner k of listed triangle i as oriented (flip reverses it). */
static uint32_t corner_vertex(const uint32_t (*tris)[3], const uint32_t *list, const uint8_t *flip,
			      uint32_t i, int k)
{
	static const int rev[3] = {0, 2, 1};

	return tris[list[i]][flip[i] ? rev[k] : k];
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
static uint32_t sheet_vertex(struct thick_out *out, const uint32_t *uv, size_t nu, uint32_t *sidx,
			     const double (*verts)[3], uint32_t v)
{
	const uint32_t *hit = bsearch(&v, uv, nu, sizeof(*uv), compare_u32);
	const size_t i = (size_t)(hit - uv);

	if (sidx[i] == UINT32_MAX) {
		memcpy(out->verts[out->nverts], verts[v], sizeof(out->verts[0]));
		out->sheet_ref[out->nverts] = v;
		sidx[i] = (uint32_t)out->nverts++;
	}
	return sidx[i];
}

struct half_edge {
	uint32_t from, to;
};

static int compare_half_edge(const void *a, const void *b)
{
	const struct half_edge *x = a, *y = b;

	if (x->from != y->from)
		return x->from < y->from ? -1 : 1;
	return x->to < y->to ? -1 : x->to > y->to;
}

/* Whether sorted array h (n entries) holds from -> to. */
static bool has_half_edge(const struct half_edge *h, size_t n, uint32_t from, uint32_t to)
{
	size_t lo = 0, hi = n;

	while (lo < hi) {
		const size_t mid = lo + (hi - lo) / 2;
		if (h[mid].from < from || (h[mid].from == from && h[mid].to < to))
			lo = mid + 1;
		else
			hi = mid;
	}
	return lo < n && h[lo].from == from && h[lo].to == to;
}

/*
 * Close the holes left where bevels and walls meet around a vertex: every
 * half-edge without its twin starts a loop of copies of one vertex, closed
 * by a fan (within half of that vertex like the copies themselves).
 */
static int fill_corner_holes(struct thick_out *out, size_t cap, struct st_error *err)
{
	const size_t nh = 3 * out->ntris;
	struct half_edge *h = malloc((nh + 1) * sizeof(*h));
	uint32_t *next = malloc((out->nverts + 1) * sizeof(*next));
	size_t nfill = 0;

	if (!h || !next) {
		free(h);
		free(next);
		return st_error_set(err, ST_ERR_NOMEM, "out of memory closing slab corners");
	}
	for (size_t t = 0; t < out->ntris; t++)
		for (int k = 0; k < 3; k++) {
			h[3 * t + (size_t)k].from = out->tris[t][k];
			h[3 * t + (size_t)k].to = out->tris[t][(k + 1) % 3];
		}
	qsort(h, nh, sizeof(*h), compare_half_edge);
	for (size_t v = 0; v < out->nverts; v++)
		next[v] = UINT32_MAX;
	for (size_t i = 0; i < nh; i++)
		if (!has_half_edge(h, nh, h[i].to, h[i].from)) {
			/* The fill runs this edge backwards: to -> from. */
			next[h[i].to] = h[i].from;
			nfill++;
		}
	free(h);
	/* Each loop of k edges takes k - 2 triangles; the caller sized the
	 * array for them (at most one loop edge per bevel or wall side). */
	for (size_t v = 0; v < out->nverts; v++) {
		if (next[v] == UINT32_MAX)
			continue;
		const uint32_t first = (uint32_t)v;
		uint32_t prev = next[first], steps = 0;
		next[first] = UINT32_MAX;
		while (prev != UINT32_MAX && prev != first && steps++ < nfill) {
			const uint32_t cur = next[prev];
			next[prev] = UINT32_MAX;
			if (cur == UINT32_MAX || cur == first)
				break;
			const uint32_t t[3] = {first, prev, cur};
			if (out->ntris >= cap) {
				free(next);
				return st_error_set(err, ST_ERR_INTERNAL,
						    "thickening: corner fans need more than the "
						    "%zu triangles reserved", cap);
			}
			memcpy(out->tris[out->ntris++], t, sizeof(t));
			prev = cur;
		}
	}
	free(next);
	return 0;
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

int thicken_sheets(const double (*verts)[3], const uint32_t (*tris)[3], const uint32_t *list,
		   size_t n, double half, double weld, struct thick_out *out, struct st_error *err)
{
	struct sheet_edge *edges = malloc((3 * n + 1) * sizeof(*edges));
	uint8_t *flip = calloc(n + 1, 1), *seen = calloc(n + 1, 1);
	uint8_t *joined = calloc(3 * n + 1, 1); /* [corner] edge is joined */
	uint8_t *crease = calloc(3 * n + 1, 1); /* [corner] joined by a bevel */
	uint32_t *mate = malloc((3 * n + 1) * sizeof(*mate)); /* [corner] other corner */
	uint32_t *queue = malloc((n + 1) * sizeof(*queue));
	uint32_t *group = malloc((3 * n + 1) * sizeof(*group));
	uint32_t *gid = malloc((3 * n + 1) * sizeof(*gid));
	uint8_t *gpar = malloc(3 * n + 1), *side = malloc(3 * n + 1);
	uint32_t *uv = NULL, *sidx = NULL; /* sheet vertices, sorted; their slab copies */
	size_t nu = 0;
	double (*gnorm)[3] = calloc(3 * n + 1, sizeof(*gnorm));
	size_t ng = 0;
	int rc = 0;

	memset(out, 0, sizeof(*out));
	if (!edges || !flip || !seen || !joined || !crease || !mate || !queue || !group || !gid ||
	    !gnorm || !gpar || !side) {
		rc = st_error_set(err, ST_ERR_NOMEM, "out of memory thickening %zu sheet triangles",
				  n);
		goto out;
	}

	/* Edges of the sheet; an edge with exactly two sheet triangles can
	 * join them, any other is a boundary of the slab. */
	for (uint32_t i = 0; i < n; i++)
		for (int k = 0; k < 3; k++) {
			uint32_t a = tris[list[i]][k], b = tris[list[i]][(k + 1) % 3];
			edges[3 * i + k].lo = a < b ? a : b;
			edges[3 * i + k].hi = a < b ? b : a;
			edges[3 * i + k].corner = 3 * i + (uint32_t)k;
		}
	qsort(edges, 3 * n, sizeof(*edges), compare_sheet_edge);
	for (size_t c = 0; c < 3 * n; c++)
		mate[c] = UINT32_MAX;
	for (size_t e = 0; e < 3 * n;) {
		size_t f = e + 1;
		while (f < 3 * n && edges[f].lo == edges[e].lo && edges[f].hi == edges[e].hi)
			f++;
		if (f - e == 2) {
			mate[edges[e].corner] = edges[e + 1].corner;
			mate[edges[e + 1].corner] = edges[e].corner;
		} else if (f - e > 2) {
			pair_straight(verts, tris, list, edges + e, f - e, mate);
		}
		e = f;
	}

	/* Orient by breadth-first search across two-triangle edges; an edge
	 * whose two triangles disagree once oriented is cut (this is what
	 * makes a Moebius strip or Klein bottle orientable). */
	for (uint32_t s = 0; s < n; s++) {
		size_t head = 0, tail = 0;
		if (seen[s])
			continue;
		seen[s] = 1;
		queue[tail++] = s;
		while (head < tail) {
			const uint32_t i = queue[head++];
			for (int k = 0; k < 3; k++) {
				const uint32_t m = mate[3 * i + (uint32_t)k];
				if (m == UINT32_MAX)
					continue;
				const uint32_t j = m / 3;
				/* Same direction along the edge in the original
				 * order means opposite orientations. */
				const bool same = tris[list[i]][k] == tris[list[j]][m % 3];
				const uint8_t want = (uint8_t)(flip[i] ^ same);
				if (!seen[j]) {
					seen[j] = 1;
					flip[j] = want;
					queue[tail++] = j;
				}
				if (is_crease(verts, tris, list, flip, i, j, want)) {
					if (flip[j] != want)
						continue; /* cut: walls on both sides */
					crease[3 * i + (uint32_t)k] = 1;
					crease[m] = 1;
				} else {
					/* Straight on: joined, reversed when the
					 * orientations conflict (Moebius). */
					joined[3 * i + (uint32_t)k] = 1;
					joined[m] = 1;
				}
			}
		}
	}

	/* Vertex copies: corners of one vertex joined across joined edges
	 * share a copy, so a cut or non-manifold vertex gets one per fan. */
	for (uint32_t c = 0; c < 3 * n; c++) {
		group[c] = c;
		gpar[c] = 0;
	}
	for (uint32_t c = 0; c < 3 * n; c++) {
		if (!joined[c])
			continue;
		const uint32_t i = c / 3, k = c % 3, m = mate[c], j = m / 3, l = m % 3;
		const uint32_t a = tris[list[i]][k], b = tris[list[i]][(k + 1) % 3];
		/* Corner of j holding a, and the one holding b. */
		const uint32_t ja = tris[list[j]][l] == a ? l : (l + 1) % 3;
		const uint32_t jb = tris[list[j]][l] == b ? l : (l + 1) % 3;
		const uint8_t rev = flip[i] ^ flip[j] ^ (uint8_t)(tris[list[i]][k] == tris[list[j]][l]);
		join(group, gpar, 3 * i + k, 3 * j + ja, rev);
		join(group, gpar, 3 * i + (k + 1) % 3, 3 * j + jb, rev);
	}
	for (uint32_t c = 0; c < 3 * n; c++)
		gid[c] = UINT32_MAX;
	for (uint32_t c = 0; c < 3 * n; c++) {
		uint8_t p;
		const uint32_t r = find(group, gpar, c, &p);
		if (gid[r] == UINT32_MAX)
			gid[r] = (uint32_t)ng++;
		gid[c] = gid[r];
		side[c] = p;
	}

	/* Angle-weighted normal of each copy, from its fan as oriented. */
	for (uint32_t i = 0; i < n; i++) {
		const double *p[3];
		for (int k = 0; k < 3; k++)
			p[k] = verts[corner_vertex(tris, list, flip, i, k)];
		const double u[3] = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
		const double v[3] = {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
		double nn[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
				u[0] * v[1] - u[1] * v[0]};
		const double l = sqrt(nn[0] * nn[0] + nn[1] * nn[1] + nn[2] * nn[2]);
		if (!(l > 0))
			continue;
		for (int k = 0; k < 3; k++) {
			const int s = oriented_slot(flip, i, k);
			const double *o = p[s], *a = p[(s + 1) % 3], *b = p[(s + 2) % 3];
			const double e1[3] = {a[0] - o[0], a[1] - o[1], a[2] - o[2]};
			const double e2[3] = {b[0] - o[0], b[1] - o[1], b[2] - o[2]};
			const double d = e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2];
			const double l1 = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
			const double l2 = sqrt(e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2]);
			double cosv = d / (l1 * l2);
			cosv = cosv > 1 ? 1 : cosv < -1 ? -1 : cosv;
			const double w = acos(cosv);
			const double sign = side[3 * i + (uint32_t)k] ? -1 : 1;
			for (int j = 0; j < 3; j++)
				gnorm[gid[3 * i + (uint32_t)k]][j] += sign * w * nn[j] / l;
		}
	}

	/* Room for: two copies per group; per triangle top and bottom, and
	 * per corner a wall or half a bevel (two faces each) plus the fans
	 * that close corners (fewer faces than the edges they close). */
	out->verts = malloc((2 * ng + 3 * n + 1) * sizeof(*out->verts));
	out->sheet_ref = malloc((2 * ng + 3 * n + 1) * sizeof(*out->sheet_ref));
	out->tris = malloc((32 * n + 1) * sizeof(*out->tris));
	uv = malloc((3 * n + 1) * sizeof(*uv));
	sidx = malloc((3 * n + 1) * sizeof(*sidx));
	if (!out->verts || !out->sheet_ref || !out->tris || !uv || !sidx) {
		rc = st_error_set(err, ST_ERR_NOMEM, "out of memory thickening %zu sheet triangles",
				  n);
		goto out;
	}
	/* Copies: 2g on the normal's side, 2g+1 on the other. */
	for (uint32_t c = 0; c < 3 * n; c++) {
		const uint32_t g = gid[c];
		const double *p = verts[tris[list[c / 3]][c % 3]];
		double *nn = gnorm[g];
		double l = sqrt(nn[0] * nn[0] + nn[1] * nn[1] + nn[2] * nn[2]);
		if (!(l > 0)) {
			nn[0] = 0; /* a fan whose normals cancel: any direction */
			nn[1] = 0;
			nn[2] = 1;
			l = 1;
		}
		for (int j = 0; j < 3; j++) {
			out->verts[2 * g][j] = p[j] + half * nn[j] / l;
			out->verts[2 * g + 1][j] = p[j] - half * nn[j] / l;
		}
	}
	out->nverts = 2 * ng;
	for (size_t v = 0; v < out->nverts; v++)
		out->sheet_ref[v] = UINT32_MAX;
	for (uint32_t c = 0; c < 3 * n; c++)
		uv[c] = tris[list[c / 3]][c % 3];
	qsort(uv, 3 * n, sizeof(*uv), compare_u32);
	for (size_t c = 0; c < 3 * n; c++)
		if (nu == 0 || uv[nu - 1] != uv[c])
			uv[nu++] = uv[c];
	for (size_t i = 0; i < nu; i++)
		sidx[i] = UINT32_MAX;
	/* copy(c, 0) lies on the side triangle c/3's normal points to (as
	 * oriented), copy(c, 1) on the other: parity maps that to the group's
	 * own two copies. */
#define COPY(c, s) (2 * gid[(c)] + (uint32_t)(side[(c)] ^ (s)))
	for (uint32_t i = 0; i < n; i++) {
		uint32_t cs[3]; /* corner ids by oriented slot */
		for (int k = 0; k < 3; k++)
			cs[oriented_slot(flip, i, k)] = 3 * i + (uint32_t)k;
		const uint32_t top[3] = {COPY(cs[0], 0), COPY(cs[1], 0), COPY(cs[2], 0)};
		const uint32_t bot[3] = {COPY(cs[0], 1), COPY(cs[2], 1), COPY(cs[1], 1)};
		memcpy(out->tris[out->ntris++], top, sizeof(top));
		memcpy(out->tris[out->ntris++], bot, sizeof(bot));
		/* A wall along every edge that neither joins nor bevels. */
		for (int k = 0; k < 3; k++) {
			if (joined[3 * i + (uint32_t)k] || crease[3 * i + (uint32_t)k])
				continue;
			const int s0 = oriented_slot(flip, i, k), s1 = oriented_slot(flip, i, (k + 1) % 3);
			/* As oriented the edge runs a -> b. */
			uint32_t a = cs[s0], b = cs[s1];
			if ((s0 + 1) % 3 != s1) {
				const uint32_t t = a;
				a = b;
				b = t;
			}
			/* The wall holds the sheet's own edge a b: walls of
			 * several fans meet exactly there instead of crossing
			 * each other within rounding of it. */
			const uint32_t pa = sheet_vertex(out, uv, nu, sidx, verts, tris[list[a / 3]][a % 3]);
			const uint32_t pb = sheet_vertex(out, uv, nu, sidx, verts, tris[list[b / 3]][b % 3]);
			const uint32_t w[4][3] = {{COPY(b, 0), COPY(a, 0), pa},
						  {COPY(b, 0), pa, pb},
						  {pb, pa, COPY(a, 1)},
						  {pb, COPY(a, 1), COPY(b, 1)}};
			memcpy(out->tris[out->ntris], w, sizeof(w));
			out->ntris += 4;
		}
	}
	/* Bevels along creases (always between consistently oriented
	 * triangles): on each side, the quad between the two triangles'
	 * copies of the edge. */
	for (uint32_t c = 0; c < 3 * n; c++) {
		const uint32_t m = mate[c];
		if (!crease[c] || c > m)
			continue;
		const uint32_t i = c / 3, k = c % 3, j = m / 3, l = m % 3;
		const uint32_t a = tris[list[i]][k];
		const uint32_t ja = tris[list[j]][l] == a ? l : (l + 1) % 3;
		const uint32_t jb = ja == l ? (l + 1) % 3 : l;
		const uint32_t ia = 3 * i + k, ib = 3 * i + (k + 1) % 3;
		const uint32_t ga = 3 * j + ja, gb = 3 * j + jb;
		/* Make i run the edge a -> b as oriented. */
		const int s0 = oriented_slot(flip, i, (int)k), s1 = oriented_slot(flip, i, (int)(k + 1) % 3);
		const bool forward = (s0 + 1) % 3 == s1;
		const uint32_t xa = forward ? ia : ib, xb = forward ? ib : ia;
		const uint32_t ya = forward ? ga : gb, yb = forward ? gb : ga;
		/* i's top runs xa -> xb, j's top yb -> ya; the bevel runs
		 * each the other way.  The bottom side mirrors it. */
		const uint32_t t1[3] = {COPY(xb, 0), COPY(xa, 0), COPY(ya, 0)};
		const uint32_t t2[3] = {COPY(xb, 0), COPY(ya, 0), COPY(yb, 0)};
		const uint32_t b1[3] = {COPY(xa, 1), COPY(xb, 1), COPY(yb, 1)};
		const uint32_t b2[3] = {COPY(xa, 1), COPY(yb, 1), COPY(ya, 1)};
		memcpy(out->tris[out->ntris++], t1, sizeof(t1));
		memcpy(out->tris[out->ntris++], t2, sizeof(t2));
		memcpy(out->tris[out->ntris++], b1, sizeof(b1));
		memcpy(out->tris[out->ntris++], b2, sizeof(b2));
	}
#undef COPY
	rc = fill_corner_holes(out, 32 * n, err);
	if (!rc)
		rc = weld_close(out, weld, err);
	if (rc)
		goto out;
	/* Every copy is exactly half from its vertex (up to rounding). */
	for (uint32_t c = 0; c < 3 * n; c++) {
		const double *p = verts[tris[list[c / 3]][c % 3]];
		for (int s = 0; s < 2; s++) {
			const double *q = out->verts[2 * gid[c] + (uint32_t)s];
			const double d = sqrt((p[0] - q[0]) * (p[0] - q[0]) +
					      (p[1] - q[1]) * (p[1] - q[1]) +
					      (p[2] - q[2]) * (p[2] - q[2]));
			out->deviation = fmax(out->deviation, d);
		}
	}
	for (uint32_t c = 0; c < 3 * n; c++)
		out->cut_edges += !joined[c] && !crease[c] && mate[c] != UINT32_MAX;
	out->cut_edges /= 2;
out:
	if (rc) {
		free(out->verts);
		free(out->sheet_ref);
		free(out->tris);
		memset(out, 0, sizeof(*out));
	}
	free(edges);
	free(flip);
	free(seen);
	free(joined);
	free(crease);
	free(mate);
	free(queue);
	free(group);
	free(gid);
	free(gpar);
	free(side);
	free(uv);
	free(sidx);
	free(gnorm);
	return rc;
}
