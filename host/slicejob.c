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

/* Repair m into *fixed (epsilon = the nozzle); 0 or the exit status. */
static int slicejob_repair(const char *cmd, const char *in, const struct mesh *m,
			   const struct slicer_config *c, struct progress *prog,
			   struct mesh **fixed, struct repair_report *rep)
{
	struct repair_options opt;
	struct st_error err = {0};
	int rc;

	repair_options_init(&opt);
	opt.epsilon = c->perim.nozzle_diameter;
	opt.precision = REPAIR_FLOAT64; /* slicing reads doubles: no float32 rounding needed */
	opt.threads = c->threads;
	if (prog) {
		opt.progress = progress_update;
		opt.progress_ctx = prog;
	}
	memset(rep, 0, sizeof(*rep));
	rc = repair_mesh(m, &opt, fixed, NULL, rep, &err);
	if (prog)
		progress_end(prog);
	if (rc < 0) {
		fprintf(stderr, "%s: %s: %s\n", cmd, in, err.msg);
		return rc == ST_ERR_ARG ? ST_EXIT_SOFTWARE : st_exit_for(rc);
	}
	if (!rep->printable) {
		fprintf(stderr, "%s: %s: could not be repaired to a printable solid: %s; "
				"nothing was written\n", cmd, in, rep->why);
		return ST_EXIT_FAILURE;
	}
	return 0;
}

int slicejob_run(const char *cmd, const char *in, const struct slicer_config *cfg,
		 bool no_repair, const char *out, bool progress, struct slicejob_result *res)
{
	struct slicer_config c = *cfg;
	struct st_error err = {0};
	struct mesh *m = NULL, *fixed = NULL;
	struct progress prog;
	bool have_prog;
	double off[3];
	int status = 0, rc;

	memset(res, 0, sizeof(*res));
	rc = meshio_read(in, MESHIO_AUTO, &m, &res->format, &err);
	if (rc) {
		fprintf(stderr, "%s: %s\n", cmd, err.msg);
		return rc == ST_ERR_NOMEM ? ST_EXIT_SOFTWARE : ST_EXIT_DATAERR;
	}
	res->input_triangles = m->ntris;
	/* Refuse a model too big before spending time on its repair. */
	rc = slicer_place(m, &c.bed, off, NULL, NULL, &err);
	if (rc) {
		fprintf(stderr, "%s: %s: %s; nothing was written\n", cmd, in, err.msg);
		status = slicejob_exit(rc);
		goto out_mesh;
	}
	if (!no_repair) {
		have_prog = progress && progress_start(&prog, cmd);
		status = slicejob_repair(cmd, in, m, &c, have_prog ? &prog : NULL, &fixed,
					 &res->rep);
		if (status)
			goto out_mesh;
		res->repaired = true;
	}
	have_prog = progress && progress_start(&prog, cmd);
	if (have_prog) {
		c.progress = progress_update;
		c.progress_ctx = &prog;
	}
	rc = slicer_run(fixed ? fixed : m, &c, out, &res->sum, &err);
	if (have_prog)
		progress_end(&prog);
	if (rc) {
		fprintf(stderr, "%s: %s: %s; nothing was written\n", cmd, in, err.msg);
		status = slicejob_exit(rc);
	}
	mesh_free(fixed);
out_mesh:
	mesh_free(m);
	return status;
}
