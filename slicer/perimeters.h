/*
 * perimeters.h - offset-aware walls of one layer (docs/architecture.md item 4).
 *
 * Flow model: a bead of width w and height h has a rectangle-with-
 * semicircular-ends cross-section, area (w - h) h + pi (h/2)^2, so beads
 * laid side by side at spacing s = w - h (1 - pi/4) fill the layer exactly
 * (s h is that area).  The outer wall's centre line runs exactly w_o/2
 * inside the surface (an erosion with round joins: every centre-line point
 * is at distance w_o/2 from the surface, concave corners included), so the
 * printed face lies on the model surface; the first inner wall runs
 * (s_o + s)/2 inside it, s_o the outer wall's spacing (PrusaSlicer's
 * ext_perimeter_spacing2), and each further one s further in.  With one
 * width for both, wall k runs w/2 + k s inside.
 *
 * A wall loop is kept only where it has room: where two sides of a loop
 * would come closer than s, the loop is cut there.  What the outer loop's
 * beads do not cover (a region too narrow for two walls, a narrow neck) is
 * printed as single centre-line beads along its medial axis, as wide as the
 * region (PATH_THIN_WALL), as long as it is at least the nozzle diameter
 * (epsilon) wide; a piece whose medial axis is only a point (a square or
 * round pillar about epsilon across) gets one short bead through its
 * centre whose flow fills its area.  A thin-wall piece narrower than
 * epsilon that gets no such bead is printed the same way down to
 * min_feature_size, each bead at least min_bead_width wide (perim_generate).
 * Strips left between walls are filled
 * the same way (PATH_GAP_FILL) when at least gap_fill_min wide, each bead
 * h (1 - pi/4) wider than the strip between the walls' spacing edges so
 * that its flow fills it, and as two beads side by side in one loop where
 * that is at least 1.5 spacings (emit_gap_fill); a strip
 * narrower than that (and than the layer height) is shared out to the
 * wall beads on its two sides, each widened by half its width and moved
 * by half of that towards it (beadwidth.h), so a 1.0 mm wall prints one
 * loop of (T + h (1 - pi/4)) / 2 wide beads.  Inside the last wall, an
 * infill piece narrower than a spacing everywhere (a 2 mm wall's middle)
 * is taken up by that wall's beads the same way and left out of the
 * infill: a 2 mm wall prints 0.45 and 0.614 mm beads, as Arachne does.
 * Centre-line beads are cut
 * into pieces of constant width as wide as the region at their middles;
 * a thin wall at least 1.5 outer spacings wide all along prints as two
 * such beads in one loop (emit_thin).
 *
 * All lengths in settings are mm; geometry is in nm (toolpath.h).
 */
#ifndef STRATUM_SLICER_PERIMETERS_H
#define STRATUM_SLICER_PERIMETERS_H

#include <stdbool.h>
#include <stddef.h>

#include "clip.h"
#include "st_error.h"
#include "toolpath.h"

/* Where each closed wall starts (and ends). */
enum perim_seam {
	PERIM_SEAM_ALIGNED = 0, /* near the previous layer's seams */
	PERIM_SEAM_NEAREST,	/* nearest to where the nozzle is */
	PERIM_SEAM_RANDOM,	/* anywhere (spreads the seam blobs) */
	PERIM_SEAM_REAR,	/* at the back: largest y, then smallest x */
	PERIM_SEAMS
};

/*
 * perim_seam_parse - the mode of PrusaSlicer's seam_position name
 * ("aligned", "nearest", "random", "rear").  Returns 0, or ST_ERR_ARG naming
 * the value and the accepted ones.
 */
int perim_seam_parse(const char *name, enum perim_seam *out, struct st_error *err);

/* Wall settings; perim_settings_init gives the defaults. */
struct perim_settings {
	double nozzle_diameter; /* mm; also epsilon, the narrowest feature printed (0.4) */
	double extrusion_width; /* mm, bead width w of the inner walls (1.125 x nozzle) */
	double external_extrusion_width; /* mm, the outer wall's w_o; 0 = extrusion_width (0) */
	int perimeters;		/* walls per island, >= 0 (2) */
	bool outer_first;	/* print the outer wall first (false: inner to outer) */
	enum perim_seam seam;	/* seam placement (PERIM_SEAM_ALIGNED); concave corners
				 * first, then convex corners, in every mode */
	bool thin_walls;	/* centre-line beads in regions too narrow for walls (true) */
	bool gap_fill;		/* beads in strips left between walls (true) */
	double gap_fill_min;	/* mm; narrower strips stay empty (0.1; never below
				 * the layer height, the flow model's narrowest bead) */
	double min_feature_size; /* mm; a thin wall narrower than the nozzle but at least
				  * this wide still prints (0.25 x nozzle; 0: down to
				  * 10 um) */
	double min_bead_width;	/* mm; such a wall's bead is at least this wide, and at
				 * least the layer height (0.85 x nozzle) */
	double transition_length; /* mm; a loop's two sides join the centre-line bead
				   * beyond its tip over this run (the nozzle) */
	double transition_angle;  /* degrees; a wedge blunter than this gets no join
				   * (10) */
	double arc_tolerance;	/* mm; chord error of rounded offsets (0.002) */
};

/* What one layer's thin walls left out or printed wider than the model. */
struct perim_thin {
	size_t dropped;	 /* islands narrower than min_feature_size, not printed */
	size_t widened;	 /* thin-wall beads widened to min_bead_width */
	double designed; /* mm, the narrowest widened feature's width */
	double printed;	 /* mm, the width its bead prints at */
};

/*
 * Seam memory across layers (opaque): the previous layer's seams for
 * PERIM_SEAM_ALIGNED, the nozzle position for PERIM_SEAM_NEAREST and the
 * random generator for PERIM_SEAM_RANDOM.  One per print; feed it the
 * layers bottom to top.  Not thread-safe.
 */
struct perim_seams;

/* perim_settings_init - defaults for a nozzle of nozzle_diameter mm. */
void perim_settings_init(struct perim_settings *s, double nozzle_diameter);

/*
 * perim_settings_check - refuse settings that cannot make walls for layers
 * layer_height mm thick: a layer thicker than the nozzle, a negative
 * perimeter count, a width <= 0 or narrower than the layer, a bad seam
 * mode, tolerances out of range.  Returns 0 or ST_ERR_ARG / ST_ERR_RANGE
 * with a message naming the setting, its value and what is allowed.
 */
int perim_settings_check(const struct perim_settings *s, double layer_height,
			 struct st_error *err);

/* perim_outer_width - the outer wall's bead width w_o, mm. */
double perim_outer_width(const struct perim_settings *s);

/* perim_spacing - centre distance of adjacent beads, mm: w - h (1 - pi/4). */
double perim_spacing(double width, double height);

/* perim_bead_area - cross-section of a bead, mm^2: (w - h) h + pi (h/2)^2. */
double perim_bead_area(double width, double height);

/*
 * perim_round_bead - the bead width whose cross-section at height h equals
 * a round thread of diameter d (bridge flow), at least h, mm.
 */
double perim_round_bead(double d, double height);

/*
 * perim_seams_new - seam memory seeded for PERIM_SEAM_RANDOM (the same seed
 * gives the same seams).  NULL when out of memory.
 */
struct perim_seams *perim_seams_new(unsigned seed);

/* perim_seams_free - NULL is safe. */
void perim_seams_free(struct perim_seams *sm);

/*
 * perim_generate - walls of one layer.
 *   region: the layer's solid regions (slice_layer.regions), nm.
 *   layer_height: mm, the bead height h.
 *   seams: seam memory (may be NULL: no memory across layers, seed 0).
 *   out: paths are appended in printing order, per island: the walls
 *        (inner to outer unless outer_first) as closed loops of width w_o
 *        (the outer) and w (the inner), wider beside a strip they absorb,
 *        with roles PATH_INNER_PERIMETER / PATH_OUTER_PERIMETER, then gap
 *        fill, then thin walls (open or closed, width per point).
 *   infill: replaced by the region left inside the innermost walls for
 *        infill (each wall counted as its flow-equivalent band of its
 *        spacing, so with one width its inner edge is w/2 + (N - 1/2) s
 *        inside the surface).
 *   thin: may be NULL; else set to what this layer's thin walls dropped
 *        or widened.  A piece the nozzle-wide thin walls leave empty is
 *        printed along its centre line where at least min_feature_size
 *        wide, each bead max(local width, min_bead_width) wide; an island
 *        with no wall, no bead and narrower than that is dropped.
 * Returns 0 or a negative class with err filled (bad settings, ST_ERR_NOMEM,
 * ST_ERR_INTERNAL); on error out may hold some of this layer's paths.
 */
int perim_generate(const struct perim_settings *s, const struct clip_expolys *region,
		   double layer_height, struct perim_seams *seams, struct layer_paths *out,
		   struct clip_expolys *infill, struct perim_thin *thin, struct st_error *err);

#endif /* STRATUM_SLICER_PERIMETERS_H */
