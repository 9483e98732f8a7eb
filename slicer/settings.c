/*
 * settings.c - the declaration of every printer and slicer setting
 * (settings.h).  Ranges are what the slicer can print with; the loader
 * refuses anything outside them when a profile is loaded.
 */
#include "settings.h"

#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "st_number.h"

#define COUNT(a) (sizeof(a) / sizeof((a)[0]))

static const char *const protocol_names[] = {"marlin", "sailfish"};

/* PrusaSlicer's gcode_flavor names (PrintConfig.cpp), in enum profile_flavor order. */
static const char *const flavor_names[] = {
    "reprap",  "reprapfirmware", "repetier", "teacup",	   "makerware", "marlin",	"marlin2",
    "klipper", "sailfish",	 "mach3",    "machinekit", "smoothie",	"no-extrusion",
};

/* PrusaSlicer's InfillPattern names (PrintConfig.cpp s_keys_map_InfillPattern). */
static const char *const pattern_names[] = {
    "rectilinear",  "monotonic",	 "monotoniclines", "alignedrectilinear", "grid",
    "triangles",    "stars",		 "cubic",	   "line",		 "concentric",
    "honeycomb",    "3dhoneycomb",	 "gyroid",	   "hilbertcurve",	 "archimedeanchords",
    "octagramspiral", "adaptivecubic", "supportcubic",   "lightning",		 "zigzag",
};

/* PrusaSlicer 2.5's top_fill_pattern and bottom_fill_pattern names. */
static const char *const skin_pattern_names[] = {
    "rectilinear", "monotonic", "alignedrectilinear", "concentric", "hilbertcurve",
    "archimedeanchords", "octagramspiral",
};

/* PrusaSlicer's MachineLimitsUsage names. */
static const char *const limits_usage_names[] = {"emit_to_gcode", "time_estimate_only", "ignore"};

static const char *const home_names[] = {"min", "max"};

/* PrusaSlicer 2.6's ArcFittingType names. */
static const char *const arc_fitting_names[] = {"disabled", "emit_center"};

/* PrusaSlicer's IroningType names, in enum iron_type order (slicer/ironing.h). */
static const char *const ironing_names[] = {"top", "topmost", "solid"};

/* PrusaSlicer's SupportMaterialStyle names, in enum support_style order
 * (2.6's organic trees are refused: profile_keys.c says so). */
static const char *const support_style_names[] = {"grid", "snug"};

/* PrusaSlicer's SupportMaterialPattern names, in enum support_pattern order. */
static const char *const support_pattern_names[] = {"rectilinear", "rectilinear-grid",
						    "honeycomb"};

/* PrusaSlicer's SeamPosition names, in enum perim_seam order. */
static const char *const seam_names[] = {"aligned", "nearest", "random", "rear"};

/* What a percentage of a speed is of (PrusaSlicer's ratio_over); the help
 * of each key says the same. */
static const struct {
	const char *key, *of;
} pct_bases[] = {
    {"external_perimeter_speed", "perimeter_speed"},
    {"small_perimeter_speed", "perimeter_speed"},
    {"solid_infill_speed", "infill_speed"},
    {"top_solid_infill_speed", "solid_infill_speed"},
    {"support_material_interface_speed", "support_material_speed"},
};

static const long baud_rates[] = {2400,	  4800,	  9600,	  19200,  38400,  57600,   115200,
				  230400, 250000, 460800, 500000, 921600, 1000000, 2000000};

#define CHOICES(a) a, COUNT(a)
#define S_ SETTING_ONE
#define EX SETTING_PER_EXTRUDER
#define FI SETTING_FIRST
#define LI SETTING_LIMITS
#define GT SETTING_GT_MIN
#define SF SETTING_SAILFISH
#define NUM SETTING_NUMBER
#define PCT SETTING_NUMBER_OR_PCT
#define INT SETTING_INT
#define BOOL SETTING_BOOL
#define STR SETTING_STRING

/* Keys in the order the loader applies and writes them. */
static const struct setting table[] = {
    {"name", STR, S_, 0, 0, 0, "", NULL, NULL, NULL, 0, "Identity",
     "display name; default: the file name without .ini"},
    {"description", STR, S_, 0, 0, 0, "", "", NULL, NULL, 0, NULL, "one line"},
    {"printer_model", STR, S_, 0, 0, 0, "", "", NULL, NULL, 0, NULL, "PrusaSlicer's model id, e.g. MK3S"},

    {"protocol", SETTING_CHOICE, S_, 0, 0, 0, "", "marlin", NULL, CHOICES(protocol_names),
     "Connection", "wire protocol; sailfish when gcode_flavor is sailfish or makerware"},
    {"baudrate", SETTING_BAUD, S_, 0, 0, 0, "", "115200", NULL, NULL, 0, NULL,
     "the firmware's BAUDRATE"},
    {"usb_ids", SETTING_USB_IDS, S_, 0, 0, 0, "", "", NULL, NULL, 0, NULL,
     "USB VID:PID pairs that identify the board (lsusb's ID vvvv:pppp)"},
    {"rx_buffer_size", INT, S_, 16, 65536, 0, "bytes", "128", NULL, NULL, 0, NULL,
     "the firmware's RX_BUFFER_SIZE (Marlin)"},
    {"bufsize", INT, S_, 0, 256, 0, "commands", "0", NULL, NULL, 0, NULL,
     "the firmware's BUFSIZE, command queue slots (Marlin); 0 = unknown: learnt from "
     "ADVANCED_OK, else only bytes are counted"},
    {"dtr_reset", BOOL, S_, 0, 0, 0, "", "1", NULL, NULL, 0, NULL,
     "opening the port resets the board"},
    {"x3g_buffer_size", INT, S_, 0, 65536, SF, "bytes", "0", NULL, NULL, 0, NULL,
     "Sailfish command buffer; 0 = ask the firmware"},

    {"gcode_flavor", SETTING_CHOICE, S_, 0, 0, 0, "", "marlin2", "sailfish", CHOICES(flavor_names),
     "Machine", "G-code dialect; must fit protocol (sailfish or makerware for sailfish)"},
    {"bed_shape", SETTING_POLYGON, S_, -10000, 10000, 0, "mm", "0x0,200x0,200x200,0x200", NULL,
     NULL, 0, NULL, "printable bed polygon in printer coordinates, 3-1024 points"},
    {"max_print_height", NUM, S_, 0, 10000, GT, "mm", "200", NULL, NULL, 0, NULL, ""},
    {"extruder_count", INT, S_, 1, 8, 0, "", NULL, NULL, NULL, 0, NULL,
     "Stratum's key; default: the length of nozzle_diameter, else 1 (sailfish: at most 2)"},
    {"use_relative_e_distances", BOOL, S_, 0, 0, 0, "", "0", NULL, NULL, 0, NULL,
     "M83 (relative E) instead of M82"},
    {"remaining_times", BOOL, S_, 0, 0, 0, "", "0", NULL, NULL, 0, NULL,
     "M73 P (percent done) R (minutes left, from the estimate) at the start, at each layer "
     "change where either changes, and P100 R0 at the end"},
    {"silent_mode", BOOL, S_, 0, 0, 0, "", "1", NULL, NULL, 0, NULL,
     "the firmware has a stealth mode: with remaining_times and the marlin or marlin2 "
     "flavour, each M73 P R is followed by M73 Q S (the same figures: the estimate uses the "
     "normal mode's limits)"},

    {"nozzle_diameter", NUM, EX, 0.05, 3, 0, "mm", "0.4", NULL, NULL, 0, "Extruders", ""},
    {"filament_diameter", NUM, EX, 1, 3.5, 0, "mm", "1.75", NULL, NULL, 0, NULL, ""},
    {"extruder_offset", SETTING_POINT, EX, -1000, 1000, 0, "mm", "0x0", NULL, NULL, 0, NULL, ""},
    {"extrusion_multiplier", NUM, EX, 0, 5, GT, "", "1", NULL, NULL, 0, NULL, ""},
    {"filament_density", NUM, FI, 0, 30, 0, "g/cm^3", "1.24", NULL, NULL, 0, NULL,
     "for the filament weight in the estimate (PLA: 1.24); 0 = unknown, weight 0 (PrusaSlicer's default)"},
    {"temperature", INT, EX, 0, 450, 0, "C", "200", NULL, NULL, 0, NULL, ""},
    {"first_layer_temperature", INT, EX, 0, 450, 0, "C", NULL, NULL, NULL, 0, NULL,
     "default: temperature"},
    {"bed_temperature", INT, FI, 0, 150, 0, "C", "0", NULL, NULL, 0, NULL, ""},
    {"first_layer_bed_temperature", INT, FI, 0, 150, 0, "C", NULL, NULL, NULL, 0, NULL,
     "default: bed_temperature"},
    {"retract_length", NUM, EX, 0, 50, 0, "mm", "2", NULL, NULL, 0, NULL, ""},
    {"retract_speed", NUM, EX, 0, 1000, GT, "mm/s", "40", NULL, NULL, 0, NULL, ""},
    {"retract_lift", NUM, EX, 0, 50, 0, "mm", "0", NULL, NULL, 0, NULL, "Z hop"},
    {"retract_lift_above", NUM, EX, 0, 10000, 0, "mm", "0", NULL, NULL, 0, NULL,
     "Z hop only where the layer is at this Z or above"},
    {"retract_lift_below", NUM, EX, 0, 10000, 0, "mm", "0", NULL, NULL, 0, NULL,
     "Z hop only where the layer is at this Z or below; 0 = no limit"},
    {"deretract_speed", NUM, EX, 0, 1000, 0, "mm/s", "0", NULL, NULL, 0, NULL,
     "0 = retract_speed"},
    {"retract_before_travel", NUM, EX, 0, 1e6, 0, "mm", "2", NULL, NULL, 0, NULL,
     "shorter travels do not retract"},
    {"wipe", BOOL, FI, 0, 0, 0, "", "0", NULL, NULL, 0, NULL,
     "retract while moving back over the last path"},
    {"retract_before_wipe", SETTING_PERCENT, FI, 0, 100, 0, "%", "0%", NULL, NULL, 0, NULL,
     "with wipe, this share of the retraction is done standing before the wipe, the rest "
     "while wiping (a bare number is a fraction)"},
    {"retract_layer_change", BOOL, FI, 0, 0, 0, "", "0", NULL, NULL, 0, NULL,
     "retract (wiping, lifting) before each layer change; the first travel of the layer "
     "unretracts"},
    {"variable_layer_height", BOOL, S_, 0, 0, 0, "", "1", NULL, NULL, 0, NULL,
     "the printer can print layers of varying height: adaptive_layer_height is refused "
     "when 0"},
    {"min_layer_height", NUM, EX, 0, 3, 0, "mm", "0.07", NULL, NULL, 0, NULL,
     "at most the nozzle and max_layer_height"},
    {"max_layer_height", NUM, EX, 0, 3, 0, "mm", "0", NULL, NULL, 0, NULL,
     "at most the nozzle; 0 means 75% of the nozzle"},

    {"layer_height", NUM, S_, 0, 3, GT, "mm", "0.2", NULL, NULL, 0, "Print",
     "at most the smallest nozzle"},
    {"first_layer_height", SETTING_NUMBER_OR_PCT, S_, 0, 3, GT, "mm", "0.2", NULL, NULL, 0, NULL,
     "at most the smallest nozzle; a percentage is of layer_height"},
    {"adaptive_layer_height", BOOL, S_, 0, 0, 0, "", "0", NULL, NULL, 0, NULL,
     "Stratum's key (`stratum slice --adaptive`): above the first layer, each layer between "
     "min_layer_height and max_layer_height (at most 75% of the nozzle) as thick as "
     "adaptive_max_cusp allows (docs/slicing.md)"},
    {"adaptive_max_cusp", NUM, S_, 0, 1, GT, "mm", "0.1", NULL, NULL, 0, NULL,
     "Stratum's key (`--max-cusp`): the largest staircase step (layer height times the facet normal's Z, unsigned) "
     "adaptive layers leave on a sloped facet"},
    {"extrusion_width", SETTING_NUMBER_OR_PCT, S_, 0, 10, 0, "mm", "0", NULL, NULL, 0, NULL,
     "0 = automatic (PrusaSlicer 2.5's: the nozzle for the top skin and support, 1.125 x "
     "the nozzle for the rest); a percentage is of layer_height (as in PrusaSlicer)"},
    {"first_layer_extrusion_width", PCT, S_, 0, 10, 0, "mm", "0", NULL, NULL, 0, NULL,
     "every bead of the first layer on the bed (support and raft too), skirt and brim; 0 = "
     "each role's own "
     "width; a percentage is of first_layer_height (PrusaSlicer's default is 200%)"},
    {"perimeter_extrusion_width", PCT, S_, 0, 10, 0, "mm", "0", NULL, NULL, 0, NULL,
     "inner walls; 0 = extrusion_width; a percentage is of layer_height"},
    {"external_perimeter_extrusion_width", PCT, S_, 0, 10, 0, "mm", "0", NULL, NULL, 0, NULL,
     "the outer wall, its outer face kept on the model's surface; 0 = extrusion_width; a "
     "percentage is of layer_height"},
    {"infill_extrusion_width", PCT, S_, 0, 10, 0, "mm", "0", NULL, NULL, 0, NULL,
     "sparse infill; 0 = extrusion_width; a percentage is of layer_height"},
    {"solid_infill_extrusion_width", PCT, S_, 0, 10, 0, "mm", "0", NULL, NULL, 0, NULL,
     "solid infill and bottom skin; likewise"},
    {"top_infill_extrusion_width", PCT, S_, 0, 10, 0, "mm", "0", NULL, NULL, 0, NULL,
     "top skin; 0 = extrusion_width, or the nozzle when that is 0 too; a percentage is of "
     "layer_height"},
    {"support_material_extrusion_width", PCT, S_, 0, 10, 0, "mm", "0", NULL, NULL, 0, NULL,
     "support and raft; likewise"},
    {"perimeters", INT, S_, 0, 100, 0, "", "3", NULL, NULL, 0, NULL, ""},
    {"elefant_foot_compensation", NUM, S_, 0, 10, 0, "mm", "0", NULL, NULL, 0, NULL,
     "the first layer's islands shrunk by this much (one the shrink would remove is kept)"},
    {"seam_position", SETTING_CHOICE, S_, 0, 0, 0, "", "aligned", NULL, CHOICES(seam_names),
     NULL, "where closed walls start: near the seams below, nearest the nozzle, anywhere, or "
     "at the back (largest Y); concave corners first"},
    {"external_perimeters_first", BOOL, S_, 0, 0, 0, "", "0", NULL, NULL, 0, NULL,
     "walls printed outside in (default: inside out)"},
    {"thin_walls", BOOL, S_, 0, 0, 0, "", "1", NULL, NULL, 0, NULL,
     "one centre-line bead where two walls do not fit"},
    {"gap_fill_enabled", BOOL, S_, 0, 0, 0, "", "1", NULL, NULL, 0, NULL,
     "beads in the strips left between walls"},
    {"min_feature_size", PCT, S_, 0, 10, 0, "mm", "25%", NULL, NULL, 0, NULL,
     "thin walls narrower than the nozzle but at least this wide print as one bead of "
     "min_bead_width (a warning says how much wider); an island narrower is dropped and "
     "counted; a percentage is of nozzle_diameter (PrusaSlicer's Arachne key)"},
    {"min_bead_width", PCT, S_, 0, 10, 0, "mm", "85%", NULL, NULL, 0, NULL,
     "the narrowest bead printed for a feature of min_feature_size or wider; a percentage "
     "is of nozzle_diameter (PrusaSlicer's Arachne key)"},
    {"wall_transition_length", PCT, S_, 0, 10, 0, "mm", "100%", NULL, NULL, 0, NULL,
     "where a wall's two sides come closer than two beads, they run diagonally over this "
     "length into the one centre-line bead that carries on, in one run; a percentage is of "
     "nozzle_diameter (PrusaSlicer's Arachne key)"},
    {"wall_transition_angle", NUM, S_, 1, 59, 0, "degrees", "10", NULL, NULL, 0, NULL,
     "a wall that narrows faster than a wedge of this angle is not joined to its centre-line "
     "bead (PrusaSlicer's Arachne key)"},
    {"overhangs", BOOL, S_, 0, 0, 0, "", "0", NULL, NULL, 0, NULL,
     "walls more than half the nozzle outside the layer below print with bridge flow, "
     "bridge_speed and bridge_fan_speed (Overhang perimeter); PrusaSlicer's default is 1"},
    {"spiral_vase", BOOL, S_, 0, 0, 0, "", "0", NULL, NULL, 0, NULL,
     "above the bottom layers one wall around the largest island (holes and smaller islands "
     "dropped), printed as a spiral rising along each loop; no top layers, no infill there"},
    {"top_solid_layers", INT, S_, 0, 1000, 0, "", "3", NULL, NULL, 0, NULL, ""},
    {"bottom_solid_layers", INT, S_, 0, 1000, 0, "", "3", NULL, NULL, 0, NULL, ""},
    {"top_solid_min_thickness", NUM, S_, 0, 1000, 0, "mm", "0", NULL, NULL, 0, NULL,
     "more top layers until the top shell is this thick"},
    {"bottom_solid_min_thickness", NUM, S_, 0, 1000, 0, "mm", "0", NULL, NULL, 0, NULL,
     "likewise for the bottom shell"},
    {"fill_angle", NUM, S_, -360, 360, 0, "degrees", "45", NULL, NULL, 0, NULL,
     "direction of infill lines (sparse lines turn 90 degrees each layer)"},
    {"bridge_angle", NUM, S_, -360, 360, 0, "degrees", "0", NULL, NULL, 0, NULL,
     "direction of bridges; 0 = the best one per bridge"},
    {"bridge_flow_ratio", NUM, S_, 0, 2, GT, "", "1", NULL, NULL, 0, NULL,
     "bridge thread area over the nozzle's"},
    {"thick_bridges", BOOL, S_, 0, 0, 0, "", "1", NULL, NULL, 0, NULL,
     "bridges as round threads of the nozzle's diameter times the square root of "
     "bridge_flow_ratio, 0.05 mm apart; 0: flat beads of the solid infill's width and the "
     "layer's height at its spacing, their cross-section times bridge_flow_ratio"},
    {"infill_overlap", PCT, S_, 0, 10, 0, "mm", "25%", NULL, NULL, 0, NULL,
     "how far infill reaches into the innermost wall; a percentage (at most 100%) is of "
     "extrusion_width"},
    {"fill_density", SETTING_PERCENT, S_, 0, 100, 0, "%", "20%", NULL, NULL, 0, NULL,
     "a bare number is a fraction (0.15 = 15%), as old Slic3r wrote it"},
    {"fill_pattern", SETTING_CHOICE, S_, 0, 0, 0, "", "rectilinear", NULL, CHOICES(pattern_names),
     NULL, "PrusaSlicer's names (monotonous is read as monotonic); rectilinear, grid, gyroid, "
     "triangles, stars, cubic, line, concentric and honeycomb are printed (docs/slicing.md), "
     "any other prints rectilinear, named in the warning"},
    {"infill_anchor", PCT, S_, 0, 1000, 0, "mm", "600%", NULL, NULL, 0, NULL,
     "a sparse line end joined to no other gets this much of the boundary (at most half way "
     "to its neighbour); a percentage is of infill_extrusion_width"},
    {"infill_anchor_max", PCT, S_, 0, 1000, 0, "mm", "0", NULL, NULL, 0, NULL,
     "sparse line ends are joined along the boundary to their neighbours where that is at "
     "most this long (not for line and concentric); 0 = not joined (PrusaSlicer's default "
     "is 50); a percentage is of infill_extrusion_width"},
    {"top_fill_pattern", SETTING_CHOICE, S_, 0, 0, 0, "", "rectilinear", NULL,
     CHOICES(skin_pattern_names), NULL,
     "the top skin's lines: rectilinear (each line from the end nearest the nozzle) or "
     "monotonic (in one sweep across each island, PrusaSlicer's default); any other prints "
     "rectilinear, named in the warning"},
    {"bottom_fill_pattern", SETTING_CHOICE, S_, 0, 0, 0, "", "rectilinear", NULL,
     CHOICES(skin_pattern_names), NULL, "likewise for the bottom skin"},
    {"solid_infill_below_area", NUM, S_, 0, 1e6, 0, "mm^2", "70", NULL, NULL, 0, NULL,
     "sparse infill islands smaller than this are solid"},
    {"ironing", BOOL, S_, 0, 0, 0, "", "0", NULL, NULL, 0, NULL,
     "after the top skin, a second pass over the same area at the same Z: lines ironing_spacing "
     "apart, 45 degrees to the skin, at low flow"},
    {"ironing_type", SETTING_CHOICE, S_, 0, 0, 0, "", "top", NULL, CHOICES(ironing_names), NULL,
     "top: every top surface; topmost: the last layer only (both need top_solid_layers > 0); "
     "solid: every solid surface, all of a layer that is solid throughout"},
    {"ironing_flowrate", SETTING_PERCENT, S_, 0, 100, 0, "%", "15%", NULL, NULL, 0, NULL,
     "of the flow of a layer_height bead over the line spacing; a bare number is a fraction"},
    {"ironing_spacing", NUM, S_, 0, 10, GT, "mm", "0.1", NULL, NULL, 0, NULL,
     "distance between ironing lines"},
    {"ironing_speed", NUM, S_, 0, 1000, GT, "mm/s", "15", NULL, NULL, 0, NULL, ""},
    {"skirts", INT, S_, 0, 100, 0, "", "1", NULL, NULL, 0, NULL, "loops"},
    {"skirt_distance", NUM, S_, 0, 1000, 0, "mm", "6", NULL, NULL, 0, NULL,
     "gap between the skirt and the part, or its brim"},
    {"skirt_height", INT, S_, 0, 10000, 0, "", "1", NULL, NULL, 0, NULL,
     "layers carrying the skirt; 0 = no skirt"},
    {"min_skirt_length", NUM, S_, 0, 1e6, 0, "mm", "0", NULL, NULL, 0, NULL,
     "loops are added until the skirt uses this much filament"},
    {"brim_width", NUM, S_, 0, 200, 0, "mm", "0", NULL, NULL, 0, NULL, ""},
    {"brim_separation", NUM, S_, 0, 100, 0, "mm", "0", NULL, NULL, 0, NULL,
     "gap between the brim and the part"},
    {"duplicate_distance", NUM, S_, 0, 1000, 0, "mm", "6", NULL, NULL, 0, NULL,
     "least gap between the footprints of several models sliced together, as arranged"},
    {"support_material", BOOL, S_, 0, 0, 0, "", "0", NULL, NULL, 0, NULL, ""},
    {"support_material_threshold", INT, S_, 0, 90, 0, "degrees", "0", NULL, NULL, 0, NULL,
     "0 = automatic"},
    {"support_material_style", SETTING_CHOICE, S_, 0, 0, 0, "", "grid", NULL,
     CHOICES(support_style_names), NULL,
     "grid: the support's islands closed into blocks; snug: they follow the overhang's "
     "outline (organic, PrusaSlicer 2.6's trees, is refused)"},
    {"support_material_pattern", SETTING_CHOICE, S_, 0, 0, 0, "", "rectilinear", NULL,
     CHOICES(support_pattern_names), NULL,
     "the body's lines: along support_material_angle on every layer, turned 90 degrees "
     "every other layer (rectilinear-grid), or hexagons (honeycomb)"},
    {"support_material_with_sheath", BOOL, S_, 0, 0, 0, "", "1", NULL, NULL, 0, NULL,
     "a loop around each island of the support's body"},
    {"support_material_buildplate_only", BOOL, S_, 0, 0, 0, "", "0", NULL, NULL, 0, NULL,
     "support only where it stands on the bed; 0: on the model too, where it meets it"},
    {"support_material_contact_distance", NUM, S_, 0, 10, 0, "mm", "0.2", NULL, NULL, 0, NULL,
     "Z gap between the support's top and the overhang, whole layers; 0 = none (soluble), "
     "no bottom gap either"},
    {"support_material_bottom_contact_distance", NUM, S_, 0, 10, 0, "mm", "0", NULL, NULL, 0,
     NULL, "Z gap between the model's top surface and support standing on it, whole layers; "
     "0 = support_material_contact_distance"},
    {"support_material_interface_layers", INT, S_, 0, 1000, 0, "", "3", NULL, NULL, 0, NULL,
     "dense layers under the top gap"},
    {"support_material_bottom_interface_layers", INT, S_, -1, 1000, 0, "", "-1", NULL, NULL, 0,
     NULL, "dense layers at the foot of support standing on the model; -1 = "
     "support_material_interface_layers"},
    {"support_material_interface_spacing", NUM, S_, 0, 1000, 0, "mm", "0", NULL, NULL, 0, NULL,
     "gap between interface beads; 0 = solid"},
    {"support_material_spacing", NUM, S_, 0, 1000, GT, "mm", "2.5", NULL, NULL, 0, NULL,
     "gap between the support body's beads"},
    {"support_material_angle", NUM, S_, 0, 359, 0, "degrees", "0", NULL, NULL, 0, NULL,
     "the support's lines turned by this much (interface and body alike)"},
    {"support_material_xy_spacing", PCT, S_, 0, 10, 0, "mm", "50%", NULL, NULL, 0, NULL,
     "least gap between support beads and the model on the same layer; a percentage is of "
     "external_perimeter_extrusion_width"},
    {"dont_support_bridges", BOOL, S_, 0, 0, 0, "", "1", NULL, NULL, 0, NULL,
     "no support under a bridge: an overhang whose lines rest on the layer below at both "
     "ends"},
    {"raft_layers", INT, S_, 0, 100, 0, "", "0", NULL, NULL, 0, NULL,
     "layers of raft under the part, which is lifted onto it; 0 = no raft"},
    {"raft_contact_distance", NUM, S_, 0, 10, 0, "mm", "0.1", NULL, NULL, 0, NULL,
     "gap between the top of the raft and the part's first layer"},
    {"raft_expansion", NUM, S_, 0, 100, 0, "mm", "1.5", NULL, NULL, 0, NULL,
     "how far the raft reaches beyond the part's first layer"},
    {"raft_first_layer_density", SETTING_PERCENT, S_, 10, 100, 0, "%", "90%", NULL, NULL, 0, NULL,
     "density of the raft's first layer (a bare number is a fraction)"},
    {"raft_first_layer_expansion", NUM, S_, 0, 100, 0, "mm", "3", NULL, NULL, 0, NULL,
     "how much further the raft's first layer reaches"},
    {"gcode_resolution", NUM, S_, 0, 1, 0, "mm", "0.0125", NULL, NULL, 0, NULL,
     "every path and travel is written as a polyline with fewer points, none of the dropped "
     "ones farther than this from it; filament and bead widths as sliced; 0 = every point"},
    {"arc_fitting", SETTING_CHOICE, S_, 0, 0, 0, "", "disabled", NULL,
     CHOICES(arc_fitting_names), NULL,
     "emit_center: runs of extrusion that an arc holds within gcode_resolution (half of it on "
     "the outer wall) are written as G2/G3 with the centre as I J; only for the marlin, marlin2 "
     "and reprapfirmware flavours (any other is warned about and gets lines)"},

    {"travel_speed", NUM, S_, 0, 1000, GT, "mm/s", "130", NULL, NULL, 0, "Speed", ""},
    {"travel_speed_z", NUM, S_, 0, 1000, 0, "mm/s", "0", NULL, NULL, 0, NULL,
     "Z moves; 0 = machine_max_feedrate_z (PrusaSlicer: travel_speed, which the firmware "
     "limits to it)"},
    {"perimeter_speed", NUM, S_, 0, 1000, GT, "mm/s", "60", NULL, NULL, 0, NULL,
     "inner walls"},
    {"external_perimeter_speed", PCT, S_, 0, 1000, GT, "mm/s", "50%", NULL, NULL, 0, NULL,
     "outermost walls and thin walls; a percentage is of perimeter_speed"},
    {"small_perimeter_speed", PCT, S_, 0, 1000, GT, "mm/s", "15", NULL, NULL, 0, NULL,
     "closed walls at most 2 pi 6.5 mm long (PrusaSlicer's small perimeters); a percentage is "
     "of perimeter_speed"},
    {"infill_speed", NUM, S_, 0, 1000, GT, "mm/s", "80", NULL, NULL, 0, NULL, "sparse infill"},
    {"solid_infill_speed", PCT, S_, 0, 1000, GT, "mm/s", "20", NULL, NULL, 0, NULL,
     "solid infill and bottom skin; a percentage is of infill_speed"},
    {"top_solid_infill_speed", PCT, S_, 0, 1000, GT, "mm/s", "15", NULL, NULL, 0, NULL,
     "top skin; a percentage is of solid_infill_speed"},
    {"bridge_speed", NUM, S_, 0, 1000, GT, "mm/s", "60", NULL, NULL, 0, NULL, ""},
    {"gap_fill_speed", NUM, S_, 0, 1000, GT, "mm/s", "20", NULL, NULL, 0, NULL, ""},
    {"support_material_speed", NUM, S_, 0, 1000, GT, "mm/s", "60", NULL, NULL, 0, NULL,
     "support, skirt and brim (as PrusaSlicer)"},
    {"support_material_interface_speed", PCT, S_, 0, 1000, GT, "mm/s", "100%", NULL, NULL, 0,
     NULL, "a percentage is of support_material_speed"},
    {"first_layer_speed", PCT, S_, 0, 1000, 0, "mm/s", "30", NULL, NULL, 0, NULL,
     "every extrusion of the first layer; a percentage is of each one's own speed; 0 = not "
     "slowed"},
    {"first_layer_speed_over_raft", PCT, S_, 0, 1000, 0, "mm/s", "30", NULL, NULL, 0, NULL,
     "every extrusion of the part's first layer on a raft, likewise"},
    {"max_volumetric_speed", NUM, S_, 0, 1000, 0, "mm^3/s", "0", NULL, NULL, 0, NULL,
     "every extrusion at most this fast in filament volume: its speed at most the limit "
     "over its bead's cross-section (before the slow-down for short layers); 0 = no limit"},
    {"filament_max_volumetric_speed", NUM, FI, 0, 1000, 0, "mm^3/s", "0", NULL, NULL, 0, NULL,
     "the filament's limit, likewise; with both set the lower applies"},
    {"default_acceleration", NUM, S_, 0, 100000, 0, "mm/s^2", "0", NULL, NULL, 0, NULL,
     "M204 S before each path's own value and after each path; 0 = never written, the per-role keys below unused"},
    {"perimeter_acceleration", NUM, S_, 0, 100000, 0, "mm/s^2", "0", NULL, NULL, 0, NULL,
     "walls (outer, inner, thin); 0 = default_acceleration"},
    {"infill_acceleration", NUM, S_, 0, 100000, 0, "mm/s^2", "0", NULL, NULL, 0, NULL,
     "sparse, solid and top infill, ironing (not gap fill); 0 = default_acceleration"},
    {"bridge_acceleration", NUM, S_, 0, 100000, 0, "mm/s^2", "0", NULL, NULL, 0, NULL,
     "bridges; 0 = default_acceleration"},
    {"first_layer_acceleration", NUM, S_, 0, 100000, 0, "mm/s^2", "0", NULL, NULL, 0, NULL,
     "every path of the first layer; 0 = the role's"},

    {"avoid_crossing_perimeters", BOOL, S_, 0, 0, 0, "", "1", NULL, NULL, 0, "Travel",
     "route travels inside the part instead of across its walls"},
    {"avoid_crossing_perimeters_max_detour", PCT, S_, 0, 1000, 0, "mm", "100%", NULL, NULL, 0,
     NULL, "a route inside the part longer than the straight travel by more than this goes "
     "straight; a percentage is of the straight travel; 0 = any detour (PrusaSlicer's "
     "default)"},
    {"only_retract_when_crossing_perimeters", BOOL, S_, 0, 0, 0, "", "1", NULL, NULL, 0, NULL,
     "no retraction for a travel that stays inside the part"},
    {"max_unretracted_travel", NUM, S_, 0, 1e6, 0, "mm", "20", NULL, NULL, 0, NULL,
     "Stratum's key: longer travels inside the part retract anyway"},

    {"cooling", BOOL, FI, 0, 0, 0, "", "1", NULL, NULL, 0, "Cooling",
     "the fan and slow-down by layer time"},
    {"fan_always_on", BOOL, FI, 0, 0, 0, "", "0", NULL, NULL, 0, NULL,
     "the fan never goes below min_fan_speed (after disable_fan_first_layers)"},
    {"min_fan_speed", INT, FI, 0, 100, 0, "%", "35", NULL, NULL, 0, NULL, "at most max_fan_speed"},
    {"max_fan_speed", INT, FI, 0, 100, 0, "%", "100", NULL, NULL, 0, NULL, ""},
    {"bridge_fan_speed", INT, FI, 0, 100, 0, "%", "100", NULL, NULL, 0, NULL, ""},
    {"disable_fan_first_layers", INT, FI, 0, 1000, 0, "", "3", NULL, NULL, 0, NULL,
     "layers printed with the fan off"},
    {"full_fan_speed_layer", INT, FI, 0, 1000, 0, "", "0", NULL, NULL, 0, NULL,
     "the fan ramps up from disable_fan_first_layers to full speed on this layer; 0 = no ramp"},
    {"fan_below_layer_time", INT, FI, 0, 3600, 0, "s", "60", NULL, NULL, 0, NULL, ""},
    {"slowdown_below_layer_time", INT, FI, 0, 3600, 0, "s", "5", NULL, NULL, 0, NULL, ""},
    {"min_print_speed", NUM, FI, 0, 1000, GT, "mm/s", "10", NULL, NULL, 0, NULL,
     "slow-down for short layers stops here"},

    {"machine_limits_usage", SETTING_CHOICE, S_, 0, 0, 0, "", "time_estimate_only", NULL,
     CHOICES(limits_usage_names), "Machine limits",
     "emit_to_gcode writes the limits (M201, M203, M204, M205) before the start G-code for "
     "the marlin and marlin2 flavours; the estimate uses them in every case"},
    {"machine_max_feedrate_x", NUM, LI, 0, 100000, GT, "mm/s", "500", NULL, NULL, 0, NULL, ""},
    {"machine_max_feedrate_y", NUM, LI, 0, 100000, GT, "mm/s", "500", NULL, NULL, 0, NULL, ""},
    {"machine_max_feedrate_z", NUM, LI, 0, 100000, GT, "mm/s", "12", NULL, NULL, 0, NULL, ""},
    {"machine_max_feedrate_e", NUM, LI, 0, 100000, GT, "mm/s", "120", NULL, NULL, 0, NULL, ""},
    {"machine_max_acceleration_x", NUM, LI, 0, 100000, GT, "mm/s^2", "9000", NULL, NULL, 0, NULL,
     ""},
    {"machine_max_acceleration_y", NUM, LI, 0, 100000, GT, "mm/s^2", "9000", NULL, NULL, 0, NULL,
     ""},
    {"machine_max_acceleration_z", NUM, LI, 0, 100000, GT, "mm/s^2", "500", NULL, NULL, 0, NULL,
     ""},
    {"machine_max_acceleration_e", NUM, LI, 0, 100000, GT, "mm/s^2", "10000", NULL, NULL, 0, NULL,
     ""},
    {"machine_max_acceleration_extruding", NUM, LI, 0, 100000, 0, "mm/s^2", "1500", NULL, NULL, 0,
     NULL, ""},
    {"machine_max_acceleration_retracting", NUM, LI, 0, 100000, 0, "mm/s^2", "1500", NULL, NULL,
     0, NULL, ""},
    {"machine_max_acceleration_travel", NUM, LI, 0, 100000, 0, "mm/s^2", "1500", NULL, NULL, 0,
     NULL, "0 = not limited separately"},
    {"machine_max_jerk_x", NUM, LI, 0, 1000, 0, "mm/s", "10", NULL, NULL, 0, NULL, ""},
    {"machine_max_jerk_y", NUM, LI, 0, 1000, 0, "mm/s", "10", NULL, NULL, 0, NULL, ""},
    {"machine_max_jerk_z", NUM, LI, 0, 1000, 0, "mm/s", "0.2", NULL, NULL, 0, NULL, ""},
    {"machine_max_jerk_e", NUM, LI, 0, 1000, 0, "mm/s", "2.5", NULL, NULL, 0, NULL, ""},
    {"machine_min_extruding_rate", NUM, LI, 0, 1000, 0, "mm/s", "0", NULL, NULL, 0, NULL,
     "written as M205 S"},
    {"machine_min_travel_rate", NUM, LI, 0, 1000, 0, "mm/s", "0", NULL, NULL, 0, NULL,
     "written as M205 T"},

    /* The sailfish defaults are GPX's Replicator 1 machine (markwal/GPX
     * src/shared/std_machines.h), the family the Creator Pro belongs to. */
    {"steps_per_mm_x", NUM, S_, 0, 100000, SF, "steps/mm", "0", "94.117647", NULL, 0,
     "Sailfish machine (X3G)", "more than 0 on a sailfish printer"},
    {"steps_per_mm_y", NUM, S_, 0, 100000, SF, "steps/mm", "0", "94.117647", NULL, 0, NULL,
     "more than 0 on a sailfish printer"},
    {"steps_per_mm_z", NUM, S_, 0, 100000, SF, "steps/mm", "0", "400", NULL, 0, NULL,
     "more than 0 on a sailfish printer"},
    {"steps_per_mm_e", NUM, EX, 0, 100000, SF, "steps/mm", "0", "96.275201870333662", NULL, 0,
     NULL, "per mm of filament; more than 0 on a sailfish printer"},
    {"home_direction_x", SETTING_CHOICE, S_, 0, 0, SF, "", "min", "max", CHOICES(home_names), NULL,
     "which end the axis homes to"},
    {"home_direction_y", SETTING_CHOICE, S_, 0, 0, SF, "", "min", "max", CHOICES(home_names), NULL,
     ""},
    {"home_direction_z", SETTING_CHOICE, S_, 0, 0, SF, "", "min", "min", CHOICES(home_names), NULL,
     ""},
    {"home_feedrate_x", NUM, S_, 0, 100000, SF, "mm/min", "0", "2500", NULL, 0, NULL,
     "homing speed (G-code F units)"},
    {"home_feedrate_y", NUM, S_, 0, 100000, SF, "mm/min", "0", "2500", NULL, 0, NULL, ""},
    {"home_feedrate_z", NUM, S_, 0, 100000, SF, "mm/min", "0", "1100", NULL, 0, NULL, ""},
    {"home_position_x", NUM, S_, -10000, 10000, SF, "mm", "0", NULL, NULL, 0, NULL,
     "position after homing, before M132 recalls the calibrated one"},
    {"home_position_y", NUM, S_, -10000, 10000, SF, "mm", "0", NULL, NULL, 0, NULL, ""},
    {"home_position_z", NUM, S_, -10000, 10000, SF, "mm", "0", NULL, NULL, 0, NULL, ""},
    {"x3g_toolhead_offset_x", NUM, S_, -1000, 1000, SF, "mm", "0", NULL, NULL, 0, NULL,
     "tool 1's offset from tool 0 (Sailfish applies its EEPROM's on tool changes)"},
    {"x3g_toolhead_offset_y", NUM, S_, -1000, 1000, SF, "mm", "0", NULL, NULL, 0, NULL, ""},
    {"x3g_toolhead_offset_z", NUM, S_, -1000, 1000, SF, "mm", "0", NULL, NULL, 0, NULL, ""},
    {"x3g_heated_platform", BOOL, S_, 0, 0, SF, "", "1", NULL, NULL, 0, NULL,
     "the platform heater is driven through the tool boards (M140/M190 are written)"},
    {"x3g_home_timeout", INT, S_, 1, 65535, SF, "s", "20", NULL, NULL, 0, NULL,
     "homing time-out in X3G commands 131/132 (GPX timeout)"},

    {"start_gcode", STR, S_, 0, 0, 0, "", "G28 ; home all axes\nG1 Z5 F5000 ; lift nozzle\n", "",
     NULL, 0, "Custom G-code", "PrusaSlicer's default; a sailfish profile must give its own"},
    {"end_gcode", STR, S_, 0, 0, 0, "",
     "M104 S0 ; turn off temperature\nG28 X0  ; home X axis\nM84     ; disable motors\n", "", NULL,
     0, NULL, "PrusaSlicer's default; a sailfish profile must give its own"},
    {"before_layer_gcode", STR, S_, 0, 0, 0, "", "", NULL, NULL, 0, NULL,
     "before each layer change; layer_num, layer_z, max_layer_z are the new layer's"},
    {"layer_gcode", STR, S_, 0, 0, 0, "", "", NULL, NULL, 0, NULL, "after each layer change"},
    {"start_filament_gcode", STR, FI, 0, 0, 0, "", "", NULL, NULL, 0, NULL,
     "after start_gcode (PrusaSlicer writes a list, \"a\";\"b\", per filament)"},
    {"end_filament_gcode", STR, FI, 0, 0, 0, "", "", NULL, NULL, 0, NULL, "before end_gcode"},
    {"toolchange_gcode", STR, S_, 0, 0, 0, "", "", NULL, NULL, 0, NULL,
     "checked, never written: one extruder prints (PrusaSlicer writes none either)"},
    {"thumbnails", STR, S_, 0, 0, 0, "", "", NULL, NULL, 0, NULL,
     "sizes WxH, comma-separated (160x120): per size a PNG picture of the part in the G-code "
     "header, PrusaSlicer's thumbnail comments; empty = none"},

};

size_t settings_count(void)
{
	return COUNT(table);
}

const struct setting *settings_at(size_t i)
{
	return i < COUNT(table) ? &table[i] : NULL;
}

/*
 * The table by name, sorted once: loading a profile looks up every key it
 * sets and every default, and a scan of the whole table for each made
 * that quadratic in the table's size (three quarters of a load's time).
 */
static const struct setting *by_name[COUNT(table)];
static pthread_once_t by_name_once = PTHREAD_ONCE_INIT;

static int compare_names(const void *a, const void *b)
{
	return strcmp((*(const struct setting *const *)a)->name,
		      (*(const struct setting *const *)b)->name);
}

static void sort_by_name(void)
{
	for (size_t i = 0; i < COUNT(table); i++)
		by_name[i] = &table[i];
	qsort(by_name, COUNT(table), sizeof(by_name[0]), compare_names);
}

const struct setting *settings_find(const char *name)
{
	const struct setting key = {.name = name}, *k = &key, *const *hit;

	if (!name)
		return NULL;
	pthread_once(&by_name_once, sort_by_name);
	hit = bsearch(&k, by_name, COUNT(table), sizeof(by_name[0]), compare_names);
	return hit ? *hit : NULL;
}

const char *setting_pct_of(const struct setting *s)
{
	for (size_t i = 0; s && i < COUNT(pct_bases); i++)
		if (!strcmp(pct_bases[i].key, s->name))
			return pct_bases[i].of;
	return NULL;
}

/* A bool has the range 0 to 1 whatever the table says. */
bool setting_in_range(const struct setting *s, double v)
{
	double lo = s->type == SETTING_BOOL ? 0 : s->min, hi = s->type == SETTING_BOOL ? 1 : s->max;

	if (!isfinite(v))
		return false;
	if (s->flags & SETTING_GT_MIN)
		return v > lo && v <= hi;
	return v >= lo && v <= hi;
}

/* Shortest %g form of v that reads back exactly. */
static void fmt_exact(char *buf, size_t cap, double v)
{
	snprintf(buf, cap, "%.15g", v);
	if (strtod(buf, NULL) != v)
		snprintf(buf, cap, "%.17g", v);
}

void setting_range_text(const struct setting *s, char *buf, size_t cap)
{
	char lo[32], hi[32];
	const char *sp = *s->unit ? " " : "";

	fmt_exact(lo, sizeof(lo), s->min);
	fmt_exact(hi, sizeof(hi), s->max);
	if (s->flags & SETTING_GT_MIN)
		snprintf(buf, cap, "more than %s and at most %s%s%s", lo, hi, sp, s->unit);
	else
		snprintf(buf, cap, "between %s and %s%s%s", lo, hi, sp, s->unit);
}

bool setting_default_number(const char *name, bool sailfish, double *out)
{
	const struct setting *s = settings_find(name);
	const char *d;
	size_t len;
	double base;

	if (!s || (s->type != SETTING_NUMBER && s->type != SETTING_INT && s->type != SETTING_BOOL &&
		   s->type != SETTING_NUMBER_OR_PCT && s->type != SETTING_PERCENT))
		return false;
	d = sailfish && s->sailfish_dflt ? s->sailfish_dflt : s->dflt;
	if (!d)
		return false;
	len = strlen(d);
	if (len && d[len - 1] == '%' && s->type == SETTING_PERCENT) /* percent itself */
		return st_parse_double(d, len - 1, 0, out) == ST_NUMBER_OK;
	if (len && d[len - 1] == '%') { /* a percentage of another key's default */
		if (!setting_pct_of(s) || st_parse_double(d, len - 1, 0, out) != ST_NUMBER_OK ||
		    !setting_default_number(setting_pct_of(s), sailfish, &base))
			return false;
		*out *= base / 100;
		return true;
	}
	return st_parse_double(d, len, 0, out) == ST_NUMBER_OK;
}

int setting_check(const char *what, const char *name, double v, struct st_error *err)
{
	const struct setting *s = settings_find(name);
	char range[96];

	if (!s)
		return st_error_set(err, ST_ERR_INTERNAL, "%s: %s is not a declared setting", what,
				    name);
	if (setting_in_range(s, v))
		return 0;
	setting_range_text(s, range, sizeof(range));
	return st_error_set(err, ST_ERR_RANGE, "%s: %s = %g is out of range (must be %s)", what,
			    name, v, range);
}

const long *settings_baud_rates(size_t *count)
{
	*count = COUNT(baud_rates);
	return baud_rates;
}

/* ---------------------------------------------------------------------------
 * The docs' key tables
 */

static const char *const type_words[] = {
    [SETTING_STRING] = "text",
    [SETTING_NUMBER] = "number",
    [SETTING_INT] = "whole number",
    [SETTING_BOOL] = "0 or 1",
    [SETTING_POINT] = "point XxY",
    [SETTING_NUMBER_OR_PCT] = "number or percentage",
    [SETTING_PERCENT] = "percentage",
    [SETTING_CHOICE] = "name",
    [SETTING_BAUD] = "baud rate",
    [SETTING_USB_IDS] = "list of VVVV:PPPP",
    [SETTING_POLYGON] = "list of points XxY",
};

static const char *const shape_words[] = {
    [SETTING_ONE] = "",
    [SETTING_PER_EXTRUDER] = ", per extruder",
    [SETTING_FIRST] = ", a list's first value is used",
    [SETTING_LIMITS] = ", 1 or 2 values (normal, stealth)",
};

/* A default as the docs show it: escapes for newlines, in backticks. */
static void put_default(FILE *f, const char *d)
{
	if (!d) {
		fputs("see meaning", f);
		return;
	}
	if (!*d) {
		fputs("empty", f);
		return;
	}
	fputc('`', f);
	for (; *d; d++)
		if (*d == '\n')
			fputs("\\n", f);
		else
			fputc(*d, f);
	fputc('`', f);
}

/* The range column: numbers, names or rates. */
static void put_range(FILE *f, const struct setting *s)
{
	char buf[128];

	switch (s->type) {
	case SETTING_NUMBER:
	case SETTING_INT:
	case SETTING_POINT:
	case SETTING_POLYGON:
	case SETTING_PERCENT:
		setting_range_text(s, buf, sizeof(buf));
		fputs(buf, f);
		return;
	case SETTING_NUMBER_OR_PCT:
		setting_range_text(s, buf, sizeof(buf));
		fprintf(f, "%s, or 0%% to 1000%%", buf);
		return;
	case SETTING_CHOICE:
		for (size_t i = 0; i < s->nnames; i++)
			fprintf(f, "%s`%s`", i ? ", " : "", s->names[i]);
		return;
	case SETTING_BAUD:
		for (size_t i = 0; i < COUNT(baud_rates); i++)
			fprintf(f, "%s%ld", i ? ", " : "", baud_rates[i]);
		return;
	case SETTING_STRING:
	case SETTING_BOOL:
	case SETTING_USB_IDS:
		return;
	}
}

int settings_write_doc(FILE *f)
{
	for (size_t i = 0; i < COUNT(table); i++) {
		const struct setting *s = &table[i];

		if (s->group)
			fprintf(f, "%s### %s\n\n| key | type | range | default | meaning |\n"
				   "|---|---|---|---|---|\n",
				i ? "\n" : "", s->group);
		fprintf(f, "| `%s` | %s%s%s | ", s->name, type_words[s->type], shape_words[s->shape],
			(s->flags & SETTING_SAILFISH) ? ", sailfish" : "");
		put_range(f, s);
		fputs(" | ", f);
		put_default(f, s->dflt);
		if (s->sailfish_dflt && strcmp(s->sailfish_dflt, s->dflt ? s->dflt : "")) {
			fputs(" (sailfish: ", f);
			put_default(f, s->sailfish_dflt);
			fputc(')', f);
		}
		fprintf(f, " | %s |\n", s->help);
	}
	return ferror(f) ? ST_ERR_IO : 0;
}
