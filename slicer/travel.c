/*
 * travel.c - routing travels inside a layer's region (see travel.h).
 *
 * The map keeps two kinds of closed polygons in one point array: the
 * region's walls (what a travel must not cross) and the routing boundary
 * (the region inset, what routes follow).  Edge i runs from point i to the
 * next point of its polygon.  Every edge is listed in the grid cells its
 * bounding box covers; a query marks the edges it has seen with a stamp so
 * an edge in several cells is tested once.
 */
#include "travel.h"
#include "st_grow.h"
#include "toolpath.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define GRID_MAX 512	     /* most cells along an axis */

struct tpoly {
	size_t start, n; /* points start .. start + n - 1 */
	int island;	 /* expolygon of the region it belongs to, -1 none */
	bool wall;	 /* a wall of the region; else a routing boundary */
};

/* Where a segment meets a boundary polygon. */
struct hit {
	double t;      /* 0..1 along the segment */
	size_t poly;   /* polygon */
	size_t edge;   /* global edge index */
	int64_t x, y;  /* the point, nm */
};

struct travel_map {
	size_t npolys, npts;
	struct tpoly *polys;
	int64_t *xy;	/* 2 * npts */
	uint32_t *epoly; /* polygon of each edge */
	/* grid */
	int64_t gx, gy, cell;
	double detour;	   /* the longest detour: nm, or percent (detour_pct); 0 = any */
	bool detour_pct;
	int nx, ny;
	uint32_t *cstart; /* nx * ny + 1 */
	uint32_t *cedge;
	uint32_t *stamp, cur;
	/* scratch */
	struct hit *hits;
	size_t nhits, hitcap;
	int64_t *chain;
	size_t nchain, chaincap;
};

/* Index of the point after global point e in its polygon. */
static size_t next_pt(const struct travel_map *m, size_t e)
{
	const struct tpoly *p = &m->polys[m->epoly[e]];
	return e + 1 == p->start + p->n ? p->start : e + 1;
}

/* Sign of the cross product (b - a) x (c - a), exact for coordinates < 2^31. */
static int orient(int64_t ax, int64_t ay, int64_t bx, int64_t by, int64_t cx, int64_t cy)
{
	long double v = (long double)(bx - ax) * (long double)(cy - ay) -
			(long double)(by - ay) * (long double)(cx - ax);
	return (v > 0) - (v < 0);
}

/* c lies within the bounding box of a-b (used when collinear). */
static bool within(int64_t ax, int64_t ay, int64_t bx, int64_t by, int64_t cx, int64_t cy)
{
	return cx >= (ax < bx ? ax : bx) && cx <= (ax > bx ? ax : bx) &&
	       cy >= (ay < by ? ay : by) && cy <= (ay > by ? ay : by);
}

/* Closed segments p-q and a-b share a point. */
static bool seg_touch(const int64_t *p, const int64_t *q, const int64_t *a, const int64_t *b)
{
	int o1 = orient(p[0], p[1], q[0], q[1], a[0], a[1]);
	int o2 = orient(p[0], p[1], q[0], q[1], b[0], b[1]);
	int o3 = orient(a[0], a[1], b[0], b[1], p[0], p[1]);
	int o4 = orient(a[0], a[1], b[0], b[1], q[0], q[1]);

	if (o1 != o2 && o3 != o4)
		return true;
	return (o1 == 0 && within(p[0], p[1], q[0], q[1], a[0], a[1])) ||
	       (o2 == 0 && within(p[0], p[1], q[0], q[1], b[0], b[1])) ||
	       (o3 == 0 && within(a[0], a[1], b[0], b[1], p[0], p[1])) ||
	       (o4 == 0 && within(a[0], a[1], b[0], b[1], q[0], q[1]));
}

/* Segments p-q and a-b cross at a point inside both. */
static bool seg_cross(const int64_t *p, const int64_t *q, const int64_t *a, const int64_t *b)
{
	return orient(p[0], p[1], q[0], q[1], a[0], a[1]) *
			       orient(p[0], p[1], q[0], q[1], b[0], b[1]) <
		       0 &&
	       orient(a[0], a[1], b[0], b[1], p[0], p[1]) *
			       orient(a[0], a[1], b[0], b[1], q[0], q[1]) <
		       0;
}

/* Grid cell coordinate of v along an axis starting at o, clamped. */
static int cell_of(const struct travel_map *m, int64_t v, int64_t o, int n)
{
	int64_t c = (v - o) / m->cell;

	if (v < o)
		return -1;
	return c >= n ? n : (int)c;
}

/* Append a polygon; xy has 2n coordinates. */
static int add_poly(struct travel_map *m, size_t *cap_polys, size_t *cap_pts, const int64_t *xy,
		    size_t n, int island, bool wall, struct st_error *err)
{
	if (n < 3)
		return 0;
	struct tpoly *g = st_grow(m->polys, cap_polys, m->npolys + 1, sizeof(*g));
	if (!g)
		return st_error_set(err, ST_ERR_NOMEM, "travel: out of memory");
	m->polys = g;
	int64_t *gxy = st_grow(m->xy, cap_pts, m->npts + n, 2 * sizeof(*gxy)); /* x, y */
	if (!gxy)
		return st_error_set(err, ST_ERR_NOMEM, "travel: out of memory");
	m->xy = gxy;
	memcpy(m->xy + 2 * m->npts, xy, 2 * n * sizeof(*xy));
	m->polys[m->npolys++] = (struct tpoly){.start = m->npts, .n = n, .island = island,
					       .wall = wall};
	m->npts += n;
	return 0;
}

/* Island of (x, y) by a ray to +x over the walls only, without the grid
 * (used while building); -1 outside. */
static int island_slow(const struct travel_map *m, int64_t x, int64_t y)
{
	int crossings = 0, island = -1;
	double best = INFINITY;

	for (size_t p = 0; p < m->npolys; p++) {
		const struct tpoly *tp = &m->polys[p];
		if (!tp->wall)
			continue;
		for (size_t k = 0; k < tp->n; k++) {
			const int64_t *a = m->xy + 2 * (tp->start + k);
			const int64_t *b = m->xy + 2 * (tp->start + (k + 1) % tp->n);
			if ((a[1] > y) == (b[1] > y))
				continue;
			double xi = a[0] + (double)(y - a[1]) * (double)(b[0] - a[0]) /
						   (double)(b[1] - a[1]);
			int o = orient(a[0], a[1], b[0], b[1], x, y);
			if ((b[1] > a[1]) ? o <= 0 : o >= 0)
				continue; /* crossing at or left of the point */
			crossings++;
			if (xi < best) {
				best = xi;
				island = tp->island;
			}
		}
	}
	return crossings % 2 ? island : -1;
}

/* Put every edge into the cells its bounding box covers. */
static int build_grid(struct travel_map *m, struct st_error *err)
{
	int64_t x0 = INT64_MAX, y0 = INT64_MAX, x1 = INT64_MIN, y1 = INT64_MIN;
	size_t total = 0, ncells;
	double side;

	for (size_t i = 0; i < m->npts; i++) {
		int64_t x = m->xy[2 * i], y = m->xy[2 * i + 1];
		x0 = x < x0 ? x : x0;
		y0 = y < y0 ? y : y0;
		x1 = x > x1 ? x : x1;
		y1 = y > y1 ? y : y1;
	}
	side = sqrt((double)(x1 - x0 + 1) * (double)(y1 - y0 + 1) / (double)m->npts);
	m->cell = (int64_t)fmax(side, fmax((double)(x1 - x0 + 1), (double)(y1 - y0 + 1)) /
					      GRID_MAX) + 1;
	m->gx = x0;
	m->gy = y0;
	m->nx = (int)((x1 - x0) / m->cell) + 1;
	m->ny = (int)((y1 - y0) / m->cell) + 1;
	ncells = (size_t)m->nx * (size_t)m->ny;
	m->cstart = calloc(ncells + 1, sizeof(*m->cstart));
	if (!m->cstart)
		return st_error_set(err, ST_ERR_NOMEM, "travel: out of memory for the grid");
	for (int pass = 0; pass < 2; pass++) {
		for (size_t e = 0; e < m->npts; e++) {
			const int64_t *a = m->xy + 2 * e, *b = m->xy + 2 * next_pt(m, e);
			int cx0 = cell_of(m, a[0] < b[0] ? a[0] : b[0], m->gx, m->nx);
			int cx1 = cell_of(m, a[0] > b[0] ? a[0] : b[0], m->gx, m->nx);
			int cy0 = cell_of(m, a[1] < b[1] ? a[1] : b[1], m->gy, m->ny);
			int cy1 = cell_of(m, a[1] > b[1] ? a[1] : b[1], m->gy, m->ny);
			for (int cy = cy0; cy <= cy1 && cy < m->ny; cy++)
				for (int cx = cx0; cx <= cx1 && cx < m->nx; cx++) {
					size_t c = (size_t)cy * (size_t)m->nx + (size_t)cx;
					if (pass == 0)
						m->cstart[c + 1]++;
					else
						m->cedge[m->cstart[c]++] = (uint32_t)e;
				}
		}
		if (pass == 0) {
			for (size_t c = 0; c < ncells; c++)
				m->cstart[c + 1] += m->cstart[c];
			total = m->cstart[ncells];
			m->cedge = malloc((total ? total : 1) * sizeof(*m->cedge));
			if (!m->cedge)
				return st_error_set(err, ST_ERR_NOMEM,
						    "travel: out of memory for the grid");
		}
	}
	/* The fill pass moved every start to the next cell's; shift back. */
	memmove(m->cstart + 1, m->cstart, ncells * sizeof(*m->cstart));
	m->cstart[0] = 0;
	m->stamp = calloc(m->npts ? m->npts : 1, sizeof(*m->stamp));
	if (!m->stamp)
		return st_error_set(err, ST_ERR_NOMEM, "travel: out of memory for the grid");
	return 0;
}

void travel_map_set_detour(struct travel_map *m, double v, bool pct)
{
	m->detour = pct ? v : v * SLICE_UNITS_PER_MM;
	m->detour_pct = pct;
}

struct travel_map *travel_map_new(const struct clip_expolys *region, int64_t inset,
				  struct st_error *err)
{
	struct travel_map *m;
	struct clip_expolys inner = {0};
	size_t cap_polys = 0, cap_pts = 0;
	int rc = 0;

	if (!region || inset <= 0) {
		st_error_set(err, ST_ERR_ARG, "travel: no region or an inset of %lld nm",
			     (long long)inset);
		return NULL;
	}
	m = calloc(1, sizeof(*m));
	if (m) {
		m->detour = TRAVEL_DETOUR_DEFAULT_PCT;
		m->detour_pct = true;
	}
	if (!m) {
		st_error_set(err, ST_ERR_NOMEM, "travel: out of memory");
		return NULL;
	}
	for (size_t i = 0; i < region->n && !rc; i++)
		for (size_t p = region->first[i]; p < region->first[i + 1] && !rc; p++)
			rc = add_poly(m, &cap_polys, &cap_pts, clip_path_xy(&region->paths, p),
				      clip_path_len(&region->paths, p), (int)i, true, err);
	if (!rc && region->n)
		rc = clip_offset_ex(&region->paths, -(double)inset, CLIP_JOIN_MITER, 3.0, 1000.0,
				    &inner, err);
	for (size_t i = 0; i < inner.n && !rc; i++) {
		const int64_t *o = clip_path_xy(&inner.paths, inner.first[i]);
		int island = island_slow(m, o[0], o[1]);
		if (island < 0)
			continue; /* offset noise outside every island */
		for (size_t p = inner.first[i]; p < inner.first[i + 1] && !rc; p++)
			rc = add_poly(m, &cap_polys, &cap_pts, clip_path_xy(&inner.paths, p),
				      clip_path_len(&inner.paths, p), island, false, err);
	}
	clip_expolys_free(&inner);
	if (!rc && m->npts) {
		m->epoly = malloc(m->npts * sizeof(*m->epoly));
		if (!m->epoly)
			rc = st_error_set(err, ST_ERR_NOMEM, "travel: out of memory");
		for (size_t p = 0; p < m->npolys && !rc; p++)
			for (size_t k = 0; k < m->polys[p].n; k++)
				m->epoly[m->polys[p].start + k] = (uint32_t)p;
		if (!rc)
			rc = build_grid(m, err);
	}
	if (rc) {
		travel_map_free(m);
		return NULL;
	}
	return m;
}

void travel_map_free(struct travel_map *m)
{
	if (!m)
		return;
	free(m->polys);
	free(m->xy);
	free(m->epoly);
	free(m->cstart);
	free(m->cedge);
	free(m->stamp);
	free(m->hits);
	free(m->chain);
	free(m);
}

void travel_route_free(struct travel_route *r)
{
	if (!r)
		return;
	free(r->xy);
	*r = (struct travel_route){0};
}

/* A fresh stamp for one query. */
static uint32_t new_stamp(struct travel_map *m)
{
	if (++m->cur == 0) {
		memset(m->stamp, 0, m->npts * sizeof(*m->stamp));
		m->cur = 1;
	}
	return m->cur;
}

/*
 * Call fn(ctx, edge) once for every edge listed in the cells the segment
 * p-q passes (row by row, the segment's x range within each row); stops
 * when fn returns true and returns true then.
 */
static bool for_edges(struct travel_map *m, const int64_t *p, const int64_t *q,
		      bool (*fn)(struct travel_map *, size_t, void *), void *ctx)
{
	uint32_t s;
	int64_t ylo = p[1] < q[1] ? p[1] : q[1], yhi = p[1] > q[1] ? p[1] : q[1];
	int r0, r1;

	if (!m->npts)
		return false;
	s = new_stamp(m);
	r0 = cell_of(m, ylo, m->gy, m->ny);
	r1 = cell_of(m, yhi, m->gy, m->ny);
	r0 = r0 < 0 ? 0 : r0;
	r1 = r1 >= m->ny ? m->ny - 1 : r1;
	for (int r = r0; r <= r1; r++) {
		double ya = fmax((double)ylo, (double)(m->gy + (int64_t)r * m->cell));
		double yb = fmin((double)yhi, (double)(m->gy + (int64_t)(r + 1) * m->cell));
		double xa, xb;
		if (p[1] == q[1]) {
			xa = (double)p[0];
			xb = (double)q[0];
		} else {
			double k = (double)(q[0] - p[0]) / (double)(q[1] - p[1]);
			xa = (double)p[0] + (ya - (double)p[1]) * k;
			xb = (double)p[0] + (yb - (double)p[1]) * k;
		}
		int c0 = (int)floor((fmin(xa, xb) - (double)m->gx) / (double)m->cell) - 1;
		int c1 = (int)floor((fmax(xa, xb) - (double)m->gx) / (double)m->cell) + 1;
		c0 = c0 < 0 ? 0 : c0;
		c1 = c1 >= m->nx ? m->nx - 1 : c1;
		for (int c = c0; c <= c1; c++) {
			size_t cell = (size_t)r * (size_t)m->nx + (size_t)c;
			for (uint32_t k = m->cstart[cell]; k < m->cstart[cell + 1]; k++) {
				uint32_t e = m->cedge[k];
				if (m->stamp[e] == s)
					continue;
				m->stamp[e] = s;
				if (fn(m, e, ctx))
					return true;
			}
		}
	}
	return false;
}

struct seg_ctx {
	const int64_t *p, *q;
	int island; /* boundary polygons of this island only (for hits and crossings) */
};

/* A wall edge touching the segment. */
static bool wall_touch(struct travel_map *m, size_t e, void *arg)
{
	const struct seg_ctx *c = arg;

	return m->polys[m->epoly[e]].wall &&
	       seg_touch(c->p, c->q, m->xy + 2 * e, m->xy + 2 * next_pt(m, e));
}

/* A boundary edge of the island crossing the segment inside both. */
static bool bound_cross(struct travel_map *m, size_t e, void *arg)
{
	const struct seg_ctx *c = arg;
	const struct tpoly *tp = &m->polys[m->epoly[e]];

	return !tp->wall && tp->island == c->island &&
	       seg_cross(c->p, c->q, m->xy + 2 * e, m->xy + 2 * next_pt(m, e));
}

/* Whether the segment p-q touches a wall. */
static bool touches_wall(struct travel_map *m, const int64_t *p, const int64_t *q)
{
	struct seg_ctx c = {p, q, -1};
	return for_edges(m, p, q, wall_touch, &c);
}

/*
 * Ray from (x, y) to +x over the walls (wall true) or over the boundary of
 * island (wall false): the parity says inside; *island gets the island of
 * the nearest crossing.
 */
static bool ray_inside(struct travel_map *m, int64_t x, int64_t y, bool wall, int want,
		       int *island)
{
	int row = cell_of(m, y, m->gy, m->ny), col = cell_of(m, x, m->gx, m->nx);
	int crossings = 0;
	double best = INFINITY;
	uint32_t s;

	*island = -1;
	if (!m->npts || row < 0 || row >= m->ny || col >= m->nx)
		return false;
	col = col < 0 ? 0 : col;
	s = new_stamp(m);
	for (int c = col; c < m->nx; c++) {
		size_t cell = (size_t)row * (size_t)m->nx + (size_t)c;
		for (uint32_t k = m->cstart[cell]; k < m->cstart[cell + 1]; k++) {
			uint32_t e = m->cedge[k];
			const struct tpoly *tp = &m->polys[m->epoly[e]];
			if (m->stamp[e] == s)
				continue;
			m->stamp[e] = s;
			if (tp->wall != wall || (!wall && tp->island != want))
				continue;
			const int64_t *a = m->xy + 2 * e, *b = m->xy + 2 * next_pt(m, e);
			if ((a[1] > y) == (b[1] > y))
				continue;
			int o = orient(a[0], a[1], b[0], b[1], x, y);
			if ((b[1] > a[1]) ? o <= 0 : o >= 0)
				continue;
			double xi = a[0] + (double)(y - a[1]) * (double)(b[0] - a[0]) /
						   (double)(b[1] - a[1]);
			crossings++;
			if (xi < best) {
				best = xi;
				*island = tp->island;
			}
		}
	}
	if (!(crossings % 2))
		*island = -1;
	return crossings % 2;
}

bool travel_segment_inside(struct travel_map *m, int64_t ax, int64_t ay, int64_t bx,
			   int64_t by)
{
	const int64_t p[2] = {ax, ay}, q[2] = {bx, by};
	int island;

	return m && !touches_wall(m, p, q) && ray_inside(m, ax, ay, true, -1, &island);
}

/* Append (x, y) to the point list xy (n used, cap allocated). */
static int xy_add(int64_t **xy, size_t *n, size_t *cap, int64_t x, int64_t y,
		  struct st_error *err)
{
	int64_t *g = st_grow(*xy, cap, *n + 1, 2 * sizeof(*g)); /* x, y */
	if (!g)
		return st_error_set(err, ST_ERR_NOMEM, "travel: out of memory for a route");
	*xy = g;
	(*xy)[2 * *n] = x;
	(*xy)[2 * *n + 1] = y;
	(*n)++;
	return 0;
}

/* Append (x, y) to the route. */
static int route_add(struct travel_route *r, int64_t x, int64_t y, struct st_error *err)
{
	return xy_add(&r->xy, &r->n, &r->cap, x, y, err);
}

/* Append (x, y) to the map's scratch chain unless it repeats the last point. */
static int chain_add(struct travel_map *m, int64_t x, int64_t y, struct st_error *err)
{
	if (m->nchain && m->chain[2 * m->nchain - 2] == x && m->chain[2 * m->nchain - 1] == y)
		return 0;
	return xy_add(&m->chain, &m->nchain, &m->chaincap, x, y, err);
}

/* Append h to the map's hits. */
static int hit_add(struct travel_map *m, const struct hit *h, struct st_error *err)
{
	struct hit *g = st_grow(m->hits, &m->hitcap, m->nhits + 1, sizeof(*g));
	if (!g)
		return st_error_set(err, ST_ERR_NOMEM, "travel: out of memory");
	m->hits = g;
	m->hits[m->nhits++] = *h;
	return 0;
}

struct hit_ctx {
	const int64_t *p, *q;
	int island;
	int rc;
	struct st_error *err;
};

/* Record where a boundary edge of the island meets the segment. */
static bool collect_hit(struct travel_map *m, size_t e, void *arg)
{
	struct hit_ctx *c = arg;
	const struct tpoly *tp = &m->polys[m->epoly[e]];
	const int64_t *a = m->xy + 2 * e, *b = m->xy + 2 * next_pt(m, e);
	double dx = (double)(c->q[0] - c->p[0]), dy = (double)(c->q[1] - c->p[1]);
	double ex = (double)(b[0] - a[0]), ey = (double)(b[1] - a[1]), den, t;

	if (tp->wall || tp->island != c->island || !seg_touch(c->p, c->q, a, b))
		return false;
	den = dx * ey - dy * ex;
	if (den == 0)
		return false; /* along the edge: the edges around it decide */
	t = ((double)(a[0] - c->p[0]) * ey - (double)(a[1] - c->p[1]) * ex) / den;
	t = fmin(1, fmax(0, t));
	c->rc = hit_add(m,
			&(struct hit){.t = t, .poly = m->epoly[e], .edge = e,
				      .x = llround(c->p[0] + t * dx), .y = llround(c->p[1] + t * dy)},
			c->err);
	return c->rc != 0;
}

/* Order hits along the segment; ties by polygon and edge so the order is
 * the same on every run. */
static int hit_cmp(const void *va, const void *vb)
{
	const struct hit *a = va, *b = vb;

	if (a->t != b->t)
		return a->t < b->t ? -1 : 1;
	if (a->poly != b->poly)
		return a->poly < b->poly ? -1 : 1;
	return (a->edge > b->edge) - (a->edge < b->edge);
}

/* Length of the walk along polygon p from h (on edge h->edge) to g, forward
 * (in point order) or backward. */
static double walk_len(const struct travel_map *m, const struct hit *h, const struct hit *g,
		       bool fwd)
{
	const struct tpoly *tp = &m->polys[h->poly];
	double len = 0, px = (double)h->x, py = (double)h->y;
	size_t e = h->edge;

	if (h->edge == g->edge) {
		const int64_t *a = m->xy + 2 * e;
		double dh = hypot((double)(h->x - a[0]), (double)(h->y - a[1]));
		double dg = hypot((double)(g->x - a[0]), (double)(g->y - a[1]));
		if ((dg >= dh) == fwd)
			return hypot((double)(g->x - h->x), (double)(g->y - h->y));
	}
	for (size_t k = 0; k <= tp->n; k++) {
		size_t v = fwd ? next_pt(m, e) : e; /* the vertex walked to next */
		len += hypot((double)m->xy[2 * v] - px, (double)m->xy[2 * v + 1] - py);
		px = (double)m->xy[2 * v];
		py = (double)m->xy[2 * v + 1];
		e = fwd ? next_pt(m, e) : (e == tp->start ? tp->start + tp->n - 1 : e - 1);
		if (e == g->edge)
			break;
	}
	return len + hypot((double)g->x - px, (double)g->y - py);
}

/* Append the walk from h to g along their polygon (the points after h, g
 * included) to the chain. */
static int walk_add(struct travel_map *m, const struct hit *h, const struct hit *g, bool fwd,
		    struct st_error *err)
{
	const struct tpoly *tp = &m->polys[h->poly];
	size_t e = h->edge;
	int rc = 0;

	if (h->edge == g->edge) {
		const int64_t *a = m->xy + 2 * e;
		double dh = hypot((double)(h->x - a[0]), (double)(h->y - a[1]));
		double dg = hypot((double)(g->x - a[0]), (double)(g->y - a[1]));
		if ((dg >= dh) == fwd)
			return chain_add(m, g->x, g->y, err);
	}
	for (size_t k = 0; k <= tp->n && !rc; k++) {
		size_t v = fwd ? next_pt(m, e) : e;
		rc = chain_add(m, m->xy[2 * v], m->xy[2 * v + 1], err);
		e = fwd ? next_pt(m, e) : (e == tp->start ? tp->start + tp->n - 1 : e - 1);
		if (e == g->edge)
			break;
	}
	return rc ? rc : chain_add(m, g->x, g->y, err);
}

/*
 * Nearest point to (x, y) on the boundary of island: *h gets its polygon,
 * edge and point; false when the island has no boundary.
 */
static bool nearest_on_bound(const struct travel_map *m, int64_t x, int64_t y, int island,
			     struct hit *h)
{
	double best = INFINITY;

	for (size_t p = 0; p < m->npolys; p++) {
		const struct tpoly *tp = &m->polys[p];
		if (tp->wall || tp->island != island)
			continue;
		for (size_t e = tp->start; e < tp->start + tp->n; e++) {
			const int64_t *a = m->xy + 2 * e, *b = m->xy + 2 * next_pt(m, e);
			double ex = (double)(b[0] - a[0]), ey = (double)(b[1] - a[1]);
			double l2 = ex * ex + ey * ey, t = 0;
			if (l2 > 0)
				t = fmin(1, fmax(0, ((double)(x - a[0]) * ex + (double)(y - a[1]) * ey) /
							   l2));
			double px = (double)a[0] + t * ex, py = (double)a[1] + t * ey;
			double d = hypot(px - (double)x, py - (double)y);
			if (d < best) {
				best = d;
				*h = (struct hit){.t = 0, .poly = p, .edge = e, .x = llround(px),
						  .y = llround(py)};
			}
		}
	}
	return best < INFINITY;
}

/*
 * Walk the chain's last point to (bx, by) on the boundary of island: the
 * segment's hits, grouped by polygon from the first hit to the last one on
 * the same polygon, each group walked round the shorter way.  from and to
 * (may be NULL) are where the ends were snapped onto the boundary.
 */
static int walk_segment(struct travel_map *m, int island, const struct hit *from,
			const struct hit *to, int64_t bx, int64_t by, struct st_error *err)
{
	int64_t p[2] = {m->chain[2 * m->nchain - 2], m->chain[2 * m->nchain - 1]};
	const int64_t q[2] = {bx, by};
	struct hit_ctx c = {p, q, island, 0, err};
	int rc = 0;

	m->nhits = 0;
	for_edges(m, p, q, collect_hit, &c);
	if (c.rc)
		return c.rc;
	if (from || to) {
		struct hit ends[2];
		size_t n = 0;
		if (from) {
			ends[n] = *from;
			ends[n++].t = 0;
		}
		if (to) {
			ends[n] = *to;
			ends[n++].t = 1;
		}
		for (size_t k = 0; k < n && !rc; k++)
			rc = hit_add(m, &ends[k], err);
		if (rc)
			return rc;
	}
	qsort(m->hits, m->nhits, sizeof(*m->hits), hit_cmp);
	for (size_t i = 0; i < m->nhits && !rc;) {
		size_t j = i;
		for (size_t k = i + 1; k < m->nhits; k++)
			if (m->hits[k].poly == m->hits[i].poly)
				j = k;
		if (j == i) {
			i++;
			continue;
		}
		const struct hit *h = &m->hits[i], *g = &m->hits[j];
		bool fwd = walk_len(m, h, g, true) <= walk_len(m, h, g, false);
		rc = chain_add(m, h->x, h->y, err);
		if (!rc)
			rc = walk_add(m, h, g, fwd, err);
		i = j + 1;
	}
	return rc ? rc : chain_add(m, bx, by, err);
}

/* Whether the shortcut p-q stays inside the island's boundary. */
static bool shortcut_ok(struct travel_map *m, const int64_t *p, const int64_t *q, int island)
{
	struct seg_ctx c = {p, q, island};
	int found;

	if (for_edges(m, p, q, bound_cross, &c))
		return false;
	return ray_inside(m, p[0] + (q[0] - p[0]) / 2, p[1] + (q[1] - p[1]) / 2, false, island,
			  &found);
}

/* Straight route: the end alone, inside when the segment is. */
static int route_straight(struct travel_route *r, int64_t ax, int64_t ay, int64_t bx, int64_t by,
			  bool inside, struct st_error *err)
{
	r->n = 0;
	r->inside = inside;
	r->length = hypot((double)(bx - ax), (double)(by - ay));
	return route_add(r, bx, by, err);
}

int travel_plan(struct travel_map *m, int64_t ax, int64_t ay, int64_t bx, int64_t by,
		struct travel_route *r, struct st_error *err)
{
	const int64_t a[2] = {ax, ay}, b[2] = {bx, by};
	struct hit from, to;
	bool snap_a, snap_b;
	int ia, ib, rc;

	if (!m || !m->npts)
		return route_straight(r, ax, ay, bx, by, false, err);
	if (!ray_inside(m, ax, ay, true, -1, &ia))
		return route_straight(r, ax, ay, bx, by, false, err);
	if (!touches_wall(m, a, b))
		return route_straight(r, ax, ay, bx, by, true, err);
	if (!ray_inside(m, bx, by, true, -1, &ib) || ia != ib)
		return route_straight(r, ax, ay, bx, by, false, err);

	/* Both ends in one island: onto its boundary, along it, back off. */
	snap_a = !ray_inside(m, ax, ay, false, ia, &(int){0});
	snap_b = !ray_inside(m, bx, by, false, ia, &(int){0});
	if ((snap_a && !nearest_on_bound(m, ax, ay, ia, &from)) ||
	    (snap_b && !nearest_on_bound(m, bx, by, ia, &to)))
		return route_straight(r, ax, ay, bx, by, false, err);
	m->nchain = 0;
	rc = chain_add(m, snap_a ? from.x : ax, snap_a ? from.y : ay, err);
	if (!rc)
		rc = walk_segment(m, ia, snap_a ? &from : NULL, snap_b ? &to : NULL,
				  snap_b ? to.x : bx, snap_b ? to.y : by, err);
	if (rc)
		return rc;

	/* Shorten: from each kept point, go as far along as a straight cut
	 * stays inside the boundary. */
	r->n = 0;
	r->length = 0;
	r->inside = true;
	if (snap_a)
		rc = route_add(r, m->chain[0], m->chain[1], err);
	for (size_t k = 1, anchor = 0; k < m->nchain && !rc; k++) {
		if (k + 1 < m->nchain &&
		    shortcut_ok(m, m->chain + 2 * anchor, m->chain + 2 * (k + 1), ia))
			continue;
		rc = route_add(r, m->chain[2 * k], m->chain[2 * k + 1], err);
		anchor = k;
	}
	if (!rc && snap_b)
		rc = route_add(r, bx, by, err);
	if (rc)
		return rc;

	/* The route must not touch a wall anywhere, nor wander off: a detour
	 * beyond the map's costs more than the crossing it avoids. */
	{
		int64_t p[2] = {ax, ay};
		for (size_t k = 0; k < r->n; k++) {
			const int64_t *q = r->xy + 2 * k;
			if (touches_wall(m, p, q))
				return route_straight(r, ax, ay, bx, by, false, err);
			r->length += hypot((double)(q[0] - p[0]), (double)(q[1] - p[1]));
			p[0] = q[0];
			p[1] = q[1];
		}
	}
	double straight = hypot((double)(bx - ax), (double)(by - ay));
	/* written so that 100% is 2 x straight to the last bit */
	double limit = straight + (m->detour_pct ? straight * (m->detour / 100) : m->detour);
	if (m->detour > 0 && r->length > limit)
		return route_straight(r, ax, ay, bx, by, false, err);
	return 0;
}
