/*
 * emit.h - append a clip path (nm coordinates) as a toolpath of constant
 * bead width (private to slicer/; skirt, brim and support use it).
 */
#ifndef STRATUM_SLICER_EMIT_H
#define STRATUM_SLICER_EMIT_H

#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>

#include "st_error.h"
#include "toolpath.h"

/*
 * slice_emit_xy - add the points xy[0 .. 2n) to l as a path of role, every
 * point with bead width width nm, starting at point first (rotating a
 * closed path; an open path is reversed when reverse is set and first is
 * ignored).  Paths too short for their kind (fewer than 2 points, or 3 when
 * closed) are skipped.  Returns 0, ST_ERR_NOMEM or what layer_add_path
 * returns.
 */
static inline int slice_emit_xy(struct layer_paths *l, enum path_role role, bool closed,
				const int64_t *xy, size_t n, int64_t width, size_t first,
				bool reverse, struct st_error *err)
{
	struct path_point *pts;
	int rc;

	if (n < (closed ? 3u : 2u))
		return 0;
	if (n > SIZE_MAX / sizeof(*pts) || !(pts = malloc(n * sizeof(*pts))))
		return st_error_set(err, ST_ERR_NOMEM, "slicer: out of memory for a %zu-point path",
				    n);
	for (size_t k = 0; k < n; k++) {
		size_t i = closed ? (first + k) % n : (reverse ? n - 1 - k : k);
		pts[k] = (struct path_point){.x = xy[2 * i], .y = xy[2 * i + 1], .width = width};
	}
	rc = layer_add_path(l, role, closed, pts, n, err);
	free(pts);
	return rc;
}

#endif /* STRATUM_SLICER_EMIT_H */
