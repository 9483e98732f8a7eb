/*
 * slicejob.h - a model file to G-code, as `stratum slice`, `stratum print`
 * and the farm node all do it: read, refuse a model that does not fit the
 * bed, repair exactly (epsilon = the nozzle), slice, write.  One path for
 * all three, so `stratum print --dry-run` and the node write the same
 * G-code as `stratum slice`.
 */
#ifndef STRATUM_HOST_SLICEJOB_H
#define STRATUM_HOST_SLICEJOB_H

#include <stdbool.h>
#include <stddef.h>

#include "meshio.h"
#include "repair.h"
#include "slicer.h"

/* Where a run stopped (slicejob_result.stage). */
enum slicejob_stage { SLICEJOB_READ, SLICEJOB_PLACE, SLICEJOB_REPAIR, SLICEJOB_SLICE };

/* What the run did, for the caller's summary. */
struct slicejob_result {
	enum slicejob_stage stage; /* the last stage begun: where a failure was */
	bool unprintable;	   /* the repair found no printable solid */
	enum meshio_format format;
	size_t input_triangles;
	bool repaired;		   /* rep is filled */
	struct repair_report rep;
	struct slicer_summary sum;
};

/*
 * slicejob_slice - slice the model file in into the G-code file out with
 * the checked settings cfg; repair first unless no_repair.  progress_name
 * non-NULL shows progress (bar or lines, progress.h) under that name;
 * nothing else is printed.  Returns 0, or the class with err filled
 * (res->stage says where): the reader's errors, ST_ERR_RANGE (does not
 * fit, not printable, nothing to print), ST_ERR_IO (out not written),
 * ST_ERR_PARSE (bad start/end G-code).  out is never half-written.
 */
int slicejob_slice(const char *in, const struct slicer_config *cfg, bool no_repair,
		   const char *out, const char *progress_name, struct slicejob_result *res,
		   struct st_error *err);

/*
 * slicejob_run - slicejob_slice for a command: messages go to stderr
 * prefixed with cmd, progress is shown under cmd when progress is true.
 * Returns 0, or the exit status with the reason printed: 1 (no printable
 * repair, does not fit, nothing to print, out not written), 65 (unreadable
 * model, bad start/end G-code), 70 (internal).  out is never half-written.
 */
int slicejob_run(const char *cmd, const char *in, const struct slicer_config *cfg,
		 bool no_repair, const char *out, bool progress, struct slicejob_result *res);

#endif /* STRATUM_HOST_SLICEJOB_H */
