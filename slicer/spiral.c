/*
 * spiral.c - the spiral vase changes to the slicing job (see spiral.h).
 */
#include "spiral.h"

#include <math.h>

size_t spiral_first_layer(const struct slice_stack *st, int bottom_solid_layers,
			  double bottom_solid_min_thickness)
{
	size_t i = bottom_solid_layers > 1 ? (size_t)bottom_solid_layers : 1;

	/* PrusaSlicer counts the layers whose slicing plane is below the thickness. */
	while (i < st->n &&
	       st->layers[i].z - st->layers[i].height / 2 < bottom_solid_min_thickness - 1e-6)
		i++;
	return i < st->n ? i : st->n;
}

int spiral_keep_outline(struct slice_layer *l, struct st_error *err)
{
	struct clip_expolys *ex = &l->regions, kept = {0};
	struct clip_paths outline = {0};
	double best = -INFINITY;
	size_t pick = 0;
	int rc = 0;

	if (ex->n == 0)
		return 0;
	for (size_t k = 0; k < ex->n && !rc; k++) {
		size_t outer = ex->first[k];
		double area = 0;

		rc = clip_area(clip_path_xy(&ex->paths, outer), clip_path_len(&ex->paths, outer),
			       &area, err);
		if (!rc && fabs(area) > best) {
			best = fabs(area);
			pick = outer;
		}
	}
	if (!rc)
		rc = clip_paths_add(&outline, clip_path_xy(&ex->paths, pick),
				    clip_path_len(&ex->paths, pick), err);
	if (!rc)
		rc = clip_boolean_ex(CLIP_UNION, &outline, NULL, CLIP_NONZERO, &kept, err);
	clip_paths_free(&outline);
	if (rc) {
		clip_expolys_free(&kept);
		return rc;
	}
	clip_expolys_free(ex);
	*ex = kept;
	return 0;
}

bool spiral_layer_fits(const struct layer_paths *m)
{
	return m->n == 1 && m->paths[0].closed && m->paths[0].role == PATH_OUTER_PERIMETER;
}
