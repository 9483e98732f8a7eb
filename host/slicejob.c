/*
 * slicejob.c - model file to G-code for `stratum slice` and `stratum
 * print` (slicejob.h).
 */
#include "slicejob.h"

#include <stdio.h>
#include <string.h>

#include "mesh.h"
#include "progress.h"
#include "st_error.h"

/* Exit status for a failed slicer_run (settings were checked before). */
static int slicejob_exit(int rc)
{
	switch (rc) {
	case ST_ERR_RANGE: /* does not fit, nothing to print, too many layers */
	case ST_ERR_IO:	   /* OUT could not be written */
		return ST_EXIT_FAILURE;
	case ST_ERR_PARSE: /* the profile's start/end G-code */
	case ST_ERR_UNSUPPORTED:
		return ST_EXIT_DATAERR;
	default:
		return ST_EXIT_SOFTWARE;
	}
}

/* Repair m into *fixed (epsilon = the nozzle); 0 or an error class. */
static int slicejob_repair(const struct mesh *m, const struct slicer_config *c,
			   struct progress *prog, struct mesh **fixed,
			   struct slicejob_result *res, struct st_error *err)
{
	struct repair_options opt;
	int rc;

	repair_options_init(&opt);
	opt.epsilon = c->perim.nozzle_diameter;
	opt.precision = REPAIR_FLOAT64; /* slicing reads doubles: no float32 rounding needed */
	opt.threads = c->threads;
	if (prog) {
		opt.progress = progress_update;
		opt.progress_ctx = prog;
	}
	memset(&res->rep, 0, sizeof(res->rep));
	rc = repair_mesh(m, &opt, fixed, NULL, &res->rep, err);
	if (prog)
		progress_end(prog);
	if (rc < 0)
		return rc;
	if (!res->rep.printable) {
		res->unprintable = true;
		return st_error_set(err, ST_ERR_RANGE, "could not be repaired to a printable "
				    "solid: %s", res->rep.why);
	}
	return 0;
}

int slicejob_slice(const char *in, const struct slicer_config *cfg, bool no_repair,
		   const char *out, const char *progress_name, struct slicejob_result *res,
		   struct st_error *err)
{
	struct slicer_config c = *cfg;
	struct mesh *m = NULL, *fixed = NULL;
	struct progress prog;
	bool have_prog;
	double off[3];
	int rc;

	memset(res, 0, sizeof(*res));
	res->stage = SLICEJOB_READ;
	if ((rc = meshio_read(in, MESHIO_AUTO, &m, &res->format, err)))
		return rc;
	res->input_triangles = m->ntris;
	/* Refuse a model too big before spending time on its repair. */
	res->stage = SLICEJOB_PLACE;
	if ((rc = slicer_place(m, &c.bed, off, NULL, NULL, err)))
		goto out_mesh;
	if (!no_repair) {
		res->stage = SLICEJOB_REPAIR;
		have_prog = progress_name && progress_start(&prog, progress_name);
		if ((rc = slicejob_repair(m, &c, have_prog ? &prog : NULL, &fixed, res, err)))
			goto out_mesh;
		res->repaired = true;
	}
	res->stage = SLICEJOB_SLICE;
	have_prog = progress_name && progress_start(&prog, progress_name);
	if (have_prog) {
		c.progress = progress_update;
		c.progress_ctx = &prog;
	}
	rc = slicer_run(fixed ? fixed : m, &c, out, &res->sum, err);
	if (have_prog)
		progress_end(&prog);
	mesh_free(fixed);
out_mesh:
	mesh_free(m);
	return rc;
}

int slicejob_run(const char *cmd, const char *in, const struct slicer_config *cfg,
		 bool no_repair, const char *out, bool progress, struct slicejob_result *res)
{
	struct st_error err = {0};
	int rc = slicejob_slice(in, cfg, no_repair, out, progress ? cmd : NULL, res, &err);

	if (!rc)
		return 0;
	switch (res->stage) {
	case SLICEJOB_READ:
		fprintf(stderr, "%s: %s\n", cmd, err.msg);
		return rc == ST_ERR_NOMEM ? ST_EXIT_SOFTWARE : ST_EXIT_DATAERR;
	case SLICEJOB_REPAIR:
		if (res->unprintable) {
			fprintf(stderr, "%s: %s: %s; nothing was written\n", cmd, in, err.msg);
			return ST_EXIT_FAILURE;
		}
		fprintf(stderr, "%s: %s: %s\n", cmd, in, err.msg);
		return rc == ST_ERR_ARG ? ST_EXIT_SOFTWARE : st_exit_for(rc);
	default:
		fprintf(stderr, "%s: %s: %s; nothing was written\n", cmd, in, err.msg);
		return slicejob_exit(rc);
	}
}
