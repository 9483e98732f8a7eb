/*
 * infill.h - skins, bridges and infill inside the walls (docs/architecture.md item 4;
 * slicer issue items 5 and 6).
 *
 * Classification, per layer i, of the region left inside the walls (R_i,
 * from perim_generate) against the layers' solid regions S_j
 * (slice_layer.regions):
 *   - shells are counted by thickness: a layer belongs to the top shell of
 *     a top surface on layer j when its top lies less than T_top below
 *     layer j's top, T_top = max(top_solid_min_thickness, top_solid_layers
 *     x layer_height) (likewise down from a bottom surface with T_bottom),
 *     so 3 layers of 0.2 mm make a 0.6 mm shell that is 6 layers of 0.1 mm
 *     where layers are thinner;
 *   - top skin: R_i not covered by every S_j above within the top shell;
 *   - bridge: on layers above the first, R_i not over S_(i-1), grown by
 *     the anchor margin (3 solid widths) into the supported area;
 *   - bottom skin: the bottom shell resting on the bed (all of layer 0);
 *   - internal solid infill: the bottom shell above bridges, regions of
 *     sparse infill smaller than solid_infill_below_area, and everything
 *     sparse when fill_density is 100 %;
 *   - sparse infill: the rest, at fill_density.
 * Where classes overlap: bridge, then bottom skin on layer 0, then top
 * skin, then bottom skin, then internal solid.
 *
 * Lines: solid lines are spaced at the flow-model spacing of their width
 * at the layer's height (perim_spacing), adjusted per island so a whole
 * number of beads spans it; direction fill_angle, turned 90 degrees on
 * every other layer.  Sparse lines are spaced spacing / density and
 * anchored to the bed (rectilinear alternates like solid; grid lays both
 * directions on every layer at twice the spacing; gyroid samples the
 * gyroid's section at the layer's mid-height; line alternates like
 * rectilinear, each line its own path, every other line tilted as
 * PrusaSlicer's; concentric loops from the region's edge inward, outermost
 * first; honeycomb hexagons sized so the lines' length is the density's).  Bridges use bridge flow: a
 * round thread of diameter nozzle x sqrt(bridge_flow_ratio) (its bead width
 * is the one whose flow-model cross-section equals that thread's area) at
 * thread + 0.05 mm spacing (with thick_bridges off: solid infill beads at
 * their spacing, the cross-section times bridge_flow_ratio, PrusaSlicer's
 * flat bridges), in the direction (tried every 5 degrees) that
 * anchors most of its lines on the layer below at both ends, the shortest
 * such lines first (bridge_angle overrides).  Line ends stop half a spacing inside the
 * region grown by infill_overlap, so beads reach into the innermost wall.
 * Strips of a solid island that its lines leave uncovered, at least
 * gap_fill_min wide, get PATH_GAP_FILL beads along their centre lines; an
 * island narrower than its line spacing everywhere gets no lines, only
 * such beads (lines across it would leave voids between them).
 *
 * Lengths in settings are mm, geometry nm (toolpath.h).
 */
#ifndef STRATUM_SLICER_INFILL_H
#define STRATUM_SLICER_INFILL_H

#include <stdbool.h>

#include "clip.h"
#include "ironing.h"
#include "section.h"
#include "st_error.h"
#include "toolpath.h"

/* Sparse infill patterns (PrusaSlicer's fill_pattern names). */
enum infill_pattern {
	INFILL_RECTILINEAR = 0, /* "rectilinear": parallel lines, alternating 90 degrees */
	INFILL_GRID,		/* "grid": both directions on every layer */
	INFILL_GYROID,		/* "gyroid": sections of the gyroid surface */
	INFILL_TRIANGLES,	/* "triangles": 3 line sets 60 degrees apart, through common points */
	INFILL_STARS,		/* "stars": the same, the third set shifted half a period */
	INFILL_CUBIC,		/* "cubic": the 3 sets shifted with z, stacking into cubes */
	INFILL_LINE,		/* "line": parallel lines, every other one tilted */
	INFILL_CONCENTRIC,	/* "concentric": closed loops offset inward from the region */
	INFILL_HONEYCOMB,	/* "honeycomb": hexagons of zig-zag lines, turned 60 degrees a layer */
	INFILL_PATTERNS
};

/* Infill settings (PrusaSlicer keys); infill_settings_init gives the defaults. */
struct infill_settings {
	double nozzle_diameter;		   /* mm (0.4) */
	double fill_density;		   /* percent, 0..100; 100 = solid (20) */
	enum infill_pattern fill_pattern;  /* sparse pattern (INFILL_GRID) */
	double fill_angle;		   /* degrees, direction of lines (45) */
	double bridge_angle;		   /* degrees; 0 = detect per bridge (0) */
	int top_solid_layers;		   /* >= 0 (3) */
	int bottom_solid_layers;	   /* >= 0 (3) */
	double top_solid_min_thickness;	   /* mm, >= 0 (0) */
	double bottom_solid_min_thickness; /* mm, >= 0 (0) */
	double layer_height;		   /* mm, the height shell counts refer to;
					    * 0 = the stack's most common height (0) */
	double perimeter_extrusion_width;  /* mm, the walls' width (1.125 x nozzle) */
	double infill_extrusion_width;	   /* mm, sparse lines (1.125 x nozzle) */
	double solid_infill_extrusion_width; /* mm, bottom/internal solid (1.125 x nozzle) */
	double top_infill_extrusion_width; /* mm, top skin (1.125 x nozzle) */
	double first_layer_extrusion_width; /* mm, every class on layer 0; 0 = their own (0) */
	double infill_overlap;		   /* percent of the perimeter width the
					    * infill reaches into the walls (25) */
	double solid_infill_below_area;	   /* mm^2; smaller sparse islands are solid (70) */
	double bridge_flow_ratio;	   /* bridge thread area / nozzle area (1) */
	bool thick_bridges;		   /* round threads, else flat beads (true) */
	/* top / bottom skin lines in one sweep across each island, each from
	 * the end nearer the last (PrusaSlicer's monotonic), else nearest
	 * first (false) */
	bool top_monotonic, bottom_monotonic;
	/* mm: sparse line ends joined along the boundary up to max apart, the
	 * others anchored (anchors.h); max 0 = neither (0, 0) */
	double infill_anchor, infill_anchor_max;
	double gap_fill_min;		   /* mm; narrower gaps stay empty (0.1) */
	bool ironing;			   /* iron after the top skin (ironing.h; false) */
	enum iron_type ironing_type;	   /* what is ironed (IRON_TOP) */
	double ironing_spacing;		   /* mm between ironing lines (0.1) */
};

/* infill_settings_init - the defaults above for a nozzle of nozzle_diameter mm. */
void infill_settings_init(struct infill_settings *s, double nozzle_diameter);

/*
 * infill_pattern_parse - the pattern called name (PrusaSlicer's fill_pattern
 * value, e.g. "gyroid") into *out.  Returns 0, ST_ERR_UNSUPPORTED for a
 * PrusaSlicer pattern Stratum does not print, ST_ERR_ARG for an unknown
 * name; the message lists the patterns that work.
 */
int infill_pattern_parse(const char *name, enum infill_pattern *out, struct st_error *err);

/* infill_pattern_name - PrusaSlicer's name of p ("rectilinear", ...). */
const char *infill_pattern_name(enum infill_pattern p);

/*
 * infill_settings_check - refuse settings that cannot make infill: density
 * outside 0..100, a bad pattern, negative layer counts or thicknesses,
 * widths <= 0 or beyond 4 x the nozzle, overlap outside 0..100 %, a bridge
 * flow ratio outside (0, 2].  Returns 0 or ST_ERR_ARG / ST_ERR_RANGE with a
 * message naming the setting, its value and what is allowed.
 */
int infill_settings_check(const struct infill_settings *s, struct st_error *err);

/*
 * infill_generate - skins, bridges, solid and sparse infill of every layer.
 *   st: the sliced layers (regions, z, height), bottom to top.
 *   inner: st->n regions, inner[i] the region inside the walls of layer i
 *     (perim_generate's infill output).
 *   out: st->n layers (z and height set by the caller, walls possibly
 *     already there); infill paths are appended, per layer in the order
 *     bottom skin, bridges, internal solid, gap fill, sparse, top skin,
 *     then with ironing the PATH_IRONING lines (ironing.h, ironing_spacing
 *     wide) at the top skin's angle plus 45 degrees, each class ordered
 *     nearest-neighbour.
 * Layers thicker than the nozzle or not above 0 are refused.  Returns 0 or
 * a negative class with err filled (bad settings, mismatched sizes,
 * ST_ERR_NOMEM, ST_ERR_INTERNAL); on error out may hold some paths.
 */
int infill_generate(const struct infill_settings *s, const struct slice_stack *st,
		    const struct clip_expolys *inner, struct layer_stack *out,
		    struct st_error *err);

/*
 * The same work a layer at a time, for callers that fill layers in
 * parallel and print them as they come.  A layer is first planned (its
 * classes, lines and gap fill; independent of every other layer's plan, so
 * plans may be made on several threads at once) and then emitted: the
 * lines are ordered nearest first from where the previous emitted layer's
 * infill ended, so layers must be emitted bottom to top, one at a time.
 * Planning and emitting every layer gives exactly infill_generate's paths.
 */
struct infill_job;
struct infill_plan;

/*
 * infill_job_new - check s and the layers of st (as infill_generate does)
 * and work out the shell thicknesses.  st must outlive the job.  Returns 0
 * with *out a new job (infill_job_free), or a negative class with err
 * filled and *out NULL.
 */
int infill_job_new(const struct infill_settings *s, const struct slice_stack *st,
		   struct infill_job **out, struct st_error *err);

/* infill_job_free - release a job; NULL is safe. */
void infill_job_free(struct infill_job *job);

/*
 * infill_plan_layer - plan layer i (< st->n) of the job, inner being the
 * region inside that layer's walls.  Reads the job and the slices only:
 * thread-safe for distinct plans.  Returns 0 with *out a new plan
 * (infill_plan_free), or a negative class with err filled and *out NULL.
 */
int infill_plan_layer(const struct infill_job *job, size_t i, const struct clip_expolys *inner,
		      struct infill_plan **out, struct st_error *err);

/*
 * infill_emit_layer - append the paths of plan to out, in infill_generate's
 * order; advances the job's nozzle position.  Returns 0, ST_ERR_NOMEM or
 * the error of a path layer_add_path refuses.
 */
int infill_emit_layer(struct infill_job *job, const struct infill_plan *plan,
		      struct layer_paths *out, struct st_error *err);

/* infill_plan_free - release a plan; NULL is safe. */
void infill_plan_free(struct infill_plan *p);

#endif /* STRATUM_SLICER_INFILL_H */
