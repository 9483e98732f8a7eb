/*
 * toolpath.h - what the slicer's geometry stages hand to the G-code writer:
 * per layer, an ordered list of extrusion paths in integer coordinates
 * (1 unit = 1 nm, docs/architecture.md item 4), each point carrying its bead width so
 * thin walls can vary their flow along the path.
 *
 * The geometry stages (perimeters, thin walls, skins, infill, skirt, brim,
 * supports) append paths to a struct layer_paths in the order they should
 * print; the writer (gcode_writer.h) adds travel, retraction, flow, speed,
 * fan and temperature.  A layer_stack owns every layer of one print.
 *
 * Ownership: toolpath_* functions copy what they are given; layer_stack_free
 * frees everything, the layers' travel maps included.  Not thread-safe on
 * one object; distinct layers may be
 * filled from distinct threads once layer_stack_new has sized the stack.
 */
#ifndef STRATUM_SLICER_TOOLPATH_H
#define STRATUM_SLICER_TOOLPATH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "st_error.h"

struct travel_map; /* travel.h */

/* Nanometres per millimetre: the integer grid of all 2-D work. */
#define SLICE_UNITS_PER_MM 1000000.0

/* What a path is: decides speed, fan, G-code ;TYPE: comment and ordering. */
enum path_role {
	PATH_OUTER_PERIMETER = 0, /* outermost wall, centre line w/2 inside the surface */
	PATH_INNER_PERIMETER,	  /* the other walls */
	PATH_THIN_WALL,		  /* single centre-line bead of a region narrower than 2 walls */
	PATH_GAP_FILL,		  /* beads filling gaps between walls */
	PATH_SOLID_INFILL,	  /* internal solid infill (under tops, over bridges) */
	PATH_TOP_SKIN,		  /* top solid surface */
	PATH_BOTTOM_SKIN,	  /* bottom solid surface */
	PATH_SPARSE_INFILL,	  /* sparse infill at the requested density */
	PATH_BRIDGE,		  /* bridge infill over air: bridge flow and fan */
	PATH_SKIRT,		  /* skirt loops around the first layers */
	PATH_BRIM,		  /* brim loops attached to the first layer */
	PATH_SUPPORT,		  /* support body */
	PATH_SUPPORT_INTERFACE,	  /* dense support layers under the part */
	PATH_IRONING,		  /* second pass over a top surface at low flow (infill.h) */
	PATH_OVERHANG_PERIMETER,  /* a wall's piece over air: bridge flow, speed and fan
				   * (overhang.h) */
	PATH_ROLES		  /* number of roles */
};

/* One vertex of a path: position and the bead width from here to the next
 * vertex, all in nm. */
struct path_point {
	int64_t x, y;
	int64_t width;
};

/* An extrusion path: an open polyline, or a closed loop whose last point
 * connects back to the first (the first point is the seam). */
struct toolpath {
	enum path_role role;
	bool closed;
	bool ordered;		 /* printed in the layer's order and direction (monotonic
				  * skins); false: the writer may pick nearest first */
	size_t n;		 /* points */
	struct path_point *pts;	 /* n points, owned */
};

/* One layer: its top Z and thickness, and the paths in printing order. */
struct layer_paths {
	double z;      /* mm, top of the layer (the nozzle height while printing it) */
	double height; /* mm, layer thickness (bead height) */
	size_t n, cap; /* paths used / allocated */
	struct toolpath *paths;
	/* The layer's region for travels that avoid crossing perimeters
	 * (travel.h), owned; NULL: travels go straight. */
	struct travel_map *travel;
	/* Spiral vase: the layer is one closed outer wall, printed with Z
	 * rising from z - height to z along its length (gcode_writer.h). */
	bool spiral;
};

/* Every layer of one print, bottom to top. */
struct layer_stack {
	size_t nlayers;
	struct layer_paths *layers;
};

/* A stack of nlayers empty layers with z/height set by the caller; NULL when
 * out of memory (err filled). */
struct layer_stack *layer_stack_new(size_t nlayers, struct st_error *err);

/* Free a stack and every path in it; NULL is fine. */
void layer_stack_free(struct layer_stack *s);

/* Free the paths and travel map of one layer, leaving it empty (z and
 * height kept); NULL is fine. */
void layer_paths_clear(struct layer_paths *l);

/* Append a copy of pts[0..n) as a path of the given role to layer l.
 * A path needs at least 2 points (3 when closed); widths must be > 0.
 * Returns 0, ST_ERR_ARG for a bad path, ST_ERR_NOMEM. */
int layer_add_path(struct layer_paths *l, enum path_role role, bool closed,
		   const struct path_point *pts, size_t n, struct st_error *err);

/* Name of a role as written in G-code comments (";TYPE:External perimeter"),
 * PrusaSlicer's names where it has one. */
const char *path_role_name(enum path_role role);

#endif
