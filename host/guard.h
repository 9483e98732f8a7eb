/*
 * guard.h - the wrong-printer guard: is a G-code file meant for this
 * printer profile?  `stratum send`, `stratum print`, `stratum x3g` and the
 * farm node's uploads ask it before anything reaches a printer or an X3G
 * file, and refuse (exit 2, HTTP 409) unless told --force (docs/printing.md,
 * "Files sliced for another printer").
 *
 * A file is refused when
 *  1. its header names another printer: both the file and the profile give
 *     a printer_model and they differ; or, when a model is missing, a file
 *     Stratum wrote names another printer_settings_id than the profile's
 *     (PrusaSlicer's preset names are only compared through the model);
 *  2. its header's nozzle_diameter differs from the profile's first nozzle
 *     by more than GUARD_NOZZLE_TOLERANCE;
 *  3. a move leaves the profile's bed: a move in X or Y ends outside the
 *     bed_shape's bounding box by more than GUARD_BED_TOLERANCE, or an
 *     extruding move is above max_print_height.  The printer's own start
 *     and end G-code is not judged (homing, a prime line or a park position
 *     off the print area): moves before the first layer comment and moves
 *     under ";TYPE:Custom" (PrusaSlicer's label for it), unless the file
 *     has no layer comments at all.
 * The header is read where Stratum writes it (the top) and where PrusaSlicer
 * does (its config block at the end): "; printer_settings_id = ",
 * "; printer_model = ", "; bed_shape = ", "; nozzle_diameter = ".
 *
 * Thread-safety: none shared; reads the file only.
 */
#ifndef STRATUM_HOST_GUARD_H
#define STRATUM_HOST_GUARD_H

#include <stdbool.h>

#include "profile.h"
#include "st_error.h"

#define GUARD_BED_TOLERANCE 0.5	     /* mm a move may pass the bed's edge (rounding, wipes) */
#define GUARD_NOZZLE_TOLERANCE 0.001 /* mm */

/*
 * guard_check_file - judge the G-code file at path for printer prof; @name
 * is the file in messages (an upload's name; NULL: path).
 * Returns 0 when it fits (a line the move walker refuses is skipped: the
 * sender's own check judges it); ST_ERR_RANGE when refused, with err naming the file, both printers
 * (or the line and the bed) and "--force"; ST_ERR_IO when it cannot be read.
 */
int guard_check_file(const char *path, const char *name, const struct profile *prof,
		     struct st_error *err);

/* What --force does, for each command's help. */
#define GUARD_FORCE_HELP "go on with G-code sliced for another printer or leaving its bed"

/*
 * guard_cli - guard_check_file for command cmd ("stratum send"): prints
 * "CMD: MESSAGE" on stderr and returns the exit status when refused; with
 * force, prints it as a warning ("..., going on: --force") and returns 0.
 * A file that cannot be read returns its exit status.
 */
int guard_cli(const char *cmd, const char *path, const struct profile *prof, bool force);

#endif /* STRATUM_HOST_GUARD_H */
