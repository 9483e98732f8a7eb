/*
 * thumbnail.h - PrusaSlicer's G-code thumbnails (its `thumbnails` key, e.g.
 * "160x120" or "16x16,220x124"): per size, a PNG picture of the part, drawn
 * here from the repaired mesh (orthographic, seen from the front right and
 * above, each triangle flat-shaded, the background transparent), written
 * into the G-code header in PrusaSlicer 2.5's form:
 *
 *     ;
 *     ; thumbnail begin 160x120 LENGTH
 *     ; BASE64 ... (lines of at most 78 characters)
 *     ; thumbnail end
 *     ;
 *
 * LENGTH is the count of base64 characters.  Printers' screens and print
 * hosts show the picture; send, print and the node pass the comments on.
 * Thread-safety: none shared.
 */
#ifndef STRATUM_HOST_THUMBNAIL_H
#define STRATUM_HOST_THUMBNAIL_H

#include <stddef.h>

#include "mesh.h"
#include "st_error.h"

#define THUMB_SIZES_MAX 8    /* sizes in one thumbnails value */
#define THUMB_SIDE_MAX 1024  /* px, the largest width or height */

/* One picture size, px. */
struct thumb_size {
	int w, h;
};

/*
 * thumb_parse - the sizes of a thumbnails value: "WxH" items separated by
 * commas (spaces around them allowed), each side 1 to THUMB_SIDE_MAX, at
 * most THUMB_SIZES_MAX of them; "" gives none.  Returns 0 with *n set, or
 * ST_ERR_RANGE naming the item and what is allowed.
 */
int thumb_parse(const char *spec, struct thumb_size out[THUMB_SIZES_MAX], size_t *n,
		struct st_error *err);

/*
 * thumb_block - the header comments (above) for every size of spec,
 * pictures of m (mm, any placement), in a new NUL-terminated string (free
 * it); *out NULL when spec names no size or m has no triangles.  Errors
 * (*out NULL): thumb_parse's, ST_ERR_NOMEM, ST_ERR_INTERNAL (cairo
 * refused).
 */
int thumb_block(const struct mesh *m, const char *spec, char **out, struct st_error *err);

#endif /* STRATUM_HOST_THUMBNAIL_H */
