/*
 * travel.h - travel moves that do not cross perimeters ("avoid crossing
 * perimeters" in PrusaSlicer, combing in Cura).
 *
 * A travel map holds one layer's region (the solid cross-section, islands
 * with holes) and a routing boundary: the region shrunk by an inset, so a
 * route along it runs over the inner walls, not over the outer face.  A
 * travel whose straight segment stays inside the region is left straight;
 * one that would leave its island (a hole, a concave bay) and come back is
 * routed along the boundary the shorter way round each obstacle it meets,
 * then shortened where a straight cut stays inside the boundary.  Every
 * route is checked against the region's own walls at the end: a route that
 * cannot be made (ends in different islands, outside the part, an island
 * too thin for the boundary) or would detour more than the map allows
 * (travel_map_set_detour) is the straight segment, flagged as crossing.
 *
 * Edges sit in a uniform grid, so a travel costs about the number of grid
 * cells it passes, not the size of the layer.
 *
 * Ownership: travel_map_new copies what it needs; travel_map_free frees.
 * Thread safety: a map keeps scratch marks for its queries, so one map is
 * used by one thread at a time; distinct maps are independent.
 */
#ifndef STRATUM_SLICER_TRAVEL_H
#define STRATUM_SLICER_TRAVEL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "clip.h"
#include "st_error.h"

/* A route whose detour beyond the straight distance is longer than this
 * share of it is not taken, unless travel_map_set_detour says otherwise
 * (PrusaSlicer's avoid_crossing_perimeters_max_detour), percent. */
#define TRAVEL_DETOUR_DEFAULT_PCT 100.0

struct travel_map;

/* A planned travel: the points after the start, the end last (nm). */
struct travel_route {
	size_t n, cap; /* points used / allocated */
	int64_t *xy;   /* 2 * n coordinates, owned */
	double length; /* nm, along the points from the start */
	bool inside;   /* the whole route stays inside one island of the region */
};

/*
 * travel_map_new - the map of one layer's region (outer contours CCW, holes
 * CW, as Clipper returns them; may be empty) with its routing boundary
 * inset nm (> 0) inside.  Returns a new map, or NULL with err filled
 * (ST_ERR_ARG, ST_ERR_NOMEM, the Clipper bridge's errors).
 */
struct travel_map *travel_map_new(const struct clip_expolys *region, int64_t inset,
				  struct st_error *err);

/*
 * travel_map_set_detour - the longest detour (route length minus the
 * straight distance) routes on m may take: v mm, or v percent of the
 * straight distance (pct); 0 = any.  A new map allows
 * TRAVEL_DETOUR_DEFAULT_PCT percent.
 */
void travel_map_set_detour(struct travel_map *m, double v, bool pct);

/* travel_map_free - release a map; NULL is fine. */
void travel_map_free(struct travel_map *m);

/*
 * travel_plan - the route from (ax, ay) to (bx, by) on map m (NULL: the
 * straight segment, not inside).  r is reused (zero-initialise it once,
 * travel_route_free at the end).  Returns 0 or ST_ERR_NOMEM.
 */
int travel_plan(struct travel_map *m, int64_t ax, int64_t ay, int64_t bx, int64_t by,
		struct travel_route *r, struct st_error *err);

/*
 * travel_segment_inside - whether the closed segment from (ax, ay) to
 * (bx, by) lies inside the map's region without touching its walls.
 */
bool travel_segment_inside(struct travel_map *m, int64_t ax, int64_t ay, int64_t bx,
			   int64_t by);

/* travel_route_free - release r's points and leave it empty; NULL is fine. */
void travel_route_free(struct travel_route *r);

#endif /* STRATUM_SLICER_TRAVEL_H */
