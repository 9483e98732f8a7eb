/*
 * slicejob.h - model files to G-code, as `stratum slice`, `stratum print`
 * and the farm node all do it: read, refuse a model that does not fit the
 * bed, repair exactly (epsilon = the nozzle), arrange several, slice,
 * write.  One path for all three, so `stratum print --dry-run` and the
 * node write the same G-code as `stratum slice`.
 */
#ifndef STRATUM_HOST_SLICEJOB_H
#define STRATUM_HOST_SLICEJOB_H

#include <stdbool.h>
#include <stddef.h>

#include "arrange.h"
#include "meshio.h"
#include "repair.h"
#include "slicer.h"

/* Where a run stopped (slicejob_result.stage). */
enum slicejob_stage { SLICEJOB_READ, SLICEJOB_PLACE, SLICEJOB_REPAIR, SLICEJOB_SLICE };

/* At most this many model files in one job (slicer/arrange.h). */
#define SLICEJOB_MODELS_MAX ARRANGE_MAX_ITEMS

/* What became of a 3MF's layer height profile (slicejob_result.profile). */
enum slicejob_profile {
	SLICEJOB_PROFILE_NONE,	      /* one model, and its file has none */
	SLICEJOB_PROFILE_USED,	      /* the layers follow it (slicer_summary.profiled) */
	SLICEJOB_PROFILE_ADAPTIVE,    /* not used: adaptive layers were asked for */
	SLICEJOB_PROFILE_NOT_ALLOWED, /* not used: the printer's variable_layer_height = 0 */
	SLICEJOB_PROFILE_SEVERAL,     /* not used: the 3MF holds several objects, or the
				       * job several models (the plate is sliced as one) */
	SLICEJOB_PROFILE_STALE,	      /* not used: it does not end at the object's top
				       * (PrusaSlicer drops it too: the object changed) */
};

/* A profile ends at most this far (mm) from the object's top (PrusaSlicer's bound). */
#define SLICEJOB_PROFILE_TOP_MM 1e-3

/* One model file of the job. */
struct slicejob_model {
	const char *path;	   /* as given; not owned */
	enum meshio_format format;
	size_t objects;		   /* 3MF <object> resources; 1 for the other formats */
	size_t input_triangles;
	struct repair_report rep;  /* filled when the job repaired */
	double offset[3];	   /* mm added to its vertices, all told, as printed */
};

/* What the run did, for the caller's summary (slicejob_result_free). */
struct slicejob_result {
	enum slicejob_stage stage; /* the last stage begun: where a failure was */
	size_t failed;		   /* in the READ, PLACE and REPAIR stages: the model's index */
	bool unprintable;	   /* the repair found no printable solid */
	enum meshio_format format; /* the first model's */
	size_t input_triangles;	   /* of every model */
	bool repaired;		   /* rep is filled */
	struct repair_report rep;  /* one model: its report; several: input and output
				    * triangles, parts and intersecting pairs summed */
	bool arranged;		   /* several models packed (arrange.h), not kept as their
				    * 3MF files place them */
	size_t nmodels;
	struct slicejob_model *models; /* [nmodels], in the order given */
	enum slicejob_profile profile; /* the 3MF's layer height profile, if any */
	double profile_top, model_top; /* mm: the profile's last Z, the model's height */
	struct slicer_summary sum;
};

/*
 * slicejob_slice - slice the n model files in[] into the G-code file out
 * with the checked settings cfg; repair each first unless no_repair.  One
 * model is placed as slicer_place places it.  Several are each repaired
 * on their own, then arranged (docs/slicing.md "Several models"): kept
 * where their files put them when every one is a 3MF and no two
 * footprints overlap, otherwise packed by arrange_footprints; each lowest
 * point goes on the bed and the pile is placed as one model.
 * progress_name non-NULL shows progress (bar or lines, progress.h) under
 * that name; otherwise cfg->progress, when set, gets the repair's phases
 * and then the slicer's (the farm node's slicingProgress).  One 3MF model
 * of one object whose file keeps a layer height profile for it
 * (meshio_3mf_layer_profile) is sliced in the profile's layers unless
 * cfg asks for adaptive ones or the printer allows no variable heights
 * (res->profile says which).  Nothing else
 * is printed.  Returns 0, or the class with err
 * filled (res->stage and res->failed say where): the reader's errors,
 * ST_ERR_RANGE (does not fit, not printable, nothing to print), ST_ERR_IO
 * (out not written), ST_ERR_PARSE (bad start/end G-code), ST_ERR_ARG (no
 * model or more than SLICEJOB_MODELS_MAX).  out is never half-written.
 * res is filled in either case; slicejob_result_free frees it.
 */
int slicejob_slice(const char *const *in, size_t n, const struct slicer_config *cfg,
		   bool no_repair, const char *out, const char *progress_name,
		   struct slicejob_result *res, struct st_error *err);

/*
 * slicejob_run - slicejob_slice for a command: messages go to stderr
 * prefixed with cmd and the model they are about, progress is shown under
 * cmd when progress is true.  Returns 0, or the exit status with the
 * reason printed: 1 (no printable repair, does not fit, nothing to print,
 * out not written), 65 (unreadable model, bad start/end G-code), 70
 * (internal).  out is never half-written.
 */
int slicejob_run(const char *cmd, const char *const *in, size_t n,
		 const struct slicer_config *cfg, bool no_repair, const char *out, bool progress,
		 struct slicejob_result *res);

/* slicejob_result_free - free what res holds (res itself is the caller's). */
void slicejob_result_free(struct slicejob_result *res);

#endif /* STRATUM_HOST_SLICEJOB_H */
