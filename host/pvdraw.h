/*
 * pvdraw.h - draw a layer preview (preview.h) as SVG or PNG.
 *
 * The picture: a title line (what layer of what file), the layer seen from
 * above with +Y up, each bead stroked at its own width in mm with round
 * ends and joins (so the picture shows the printed plastic, gaps and
 * overlaps included), one colour per feature, travels thin and dashed on
 * top, the model's section outline in black on top of everything, then a
 * legend (only the features present, with their path counts) and a scale
 * bar in mm.  The frame is the file's printed area, the same for every
 * layer, so pictures of different layers line up.
 *
 * SVG is written by hand: one <g id="FEATURE"> per feature present
 * (preview_feature_id; the outline is <g id="model-outline">) holding one
 * <path> per preview path in G-code millimetres under one transform, so
 * the file can be read, measured and tested.  Legend and scale bar use
 * <rect>, <line> and <text> only.  PNG goes through cairo (anti-aliased
 * strokes of a given width, text, the PNG encoder).
 *
 * Thread-safety: none shared.
 */
#ifndef STRATUM_HOST_PVDRAW_H
#define STRATUM_HOST_PVDRAW_H

#include <stdbool.h>
#include <stdio.h>

#include "preview.h"
#include "st_error.h"

#define PVDRAW_WIDTH_DEFAULT 1000 /* px */
#define PVDRAW_WIDTH_MIN 200	  /* px: room for the legend */
#define PVDRAW_WIDTH_MAX 8192	  /* px */

enum pvdraw_format {
	PVDRAW_SVG,
	PVDRAW_PNG,
};

/* How to draw. */
struct pvdraw_opts {
	int width_px;	   /* PVDRAW_WIDTH_MIN..MAX; the height follows the frame */
	const char *title; /* text after the layer line (the file name), may be NULL */
};

/* pvdraw_format_of - true and *f set when path ends in .svg or .png (any case). */
bool pvdraw_format_of(const char *path, enum pvdraw_format *f);

/*
 * pvdraw_size - the picture's width and height in px for pv and o.
 * Returns 0 or ST_ERR_ARG (width out of range, empty frame).
 */
int pvdraw_size(const struct preview *pv, const struct pvdraw_opts *o, int *w, int *h,
		struct st_error *err);

/*
 * pvdraw_to_px - where the point (x, y) mm lands in the picture, px from
 * the top left corner.  Returns 0 or ST_ERR_ARG as pvdraw_size.
 */
int pvdraw_to_px(const struct preview *pv, const struct pvdraw_opts *o, double x, double y,
		 double *px, double *py, struct st_error *err);

/*
 * pvdraw_write - write the picture to path in the format its extension
 * names, through a temporary file beside it renamed over path on success
 * (path is untouched on any error).  Returns 0, ST_ERR_ARG (as pvdraw_size,
 * or an extension other than .svg or .png), ST_ERR_IO naming path,
 * ST_ERR_NOMEM or ST_ERR_INTERNAL (cairo refused).
 */
int pvdraw_write(const struct preview *pv, const struct pvdraw_opts *o, const char *path,
		 struct st_error *err);

#endif /* STRATUM_HOST_PVDRAW_H */
