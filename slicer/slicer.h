/*
 * slicer.h - the whole slicing job (docs/architecture.md item 4): a repaired mesh in,
 * a printable G-code file and a summary out.
 *
 * Pipeline of slicer_run, stage by stage:
 *   1. place: the part's bounding box is centred on the bed (or on a given
 *      point) with its lowest point at z = 0, and refused when it does not
 *      fit the bed's bounding box or the printer's maximum height;
 *   2. slice (section.h): per layer, the solid cross-section, cleaned of
 *      vertices within SLICER_CLEAN_NM of their neighbours' line;
 *   3. support (support.h, when the job asks for it) and skirt/brim
 *      (skirt.h, around the first layer and its support), whole stack;
 *      with raft.layers > 0, the raft (support.h, support_raft) under the
 *      first layer: the part is sliced with a first layer of layer_height,
 *      lifted onto the raft (no elefant foot compensation, as PrusaSlicer
 *      compensates only on the bed), and the skirt/brim goes around the
 *      raft's first layer on the raft's layers;
 *   4. the layer pipeline: walls (perimeters.h: walls, gap fill and thin
 *      walls) in chunks of SLICER_CHUNK_LAYERS layers and each layer's
 *      infill plan (infill.h: skins, bridges, solid and sparse infill in the
 *      region inside the walls, then ironing, ironing.h) on worker threads;
 *      bottom to top, each layer's infill is emitted, its paths merged in
 *      the order skirt/brim, support, walls, infill, and the layer written
 *      (gcode_writer.h, to a temporary file renamed on success) and freed;
 *      the raft's layers, skirt/brim then raft, are written before the part's.
 * With gcodew.spiral_vase (spiral.h), after stage 2 the layers above the
 * bottom ones keep their largest island's outline, get no infill, and
 * those that are one outer wall are marked layer_paths.spiral.
 * struct slicer_summary says which stages produced paths.
 * Each chunk of walls carries its own seam memory, warmed up on the layer
 * below the chunk, and infill is ordered from where the layer below ended,
 * so the output does not depend on the number of threads.
 *
 * Thread safety: no global state; distinct calls are independent.  The
 * progress callback is called from the calling thread only.
 */
#ifndef STRATUM_SLICER_SLICER_H
#define STRATUM_SLICER_SLICER_H

#include <stdbool.h>
#include <stddef.h>

#include "gcode_writer.h"
#include "mesh.h"
#include "perimeters.h"
#include "section.h"
#include "st_error.h"
#include "toolpath.h"

struct support_settings;  /* support.h */
struct adaptive_settings; /* adaptive.h */

/* Layers per unit of parallel wall work (and per seam-memory restart). */
#define SLICER_CHUNK_LAYERS 32
/* Section vertices that move the outline less than this are dropped once
 * after slicing, nm: far below the 0.02 mm accuracy bound, and every wall
 * offset makes two or three points of each vertex it keeps. */
#define SLICER_CLEAN_NM 1000.0
/* Most worker threads used. */
#define SLICER_MAX_THREADS 256
/* Slack allowed when checking the fit on the bed, mm (rounding of the placement). */
#define SLICER_FIT_SLACK 1e-6

/* Where the part goes: the printer's bed and build height. */
struct slicer_bed {
	double min_x, min_y, max_x, max_y; /* mm, bounding box of bed_shape */
	double max_height;		   /* mm, max_print_height */
	bool has_center;		   /* place at center_x/y instead of the bed centre */
	double center_x, center_y;	   /* mm, where the part's bounding-box centre goes */
	double object_distance;		   /* mm between the footprints of several models
					    * (arrange.h; duplicate_distance, 6) */
};

/*
 * Settings of the stages that are merged later (infill, support,
 * skirt/brim).  The values are checked and carried so the stages find them
 * here; until their code is merged nothing reads them (see the top).
 */
struct slicer_infill_settings {
	double density;		 /* percent, 0-100 (fill_density) */
	const char *pattern;	 /* fill_pattern, PrusaSlicer's name; not owned, not NULL */
	int top_solid_layers;	 /* >= 0 */
	int bottom_solid_layers; /* >= 0 */
	double solid_infill_below_area; /* mm^2, >= 0 (70) */
	double top_solid_min_thickness, bottom_solid_min_thickness; /* mm, >= 0 (0) */
	double fill_angle, bridge_angle; /* degrees (45, 0 = per bridge) */
	double bridge_flow_ratio;	 /* (0, 2] (1) */
	bool thick_bridges;		 /* round threads, else flat beads (true) */
	bool top_monotonic, bottom_monotonic; /* skins' lines in one sweep (false) */
	double anchor, anchor_max; /* mm, infill_anchor(_max) (anchors.h; 0, 0) */
	double infill_overlap;		 /* percent of the walls' width, 0-100 (25) */
	/* mm: sparse, solid and bottom, top; 0 = the walls' extrusion_width (0) */
	double infill_extrusion_width, solid_infill_extrusion_width, top_infill_extrusion_width;
};

struct slicer_support_settings {
	bool enabled;	/* support_material */
	int threshold;	/* degrees, 0-90, 0 = automatic (support_material_threshold) */
	/* The other support_material_* keys and dont_support_bridges, as
	 * support.h's struct support_settings has them (xy_spacing in mm). */
	bool buildplate_only, dont_support_bridges, with_sheath;
	const char *style, *pattern; /* declared names (settings.c), not owned */
	double contact_distance, bottom_contact_distance;
	int interface_layers, bottom_interface_layers;
	double interface_spacing, spacing, angle, xy_spacing;
	/* mm, support's and the raft's beads; 0 = the walls' extrusion_width (0) */
	double extrusion_width;
};

/* The raft (support.h, support_raft), PrusaSlicer's keys. */
struct slicer_raft_settings {
	int layers;		      /* raft_layers, 0 = no raft (0) */
	double contact_distance;      /* mm, raft_contact_distance (0.1) */
	double expansion;	      /* mm, raft_expansion (1.5) */
	double first_layer_density;   /* percent, raft_first_layer_density (90) */
	double first_layer_expansion; /* mm, raft_first_layer_expansion (3) */
};

struct slicer_skirt_settings {
	int skirts;		 /* loops, >= 0 (1) */
	double skirt_distance;	 /* mm, >= 0 (6) */
	int skirt_height;	 /* layers, 0 = no skirt (1) */
	double min_skirt_length; /* mm of filament, >= 0 (0) */
	double brim_width;	 /* mm, >= 0 (0) */
	double brim_separation;	 /* mm, >= 0 (0) */
};

/* Adaptive layer heights (adaptive.h): keys of the printer and Stratum's. */
struct slicer_adaptive_settings {
	bool enabled;	   /* adaptive_layer_height (false) */
	bool allowed;	   /* variable_layer_height: the printer allows it (true) */
	double max_cusp;   /* mm, adaptive_max_cusp (0.1) */
	double min_height; /* mm, min_layer_height (0.07) */
	double max_height; /* mm, max_layer_height, 0 = 75 % of the nozzle; at most
			    * that in any case (0) */
	/* A layer height profile (PrusaSlicer's variable layer height, as a
	 * 3MF keeps it: meshio_3mf_layer_profile): profile_pairs (z, height)
	 * pairs in mm, z from the part's bottom; not owned.  Used when set and
	 * enabled is false (adaptive_plan_profile). */
	const double *profile;
	size_t profile_pairs;
};

/* Everything a job needs; slicer_config_init gives the defaults. */
struct slicer_config {
	double layer_height;	   /* mm, > 0, at most the nozzle diameter (0.2) */
	double first_layer_height; /* mm, likewise (0.2) */
	struct slice_settings slice;
	struct perim_settings perim;
	struct gcodew_settings gcodew; /* its layer heights, nozzle and raft keys are
					* overwritten from the fields here and perim */
	struct slicer_infill_settings infill;
	struct slicer_support_settings support;
	struct slicer_raft_settings raft;
	struct slicer_skirt_settings skirt;
	struct slicer_adaptive_settings adaptive;
	struct slicer_bed bed;
	double elefant_foot_compensation; /* mm the first layer's islands shrink, >= 0 (0) */
	/* mm, every bead of the part's first layer on the bed (walls, skins,
	 * infill; not over a raft) and of the skirt and brim; 0 = each role's
	 * own width (0) */
	double first_layer_extrusion_width;
	/* the longest detour of a travel routed inside the part (travel.h,
	 * travel_map_set_detour): mm, or percent of the straight travel;
	 * 0 = any (100%) */
	double max_detour;
	bool max_detour_is_percent;
	/* walls' pieces over air printed with bridge flow, speed and fan
	 * (overhang.h; PrusaSlicer's overhangs; false) */
	bool overhangs;
	int threads; /* workers for walls and infill; 0 = all online cores */
	/* Called with the phase as a sentence ("cutting the model into
	 * layers", "slicing layer 12 of 80", "writing the G-code") and 0..1 of
	 * it done; may be NULL. */
	void (*progress)(void *ctx, const char *stage, double done);
	void *progress_ctx;
	/* Called once with the layers as printed (the raft's, then the
	 * part's: tops above the bed, heights), before any is written; may be
	 * NULL. */
	void (*planned)(void *ctx, const struct layer_span *layers, size_t n);
	void *planned_ctx;
};

/* Thin walls narrower than the nozzle (perimeters.h struct perim_thin). */
struct slicer_thin {
	size_t dropped;		/* islands narrower than min_feature_size, not printed */
	size_t widened_layers;	/* layers with beads widened to min_bead_width */
	size_t first, last;	/* the first and last such layer, 1-based (raft included) */
	double designed, printed; /* mm: the narrowest widened feature, its bead's width */
};

/* What a job produced. */
struct slicer_summary {
	size_t layers;		       /* layers written */
	double time_s;		       /* estimated print time, s (heating excluded) */
	double filament_mm;	       /* filament length, mm */
	double filament_cm3;	       /* its volume */
	double filament_g;	       /* its mass */
	size_t moves;		       /* G1 lines */
	size_t paths[PATH_ROLES];      /* extrusion paths per role */
	double offset[3];	       /* mm: translation applied to the mesh */
	double min[3], max[3];	       /* mm: the part's bounding box as placed */
	bool walls, infill, support, skirt; /* which stages produced paths in this build */
	size_t raft_layers;	       /* of layers, those of the raft under the part */
	size_t open_dropped;	       /* open contour pieces the slicer could not close */
	struct slicer_thin thin;       /* thin walls dropped or printed wider than designed */
	bool adaptive;		       /* the part's layers are adaptive (adaptive.h) */
	bool profiled;		       /* the part's layers follow adaptive.profile */
	size_t profile_clamped;	       /* of those, layers whose profile height lay outside
					* min_layer_height..max_layer_height */
	double height_min, height_max; /* mm: the part's thinnest and thickest layer above
					* its first */
	double cusp_max, cusp_mean;    /* mm, adaptive or profiled only: the cusp of the part's layers above
					* its first (adaptive_measure) */
};

/*
 * slicer_config_init - defaults for a nozzle of nozzle_diameter mm: the
 * defaults of slice_settings_init, perim_settings_init and
 * gcodew_settings_init, 0.2 mm layers, 20 % infill, 3 top and bottom
 * layers, one skirt loop, no support, a 200 x 200 x 200 mm bed.
 */
void slicer_config_init(struct slicer_config *c, double nozzle_diameter);

/*
 * slicer_config_modes - c as its print modes print it (PrusaSlicer's
 * normalisation): with gcodew.spiral_vase one wall (perimeters 1), no top
 * layers (top_solid_layers and top_solid_min_thickness 0) and no infill
 * (density 0); otherwise c is left alone.  slicer_toolpaths and slicer_run
 * apply it after slicer_config_check; callers apply it to report the
 * values printed with.
 */
void slicer_config_modes(struct slicer_config *c);

/*
 * slicer_settings_text - the G-code header's lines ("; key = value", under
 * PrusaSlicer's keys) of the settings the slicer itself prints with and the
 * G-code writer does not list: walls, skins, sparse infill, skirt and brim,
 * support, seam, elephant foot; as c prints them (after slicer_config_modes:
 * a spiral vase lists its one wall and no infill; a fill_pattern Stratum does
 * not print lists the rectilinear printed instead).  Writes at most cap
 * bytes, NUL included; returns the length of the whole text (as snprintf).
 */
size_t slicer_settings_text(const struct slicer_config *c, char *buf, size_t cap);

/*
 * slicer_config_check - refuse settings that cannot make a print before any
 * work: layer heights not > 0 or above the nozzle, the walls' settings
 * (perim_settings_check for both layer heights), infill density outside
 * 0-100 %, negative layer or loop counts or brim width, a support threshold
 * outside 0-90, raft keys outside their declared ranges (settings.h), a
 * first-layer width the first layer's walls cannot take, an empty bed or a height <= 0, a negative thread count;
 * with adaptive layers, a printer that does not allow them
 * (variable_layer_height), a cusp bound outside its declared range, and
 * min/max_layer_height the walls cannot take or whose minimum is above the
 * largest height (max_layer_height, at most 75 % of the nozzle).
 * Returns 0 or ST_ERR_RANGE / ST_ERR_ARG with a message naming the setting
 * (PrusaSlicer's key), its value and what is allowed.
 */
int slicer_config_check(const struct slicer_config *c, struct st_error *err);

/*
 * slicer_first_layer_walls - the walls' settings of the part's first layer:
 * c->perim with both widths first_layer_extrusion_width when that applies
 * (set, and no raft), else c->perim as it is.
 */
void slicer_first_layer_walls(const struct slicer_config *c, struct perim_settings *out);

/*
 * slicer_adaptive_settings - the settings of adaptive_plan (adaptive.h)
 * for c: the part's first layer as slicer_toolpaths slices it, c's
 * minimum, and c's maximum capped at 75 % of the nozzle.
 */
void slicer_adaptive_settings(const struct slicer_config *c, struct adaptive_settings *out);

/*
 * slicer_raft_support - the settings of support_raft (support.h) for c,
 * and the base of support's: support's defaults for the nozzle, c's support
 * width (the walls' when 0), c's other support keys (c->support) and raft
 * keys.
 */
void slicer_raft_support(const struct slicer_config *c, struct support_settings *s);

/*
 * slicer_place - where the mesh goes on the bed: offset[3] (mm) to add to
 * every vertex so that its bounding box is centred on the bed (or on the
 * bed's center_x/y) and its lowest point is at z = 0; min and max (may be
 * NULL) receive the placed bounding box.  Returns 0, or ST_ERR_RANGE when
 * the placed box leaves the bed's bounding box or is taller than
 * max_height (the message gives the part's size and the room there is),
 * ST_ERR_ARG for an empty mesh.
 */
int slicer_place(const struct mesh *m, const struct slicer_bed *bed, double offset[3],
		 double min[3], double max[3], struct st_error *err);

/*
 * slicer_toolpaths - stages 1-4: the merged layer stack of mesh m (mm,
 * closed surface as the repair leaves it; not modified).  On success *out
 * is a new stack (layer_stack_free) and sum (may be NULL) has the fields
 * that do not need the G-code (paths, offset, min/max, stages, layers).
 * Errors: those of slicer_config_check and slicer_place, then ST_ERR_RANGE
 * (too many layers), ST_ERR_NOMEM, ST_ERR_INTERNAL; *out is NULL.
 */
int slicer_toolpaths(const struct mesh *m, const struct slicer_config *c,
		     struct layer_stack **out, struct slicer_summary *sum, struct st_error *err);

/*
 * slicer_run - the whole job: slicer_toolpaths, then the G-code written to
 * path through a temporary file renamed over it only on success (on any
 * error path is untouched).  sum (may be NULL) is filled on success.
 * Errors: as slicer_toolpaths, plus gcodew_write_file's (ST_ERR_IO for the
 * file, ST_ERR_PARSE / ST_ERR_UNSUPPORTED for start/end G-code
 * placeholders, ST_ERR_RANGE for a G-code setting).
 */
int slicer_run(const struct mesh *m, const struct slicer_config *c, const char *path,
	       struct slicer_summary *sum, struct st_error *err);

#endif /* STRATUM_SLICER_SLICER_H */
