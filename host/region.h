/*
 * region.h - the slicer's "Done when" check (issue 5): does the region a
 * G-code file prints match the model's cross-sections?
 *
 * Reading (region_read): any Marlin-flavour G-code file, through our own
 * parser and its move walker (gcwalk.h: G90/G91, M82/M83, G92 tracked).
 * Every extruding move (E increases while X/Y move) is a bead whose width
 * follows from the flow model of perimeters.h: the filament volume per mm
 * of move is the bead cross-section (w - h) h + pi (h/2)^2, solved for w,
 * with h the layer height (this layer's Z minus the previous one's).  The
 * beads, swept with round joins and ends (clip_sweep), are united into the
 * layer's printed region.  Only the part counts: moves under the feature
 * comments ";TYPE:Skirt/Brim" (and Skirt, Brim), ";TYPE:Support material*",
 * ";TYPE:Wipe tower", ";TYPE:Custom", and moves before the first ;TYPE:
 * comment (start G-code, prime lines) are skipped.  Stratum and PrusaSlicer
 * both write these comments.
 *
 * Comparing (region_compare): the model is placed as the slicers place it
 * (bounding-box centre on a given point or on the printed part's centre,
 * lowest point at z = 0) and cut (section.h) at each printed layer's
 * mid-height.  Per layer:
 *  - the envelope is the printed region with its interior voids filled:
 *    a hole of the printed region is a void when more than half of it lies
 *    inside the cross-section (sparse infill gaps); holes that follow the
 *    model's holes stay holes;
 *  - outer deviation: the distance from points every sample_step along the
 *    envelope's boundary to the cross-section's boundary, and from points
 *    along the cross-section's boundary to the envelope's boundary (both
 *    directions pooled into one distribution);
 *  - area error: area(envelope XOR section) / area(section), summed over
 *    the layers; area_error_raw counts the voids too (printed XOR section);
 *  - gap: area(section minus printed) / area(section), the model's area no
 *    bead covers (sparse infill's gaps count);
 *  - overlap: the area two or more runs of extrusion (moves joined end to
 *    start) both cover, / area(section): each run swept alone, the areas
 *    summed, minus the union.  Beads side by side at the flow model's
 *    spacing overlap by h (1 - pi/4) by design (their round edges).
 *
 * Units: mm in every field and setting; nm inside the clip containers.
 * Thread-safety: no shared state.
 */
#ifndef STRATUM_SLICER_REGION_H
#define STRATUM_SLICER_REGION_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "clip.h"
#include "mesh.h"
#include "st_error.h"

/* Settings of a check; region_opts_init gives the defaults. */
struct region_opts {
	double filament_diameter; /* mm; 0 = take it from the file's
				   * "; filament_diameter = " comment (0) */
	double arc_tolerance;	  /* mm, chord error of the swept beads' arcs (0.001) */
	double sample_step;	  /* mm, spacing of boundary samples (0.01) */
	bool has_center;	  /* place the model's bounding-box centre at center_x/y;
				   * false: at the printed part's bounding-box centre */
	double center_x, center_y; /* mm */
};

/* One printed layer. */
struct region_layer {
	double z;		  /* mm, the nozzle height of the layer's beads */
	double height;		  /* mm, z minus the previous layer's z (z for the first) */
	size_t beads;		  /* extruding moves of the part */
	struct clip_paths printed; /* union of the beads, nm: outer CCW, holes CW */
	double runs_mm2;	  /* sum over the runs (moves joined end to start) of
				   * each run's own swept area */
};

/* The part as printed by one G-code file. */
struct region_print {
	size_t n;		   /* layers, bottom to top */
	struct region_layer *layers;
	double filament_diameter;  /* mm, as used */
	size_t beads;		   /* extruding moves counted */
	size_t skipped;		   /* extruding moves skipped (skirt, support, custom) */
	double min[2], max[2];	   /* mm, bounding box of the counted beads' centre lines */
	double width_min, width_max; /* mm, narrowest and widest bead */
};

/* One compared layer. */
struct region_layer_result {
	double z, height;      /* mm, as in region_layer */
	double section_mm2;    /* area of the model's cross-section */
	double envelope_mm2;   /* area of the envelope (printed, voids filled) */
	double xor_mm2;	       /* area(envelope XOR section) */
	double xor_raw_mm2;    /* area(printed XOR section) */
	double dev_max;	       /* mm, largest boundary distance in this layer */
	double gap_mm2;	       /* area(section minus printed): the model no bead covers */
	double overlap_mm2;    /* area under two or more runs: the runs' own areas
				* summed minus their union */
};

/* The answer. */
struct region_report {
	size_t layers;	       /* layers compared */
	size_t empty_sections; /* printed layers where the model has no cross-section */
	double offset[3];      /* mm added to the model to place it */
	double dev_p95, dev_max;	 /* mm, both directions pooled */
	double dev_p95_printed;		 /* mm, envelope -> section only */
	double dev_p95_model;		 /* mm, section -> envelope only */
	double outside_max;		 /* mm, farthest envelope point outside the model */
	double inside_max;		 /* mm, farthest envelope point inside the model */
	size_t samples;			 /* boundary points measured */
	double area_error;		 /* sum xor / sum section */
	double area_error_raw;		 /* sum xor_raw / sum section */
	double layer_area_error_max;	 /* largest per-layer xor / section */
	double gap;			 /* sum gap_mm2 / sum section */
	double overlap;			 /* sum overlap_mm2 / sum section */
	struct region_layer_result *per_layer; /* layers entries */
};

/* region_opts_init - the defaults named in struct region_opts. */
void region_opts_init(struct region_opts *o);

/*
 * region_read - the printed region of the G-code file at path, layer by
 * layer.  o may be NULL for the defaults.  On success *out is new
 * (region_print_free) and 0 is returned.  Errors (*out NULL, err filled
 * with the file name and line): ST_ERR_IO (cannot open or read),
 * ST_ERR_PARSE (a line our parser refuses, no filament diameter known),
 * ST_ERR_UNSUPPORTED (G20 inches), ST_ERR_RANGE
 * (coordinates beyond +-1e6 mm, nothing of the part extruded),
 * ST_ERR_NOMEM.
 */
int region_read(const char *path, const struct region_opts *o, struct region_print **out,
		struct st_error *err);

/* region_print_free - free what region_read made; NULL is safe. */
void region_print_free(struct region_print *p);

/*
 * region_compare - compare p with the cross-sections of mesh m (mm, closed,
 * as given to the slicer; not modified).  o may be NULL.  On success *out
 * is new (region_report_free).  Errors: ST_ERR_ARG (empty mesh or print),
 * ST_ERR_NOMEM, ST_ERR_INTERNAL, and those of slice_plane / clip.
 */
int region_compare(const struct mesh *m, const struct region_print *p,
		   const struct region_opts *o, struct region_report **out, struct st_error *err);

/*
 * region_place - where region_compare puts the model: the offset (mm) added
 * to m's coordinates so that its bounding-box centre lies on o's center
 * (has_center) or else on the centre of the box pmin..pmax (mm, the
 * printed part's: struct region_print min/max), and its lowest point on
 * z = 0.  o may be NULL (no center).  m must have vertices.
 */
void region_place(const struct mesh *m, const struct region_opts *o, const double pmin[2],
		  const double pmax[2], double offset[3]);

/* region_report_free - NULL is safe. */
void region_report_free(struct region_report *r);

/*
 * region_section - the cross-section of m at mesh height zm (mm), moved by
 * (dx, dy) nm, as regions (outer CCW, holes CW) in sec.  Returns 0 or the
 * errors of slice_plane / clip.
 */
int region_section(const struct mesh *m, double zm, int64_t dx, int64_t dy,
		   struct clip_paths *sec, struct st_error *err);

/*
 * The support a G-code file prints (region_support.c): the moves under
 * ";TYPE:Support material" (and "... interface"), swept like the part's
 * beads, on the part's layers (same Z), against m placed as region_compare
 * places it (offset from region_place) and cut at each layer's mid-height:
 *  - inside: the area of support beads inside the cross-section;
 *  - overhangs: on layer i >= 1, O_i = section_i minus section_{i-1} grown
 *    by h_i / tan(threshold), what reaches out flatter than the threshold;
 *    a point of O_i is supported when it lies within reach of support
 *    printed under layer i's bottom, on the layers from just below it down
 *    to the first one at least gap below it.
 */
struct region_support_report {
	size_t layers;		/* printed layers checked */
	size_t beads;		/* support moves swept */
	size_t stray;		/* support moves on no layer of the part (a raft) */
	double inside_mm2;	/* support inside the model */
	double overhang_mm2;	/* O_i summed over the layers */
	double unsupported_mm2; /* of it, not within reach of support */
	double worst_z;		/* mm, the layer with the most unsupported area (0: none) */
};

/*
 * region_support_check - read the support of the G-code file at path (the
 * file p was read from) and check it against m as above.  threshold_deg in
 * (0, 90), gap (the top contact distance) and reach >= 0, mm.  Returns 0
 * with *out filled, or ST_ERR_ARG (bad arguments), the errors of
 * region_read, region_section and clip.
 */
int region_support_check(const char *path, const struct mesh *m, const struct region_print *p,
			 const struct region_opts *o, double threshold_deg, double gap,
			 double reach, struct region_support_report *out, struct st_error *err);

/*
 * region_bead_width - the width (mm) of a bead of height h (mm) whose
 * cross-section is area (mm^2): (area - pi h^2 / 4) / h + h, or a round bead
 * of that area when it is smaller than pi h^2 / 4 (narrower than high).
 * 0 for area <= 0 or h <= 0.
 */
double region_bead_width(double area, double h);

#endif /* STRATUM_SLICER_REGION_H */
