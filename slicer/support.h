/*
 * support.h - support material under overhangs (slicer issue item 6).
 *
 * Overhangs: layer i (i >= 1) overhangs where its regions reach more than
 * d beyond layer i-1's: O_i = M_i - (M_{i-1} grown by d).  With a threshold
 * angle a (degrees from horizontal; a surface flatter than a needs
 * support), d = h_{i-1} / tan(a + 1 deg), the extra degree as PrusaSlicer
 * adds it so a slope of exactly a prints unsupported (capped at 89 deg).
 * With threshold 0 (automatic) d is half the extrusion width, PrusaSlicer's
 * automatic rule: a bead that sits less than half on the layer below
 * needs support.  Where O_i is not empty, the contact area is the whole
 * unsupported strip around it, C_i = (M_i - M_{i-1}) within d + w of O_i,
 * so the strips of a slope close up across layers.
 *
 * Bridges (dont_support_bridges, support_bridge.c): the part of C_i that
 * lines resting on layer i-1 at both ends cross is no contact; only
 * threads with a free end are held up.
 *
 * Columns: the contact area of layer i starts at the top support layer
 * t(i), the highest layer whose top is at most
 * support_material_contact_distance below the bottom of layer i (the
 * interface gap; 0 puts the support right under the overhang).  Gaps are
 * whole layers, as support shares the part's layers.  Going down:
 *   on the model (support_material_buildplate_only off, PrusaSlicer's
 *     default): a column stops where it meets B_j, the model on the layers
 *     k <= j whose top lies less than the bottom gap under layer j's bottom
 *     (support_material_bottom_contact_distance, 0 = the top gap; no gap
 *     when the top gap is 0, as PrusaSlicer has it), so it stands on the
 *     model's top surfaces that gap above them; the support area of layer
 *     j is every column passing j minus B_j grown by
 *     support_material_xy_spacing;
 *   buildplate_only: a column stops where it meets the model, and only
 *     support that reaches the bed is kept: the support area of layer j is
 *     every column passing j minus everything the model occupies on layers
 *     0 .. j grown by support_material_xy_spacing.
 *
 * Paths: on layers t(i) - interface_layers + 1 .. t(i) the area under C_i
 * is interface, and so is a column's foot on the model: the area of layer
 * j that B_{j-1} .. B_{j-m} cut off, m the bottom interface layers
 * (support_material_bottom_interface_layers, -1 = interface_layers).
 * Interface is lines support_material_interface_spacing apart edge to edge
 * (0: solid, at the flow spacing of perimeters.h) alternating direction by
 * layer (PATH_SUPPORT_INTERFACE), joined along the area's boundary where
 * the link is at most three lines long, as the body's and the raft's lines
 * are (PrusaSlicer's link_max_length); the rest is body (PATH_SUPPORT), lines
 * support_material_spacing apart edge to edge (a pitch of that plus the
 * flow spacing, as PrusaSlicer reads the key).  Directions are X and Y
 * turned by support_material_angle:
 *   SUPPORT_GRID: the column areas closed by the line spacing (nearby
 *     islands and notches merged into blocks) and filled with a grid of
 *     lines in X and Y;
 *   SUPPORT_SNUG: the column areas as they are, following the overhang
 *     outline, each island wrapped by a loop and filled with lines in Y.
 * Every bead stays inside its area (centre lines w/2 inside), so no bead
 * comes closer than the xy spacing to the model.  Line positions are on a
 * global grid, so lines stack from layer to layer.
 *
 * Lengths in settings are mm; geometry is nm (toolpath.h).
 */
#ifndef STRATUM_SLICER_SUPPORT_H
#define STRATUM_SLICER_SUPPORT_H

#include <stdbool.h>

#include "section.h"
#include "st_error.h"
#include "toolpath.h"

/* Support shape (PrusaSlicer's support_material_style). */
enum support_style {
	SUPPORT_GRID = 0, /* blocks filled with a grid of lines */
	SUPPORT_SNUG,	  /* follows the overhang outline, wrapped by a loop */
	SUPPORT_STYLES
};

/* The body's lines (PrusaSlicer's support_material_pattern). */
enum support_pattern {
	SUPPORT_RECTILINEAR = 0,  /* along the angle on every layer */
	SUPPORT_RECTILINEAR_GRID, /* along the angle and at 90 degrees, layers alternating */
	SUPPORT_HONEYCOMB,	  /* hexagons, as the honeycomb infill */
	SUPPORT_PATTERNS
};

/* Support settings (PrusaSlicer key names); support_settings_init. */
struct support_settings {
	bool support_material;			  /* generate support (false) */
	double support_material_threshold;	  /* degrees from horizontal, [0, 90];
						   * 0 = automatic (0) */
	enum support_style support_material_style; /* SUPPORT_GRID */
	enum support_pattern support_material_pattern; /* SUPPORT_RECTILINEAR */
	bool support_material_with_sheath;	  /* a loop around each body island (true) */
	bool support_material_buildplate_only;	  /* only support standing on the bed (false) */
	double support_material_contact_distance; /* mm, top Z gap, >= 0 (0.2) */
	double support_material_bottom_contact_distance; /* mm, Z gap above the model,
							  * 0 = the top's (0) */
	int support_material_interface_layers;	  /* dense layers under the gap, >= 0 (3) */
	int support_material_bottom_interface_layers; /* on the model; -1 = the top's (-1) */
	double support_material_interface_spacing; /* mm of air between interface lines,
						    * 0 = solid (0) */
	double support_material_spacing;	  /* mm of air between body lines, > 0 (2.5) */
	double support_material_angle;		  /* degrees the lines turn, 0-359 (0) */
	double support_material_xy_spacing;	  /* mm clearance from the model, >= 0
						   * (50 % of the width) */
	bool dont_support_bridges;		  /* no support under bridges (true) */
	double extrusion_width;			  /* mm, support bead width (1.125 x nozzle) */
	double first_layer_extrusion_width;	  /* mm, the beads of the stack's layer 0
						   * (support on the bed, the raft's
						   * first layer); 0 = extrusion_width (0) */
	double arc_tolerance;			  /* mm, chord error of round offsets (0.002) */
	/* The raft (support_raft), in the declared ranges of settings.h */
	int raft_layers;		   /* 0 = no raft (0) */
	double raft_contact_distance;	   /* mm, raft top to the part's bottom (0.1) */
	double raft_expansion;		   /* mm beyond the part's first layer (1.5) */
	double raft_first_layer_density;   /* percent, 10-100 (90) */
	double raft_first_layer_expansion; /* mm, layer 0 reaches this much further (3) */
};

/* support_settings_init - PrusaSlicer's defaults for a nozzle of nozzle_diameter mm. */
void support_settings_init(struct support_settings *s, double nozzle_diameter);

/*
 * support_choice_parse - the index of name among the declared names of
 * key (support_material_style or support_material_pattern: the enums'
 * order) into *out.  Returns 0 or ST_ERR_ARG naming the key, the value and
 * the names allowed.
 */
int support_choice_parse(const char *key, const char *name, int *out, struct st_error *err);

/*
 * support_settings_check - refuse settings that cannot make support: a
 * threshold outside [0, 90] degrees, a negative gap, xy spacing or
 * interface count, a line spacing or width <= 0, a bad style, an arc
 * tolerance outside (0, w/4], a key outside its declared range
 * (settings.h: the raft's, the bottom gap and interface layers, the
 * interface spacing, the angle).  Returns 0 or ST_ERR_ARG / ST_ERR_RANGE with
 * a message naming the setting, its value and what is allowed.
 */
int support_settings_check(const struct support_settings *s, struct st_error *err);

/*
 * support_generate - append the support paths of every layer to out.
 *   st: the sliced model (its regions are M_i).
 *   out: st->n layers (z and height set by the caller); each layer gets
 *        its interface paths, then its body paths.
 * Nothing is added when support_material is off.  Returns 0 or a negative
 * class with err filled (bad settings, a layer count that does not match,
 * a layer width the flow model cannot lay, ST_ERR_NOMEM, ST_ERR_INTERNAL);
 * on error out may hold some paths.  Not thread-safe on one out.
 */
int support_generate(const struct support_settings *s, const struct slice_stack *st,
		     struct layer_stack *out, struct st_error *err);

/*
 * support_beads - out = the area the support beads (PATH_SUPPORT and
 * PATH_SUPPORT_INTERFACE, open or closed) of layer l cover, each bead its
 * width wide with round ends; arc: nm, > 0 (the offsets' arc tolerance).
 * Returns 0 or a negative class with err filled.
 */
int support_beads(const struct layer_paths *l, double arc, struct clip_paths *out,
		  struct st_error *err);

/*
 * The raft (PrusaSlicer's raft_layers), printed on the bed under the part,
 * which is lifted onto it.  Its N = raft_layers layers split as PrusaSlicer
 * splits them: ceil(N/2) interface layers on top, the N - ceil(N/2) below
 * them base layers; the first layer of all is first_layer_height thick, the
 * others max(layer_height, 0.75 nozzle).  The part's first layer starts
 * raft_contact_distance above the raft's top and is layer_height thick
 * (PrusaSlicer's first object layer over a raft).
 *
 * Area: the part's first-layer regions (with the support's first layer,
 * support_beads, when there is support) grown (round joins) by
 * raft_expansion on the raft's top (contact) layer, by 0.5 mm more on the
 * layers under it, and on layer 0 by raft_expansion plus
 * raft_first_layer_expansion (at least plus 0.5 mm); a one-layer raft is
 * its contact layer.  Paths: lines
 * alternating X (even layers) and Y (odd layers), centre lines w/2 inside
 * the area, on the global grid of the support; layer 0 at
 * raft_first_layer_density of the flow spacing (PATH_SUPPORT), the other
 * base layers as support body (support_material_spacing between beads,
 * PATH_SUPPORT), the interface layers dense (PATH_SUPPORT_INTERFACE).
 */

/*
 * support_raft_new - the raft's layers under the part sliced as st (mm, as
 * slice_mesh gives them, with a first layer of layer_height): *raft gets
 * s->raft_layers layers with their z and height and no regions yet
 * (slice_stack_free), and every layer of st is lifted by *lift mm, the
 * raft's top plus raft_contact_distance.  Returns 0, or ST_ERR_ARG (no raft
 * asked for, an empty st) / ST_ERR_NOMEM with err filled and st unchanged.
 */
int support_raft_new(const struct support_settings *s, double first_layer_height,
		     double layer_height, double nozzle_diameter, struct slice_stack *st,
		     struct slice_stack **raft, double *lift, struct st_error *err);

/*
 * support_raft - the raft under the part's first layer (st's layer 0) and
 * the support's (support: support_generate's output, or NULL).
 *   raft: support_raft_new's layers; each one's regions are replaced by its
 *         raft area.
 *   out:  as many layers (z and height set); the raft's paths are appended.
 * Returns 0 or a negative class with err filled (bad settings, layer counts
 * that do not match, a width narrower than a layer, ST_ERR_NOMEM,
 * ST_ERR_INTERNAL).
 */
int support_raft(const struct support_settings *s, const struct slice_stack *st,
		 const struct layer_stack *support, struct slice_stack *raft,
		 struct layer_stack *out, struct st_error *err);

#endif /* STRATUM_SLICER_SUPPORT_H */
