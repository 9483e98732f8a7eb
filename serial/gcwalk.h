/*
 * gcwalk.h - walk the moves of a G-code file with absolute positions: the
 * machine state a reader of sliced G-code needs (G90/G91, M82/M83, G92,
 * G28) kept once, on top of the one parser (gcode.h), for the region check
 * (host/region.c) and the layer preview (host/preview.c).
 *
 * Each G0-G3 line becomes one struct gcwalk_move with where the nozzle was
 * and where it goes (mm), the change of E (mm of filament) and what the
 * slicer's comments said about it: the last ";TYPE:" feature name
 * (Stratum, PrusaSlicer, SuperSlicer) and the layer counted from the layer
 * comments gcode_layer_comment knows.  Header comments
 * "; filament_diameter = D" are picked up on the way.
 *
 * Machine model (Marlin's): positions start at 0 in absolute mode; G90/G91
 * set X, Y, Z and E, a later M82/M83 sets E alone; G92 sets the axes it
 * names; G28 puts X, Y and Z at 0 (homing positions are not known here).
 * G20 (inches) and arcs that extrude (G2/G3 with E growing while X/Y move)
 * are refused; arcs that do not extrude are taken as straight moves.
 *
 * Thread-safety: none shared; one walker per thread.
 */
#ifndef STRATUM_SERIAL_GCWALK_H
#define STRATUM_SERIAL_GCWALK_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "st_error.h"

/* Farthest coordinate accepted, mm (keeps nm coordinates within int64). */
#define GCWALK_COORD_MAX 1e6

/* One motion line. */
struct gcwalk_move {
	int g;		       /* 0, 1, 2 or 3 */
	double from[3], to[3]; /* mm, absolute X Y Z before and after */
	double de;	       /* mm of filament: > 0 extrudes, < 0 retracts */
	double feed;	       /* mm/min, the modal F (0 before any) */
	const char *type;      /* last ";TYPE:" text, "" before the first; owned by
				* the walker, valid until the next call */
	long layer;	       /* layer comments seen, minus 1: -1 before the first */
	double layer_z;	       /* mm, Z named by the current layer's comments, NAN if none */
	double layer_height;   /* mm, ";HEIGHT:" of the current layer, NAN if none */
	uint64_t line;	       /* file line, from 1 */
};

struct gcwalk;

/*
 * gcwalk_new - a walker over fp, which stays the caller's.  @name is used in
 * messages ("NAME: line N: ...") and copied; NULL means "<input>".
 * Returns 0, ST_ERR_ARG or ST_ERR_NOMEM; *out is NULL on error.
 */
int gcwalk_new(FILE *fp, const char *name, struct gcwalk **out, struct st_error *err);

/* gcwalk_free - NULL is safe. */
void gcwalk_free(struct gcwalk *w);

/*
 * gcwalk_next - the next motion line.  Returns 1 with *m filled, 0 at the end
 * of the file, or a negative class with err filled as "NAME: line N: ...":
 * ST_ERR_PARSE (a line gcode.h refuses), ST_ERR_IO, ST_ERR_UNSUPPORTED (G20,
 * an extruding arc), ST_ERR_RANGE (a position beyond GCWALK_COORD_MAX).
 */
int gcwalk_next(struct gcwalk *w, struct gcwalk_move *m, struct st_error *err);

/* gcwalk_filament_diameter - mm from the first "; filament_diameter = D"
 * comment read so far (PrusaSlicer writes it at the end), 0 if none. */
double gcwalk_filament_diameter(const struct gcwalk *w);

/* gcwalk_layer_marks - layer-start comments read so far. */
long gcwalk_layer_marks(const struct gcwalk *w);

#endif /* STRATUM_SERIAL_GCWALK_H */
