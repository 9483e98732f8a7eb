/*
 * clip.h - the slicer's only door to Clipper (libpolyclipping 6.4): polygon
 * booleans, offsets, simplification, area and point-in-polygon on integer
 * coordinates (1 unit = 1 nm, SLICE_UNITS_PER_MM in toolpath.h).
 *
 * Plain C11: no Clipper type or exception crosses this header (STYLE rule
 * 14).  Every function that can fail returns 0 or a negative enum st_status
 * class and fills err; enum arguments are range-checked.  The containers
 * below are allocated and freed by clip.cpp only: fill them through
 * clip_paths_add / the operations, release them with clip_paths_free /
 * clip_expolys_free.  A zero-initialised container is a valid empty set.
 *
 * Orientation: results of booleans and offsets have outer contours
 * counter-clockwise (positive area, y up) and holes clockwise.
 *
 * Thread-safety: no shared state; distinct containers may be used from
 * distinct threads.
 */
#ifndef STRATUM_SLICER_CLIP_H
#define STRATUM_SLICER_CLIP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "st_error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Boolean operation of subject (A) and clip (B). */
enum clip_op {
	CLIP_UNION = 0,	       /* A or B */
	CLIP_DIFFERENCE,       /* A and not B */
	CLIP_INTERSECTION,     /* A and B */
	CLIP_XOR,	       /* exactly one of A, B */
	CLIP_OPS
};

/* Which winding numbers count as inside (applied to subject and clip). */
enum clip_fill {
	CLIP_EVEN_ODD = 0,	/* odd winding */
	CLIP_NONZERO,		/* winding != 0 */
	CLIP_POSITIVE,		/* winding > 0 */
	CLIP_NEGATIVE,		/* winding < 0 */
	CLIP_FILLS
};

/* How offset edges are joined where they separate (reflex side). */
enum clip_join {
	CLIP_JOIN_MITER = 0,	/* sharp, cut at miter_limit x delta */
	CLIP_JOIN_ROUND,	/* arc, chords within arc_tolerance */
	CLIP_JOIN_SQUARE,	/* squared off at distance delta */
	CLIP_JOINS
};

/* How the ends of offset open polylines are closed. */
enum clip_end {
	CLIP_END_BUTT = 0,	/* flat, at the end point */
	CLIP_END_SQUARE,	/* flat, extended by delta */
	CLIP_END_ROUND,		/* half circle of radius delta */
	CLIP_ENDS
};

/*
 * A set of paths: path i has the points start[i] .. start[i+1]-1, point j at
 * (xy[2j], xy[2j+1]) in nm.  start has n + 1 entries when n > 0.
 */
struct clip_paths {
	size_t n;		/* paths */
	size_t *start;		/* n + 1 point offsets */
	int64_t *xy;		/* 2 * start[n] coordinates, nm */
	size_t cap_paths;	/* allocated (internal) */
	size_t cap_pts;
};

/*
 * Polygons with holes ("expolygons"): contour lists of paths; expolygon i
 * is paths.first[i] (its outer contour, CCW) followed by its holes (CW) up
 * to paths first[i+1] - 1.  first has n + 1 entries when n > 0.  Taken as a
 * whole, paths is the same area as a plain polygon set.
 */
struct clip_expolys {
	struct clip_paths paths;
	size_t n;		/* expolygons */
	size_t *first;		/* n + 1 path indices */
	size_t cap;		/* allocated (internal) */
};

/* Number of points of path i (i < ps->n). */
static inline size_t clip_path_len(const struct clip_paths *ps, size_t i)
{
	return ps->start[i + 1] - ps->start[i];
}

/* Coordinates of path i: x0, y0, x1, y1, ... (i < ps->n). */
static inline const int64_t *clip_path_xy(const struct clip_paths *ps, size_t i)
{
	return ps->xy + 2 * ps->start[i];
}

/* Total number of points over all paths. */
static inline size_t clip_paths_points(const struct clip_paths *ps)
{
	return ps->n ? ps->start[ps->n] : 0;
}

/*
 * clip_paths_add - append a copy of the path xy[0 .. 2*npts) to ps (npts may
 * be 0 only if xy is NULL too, which adds nothing).  Returns 0 or
 * ST_ERR_NOMEM / ST_ERR_ARG.
 */
int clip_paths_add(struct clip_paths *ps, const int64_t *xy, size_t npts, struct st_error *err);

/* clip_paths_append - append copies of every path of src to dst (distinct). */
int clip_paths_append(struct clip_paths *dst, const struct clip_paths *src,
		      struct st_error *err);

/* clip_paths_clear - make ps empty, keeping its memory. */
void clip_paths_clear(struct clip_paths *ps);

/* clip_paths_free - release ps's arrays and leave it empty; NULL is safe. */
void clip_paths_free(struct clip_paths *ps);

/* clip_expolys_clear / clip_expolys_free - as for clip_paths. */
void clip_expolys_clear(struct clip_expolys *ex);
void clip_expolys_free(struct clip_expolys *ex);

/*
 * clip_expolys_get - replace out with the contours of expolygon i of ex
 * (outer first, then holes).  Returns 0, ST_ERR_ARG (i out of range),
 * ST_ERR_NOMEM.
 */
int clip_expolys_get(const struct clip_expolys *ex, size_t i, struct clip_paths *out,
		     struct st_error *err);

/*
 * clip_boolean - out = subject <op> clip, both read with fill rule fill;
 * clip may be NULL (an empty set), so CLIP_UNION of subject alone resolves
 * self-overlaps.  out is replaced and may be subject or clip.  Returns 0,
 * ST_ERR_ARG (bad enum), ST_ERR_RANGE (coordinates beyond Clipper's range,
 * about 4.6e18), ST_ERR_NOMEM, ST_ERR_INTERNAL.
 */
int clip_boolean(enum clip_op op, const struct clip_paths *subject, const struct clip_paths *clip,
		 enum clip_fill fill, struct clip_paths *out, struct st_error *err);

/* clip_boolean_ex - clip_boolean with the result as polygons with holes. */
int clip_boolean_ex(enum clip_op op, const struct clip_paths *subject,
		    const struct clip_paths *clip, enum clip_fill fill, struct clip_expolys *out,
		    struct st_error *err);

/*
 * clip_lines - clip the open polylines lines by the polygon set polys (fill
 * rule fill): CLIP_INTERSECTION keeps the pieces inside, CLIP_DIFFERENCE the
 * pieces outside; other ops are ST_ERR_ARG.  out (open polylines) is
 * replaced and must not be lines or polys.
 */
int clip_lines(enum clip_op op, const struct clip_paths *lines, const struct clip_paths *polys,
	       enum clip_fill fill, struct clip_paths *out, struct st_error *err);

/*
 * clip_offset - offset the closed polygon set in (outer CCW, holes CW, as
 * booleans return it) by delta nm: > 0 grows, < 0 shrinks.  join applies on
 * the side where edges separate; miter_limit (>= 2, in multiples of |delta|)
 * only matters for CLIP_JOIN_MITER, arc_tolerance (nm, > 0) only for
 * CLIP_JOIN_ROUND.  out is replaced and may be in.
 */
int clip_offset(const struct clip_paths *in, double delta, enum clip_join join,
		double miter_limit, double arc_tolerance, struct clip_paths *out,
		struct st_error *err);

/* clip_offset_ex - clip_offset with the result as polygons with holes. */
int clip_offset_ex(const struct clip_paths *in, double delta, enum clip_join join,
		   double miter_limit, double arc_tolerance, struct clip_expolys *out,
		   struct st_error *err);

/*
 * clip_offset_open - the area within |delta| nm of the open polylines lines:
 * closed polygons, ends shaped by end.  out is replaced and may be lines.
 */
int clip_offset_open(const struct clip_paths *lines, double delta, enum clip_join join,
		     enum clip_end end, double miter_limit, double arc_tolerance,
		     struct clip_paths *out, struct st_error *err);

/*
 * clip_sweep - the union of beads swept along open polylines: path i of
 * lines becomes the area within delta[i] nm (> 0) of it, with round joins
 * and round ends (a disk swept along the centre line, what a nozzle leaves),
 * arcs within arc_tolerance nm (> 0); all of them are united (non-zero).
 * Paths of one point give a disk.  Paths sharing a delta are offset
 * together, so few distinct deltas are cheaper than many.  out is replaced
 * and must not be lines.  Returns 0, ST_ERR_ARG (a delta not > 0 or not
 * finite, a bad tolerance), ST_ERR_RANGE, ST_ERR_NOMEM, ST_ERR_INTERNAL.
 */
int clip_sweep(const struct clip_paths *lines, const double *delta, double arc_tolerance,
	       struct clip_paths *out, struct st_error *err);

/*
 * clip_simplify - resolve self-intersections of in under fill rule fill into
 * simple polygons.  out is replaced and may be in.
 */
int clip_simplify(const struct clip_paths *in, enum clip_fill fill, struct clip_paths *out,
		  struct st_error *err);

/*
 * clip_clean - in place, drop vertices closer than distance nm to a
 * neighbour or to the line through their neighbours; paths left with fewer
 * than 3 points are removed.
 */
int clip_clean(struct clip_paths *ps, double distance, struct st_error *err);

/*
 * clip_expolys_clean - clip_clean on every contour of ex, keeping the
 * expolygon structure: an outer contour left with fewer than 3 points
 * drops its expolygon, a hole so left is dropped alone.  Returns 0,
 * ST_ERR_ARG, ST_ERR_NOMEM (ex unchanged then).
 */
int clip_expolys_clean(struct clip_expolys *ex, double distance, struct st_error *err);

/* clip_area - signed area of one closed path in nm^2 (> 0 for CCW) into *area. */
int clip_area(const int64_t *xy, size_t npts, double *area, struct st_error *err);

/* clip_paths_area - sum of the signed areas of every path of ps, nm^2. */
int clip_paths_area(const struct clip_paths *ps, double *area, struct st_error *err);

/*
 * clip_erosion_kept - true when the region ps (as the operations return it:
 * outer contours CCW, holes CW, none overlapping) surely keeps some area
 * when shrunk by r nm, so the caller may skip an offset done only to see
 * whether anything is left.  The points within r of the boundary lie in a
 * strip of width r along each edge plus a sector of radius r at each
 * reflex vertex; when the area exceeds that bound some point is farther
 * than r from every edge.  false means "not known", never "empty".
 */
bool clip_erosion_kept(const struct clip_paths *ps, double r);

/*
 * clip_point_in_polygon - where (x, y) lies against one closed path: *where
 * is 1 inside, 0 outside, -1 on the boundary.
 */
int clip_point_in_polygon(int64_t x, int64_t y, const int64_t *xy, size_t npts, int *where,
			  struct st_error *err);

/*
 * A polygon set prepared for many point queries: the paths are converted
 * once and each keeps its bounding box, so a query skips the paths whose
 * box does not hold the point (where Clipper's test cannot answer anything
 * but outside) instead of copying every path per query.
 */
struct clip_locator;

/*
 * clip_locator_new - a locator of a copy of ps (ps may be changed or freed
 * afterwards).  Returns NULL with err filled (ST_ERR_ARG, ST_ERR_NOMEM).
 */
struct clip_locator *clip_locator_new(const struct clip_paths *ps, struct st_error *err);

/*
 * clip_locator_inside - whether (x, y) lies on the boundary of a path of the
 * set or inside an odd number of its paths (even-odd over the contours of
 * expolygons: inside a contour and not in one of its holes), with
 * clip_point_in_polygon's answer per path.  Read-only: one locator may be
 * queried from several threads.
 */
bool clip_locator_inside(const struct clip_locator *loc, int64_t x, int64_t y);

/* clip_locator_free - release a locator; NULL is safe. */
void clip_locator_free(struct clip_locator *loc);

#ifdef __cplusplus
}
#endif

#endif /* STRATUM_SLICER_CLIP_H */
