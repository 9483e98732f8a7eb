/*
 * slicejob.h - a model file to G-code, as `stratum slice` and `stratum
 * print` both do it: read, refuse a model that does not fit the bed,
 * repair exactly (epsilon = the nozzle), slice, write.  One path for both
 * so `stratum print --dry-run` writes the same G-code as `stratum slice`.
 * Host code: messages go to stderr prefixed with the command's name.
 */
#ifndef STRATUM_HOST_SLICEJOB_H
#define STRATUM_HOST_SLICEJOB_H

#include <stdbool.h>
#include <stddef.h>

#include "meshio.h"
#include "repair.h"
#include "slicer.h"

/* What the run did, for the caller's summary. */
struct slicejob_result {
	enum meshio_format format;
	size_t input_triangles;
	bool repaired;		   /* rep is filled */
	struct repair_report rep;
	struct slicer_summary sum;
};

/*
 * slicejob_run - slice the model file in into the G-code file out with
 * the checked settings cfg; repair first unless no_repair.  Progress (bar
 * or lines, progress.h) is shown under the name cmd when progress is true.
 * Returns 0, or the exit status with the reason printed: 1 (no printable
 * repair, does not fit, nothing to print, out not written), 65 (unreadable
 * model, bad start/end G-code), 70 (internal).  out is never half-written.
 */
int slicejob_run(const char *cmd, const char *in, const struct slicer_config *cfg,
		 bool no_repair, const char *out, bool progress, struct slicejob_result *res);

#endif /* STRATUM_HOST_SLICEJOB_H */
