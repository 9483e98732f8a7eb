/*
 * gcode_writer.h - turn a struct layer_stack into a printable Marlin G-code
 * file: travel and path ordering, retraction / z-hop / wipe, flow from the
 * bead model, speeds per role, cooling (fan by layer time, bridge fan,
 * minimum layer time slow-down), temperatures, start/end G-code with
 * PrusaSlicer placeholders, and a header with the settings used and the
 * estimates (print time from the planner of estimate.h, filament length,
 * volume and mass).
 *
 * Travel: when the layer has a travel map (layer_paths.travel) and
 * avoid_crossing_perimeters is set, a travel whose straight line would
 * leave the part (a hole, a concave bay) and come back is routed inside the
 * part along a boundary 1.5 perimeter spacings inside the surface
 * (travel.h).  A travel retracts when it is longer than
 * retract_before_travel, except, with only_retract_when_crossing_perimeters,
 * when it stays inside one island and is at most max_unretracted_travel
 * long: the ooze then falls inside the part.
 *
 * Ordering: the paths of a layer print in the given order of roles; within
 * a run of consecutive paths of the same role the writer picks the nearest
 * next path (greedy nearest neighbour from the nozzle), entering a closed
 * loop at its seam (first point) and an open path at its nearer end.  Runs
 * of outer and inner perimeters keep their given order: the geometry stage
 * orders walls on purpose.
 *
 * Spiral vase (PrusaSlicer's SpiralVase): a layer marked spiral is one
 * closed loop entered at its vertex nearest the nozzle, so it continues
 * where the loop below ended, and printed with Z rising linearly with the
 * length printed, from the layer below's top (z - height) to z: no Z move,
 * no seam and, after a spiral layer, no retraction.  On the first spiral
 * layer (a flat one below) the flow rises in proportion, from nothing to
 * full, as the gap under the nozzle does (PrusaSlicer's transition layer).
 *
 * Flow: a segment of bead width w (path_point.width of its first point)
 * and layer height h has the cross-section of a rectangle with semicircular
 * ends, A = (w - h)·h + π(h/2)²; it needs E = A·length / (π(d/2)²) ·
 * extrusion_multiplier mm of filament of diameter d.  A width below the
 * layer height has no such bead and is refused.  Ironing (PATH_IRONING)
 * only smooths: its lines are w = ironing_spacing apart and carry
 * PrusaSlicer's flow, A = w · layer_height · ironing_flowrate / 100, at
 * ironing_speed.
 *
 * Cooling, as PrusaSlicer's: layer time is estimated with the planner; the
 * fan is off for the first disable_fan_first_layers layers, at
 * max_fan_speed below slowdown_below_layer_time, interpolated down to
 * min_fan_speed at fan_below_layer_time, and off above (min_fan_speed with
 * fan_always_on); bridges run at bridge_fan_speed; with
 * full_fan_speed_layer both ramp up linearly to full on that layer.  The
 * fan is M106/M107, or M126/M127 with fan_on_off.  A layer faster than
 * slowdown_below_layer_time has its extrusion moves slowed down uniformly
 * until it takes that long, never below min_print_speed (a move already
 * slower keeps its speed).
 *
 * Temperatures, PrusaSlicer's rule: before the start G-code, M190 (bed) when
 * the start G-code has no M140/M190 and M104 (nozzle) when it has no
 * M104/M109; after it, M109 when it has no M104/M109.  First-layer values
 * there; M104/M140 to the other values at the start of layer 2 when they
 * differ.
 *
 * Output to a path is written to a temporary file in the same directory,
 * flushed, fsync'ed and renamed over the path only when everything
 * succeeded (STYLE rule 7); on any error no file is left behind.
 *
 * Thread safety: no global state; distinct calls are independent.
 */
#ifndef STRATUM_SLICER_GCODE_WRITER_H
#define STRATUM_SLICER_GCODE_WRITER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

#include "estimate.h"
#include "placeholder.h"
#include "st_error.h"
#include "toolpath.h"

/*
 * Everything the writer needs, filled by host code from the printer profile
 * (host/profile.h) and the print settings.  Names are PrusaSlicer's keys;
 * units mm, mm/s, degrees C, percent, seconds.
 */
/* How the machine limits are written (PrusaSlicer's print_machine_envelope):
 * not at all; Marlin 1 (M204 T = the printing acceleration, as legacy
 * Marlin takes travel from it); Marlin 2 (M204 T = the travel acceleration). */
enum gcodew_limits_form {
	GCODEW_LIMITS_NONE,
	GCODEW_LIMITS_MARLIN_LEGACY,
	GCODEW_LIMITS_MARLIN2,
};

/* How an acceleration is set (PrusaSlicer's set_acceleration): M204 S
 * (Marlin and most), M204 P (RepRapFirmware), M201 X Y then M202 X Y
 * (Repetier). */
enum gcodew_accel_form {
	GCODEW_ACCEL_M204_S,
	GCODEW_ACCEL_M204_P,
	GCODEW_ACCEL_M201_M202,
};

struct gcodew_settings {
	/* Machine and filament */
	double nozzle_diameter;	       /* mm; 0.4 */
	double filament_diameter;      /* mm; 1.75 */
	double extrusion_multiplier;   /* 1 */
	double filament_density;       /* g/cm^3; 1.24 (PLA) */
	bool use_relative_e_distances; /* M83 and relative E; false (M82, G92 E0 each layer) */
	double layer_height;	       /* mm, reported and for placeholders; 0.2 */
	double first_layer_height;     /* mm, likewise; 0.2 */

	/* Temperatures, degrees C (0 = leave alone) */
	int temperature;		 /* nozzle, layers 2 and up; 200 */
	int first_layer_temperature;	 /* nozzle, layer 1; 200 */
	int bed_temperature;		 /* 0 */
	int first_layer_bed_temperature; /* 0 */

	/* Retraction */
	double retract_length;	      /* mm; 2 (0 = never retract) */
	double retract_speed;	      /* mm/s; 40 */
	double deretract_speed;	      /* mm/s; 0 = retract_speed */
	double retract_lift;	      /* mm of Z hop while travelling retracted; 0 */
	/* ... only where the layer's Z is at least retract_lift_above and, when
	 * retract_lift_below is not 0, at most that (PrusaSlicer's range) */
	double retract_lift_above; /* mm; 0 */
	double retract_lift_below; /* mm; 0 = no upper limit */
	double retract_before_travel; /* mm: retract on travels longer than this; 2 */
	bool wipe;		      /* retract while moving back over the last path; false */
	/* With wipe, this share of the retraction is done standing before the
	 * wipe (the wipe is then as long as the rest needs), as PrusaSlicer's
	 * retract_before_wipe; listed in the header when not 0.  percent; 0 */
	double retract_before_wipe;
	/* Retract (wiping when wipe is set) and lift before each layer change,
	 * as PrusaSlicer's retract_layer_change: the first travel of the new
	 * layer then unretracts; not between spiral vase layers, which
	 * continue each other, nor before the first layer (PrusaSlicer
	 * retracts there too, after the start G-code).  false */
	bool retract_layer_change;
	/* Travels that would leave the part and come back are routed inside
	 * the layer's region (layer_paths.travel); true (PrusaSlicer: false) */
	bool avoid_crossing_perimeters;
	/* A travel that stays inside one island does not retract; true */
	bool only_retract_when_crossing_perimeters;
	double max_unretracted_travel; /* mm: ... unless longer than this; 20 (0 = any length) */

	/* Speeds, mm/s */
	double perimeter_speed;			 /* 60 */
	double external_perimeter_speed;	 /* 30 (50% of perimeter_speed) */
	double small_perimeter_speed;		 /* closed walls up to 2 pi 6.5 mm long; 15 */
	double infill_speed;			 /* 80 */
	double solid_infill_speed;		 /* 20 */
	double top_solid_infill_speed;		 /* 15 */
	double bridge_speed;			 /* 60 */
	double gap_fill_speed;			 /* 20 */
	double support_material_speed;		 /* 60, also skirt and brim */
	double support_material_interface_speed; /* 60 (100% of support_material_speed) */
	double travel_speed;			 /* 130 */
	double travel_speed_z;			 /* 0 = machine_max_feedrate_z */
	double first_layer_speed;		 /* every extrusion of layer 1; 30 (0 = off) */
	bool first_layer_speed_is_percent;	 /* ... is a percentage of each role's speed */
	/* Likewise for the part's first layer on a raft (layer raft_layers + 1,
	 * with a raft only); 30 */
	double first_layer_speed_over_raft;
	bool first_layer_speed_over_raft_is_percent;

	/* Volumetric limits, mm^3/s, PrusaSlicer's: each extrusion's speed at
	 * most the lower of those above 0 over its bead's cross-section (the
	 * flow model's, before extrusion_multiplier); listed in the header
	 * when not 0. */
	double max_volumetric_speed;	      /* 0 */
	double filament_max_volumetric_speed; /* 0 */

	/* Accelerations, mm/s^2, PrusaSlicer 2.5's: with default_acceleration
	 * above 0, each path is preceded by its value (first_layer_, else
	 * perimeter_, bridge_ or infill_acceleration by role, each when above
	 * 0, else the default) and followed by the default, written (rounded;
	 * at most the machine's extruding limit when the limits are written)
	 * only when it changes, as accel_form says; the estimate takes each
	 * within the machine limits.  All listed in the header when not 0. */
	double default_acceleration;	 /* 0 */
	double perimeter_acceleration;	 /* 0 */
	double infill_acceleration;	 /* 0 */
	double bridge_acceleration;	 /* 0 */
	double first_layer_acceleration; /* 0 */
	enum gcodew_accel_form accel_form; /* GCODEW_ACCEL_M204_S */

	/* Cooling */
	bool cooling;			  /* true */
	bool fan_always_on;		  /* false */
	int min_fan_speed;		  /* percent; 35 */
	int max_fan_speed;		  /* percent; 100 */
	int bridge_fan_speed;		  /* percent; 100 */
	int disable_fan_first_layers;	  /* 3 */
	int full_fan_speed_layer;	  /* the fan ramps up to full on this layer (1-based); 0 */
	double fan_below_layer_time;	  /* s; 60 */
	double slowdown_below_layer_time; /* s; 5 */
	double min_print_speed;		  /* mm/s; 10 */
	/* The part fan is only switched, M126 on / M127 off, as PrusaSlicer
	 * writes it for the makerware and sailfish flavours (their M106 drives
	 * another fan); false: M106 S0-255 / M107 */
	bool fan_on_off;

	/* The raft the layers were sliced with (slicer.h), reported in the
	 * header when raft_layers > 0; the writer prints whatever layers it
	 * is given. */
	int raft_layers;		   /* 0 */
	double raft_contact_distance;	   /* mm; 0.1 */
	double raft_expansion;		   /* mm; 1.5 */
	double raft_first_layer_density;   /* percent; 90 */
	double raft_first_layer_expansion; /* mm; 3 */

	/* Machine limits, for the estimates and the layer times */
	struct est_limits limits; /* est_limits_init */
	/* ... and, as PrusaSlicer's machine_limits_usage = emit_to_gcode, in
	 * the G-code before the start G-code (M201, M203, M204, M205) */
	enum gcodew_limits_form limits_form; /* GCODEW_LIMITS_NONE */
	double min_extruding_rate;	     /* mm/s, M205 S; 0 */
	double min_travel_rate;		     /* mm/s, M205 T; 0 */

	/* Custom G-code in PrusaSlicer's placeholder language (placeholder.h);
	 * not owned, not NULL.  Written where PrusaSlicer writes them: the start
	 * G-code, then the first filament's; before each layer change, after
	 * it; the filament's end G-code, then the end G-code. */
	const char *start_gcode; /* "G28 ; home all axes\nG1 Z5 F5000 ; lift nozzle\n" */
	const char *end_gcode;	 /* "M104 S0 ; turn off temperature\nG28 X0  ; home X axis\nM84 ..." */
	const char *before_layer_gcode;	  /* "" */
	const char *layer_gcode;	  /* "" */
	const char *start_filament_gcode; /* "" */
	const char *thumbnails;		  /* the sizes, "WxH,..." ("": none); the host
					   * draws them into thumbnail_block */
	const char *thumbnail_block;	  /* comment lines written after the header's
					   * first line; not owned; NULL: none */
	const char *slicer_block;	  /* the slicer's own settings' header lines
					   * (slicer_settings_text), written after the
					   * writer's; not owned; NULL: none */
	const char *end_filament_gcode;	  /* "" */
	/* The printer's config for the placeholders (every key of its files,
	 * host/profile.h), under the writer's own variables; NULL: none.  Not
	 * owned; must outlive the writer. */
	const struct ph_vars *vars;

	/* The printer, recorded in the header under PrusaSlicer's keys so that
	 * a sender can refuse the file for another printer (docs/printing.md);
	 * not owned, not NULL. */
	const char *printer_settings_id; /* the profile's name; "" */
	const char *printer_model;	 /* "" */
	const char *bed_shape;		 /* PrusaSlicer's text, "0x0,200x0,200x200,0x200" */
	/* The model files of a print of several models sliced together, one
	 * "; input file = NAME" header line each when there are two or more
	 * (none for one, as before several could be sliced); not owned. */
	const char *const *input_files; /* NULL */
	size_t input_file_count;	/* 0 */

	/* Spiral vase (layer_paths.spiral marks the layers it shapes; the
	 * slicer reads this flag); listed in the header when set. false */
	bool spiral_vase;
	/* Ironing (the slicer plans it from ironing, ironing_type and
	 * ironing_spacing, the writer prints it with ironing_flowrate and
	 * ironing_speed); all five listed in the header when ironing is set. */
	bool ironing;		 /* false */
	const char *ironing_type; /* top, topmost or solid; "top"; not owned, not NULL */
	double ironing_flowrate; /* percent of a layer_height bead's flow; 15 */
	double ironing_spacing;	 /* mm between lines; 0.1 */
	double ironing_speed;	 /* mm/s; 15 */

	/* Each path and routed travel is simplified (Douglas-Peucker,
	 * simplify.h) before it is planned: no point of it lies farther than
	 * this from the polyline printed (half of it for the outer wall, the
	 * part's face); a path's kept points are moved so that it keeps its
	 * area (simplify_balance).  Points where the bead width changes are
	 * kept, and each run of one width keeps its filament (its segments
	 * print with its original length over its new one); speeds are the
	 * original path's.  Listed in the header when not 0.
	 * mm; 0.0125 (PrusaSlicer's gcode_resolution), 0 = every point */
	double gcode_resolution;
	/* PrusaSlicer 2.6's arc_fitting = emit_center (host code sets it only
	 * for a flavour whose firmware takes arcs): each run of one bead width
	 * of an extrusion path is first fitted with circular arcs within the
	 * same tolerance as gcode_resolution (arcfit.h: every point of the
	 * path within it of the arc and the arc within it of the path), the
	 * rest simplified as above; an arc is written as G2 (clockwise) or G3
	 * with its centre as I J from its start, its filament the arc's
	 * length times the run's flow (the run keeps its filament as above).
	 * Travels stay lines, as PrusaSlicer's, and so does the spiral vase's
	 * transition layer (its flow ramp).  The estimate (and M73) times
	 * an arc as Marlin prints it, in chords (st_arc.h).  Listed in the
	 * header when set.  false (PrusaSlicer's disabled) */
	bool arc_fitting;

	/* Progress for the firmware's display (PrusaSlicer's remaining_times):
	 * M73 P<percent of the estimated time done> R<minutes left> first in
	 * the body, before each layer change where either number changed, and
	 * M73 P100 R0 after the end G-code; percent floored, minutes of the
	 * seconds rounded then floored, as PrusaSlicer 2.5.  Listed in the
	 * header when set.  false */
	bool remaining_times;
	/* ... each followed by M73 Q S with the same figures (the stealth
	 * mode's; host code sets it for silent_mode and a marlin flavour) */
	bool remaining_times_silent; /* false */
};

/* What a written print will take; also written into the G-code header. */
struct gcodew_summary {
	double time_s;	     /* estimated printing time of the moves (heating excluded) */
	double filament_mm;  /* filament extruded, retractions excluded */
	double filament_cm3; /* its volume */
	double filament_g;   /* its mass at filament_density */
	size_t layers;	     /* layers written */
	size_t moves;	     /* G1 lines written */
};

/* gcodew_settings_init - the declared defaults (settings.h), as listed beside each field. */
void gcodew_settings_init(struct gcodew_settings *s);

/*
 * gcodew_settings_check - every setting inside its declared range
 * (settings.h, the ranges the profile loader applies), min_fan_speed at most
 * max_fan_speed, start and end G-code given.  Returns 0, ST_ERR_RANGE or
 * ST_ERR_ARG naming the first bad key.
 */
int gcodew_settings_check(const struct gcodew_settings *s, struct st_error *err);

/*
 * gcodew_write_stream - write the whole print to @fp.
 * @stack: the layers (not changed); @s: settings (checked first: a value
 *         out of range is ST_ERR_RANGE naming the key).
 * @sum:   filled on success (may be NULL).
 * The print is generated once into an anonymous temporary file while its
 * moves are timed; then the header with the estimates is written to fp and
 * the body copied after it, so nothing reaches fp unless generation
 * succeeded.  Errors: ST_ERR_RANGE (settings, a bead narrower than its
 * layer, a bad layer Z/height), ST_ERR_PARSE / ST_ERR_UNSUPPORTED (start or
 * end G-code placeholders: the message names the placeholder), ST_ERR_IO (a
 * write failed; fp may then hold part of the output), ST_ERR_NOMEM.
 */
int gcodew_write_stream(const struct layer_stack *stack, const struct gcodew_settings *s,
			FILE *fp, struct gcodew_summary *sum, struct st_error *err);

/*
 * gcodew_write_file - as gcodew_write_stream, to the file @path, through a
 * temporary file in the same directory renamed over @path on success.  On
 * error @path is untouched and no temporary file remains.
 */
int gcodew_write_file(const struct layer_stack *stack, const struct gcodew_settings *s,
		      const char *path, struct gcodew_summary *sum, struct st_error *err);

/*
 * The same output a layer at a time, so a caller can free each layer once
 * it is written instead of holding the whole print:
 *   gcodew_begin  - check the settings, expand the start and end G-code for
 *                   nlayers layers, open the body's temporary file and
 *                   write the start of the print;
 *   gcodew_layer  - plan, cool and write the next layer (bottom to top;
 *                   l is only read, and may be freed on return);
 *   gcodew_finish - after the nlayers-th layer: the end of the print, then
 *                   the header with the estimates and the body, to fp;
 *   gcodew_free   - release the writer (NULL is safe), finished or not.
 * For a file, gcodew_begin_file first creates a temporary file beside path
 * (path is kept, not copied) and gcodew_finish_file ends the print there,
 * fsyncs it and renames it over path, as gcodew_write_file does; freeing a
 * writer whose file was not finished removes the temporary file.  s must
 * outlive the writer.
 * Writing every layer of a stack this way gives exactly
 * gcodew_write_stream's bytes.  Errors as gcodew_write_stream's, plus
 * ST_ERR_ARG for a layer beyond nlayers or a finish before the last one.
 * One writer is used by one thread at a time.
 */
struct gcodew;

int gcodew_begin(const struct gcodew_settings *s, size_t nlayers, struct gcodew **out,
		 struct st_error *err);
int gcodew_layer(struct gcodew *w, const struct layer_paths *l, struct st_error *err);
int gcodew_finish(struct gcodew *w, FILE *fp, struct gcodew_summary *sum, struct st_error *err);
int gcodew_begin_file(const struct gcodew_settings *s, size_t nlayers, const char *path,
		      struct gcodew **out, struct st_error *err);
int gcodew_finish_file(struct gcodew *w, struct gcodew_summary *sum, struct st_error *err);
void gcodew_free(struct gcodew *w);

/*
 * gcodew_expand - @text in PrusaSlicer's placeholder language
 * (placeholder.h) as the writer expands its start G-code: the numeric
 * fields of struct gcodew_settings by their PrusaSlicer key (per-extruder
 * ones as one-value vectors), over s->vars; total_layer_count (@nlayers);
 * initial_extruder, initial_tool, current_extruder, next_extruder,
 * filament_extruder_id and layer_num 0; layer_z the first layer's height,
 * max_layer_z 0; has_wipe_tower and
 * has_single_extruder_multi_material_priming false.  Before and after each
 * layer change, layer_num (from 0), layer_z and max_layer_z are that
 * layer's; in the end G-code the last layer's.  @what names the text in
 * messages ("start_gcode").  On success *out is a new string (free() it);
 * on error NULL, with err as ph_expand's (line and column).
 */
int gcodew_expand(const char *text, const char *what, const struct gcodew_settings *s,
		  size_t nlayers, char **out, struct st_error *err);

#endif /* STRATUM_SLICER_GCODE_WRITER_H */
