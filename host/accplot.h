/*
 * accplot.h - the pictures of the accuracy commands (docs/accuracy.md),
 * PNG through cairo like the layer previews (pvdraw.h):
 *
 * - the cusp height against Z (`stratum analyze --png`): each box's value
 *   as a grey dot at its layer's plane, each layer's maximum and mean as
 *   lines, as seed 004's figure 14 plots them;
 * - a mesh coloured by a value per facet (`stratum compare --png`): the
 *   mesh seen from the front left and above, shaded, each facet in the
 *   colour of its value on a blue-to-red scale (or grey when the value is
 *   within a tolerance), the scale beside it, and under it the histogram
 *   of the distances when there is one.
 *
 * Both are written through a temporary file renamed over the path, so the
 * path is untouched on any error.
 */
#ifndef STRATUM_HOST_ACCPLOT_H
#define STRATUM_HOST_ACCPLOT_H

#include <stdbool.h>
#include <stddef.h>

#include "cusp_measure.h"
#include "mesh.h"
#include "st_error.h"

/* accplot_cusp - r's plot into path (.png), title above it.  0, ST_ERR_IO,
 * ST_ERR_NOMEM or ST_ERR_INTERNAL (cairo refused) with err filled. */
int accplot_cusp(const struct cusp_report *r, const char *title, const char *path,
		 struct st_error *err);

/* A histogram: share of the area in each of n bins bin_width mm wide. */
struct accplot_hist {
	const double *share;
	size_t n;
	double bin_width;
};

/* What accplot_mesh colours and how. */
struct accplot_values {
	const float *value; /* per facet, mm */
	double vmax;	    /* the scale's top; values above it get its colour */
	double grey_to;	    /* values up to this are drawn grey (< 0: none are) */
	const char *what;   /* the scale's name ("distance to B") */
	bool outline;	    /* edges drawn darker, to show the facets' sizes */
};

/*
 * accplot_mesh - m with facet t coloured by v->value[t] on the scale 0 ..
 * vmax, hist under it (NULL: none).  Errors as accplot_cusp.
 */
int accplot_mesh(const struct mesh *m, const struct accplot_values *v,
		 const struct accplot_hist *hist, const char *title, const char *path,
		 struct st_error *err);

#endif /* STRATUM_HOST_ACCPLOT_H */
