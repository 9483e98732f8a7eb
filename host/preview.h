/*
 * preview.h - one layer of a G-code file as drawable paths, for
 * `stratum preview` and `stratum print --preview` (pvdraw.h draws them).
 *
 * Layers: when the file has layer comments (gcode_layer_comment: Stratum,
 * PrusaSlicer, Cura, Simplify3D), layer N is the span after the N-th layer
 * comment, its Z the comment's (";Z:", "; layer n, Z = z") or else the Z
 * of its first bead; moves before the first comment (start G-code, prime
 * lines) belong to no layer.  Without layer comments the layers are the
 * distinct Zs of the extruding moves (as region.h reads them), and a move
 * belongs to the layer whose Z it goes to (a Z hop stays in its layer).
 *
 * Every extruding move (E grows while X/Y move) of the layer is a bead of
 * the feature its ";TYPE:" comment names, as wide as its filament volume
 * makes it under the flow model (region_bead_width) with the layer's
 * height (";HEIGHT:" or the Z step from the layer below); every other X/Y
 * move is a travel.  Consecutive moves that join end to start with the
 * same feature and a width within PREVIEW_WIDTH_JOIN become one path.
 *
 * With a model, its cross-section at the layer's mid-height is placed as
 * region_compare places it (region_place: bounding-box centre on the given
 * centre, or else on the printed part's, lowest point on the bed).
 *
 * Units: mm, G-code coordinates.  Thread-safety: no shared state.
 */
#ifndef STRATUM_HOST_PREVIEW_H
#define STRATUM_HOST_PREVIEW_H

#include <stdbool.h>
#include <stddef.h>

#include "mesh.h"
#include "st_error.h"

/* Widths within this fraction of a path's first bead extend the path. */
#define PREVIEW_WIDTH_JOIN 0.05

/* What a path is, in drawing order (bottom first). */
enum preview_feature {
	PREVIEW_SKIRT = 0,	 /* Skirt/Brim, Skirt, Brim */
	PREVIEW_SUPPORT,	 /* Support material (interface included) */
	PREVIEW_INFILL,		 /* Internal infill */
	PREVIEW_SKIN,		 /* Solid, Top solid, Bottom solid infill, Ironing */
	PREVIEW_BRIDGE,		 /* Bridge infill */
	PREVIEW_THIN,		 /* Gap fill, Thin wall */
	PREVIEW_INNER_PERIMETER, /* Perimeter */
	PREVIEW_OUTER_PERIMETER, /* External perimeter, Overhang perimeter */
	PREVIEW_OTHER,		 /* Custom, Wipe tower, unknown or no ;TYPE: */
	PREVIEW_TRAVEL,		 /* moves that do not extrude */
	PREVIEW_FEATURES
};

/* One polyline. */
struct preview_path {
	enum preview_feature feature;
	double width;  /* mm, length-weighted mean bead width; 0 for travel and outline */
	bool closed;   /* last point equals the first (the point is not repeated) */
	size_t n;      /* points */
	double *xy;    /* x0 y0 x1 y1 ... mm */
};

/* What to show; preview_opts_init gives the defaults. */
struct preview_opts {
	long layer;		  /* from 1; 0 = choose by z */
	double z;		  /* mm: the layer printed at this height (layer == 0) */
	double filament_diameter; /* mm; 0 = the file's "; filament_diameter =" (0) */
	bool has_center;	  /* model centre given (else the printed part's centre) */
	double center_x, center_y; /* mm */
};

/* The chosen layer. */
struct preview {
	size_t layer;	       /* shown layer, from 1 */
	size_t layers;	       /* layers in the file */
	bool by_comments;      /* layers from comments (else by Z) */
	double z, height;      /* mm, the shown layer's */
	double filament_diameter; /* mm, as used */
	size_t n;	       /* paths, in file order */
	struct preview_path *paths;
	size_t count[PREVIEW_FEATURES]; /* paths per feature */
	size_t noutline;	      /* model section loops (preview_add_model) */
	struct preview_path *outline; /* closed, feature PREVIEW_OTHER, width 0 */
	bool has_model;		      /* preview_add_model was called */
	double min[2], max[2]; /* mm: every bead of the file (all layers) and the outline,
				* widths included: the frame, alike for every layer */
	double part_min[2], part_max[2]; /* mm, bead centre lines of the part (no
					  * skirt, support or other) over all layers */
	double model_offset[3]; /* mm added to the model's coordinates */
};

/* preview_opts_init - the defaults named in struct preview_opts (layer 1). */
void preview_opts_init(struct preview_opts *o);

/*
 * preview_load - read the G-code file at path (two passes: the layer table,
 * then the chosen layer's moves).  On success *out is new (preview_free).
 * Errors (*out NULL): ST_ERR_ARG (no such layer or no layer at that Z: the
 * message gives the file's range), ST_ERR_IO, ST_ERR_PARSE (a bad line,
 * no filament diameter known, an arc without its centre), ST_ERR_RANGE
 * (nothing extruded), ST_ERR_UNSUPPORTED (G20), ST_ERR_NOMEM.
 */
int preview_load(const char *path, const struct preview_opts *o, struct preview **out,
		 struct st_error *err);

/*
 * preview_add_model - the cross-section of m (mm, as given to the slicer)
 * at the shown layer's mid-height, placed as region_place does, into
 * pv->outline; the frame grows to hold it.  o as given to preview_load
 * (centre).  An empty section is not an error (noutline 0).  Errors:
 * ST_ERR_ARG (empty mesh), ST_ERR_NOMEM, those of slice_plane.
 */
int preview_add_model(struct preview *pv, const struct mesh *m, const struct preview_opts *o,
		      struct st_error *err);

/* preview_free - NULL is safe. */
void preview_free(struct preview *pv);

/* preview_feature_name - legend text, "outer perimeter" ... "travel". */
const char *preview_feature_name(enum preview_feature f);

/* preview_feature_id - stable identifier, "outer-perimeter" ... "travel"
 * (the SVG group ids). */
const char *preview_feature_id(enum preview_feature f);

#endif /* STRATUM_HOST_PREVIEW_H */
