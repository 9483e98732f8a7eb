/*
 * layerplot.h - the layer-height profile of a slice as a PNG (`stratum
 * slice --png`, docs/slicing.md "Adaptive layer heights"): Z along the
 * horizontal axis, each layer a step as high as the layer is thick over the
 * Z it spans, the raft's layers grey and the part's blue, dashed lines at
 * the smallest and largest height allowed, axes in mm.  Drawn with cairo
 * (as the previews, pvdraw.h).
 */
#ifndef STRATUM_HOST_LAYERPLOT_H
#define STRATUM_HOST_LAYERPLOT_H

#include <stddef.h>

#include "section.h"
#include "st_error.h"

#define LAYERPLOT_WIDTH 900  /* px */
#define LAYERPLOT_HEIGHT 420 /* px */

/* What to draw besides the layers. */
struct layerplot_opts {
	const char *title;	       /* top line (the model and the mode), may be NULL */
	size_t raft_layers;	       /* the first layers that are the raft's */
	double min_height, max_height; /* mm, the dashed bounds; 0 = not drawn */
};

/*
 * layerplot_write - plot the n layers (tops above the bed, rising) into
 * path through a temporary file renamed on success (path untouched on any
 * error).  Returns 0, ST_ERR_ARG (no layers), ST_ERR_IO naming path,
 * ST_ERR_NOMEM or ST_ERR_INTERNAL (cairo refused).
 */
int layerplot_write(const char *path, const struct layer_span *layers, size_t n,
		    const struct layerplot_opts *o, struct st_error *err);

#endif /* STRATUM_HOST_LAYERPLOT_H */
