/*
 * ironing.c - the area and lines of ironing (see ironing.h).
 */
#include "ironing.h"

#include <string.h>

#include "patterns.h"
#include "settings.h"
#include "toolpath.h"

/* Chord error of the inward offset, nm. */
#define IRON_ARC_NM 2000.0

int iron_type_parse(const char *name, enum iron_type *out, struct st_error *err)
{
	const struct setting *d = settings_find("ironing_type");

	for (size_t i = 0; d && name && i < d->nnames; i++)
		if (!strcmp(d->names[i], name)) {
			*out = (enum iron_type)i;
			return 0;
		}
	return st_error_set(err, ST_ERR_ARG,
			    "ironing: ironing_type \"%.32s\" is unknown; use top, topmost or solid",
			    name ? name : "(none)");
}

/* Whether the region inside the walls is filled solid throughout: what the
 * solid classes leave of it is less than a nozzle's square. */
static int solid_throughout(const struct clip_paths *inner, const struct clip_paths *solid,
			    double nozzle, bool *all, struct st_error *err)
{
	struct clip_paths rest = {0};
	double area = 0;
	int rc = clip_boolean(CLIP_DIFFERENCE, inner, solid, CLIP_NONZERO, &rest, err);

	if (!rc)
		rc = clip_paths_area(&rest, &area, err);
	*all = !rc && area < nozzle * nozzle * SLICE_UNITS_PER_MM * SLICE_UNITS_PER_MM;
	clip_paths_free(&rest);
	return rc;
}

int iron_area(enum iron_type type, bool top_layers, const struct slice_stack *st, size_t i,
	      const struct clip_paths *inner, const struct clip_paths *solid, double nozzle,
	      struct clip_paths *out, struct st_error *err)
{
	const struct clip_paths *S = &st->layers[i].regions.paths;
	const struct clip_paths *above = i + 1 < st->n ? &st->layers[i + 1].regions.paths : NULL;
	struct clip_paths A = {0}, inset = {0};
	bool all = false;
	int rc = 0;

	clip_paths_clear(out);
	if (type == IRON_SOLID)
		rc = solid_throughout(inner, solid, nozzle, &all, err);
	else if (!top_layers || (type == IRON_TOPMOST && above))
		return 0;
	if (!rc && all) {
		rc = clip_paths_append(&A, S, err);
	} else if (!rc) {
		rc = clip_boolean(CLIP_DIFFERENCE, S, above, CLIP_NONZERO, &A, err);
		if (!rc && type == IRON_SOLID) /* the first layer, and solid infill */
			rc = clip_paths_append(&A, i == 0 ? S : solid, err);
	}
	if (!rc)
		rc = clip_offset(S, -nozzle / 2 * SLICE_UNITS_PER_MM, CLIP_JOIN_ROUND, 0.0,
				 IRON_ARC_NM, &inset, err);
	if (!rc)
		rc = clip_boolean(CLIP_INTERSECTION, &A, &inset, CLIP_NONZERO, out, err);
	clip_paths_free(&A);
	clip_paths_free(&inset);
	return rc;
}

int iron_lines(const struct clip_paths *area, double a, double spacing, struct clip_paths *segs,
	       struct st_error *err)
{
	struct clip_paths lines = {0};
	struct pat_box box;
	int rc = 0;

	clip_paths_clear(segs);
	if (!pat_box_of(area, &box))
		return 0;
	rc = pat_lines(a, spacing, 0.0, &box, &lines, err);
	if (!rc)
		rc = clip_lines(CLIP_INTERSECTION, &lines, area, CLIP_NONZERO, segs, err);
	clip_paths_free(&lines);
	return rc;
}
