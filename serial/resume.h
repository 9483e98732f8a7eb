/*
 * resume.h - continuing an interrupted print: where the printer was at a
 * byte of the G-code file (heater targets, position, modes) and the
 * commands that bring it back there.  The printer adapters send them
 * (printer.h, job.resume): Marlin's form as it is (printer_marlin.c), the
 * Sailfish form (resume_preamble_x3g) translated to X3G by the stream's
 * own translator (printer_sailfish.c).  docs/serve.md and
 * docs/printing.md describe the sequence.
 */
#ifndef STRATUM_SERIAL_RESUME_H
#define STRATUM_SERIAL_RESUME_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "st_error.h"

/* Longest preamble line (bytes), Marlin's command limit (marlin.h). */
#define RESUME_LINE_MAX 81
/* Largest |value| (mm, mm/min, C) a preamble line carries: 9 digits and 5
 * decimals stay within the G-code parser's 15 significant digits. */
#define RESUME_VALUE_MAX 1e9
/* Room for the longest preamble resume_preamble writes. */
#define RESUME_LINES 20

/* The printer's state at a byte of a file, for a resume. */
struct resume_state {
	double tool, bed, fan;	   /* targets; fan 0-255 */
	double x, y, z, e, f;	   /* positions (mm) in the file's own coordinates */
	bool rel_xyz, rel_e;	   /* G91, M83 */
	bool moved;		   /* a move was seen: x, y, z mean something */
	double z_nozzle;	   /* where the nozzle stands (mm): the Z of the last
				    * command the printer executed, which may be in the
				    * layer after z's (resume_locate); resume_scan: z */
};

/*
 * resume_scan - read the G-code file path up to byte end and work out the
 * state there into *rs.  Returns 0, ST_ERR_IO (cannot open), the parser's
 * error for a bad line (err names file and line), or ST_ERR_RANGE when a
 * position, feed rate or target reaches RESUME_VALUE_MAX (relative moves
 * add up): the preamble could not write it.
 */
int resume_scan(const char *path, int64_t end, struct resume_state *rs, struct st_error *err);

/*
 * resume_locate - the state a resume needs: resume_scan at offset (where
 * the stream starts again, a layer start) and rs->z_nozzle the Z at saved,
 * the byte just past the last command the printer executed (0 or <= offset:
 * the same as offset).  Resuming from a layer start while the nozzle is
 * already in that layer, a Z set to the layer below would print every
 * remaining layer one layer high.  Returns resume_scan's errors.
 */
int resume_locate(const char *path, int64_t offset, int64_t saved, struct resume_state *rs,
		  struct st_error *err);

/*
 * resume_preamble - the commands that bring a printer back to rs: bed heat
 * first so the part stays stuck, Z taken as it was (never homed: that
 * would drive into the part; z_nozzle), lift, home X and Y only, nozzle heat, back
 * over the part, down (no lower than z_nozzle, above the part), modes, extruder position, fan.  Writes at most cap
 * lines into out; returns how many.
 */
size_t resume_preamble(const struct resume_state *rs, char out[][RESUME_LINE_MAX + 1], size_t cap);

/*
 * resume_preamble_x3g - the same restoring sequence as G-code the X3G
 * translator takes (serial/x3g.h), for Sailfish printers: build start
 * (M73), bed heat and wait (M190 S), nozzle heat (M104), Z set with
 * G92 (X3G sets all five axes at once, so X, Y and the extruders are set
 * too, and the translator's position agrees), lift, G28 X Y (the
 * translator homes each axis to the end the machine's endstop is at: the
 * Creator Pro's X and Y are at max), M132 X Y (the calibrated home
 * offsets, so X and Y are in the file's frame again), nozzle wait (M133:
 * M109 means the platform to GPX), back over the part, down, modes,
 * extruder position, feed rate, fan.  Writes at most cap lines; returns
 * how many.
 */
size_t resume_preamble_x3g(const struct resume_state *rs, char out[][RESUME_LINE_MAX + 1],
			   size_t cap);

/*
 * resume_return - the commands that bring a held print back to rs after an
 * operator's commands ran while it held (printer.h inject: a jog, an
 * extrusion, a mode change): lift, absolute mode, back over the part,
 * down (none of the three before the file's first move), then the file's
 * modes, extruder position and feed rate as resume_preamble ends (set_e
 * false leaves E alone: G92 E would be a set-position of every axis in
 * X3G).  Heat stays as the operator left it.
 * Writes at most cap lines; returns how many.
 */
size_t resume_return(const struct resume_state *rs, bool set_e, char out[][RESUME_LINE_MAX + 1],
		     size_t cap);

/* Room for the text resume_x3g_text writes. */
#define RESUME_TEXT_MAX (RESUME_LINES * (RESUME_LINE_MAX + 2))

/*
 * resume_x3g_text - resume_locate of path at byte offset (saved: the byte
 * past the last command executed, 0 = offset), then
 * resume_preamble_x3g as one string, '\n' after each line, the form the
 * Sailfish sources take (sf_source.h pre).  buf holds RESUME_TEXT_MAX
 * bytes.  Returns 0 or resume_scan's error.
 */
int resume_x3g_text(const char *path, int64_t offset, int64_t saved,
		    char buf[RESUME_TEXT_MAX], struct st_error *err);

/*
 * resume_layer_start - where a Sailfish resume starts: the layer (by the
 * slicer's layer comments, gcode_layer_comment) that holds the last line
 * ending at or before byte pos, or the first layer when none does.  Its
 * comment line's byte offset in *offset, its 0-based number in *layer.
 * Returns 0; ST_ERR_IO (cannot open), the parser's error, or ST_ERR_PARSE
 * "has no layer comments" (then nobody can tell where a layer starts).
 */
int resume_layer_start(const char *path, int64_t pos, int64_t *offset, long *layer,
		       struct st_error *err);

#endif /* STRATUM_SERIAL_RESUME_H */
