/*
 * profile.h - printer profiles: flat `key = value` files in PrusaSlicer's
 * syntax (printers/NAME.ini), loaded, type-checked and range-checked into one
 * struct profile, with a default for every key the file leaves out.
 *
 * Key names are PrusaSlicer's wherever PrusaSlicer has the setting
 * (nozzle_diameter, bed_shape, gcode_flavor, retract_length, start_gcode ...);
 * the serial side and the Sailfish machine definition use our own keys
 * (protocol, baudrate, usb_ids, rx_buffer_size, dtr_reset, steps_per_mm_x ...).
 * Every key is declared once, with its type, range, default, unit and help,
 * in slicer/settings.h; docs/printers.md's key tables are generated from
 * that declaration.  A profile that loads is one the slicer accepts.
 *
 * Resolving a name: profile_find("NAME") reads NAME.ini from the first of
 *   1. $STRATUM_PRINTERS_DIR, when set and not empty;
 *   2. the user's profiles, $XDG_CONFIG_HOME/stratum/printers (default
 *      ~/.config/stratum/printers), when it exists;
 *   3. the profiles installed beside the executable: <exe dir>/../share/
 *      stratum/printers (PREFIX/bin/stratum of `make install`, wherever
 *      PREFIX and DESTDIR put it); else the printers/ folder of the source
 *      tree: <exe dir>/../printers, or <exe dir>/../../printers
 *      (build/stratum and build/asan/stratum both find the source tree's);
 *      the first of these three that exists;
 *   4. STRATUM_DATADIR, the profiles of the default install (default
 *      /usr/local/share/stratum/printers), for a binary copied elsewhere;
 *   5. a [printer:NAME] preset of PrusaSlicer's installed vendor bundles
 *      ($STRATUM_VENDOR_DIR, else PROFILE_VENDOR_DIR), by its name ("Original
 *      Prusa i3 MK3S & MK3S+") or its slug (original-prusa-i3-mk3s-mk3s:
 *      lower-case letters and digits, '-' for the rest), with the preset's
 *      default print and filament presets.
 * An argument containing '/' or ending in ".ini" is a file path instead.
 *
 * Errors: every function that can fail fills a caller-supplied struct
 * st_error whose message starts with the file name and, for content errors,
 * "line N: KEY: ". Classes: ST_ERR_IO (cannot open/read), ST_ERR_PARSE
 * (syntax or type: "0.4mm", a line without '=', a duplicate key),
 * ST_ERR_RANGE (a well-formed value outside its range or inconsistent with
 * another key), ST_ERR_ARG (no such profile name), ST_ERR_NOMEM.
 *
 * Thread safety: loading reads the environment and the file system only;
 * a loaded struct profile is immutable and may be shared between threads.
 */
#ifndef STRATUM_HOST_PROFILE_H
#define STRATUM_HOST_PROFILE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "st_error.h"

#ifndef PROFILE_VENDOR_DIR
#define PROFILE_VENDOR_DIR "/usr/share/PrusaSlicer/profiles" /* PrusaSlicer's bundles */
#endif

#ifndef STRATUM_DATADIR
#define STRATUM_DATADIR "/usr/local/share/stratum/printers"
#endif

#define PROFILE_MAX_EXTRUDERS 8	    /* per-extruder lists hold at most this many */
#define PROFILE_MAX_USB_IDS 16	    /* usb_ids entries */
#define PROFILE_MAX_BED_POINTS 1024 /* bed_shape polygon corners */
#define PROFILE_MAX_DIRS 4	    /* search directories, see above */
#define PROFILE_PATH_MAX 4096	    /* longest directory or file path handled */

/* Wire protocol the printer speaks (our key `protocol`). */
enum profile_protocol {
	PROFILE_PROTOCOL_MARLIN = 0, /* Marlin text G-code, line numbers + checksums */
	PROFILE_PROTOCOL_SAILFISH,   /* S3G/X3G binary packets (Makerbot, FlashForge) */
};

/* PrusaSlicer's `gcode_flavor` values, in PrusaSlicer's order. */
enum profile_flavor {
	PROFILE_FLAVOR_REPRAP = 0,     /* "reprap" (RepRap/Sprinter) */
	PROFILE_FLAVOR_REPRAPFIRMWARE, /* "reprapfirmware" */
	PROFILE_FLAVOR_REPETIER,       /* "repetier" */
	PROFILE_FLAVOR_TEACUP,	       /* "teacup" */
	PROFILE_FLAVOR_MAKERWARE,      /* "makerware" (MakerBot) */
	PROFILE_FLAVOR_MARLIN,	       /* "marlin" (Marlin 1.x, legacy) */
	PROFILE_FLAVOR_MARLIN2,	       /* "marlin2" */
	PROFILE_FLAVOR_KLIPPER,	       /* "klipper" */
	PROFILE_FLAVOR_SAILFISH,       /* "sailfish" (MakerBot) */
	PROFILE_FLAVOR_MACH3,	       /* "mach3" */
	PROFILE_FLAVOR_MACHINEKIT,     /* "machinekit" */
	PROFILE_FLAVOR_SMOOTHIE,       /* "smoothie" */
	PROFILE_FLAVOR_NO_EXTRUSION,   /* "no-extrusion" */
};

/* Which end of an axis its homing endstop sits at (GPX ENDSTOP_IS_MIN/MAX). */
enum profile_home {
	PROFILE_HOME_MIN = 0,
	PROFILE_HOME_MAX,
};

/* Axis indices for the per-axis arrays below. */
enum profile_axis {
	PROFILE_AXIS_X = 0,
	PROFILE_AXIS_Y,
	PROFILE_AXIS_Z,
	PROFILE_AXIS_E,
	PROFILE_AXES
};

/* A point of bed_shape or extruder_offset, in mm. */
struct profile_point {
	double x, y;
};

/* A value (a speed in mm/s, a width in mm), or a percentage of another
 * (PrusaSlicer's FloatOrPercent; slicer/settings.h says of what). */
struct profile_pct {
	double value;
	bool is_percent;
};

/* One USB VID:PID pair from usb_ids. */
struct profile_usb_id {
	uint16_t vid, pid;
};

struct profile_keys; /* the file's raw key = value lines (private) */
struct ph_vars;	     /* slicer/placeholder.h */

/*
 * A loaded profile.  Every field holds the file's value or the documented
 * default; per-extruder arrays are filled for [0, extruder_count).  Strings
 * are owned by the profile and never NULL (empty when unset).  Speeds are in
 * mm/s, lengths in mm, temperatures in degrees C, as in PrusaSlicer.
 */
struct profile {
	/* Identity */
	const char *id;		   /* file base name without .ini: what --printer takes */
	const char *path;	   /* the file it was loaded from */
	const char *name;	   /* `name`: display name; default: id */
	const char *description;   /* `description`: one line; default "" */
	const char *printer_model; /* `printer_model` (PrusaSlicer), e.g. "MK3S" */

	/* Serial side (our keys) */
	enum profile_protocol protocol; /* `protocol`; default from gcode_flavor, else marlin */
	long baudrate;			/* `baudrate`: a standard rate; default 115200 */
	struct profile_usb_id usb_ids[PROFILE_MAX_USB_IDS]; /* `usb_ids` */
	size_t usb_id_count;
	int rx_buffer_size;  /* `rx_buffer_size`: Marlin RX ring, bytes; default 128 */
	int bufsize;	     /* `bufsize`: Marlin BUFSIZE (command slots), 0 = unknown */
	bool dtr_reset;	     /* `dtr_reset`: opening the port resets the board; default 1 */
	int x3g_buffer_size; /* `x3g_buffer_size`: bytes, 0 = ask the firmware; default 0 */

	/* Machine */
	enum profile_flavor gcode_flavor; /* default: marlin2 (marlin), sailfish (sailfish) */
	struct profile_point *bed_shape;  /* `bed_shape` polygon, bed_points corners */
	size_t bed_points;
	double bed_min_x, bed_min_y, bed_max_x, bed_max_y; /* bed_shape bounding box, mm */
	double max_print_height;			   /* mm; default 200 */
	bool use_relative_e_distances;			   /* M83 instead of M82; default 0 */
	bool remaining_times; /* M73 progress lines; default 0 */
	bool silent_mode;     /* ... with M73 Q S too (marlin flavours); default 1 */
	int extruder_count; /* `extruder_count`, else the length of nozzle_diameter, else 1 */

	/* Per extruder (comma lists; one value applies to every extruder) */
	double nozzle_diameter[PROFILE_MAX_EXTRUDERS];		     /* mm, 0.05-3; default 0.4 */
	double filament_diameter[PROFILE_MAX_EXTRUDERS];	     /* mm, 1-3.5; default 1.75 */
	double extrusion_multiplier[PROFILE_MAX_EXTRUDERS];	     /* default 1 */
	double filament_density; /* g/cm^3, the first filament's; default 1.24 */
	struct profile_point extruder_offset[PROFILE_MAX_EXTRUDERS]; /* mm; default 0x0 */
	int temperature[PROFILE_MAX_EXTRUDERS];			     /* C, 0-450; default 200 */
	int first_layer_temperature[PROFILE_MAX_EXTRUDERS];	     /* C; default: temperature */
	double retract_length[PROFILE_MAX_EXTRUDERS];		     /* mm; default 2 */
	double retract_speed[PROFILE_MAX_EXTRUDERS];		     /* mm/s; default 40 */
	double retract_lift[PROFILE_MAX_EXTRUDERS];		     /* mm (Z hop); default 0 */
	double retract_lift_above[PROFILE_MAX_EXTRUDERS]; /* mm, hop at or above; default 0 */
	double retract_lift_below[PROFILE_MAX_EXTRUDERS]; /* mm, ... at or below, 0 = any; default 0 */
	double deretract_speed[PROFILE_MAX_EXTRUDERS]; /* mm/s, 0 = retract_speed; default 0 */
	double retract_before_travel[PROFILE_MAX_EXTRUDERS]; /* mm; default 2 */
	bool wipe; /* the first extruder's (one prints); default 0 */
	double retract_before_wipe; /* percent, the first extruder's; default 0 */
	bool retract_layer_change; /* likewise; default 0 */
	bool variable_layer_height; /* the printer allows adaptive layers; default 1 */
	double min_layer_height[PROFILE_MAX_EXTRUDERS];		     /* mm; default 0.07 */
	double max_layer_height[PROFILE_MAX_EXTRUDERS]; /* mm; 0 in the file = 75% of nozzle */
	double steps_per_mm_e[PROFILE_MAX_EXTRUDERS];	/* steps/mm; sailfish only */

	/* Bed (PrusaSlicer keeps one per filament: the first is used) */
	int bed_temperature;		 /* C, 0-150; default 0 */
	int first_layer_bed_temperature; /* C; default: bed_temperature */

	/* Print settings */
	double layer_height;	   /* mm, > 0 and <= the smallest nozzle; default 0.2 */
	double first_layer_height; /* mm (a percentage in the file is of layer_height) */
	bool adaptive_layer_height; /* Stratum's: adaptive layers; default 0 */
	double adaptive_max_cusp;   /* mm, Stratum's: their cusp bound; default 0.1 */
	double extrusion_width;	   /* mm, 0 = auto (a percentage is of layer_height) */
	int perimeters, top_solid_layers, bottom_solid_layers; /* defaults 3, 3, 3 */
	const char *seam_position; /* aligned, nearest, random or rear; default aligned */
	double elefant_foot_compensation; /* mm, first layer shrunk; default 0 */
	bool external_perimeters_first, thin_walls, gap_fill_enabled; /* defaults 0, 1, 1 */
	bool overhangs; /* overhanging walls with bridge flow; default 0 */
	bool spiral_vase; /* default 0 */
	double top_solid_min_thickness, bottom_solid_min_thickness; /* mm; defaults 0, 0 */
	double fill_angle, bridge_angle; /* degrees; defaults 45, 0 (0 = per bridge) */
	double bridge_flow_ratio;	 /* default 1 */
	bool thick_bridges;		 /* round bridge threads; default 1 */
	struct profile_pct infill_overlap; /* mm or % of extrusion_width; default 25% */
	/* mm or % of nozzle_diameter; defaults 25%, 85% */
	struct profile_pct min_feature_size, min_bead_width;
	/* mm or % of nozzle_diameter, default 100%; degrees 1-59, default 10 */
	struct profile_pct wall_transition_length;
	double wall_transition_angle;
	/* mm or % of first_layer_height; 0 = each role's width; default 0 */
	struct profile_pct first_layer_extrusion_width;
	/* mm or % of layer_height; 0 = extrusion_width; defaults 0 */
	struct profile_pct perimeter_extrusion_width, external_perimeter_extrusion_width;
	struct profile_pct infill_extrusion_width, solid_infill_extrusion_width;
	struct profile_pct top_infill_extrusion_width;
	struct profile_pct support_material_extrusion_width; /* support and raft */
	double fill_density;				       /* percent, 0-100; default 20 */
	const char *fill_pattern;	/* a PrusaSlicer pattern name; default "rectilinear" */
	const char *top_fill_pattern, *bottom_fill_pattern; /* default "rectilinear" */
	/* mm or % of infill_extrusion_width; defaults 600%, 0 */
	struct profile_pct infill_anchor, infill_anchor_max;
	double solid_infill_below_area;	/* mm^2; default 70 */
	bool ironing;			/* default 0 */
	const char *ironing_type;	/* top, topmost or solid; default top */
	double ironing_flowrate;	/* percent, 0-100; default 15 */
	double ironing_spacing;		/* mm; default 0.1 */
	double ironing_speed;		/* mm/s; default 15 */
	int skirts;			/* loops; default 1 */
	double skirt_distance;		/* mm; default 6 */
	int skirt_height;		/* layers, 0 = no skirt; default 1 */
	double min_skirt_length;	/* mm of filament; default 0 */
	double brim_width;		/* mm; default 0 */
	double brim_separation;		/* mm; default 0 */
	double duplicate_distance;	/* mm between several models' footprints; default 6 */
	bool support_material;		/* default 0 */
	int support_material_threshold; /* degrees, 0 = automatic; default 0 */
	const char *support_material_style;    /* grid or snug; default grid */
	const char *support_material_pattern;  /* rectilinear, rectilinear-grid or honeycomb */
	bool support_material_with_sheath;     /* default 1 */
	bool support_material_buildplate_only; /* default 0 */
	/* mm; defaults 0.2, 0 (= the top's) */
	double support_material_contact_distance, support_material_bottom_contact_distance;
	/* layers; defaults 3, -1 (= the top's) */
	int support_material_interface_layers, support_material_bottom_interface_layers;
	double support_material_interface_spacing; /* mm, 0 = solid; default 0 */
	double support_material_spacing;	   /* mm; default 2.5 */
	double support_material_angle;		   /* degrees; default 0 */
	/* mm or % of external_perimeter_extrusion_width; default 50% */
	struct profile_pct support_material_xy_spacing;
	bool dont_support_bridges; /* default 1 */
	int raft_layers;		/* 0 = no raft; default 0 */
	double raft_contact_distance;	/* mm; default 0.1 */
	double raft_expansion;		/* mm; default 1.5 */
	double raft_first_layer_density; /* percent, 10-100; default 90 */
	double raft_first_layer_expansion; /* mm; default 3 */
	double gcode_resolution;	/* mm, paths simplified within it, 0 = off; default 0.0125 */
	const char *arc_fitting;	/* disabled or emit_center; default disabled */

	/* Speeds, mm/s (a percentage is of the key slicer/settings.h names) */
	double travel_speed;			       /* default 130 */
	double travel_speed_z;			       /* 0 = machine_max_feedrate_z; default 0 */
	double perimeter_speed;			       /* default 60 */
	struct profile_pct external_perimeter_speed; /* default 50% */
	struct profile_pct small_perimeter_speed;    /* default 15 */
	double infill_speed;			       /* default 80 */
	struct profile_pct solid_infill_speed;       /* default 20 */
	struct profile_pct top_solid_infill_speed;   /* default 15 */
	double bridge_speed;			       /* default 60 */
	double gap_fill_speed;			       /* default 20 */
	double support_material_speed;		       /* default 60 */
	struct profile_pct support_material_interface_speed; /* default 100% */
	struct profile_pct first_layer_speed; /* a percentage is of each role's speed */
	struct profile_pct first_layer_speed_over_raft; /* the part's first layer on a raft */
	/* mm^3/s, each extrusion's cap (the lower of those above 0); defaults 0 */
	double max_volumetric_speed, filament_max_volumetric_speed;
	double default_acceleration; /* mm/s^2, M204 S; default 0 */
	double perimeter_acceleration; /* mm/s^2, M204 S; default 0 */
	double infill_acceleration; /* mm/s^2, M204 S; default 0 */
	double bridge_acceleration; /* mm/s^2, M204 S; default 0 */
	double first_layer_acceleration; /* mm/s^2, M204 S; default 0 */

	/* Travel */
	bool avoid_crossing_perimeters;		    /* default 1 */
	struct profile_pct avoid_crossing_perimeters_max_detour; /* mm or %; default 100% */
	bool only_retract_when_crossing_perimeters; /* default 1 */
	double max_unretracted_travel;		    /* mm; default 20 */

	/* Cooling (per filament in PrusaSlicer: the first is used) */
	bool cooling;			  /* default 1 */
	bool fan_always_on;		  /* default 0 */
	int min_fan_speed, max_fan_speed; /* percent; defaults 35, 100 */
	int bridge_fan_speed;		  /* percent; default 100 */
	int disable_fan_first_layers;	  /* layers; default 3 */
	int full_fan_speed_layer;	  /* 1-based, 0 = no ramp; default 0 */
	int fan_below_layer_time;	  /* s; default 60 */
	int slowdown_below_layer_time;	  /* s; default 5 */
	double min_print_speed;		  /* mm/s; default 10 */

	/* Machine limits (PrusaSlicer keeps normal,stealth: the first is used) */
	double machine_max_feedrate[PROFILE_AXES];     /* mm/s, machine_max_feedrate_x... */
	double machine_max_acceleration[PROFILE_AXES]; /* mm/s^2, machine_max_acceleration_x... */
	double machine_max_acceleration_extruding;     /* mm/s^2 */
	double machine_max_acceleration_retracting;    /* mm/s^2 */
	double machine_max_acceleration_travel;	       /* mm/s^2, 0 = not limited separately */
	double machine_max_jerk[PROFILE_AXES];	       /* mm/s, machine_max_jerk_x... */
	double machine_min_extruding_rate;	       /* mm/s (M205 S) */
	double machine_min_travel_rate;		       /* mm/s (M205 T) */
	const char *machine_limits_usage; /* emit_to_gcode, time_estimate_only or ignore */

	/* Sailfish machine definition for X3G (GPX `Machine`); 0 = unknown */
	double steps_per_mm[3];		     /* X, Y, Z steps/mm: steps_per_mm_x/y/z */
	enum profile_home home_direction[3]; /* home_direction_x/y/z = min|max */
	double home_feedrate[3];	     /* mm/min (as G-code F): home_feedrate_x/y/z */
	double home_position[3];	     /* mm after homing: home_position_x/y/z */
	double x3g_toolhead_offset[3];	     /* mm, tool 1 from tool 0: x3g_toolhead_offset_x/y/z */
	bool x3g_heated_platform;	     /* the platform heater is on the tool boards; default 1 */
	int x3g_home_timeout;		     /* s, homing time-out of X3G 131/132; default 20 */

	/* Custom G-code, escapes decoded (PrusaSlicer placeholders left as written) */
	const char *start_gcode;
	const char *end_gcode;
	const char *before_layer_gcode, *layer_gcode; /* around each layer change */
	const char *start_filament_gcode, *end_filament_gcode; /* the first filament's */
	const char *toolchange_gcode; /* checked only: one extruder prints */
	const char *thumbnails;	      /* "WxH,..." (host/thumbnail.h); default "" */

	struct profile_keys *keys; /* private: every key = value of the file */
	/* Every key of the file, and every declared key's resolved value or
	 * default, as placeholder variables for the custom G-code; also
	 * print_settings_id, filament_settings_id, printer_settings_id ("" when
	 * the file has none). */
	struct ph_vars *vars;
};

/* A profile file found by profile_list(). */
struct profile_entry {
	char *id;   /* file base name, what --printer takes */
	char *path; /* full path of the .ini file */
};

/* The directories NAME lookups search, in order (see the top of this file). */
struct profile_dirs {
	size_t count;
	char path[PROFILE_MAX_DIRS][PROFILE_PATH_MAX];
};

/*
 * profile_load_file - read and validate one profile file.
 * @path: the .ini file.
 * @out:  on success *out is a new profile (free with profile_free); NULL on error.
 * @err:  filled on error (may be NULL).
 * Returns 0 or a negative st_status class (IO, PARSE, RANGE, NOMEM).  The
 * whole file is checked before anything is returned: a profile with any bad
 * line is rejected, never partly applied.  Unknown keys are kept (see
 * profile_get), duplicate keys are an error.
 */
int profile_load_file(const char *path, struct profile **out, struct st_error *err);

/*
 * profile_load_buffer - as profile_load_file, from memory.
 * @text, @len: the file's bytes (need not be NUL-terminated).
 * @origin: the name used in error messages and as `path`; its base name
 *          without ".ini" becomes the id.
 */
int profile_load_buffer(const char *text, size_t len, const char *origin, struct profile **out,
			struct st_error *err);

/* One layer of settings for profile_load_layers: a file, or one key. */
struct profile_layer {
	const char *path;	 /* a flat config or a PrusaSlicer bundle; NULL: a key */
	const char *key, *value; /* the key to set (path NULL), value as in a file */
	const char *option;	 /* names the key's origin in messages ("--set"); NULL: --set */
};

/* The presets to take from a bundle; NULL members: the printer's defaults. */
struct profile_presets {
	const char *printer;  /* [printer:NAME]; required when a layer is a bundle */
	const char *print;    /* [print:NAME]; default: its default_print_profile */
	const char *filament; /* [filament:NAME]; default: its default_filament_profile */
};

/*
 * profile_load_layers - a profile from layers, later ones replacing the
 * keys of earlier ones, as PrusaSlicer's repeated --load:
 * @base:   a loaded profile whose keys come first (e.g. --printer), or NULL;
 * @layers: files and single keys in order.  A file with [printer:...],
 *          [print:...] or [filament:...] sections is a PrusaSlicer bundle:
 *          @pre's presets are resolved through `inherits` (parents split at
 *          ';', applied left to right, abstract *name* presets included)
 *          and applied printer, print, filament, with print_settings_id,
 *          filament_settings_id and printer_settings_id set to their names;
 *          [vendor] and [printer_model:...] set nothing.  Any other file is
 *          a flat config (a duplicate key in it is an error).  After each
 *          file a filament's filament_retract_* values that are not "nil"
 *          replace the printer's, as PrusaSlicer does.
 * The result is then checked as one file is; messages name the file and
 * line that set the key ("--set: layer_height: ..." for a key layer).
 * Returns 0 or as profile_load_file; ST_ERR_ARG for a bundle without a
 * printer preset or a preset it does not have.
 */
int profile_load_layers(const struct profile *base, const struct profile_layer *layers,
			size_t n, const struct profile_presets *pre, struct profile **out,
			struct st_error *err);

/*
 * profile_find - load a profile by NAME or by path.
 * @name_or_path: a value containing '/' or ending in ".ini" is a file path;
 *                anything else is a NAME looked up as NAME.ini in the
 *                directories of profile_search_dirs(), first match wins,
 *                then as a PrusaSlicer printer preset (see the top).
 * @out, @err: as profile_load_file.
 * Returns 0; ST_ERR_ARG when NAME is empty, not a plain name, or no
 * directory has it (the message lists where it looked); else as
 * profile_load_file.
 */
int profile_find(const char *name_or_path, struct profile **out, struct st_error *err);

/*
 * profile_exit_status - the exit status for a failed profile_find,
 * profile_load_file or profile_slicer_config, the one rule of every command
 * that loads a profile (printers --show, repair, slice, x3g, send, print,
 * ports): a value out of range or settings that cannot slice (ST_ERR_RANGE)
 * are refused like a bad --layer-height (ST_EXIT_USAGE), an unknown name too
 * (ST_ERR_ARG); anything else by its class (65 for a file that cannot be
 * read or parsed).
 */
int profile_exit_status(int rc);

/*
 * profile_search_dirs - the directories NAME lookups search, in order.
 * Reads $STRATUM_PRINTERS_DIR and /proc/self/exe; never fails (a directory
 * that cannot be determined is left out).
 */
void profile_search_dirs(struct profile_dirs *dirs);

/*
 * profile_list - every NAME.ini in the search directories, sorted by id.
 * A name found in an earlier directory hides the same name in later ones.
 * Files are only listed, not loaded.  Missing or unreadable directories are
 * skipped.
 * @out: on success a new array (free with profile_list_free), NULL when empty.
 * @count: number of entries.
 * Returns 0 or ST_ERR_NOMEM.
 */
int profile_list(struct profile_entry **out, size_t *count, struct st_error *err);

/* profile_list_free - free a profile_list() result; NULL is fine. */
void profile_list_free(struct profile_entry *list, size_t count);

/* profile_free - free a profile; NULL is fine. */
void profile_free(struct profile *p);

/*
 * profile_get - the value of any key of the file, escapes decoded, or NULL
 * when the file does not set it (defaults are not returned here; read the
 * struct fields for resolved values).  The string is owned by the profile.
 * This is how later code reads keys the loader does not type yet.
 */
const char *profile_get(const struct profile *p, const char *key);

/*
 * profile_printer_name - the printer as G-code headers name it
 * (printer_settings_id): a bundle's printer preset, else the profile's id.
 */
const char *profile_printer_name(const struct profile *p);

/*
 * profile_unsupported - the keys p sets that Stratum does not honour, as
 * one list "spiral_vase=1, ironing=1" (values cut at 24 bytes), and a
 * fill_pattern Stratum does not print ("fill_pattern=stars (rectilinear
 * used)").  A key is honoured when the loader types it, when it cannot
 * change what Stratum prints (notes, preset names, multi-material ...) or
 * when its value asks for what Stratum does anyway (ironing = 0).
 * *out: a new string (free()), NULL when every key is honoured.
 * Returns 0 or ST_ERR_NOMEM.
 */
int profile_unsupported(const struct profile *p, char **out);

/* Names for the enums, as written in profile files ("marlin", "marlin2", "max"). */
const char *profile_protocol_name(enum profile_protocol protocol);
const char *profile_flavor_name(enum profile_flavor flavor);
const char *profile_home_name(enum profile_home dir);

/*
 * profile_write - write the resolved settings as a flat profile file: every
 * key the loader knows with its resolved value (defaults included), then the
 * file's other keys unchanged.  Loading the output gives the same profile.
 * @f: an open stream; returns 0 or ST_ERR_IO (errno from the stream).
 */
int profile_write(const struct profile *p, FILE *f);

struct json_t;
/*
 * profile_to_json - the resolved settings as a new JSON object: "id",
 * "path", "settings" (every known key, typed: numbers, booleans, arrays,
 * strings) and "other" (the file's remaining keys as strings).  NULL when
 * out of memory.  The caller owns the reference (json_decref).
 */
struct json_t *profile_to_json(const struct profile *p);

#endif /* STRATUM_HOST_PROFILE_H */
