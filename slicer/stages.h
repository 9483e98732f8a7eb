/*
 * stages.h - private to slicer/: the job's stages as slicer.c runs them,
 * each given its settings from struct slicer_config, and the layer stacks
 * they fill.  A stage that produces nothing leaves its stack empty.
 */
#ifndef STRATUM_SLICER_STAGES_H
#define STRATUM_SLICER_STAGES_H

#include <stdbool.h>

#include "infill.h"
#include "section.h"
#include "slicer.h"
#include "st_error.h"
#include "toolpath.h"

/*
 * stage_print_stack - an empty stack with the layers (z, height) of the
 * raft (may be NULL), then those of st; NULL when out of memory (err
 * filled).  stage_stack - the same for st alone.
 */
struct layer_stack *stage_print_stack(const struct slice_stack *raft, const struct slice_stack *st,
				      struct st_error *err);
struct layer_stack *stage_stack(const struct slice_stack *st, struct st_error *err);

/*
 * stage_slice - the part's layers (uniform, adaptive.h's plan with
 * c->adaptive.enabled, or c->adaptive.profile's (adaptive_plan_profile)
 * when set; the first layer is layer_height thick over a raft) cut from m
 * into *st; sum gets the plan's heights and, adaptive or profiled, its
 * cusp (adaptive_measure).  Returns 0 or the plan's or slice_mesh_plan's error.
 */
int stage_slice(const struct mesh *m, const struct slicer_config *c, struct slice_stack **st,
		struct slicer_summary *sum, struct st_error *err);

/*
 * stage_report_plan - c->planned (when set) with the raft's layers (may
 * be NULL), then st's.  Returns 0 or ST_ERR_NOMEM.
 */
int stage_report_plan(const struct slicer_config *c, const struct slice_stack *raft,
		      const struct slice_stack *st, struct st_error *err);

/*
 * stage_support - support material under overhangs, from the bed
 * (support.h), into out when the job asks for it; *ran is set when it
 * produced paths.  Returns 0 or support_generate's error.
 */
int stage_support(const struct slicer_config *c, const struct slice_stack *st,
		  struct layer_stack *out, bool *ran, struct st_error *err);

/*
 * stage_raft_layers - the raft's layers into *raft (support_raft_new) and
 * st lifted onto them by *lift mm.  Returns 0, support_raft_new's error,
 * or ST_ERR_RANGE when the lifted part reaches above max_print_height
 * (*raft is then set and the caller frees it).
 */
int stage_raft_layers(const struct slicer_config *c, struct slice_stack *st,
		      struct slice_stack **raft, double *lift, struct st_error *err);

/*
 * stage_raft - the raft's areas and paths (support_raft) into raft and out,
 * under st's first layer and the support's first layer (support may be
 * NULL).  Returns 0 or support_raft's error.
 */
int stage_raft(const struct slicer_config *c, const struct slice_stack *st,
	       const struct layer_stack *support, struct slice_stack *raft, struct layer_stack *out,
	       struct st_error *err);

/*
 * stage_skirt - skirt and brim (skirt.h) around st's first layer and the
 * support's first layer (support may be NULL), into out; run after the
 * support stage so the skirt goes around it too.  *ran is set when it
 * produced paths.  Returns 0 or skirt_generate's error.
 */
int stage_skirt(const struct slicer_config *c, const struct slice_stack *st,
		const struct layer_stack *support, struct layer_stack *out, bool *ran,
		struct st_error *err);

/*
 * stage_infill_job - the infill job (infill.h) of the settings, with the
 * walls' width for any width left 0.  Returns 0 or the error of
 * infill_pattern_parse / infill_job_new; *job is then NULL.
 */
int stage_infill_job(const struct slicer_config *c, const struct slice_stack *st,
		     struct infill_job **job, struct st_error *err);

#endif /* STRATUM_SLICER_STAGES_H */
