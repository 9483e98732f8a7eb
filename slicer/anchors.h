/*
 * anchors.h - PrusaSlicer's infill_anchor / infill_anchor_max for sparse
 * infill: line ends that lie on the boundary the lines were clipped to are
 * joined to their neighbours along it by the boundary between them when
 * that piece is at most max long (shortest first, never closing a loop, each
 * end once), and an end left over gets an anchor: the boundary from it,
 * toward its farther neighbour, at most anchor long and at most half way
 * to that neighbour.
 * Thread safety: no shared state.
 */
#ifndef STRATUM_SLICER_ANCHORS_H
#define STRATUM_SLICER_ANCHORS_H

#include "clip.h"
#include "st_error.h"

/* A line end this close to the boundary lies on it, nm. */
#define ANCHOR_ON_BOUNDARY_NM 1000.0

/*
 * anchors_connect - replace lines (open polylines, nm) by the polylines
 * joined and anchored along boundary (closed contours, nm) as above;
 * anchor and max in nm (max 0: lines is left as it is).  Returns 0,
 * ST_ERR_NOMEM, or the Clipper bridge's errors; on error lines is
 * unchanged.
 */
int anchors_connect(const struct clip_paths *boundary, struct clip_paths *lines, double anchor,
		    double max, struct st_error *err);

#endif /* STRATUM_SLICER_ANCHORS_H */
