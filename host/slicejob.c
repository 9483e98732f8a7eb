/*
 * slicejob.c - model files to G-code for `stratum slice`, `stratum print`
 * and the farm node (slicejob.h).
 */
#include "slicejob.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mesh.h"
#include "progress.h"
#include "st_error.h"
#include "thumbnail.h"

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

/* Repair m into *fixed (epsilon = the nozzle) with *rep; 0 or an error class. */
static int slicejob_repair(const struct mesh *m, const struct slicer_config *c,
			   const char *progress_name, struct mesh **fixed,
			   struct repair_report *rep, bool *unprintable, struct st_error *err)
{
	struct repair_options opt;
	struct progress prog;
	bool have_prog = progress_name && progress_start(&prog, progress_name);
	int rc;

	repair_options_init(&opt);
	opt.epsilon = c->perim.nozzle_diameter;
	opt.precision = REPAIR_FLOAT64; /* slicing reads doubles: no float32 rounding needed */
	opt.threads = c->threads;
	if (have_prog) {
		prog.prefix = "repairing the mesh: ";
		opt.progress = progress_update;
		opt.progress_ctx = &prog;
	} else if (c->progress) { /* the caller's own: the repair's phases too */
		opt.progress = c->progress;
		opt.progress_ctx = c->progress_ctx;
	}
	memset(rep, 0, sizeof(*rep));
	rc = repair_mesh(m, &opt, fixed, NULL, rep, err);
	if (have_prog)
		progress_end(&prog);
	if (rc < 0)
		return rc;
	if (!rep->printable) {
		*unprintable = true;
		return st_error_set(err, ST_ERR_RANGE, "could not be repaired to a printable "
				    "solid: %s", rep->why);
	}
	return 0;
}

/* The footprints of meshes m[0..n) into it[]. */
static void footprints(struct mesh *const *m, size_t n, struct arrange_item *it)
{
	for (size_t i = 0; i < n; i++) {
		double lo[3], hi[3];
		mesh_bbox(m[i], lo, hi);
		it[i] = (struct arrange_item){.min = {lo[0], lo[1]}, .max = {hi[0], hi[1]}};
	}
}

/*
 * Where each of several models goes before the pile is placed as one:
 * it[i].shift in X and Y (zero when they keep the places their 3MF files
 * give them), lowest point on z = 0.  0, or ST_ERR_RANGE with res->failed.
 */
static int slicejob_arrange(struct mesh *const *m, size_t n, const struct slicer_config *c,
			    struct arrange_item *it, struct slicejob_result *res,
			    struct st_error *err)
{
	bool all_3mf = true;

	footprints(m, n, it);
	for (size_t i = 0; i < n; i++)
		all_3mf = all_3mf && res->models[i].format == MESHIO_3MF;
	res->arranged = !all_3mf || arrange_overlap(it, n);
	if (res->arranged)
		return arrange_footprints(it, n, &c->bed, &res->failed, err);
	return 0;
}

/* The n models moved by it[] (z: each onto the bed) into one mesh *out. */
static int slicejob_merge(struct mesh *const *m, size_t n, const struct arrange_item *it,
			  struct slicejob_result *res, struct mesh **out, struct st_error *err)
{
	size_t tris = 0;
	struct mesh_builder *b;
	int rc = 0;

	for (size_t i = 0; i < n; i++)
		tris += m[i]->ntris;
	if (!(b = mesh_builder_new(tris)))
		return st_error_set(err, ST_ERR_NOMEM, "out of memory for the models together");
	for (size_t i = 0; i < n && !rc; i++) {
		double lo[3], hi[3], *o = res->models[i].offset;

		mesh_bbox(m[i], lo, hi);
		o[0] = it[i].shift[0];
		o[1] = it[i].shift[1];
		o[2] = 0.0 - lo[2];
		for (size_t v = 0; v < m[i]->nverts; v++)
			for (int k = 0; k < 3; k++)
				m[i]->verts[v][k] += o[k];
		rc = mesh_builder_append(b, m[i], err);
	}
	if (rc) {
		mesh_builder_free(b);
		return rc;
	}
	if (!(*out = mesh_builder_finish(b)))
		return st_error_set(err, ST_ERR_NOMEM, "out of memory for the models together");
	return 0;
}

/* Add model k's repair counts to the job's (several models). */
static void sum_repair(struct slicejob_result *res, const struct repair_report *r)
{
	res->rep.input_triangles += r->input_triangles;
	res->rep.output_triangles += r->output_triangles;
	res->rep.components += r->components;
	res->rep.intersecting_pairs += r->intersecting_pairs;
}

/* Read model i and refuse it when it alone cannot fit the bed. */
static int read_one(const char *path, size_t i, const struct slicer_config *c, struct mesh **m,
		    struct slicejob_result *res, struct st_error *err)
{
	struct meshio_info info;
	double off[3];
	int rc;

	res->failed = i;
	res->stage = SLICEJOB_READ;
	res->models[i].path = path;
	if ((rc = meshio_read_info(path, MESHIO_AUTO, m, &info, err)))
		return rc;
	res->models[i].format = info.format;
	res->models[i].objects = info.objects;
	if (i == 0)
		res->format = res->models[0].format;
	res->models[i].input_triangles = (*m)->ntris;
	res->input_triangles += (*m)->ntris;
	/* Refuse a model too big before spending time on its repair. */
	res->stage = SLICEJOB_PLACE;
	return slicer_place(*m, &c->bed, off, NULL, NULL, err);
}

/*
 * The layer height profile of the one 3MF model, when the job can use it
 * (its object is the file's only one; it ends at the object's top, as
 * PrusaSlicer requires): c->adaptive.profile points to *zh (the caller
 * frees it).  m[] are the models as read.  0, or the reader's error (a
 * profile that does not parse).
 */
static int layer_profile(const char *const *in, size_t n, struct mesh *const *m,
			 struct slicer_config *c, struct slicejob_result *res, double **zh,
			 struct st_error *err)
{
	size_t pairs = 0, profiles = 0;
	double lo[3], hi[3];
	int rc;

	*zh = NULL;
	res->profile = SLICEJOB_PROFILE_NONE;
	for (size_t i = 0; i < n; i++) {
		if (res->models[i].format != MESHIO_3MF)
			continue;
		res->stage = SLICEJOB_READ;
		res->failed = i;
		rc = meshio_3mf_layer_profile(in[i], 1, zh, &pairs, &profiles, err);
		if (rc)
			return rc;
		if (!profiles)
			continue;
		if (n > 1 || res->models[i].objects != 1)
			res->profile = SLICEJOB_PROFILE_SEVERAL;
		else if (c->adaptive.enabled)
			res->profile = SLICEJOB_PROFILE_ADAPTIVE;
		else if (!c->adaptive.allowed)
			res->profile = SLICEJOB_PROFILE_NOT_ALLOWED;
		if (res->profile == SLICEJOB_PROFILE_NONE && *zh) {
			mesh_bbox(m[i], lo, hi);
			res->profile_top = (*zh)[2 * pairs - 2];
			res->model_top = hi[2] - lo[2];
			res->profile = fabs(res->profile_top - res->model_top) > SLICEJOB_PROFILE_TOP_MM
					   ? SLICEJOB_PROFILE_STALE
					   : SLICEJOB_PROFILE_USED;
		}
		if (res->profile == SLICEJOB_PROFILE_USED) {
			c->adaptive.profile = *zh;
			c->adaptive.profile_pairs = pairs;
			return 0;
		}
		free(*zh);
		*zh = NULL;
	}
	return 0;
}

/* Read, check and (unless no_repair) repair every model into m[]; then
 * several are arranged and merged into m[0].  A 3MF's layer height profile
 * is read before the repairs (layer_profile).  0 or an error class. */
static int prepare(const char *const *in, size_t n, struct slicer_config *c, bool no_repair,
		   const char *progress_name, struct mesh **m, double **zh,
		   struct slicejob_result *res, struct st_error *err)
{
	struct arrange_item *it = n > 1 ? calloc(n, sizeof(*it)) : NULL;
	struct mesh *merged = NULL;
	int rc = 0;

	if (n > 1 && !it)
		return st_error_set(err, ST_ERR_NOMEM, "out of memory for %zu models", n);
	for (size_t i = 0; i < n && !rc; i++)
		rc = read_one(in[i], i, c, &m[i], res, err);
	if (!rc)
		rc = layer_profile(in, n, m, c, res, zh, err);
	/* Together too, before the repairs. */
	if (!rc && n > 1)
		rc = slicejob_arrange(m, n, c, it, res, err);
	for (size_t i = 0; i < n && !rc && !no_repair; i++) {
		struct mesh *fixed = NULL;

		res->failed = i;
		res->stage = SLICEJOB_REPAIR;
		rc = slicejob_repair(m[i], c, progress_name, &fixed, &res->models[i].rep,
				     &res->unprintable, err);
		if (!rc) {
			mesh_free(m[i]);
			m[i] = fixed;
		}
	}
	if (!rc && !no_repair) {
		res->repaired = true;
		if (n == 1)
			res->rep = res->models[0].rep;
		for (size_t i = 0; n > 1 && i < n; i++)
			sum_repair(res, &res->models[i].rep);
	}
	if (!rc && n > 1) {
		res->stage = SLICEJOB_PLACE;
		rc = slicejob_arrange(m, n, c, it, res, err);
		if (!rc)
			rc = slicejob_merge(m, n, it, res, &merged, err);
		if (!rc) {
			mesh_free(m[0]);
			m[0] = merged;
		}
	}
	free(it);
	return rc;
}

int slicejob_slice(const char *const *in, size_t n, const struct slicer_config *cfg,
		   bool no_repair, const char *out, const char *progress_name,
		   struct slicejob_result *res, struct st_error *err)
{
	struct slicer_config c = *cfg;
	double *zh = NULL; /* the 3MF's layer height profile, while c points to it */
	struct mesh **m;
	struct progress prog;
	bool have_prog;
	int rc;

	memset(res, 0, sizeof(*res));
	if (n == 0 || n > SLICEJOB_MODELS_MAX)
		return st_error_set(err, ST_ERR_ARG, "%zu model files; give 1 to %d", n,
				    SLICEJOB_MODELS_MAX);
	m = calloc(n, sizeof(*m));
	res->models = calloc(n, sizeof(*res->models));
	if (!m || !res->models) {
		free(m);
		return st_error_set(err, ST_ERR_NOMEM, "out of memory for %zu models", n);
	}
	res->nmodels = n;
	rc = prepare(in, n, &c, no_repair, progress_name, m, &zh, res, err);
	if (!rc) {
		res->stage = SLICEJOB_SLICE;
		c.gcodew.input_files = in;
		c.gcodew.input_file_count = n;
		have_prog = progress_name && progress_start(&prog, progress_name);
		if (have_prog) {
			c.progress = progress_update;
			c.progress_ctx = &prog;
		}
		char *thumbs = NULL;
		rc = thumb_block(m[0], c.gcodew.thumbnails, &thumbs, err);
		c.gcodew.thumbnail_block = thumbs;
		if (!rc)
			rc = slicer_run(m[0], &c, out, &res->sum, err);
		free(thumbs);
		if (have_prog)
			progress_end(&prog);
		for (size_t i = 0; !rc && i < n; i++)
			for (int k = 0; k < 3; k++)
				res->models[i].offset[k] += res->sum.offset[k];
	}
	for (size_t i = 0; i < n; i++)
		mesh_free(m[i]);
	free(m);
	free(zh);
	return rc;
}

void slicejob_result_free(struct slicejob_result *res)
{
	free(res->models);
	res->models = NULL;
	res->nmodels = 0;
}

int slicejob_run(const char *cmd, const char *const *in, size_t n,
		 const struct slicer_config *cfg, bool no_repair, const char *out, bool progress,
		 struct slicejob_result *res)
{
	struct st_error err = {0};
	int rc = slicejob_slice(in, n, cfg, no_repair, out, progress ? cmd : NULL, res, &err);
	const char *name;

	if (!rc)
		return 0;
	if (!res->nmodels) { /* no model or too many: the caller's mistake */
		fprintf(stderr, "%s: %s\n", cmd, err.msg);
		return st_exit_for(rc);
	}
	name = res->stage != SLICEJOB_SLICE ? in[res->failed]
	       : n > 1			    ? "the models together"
					    : in[0];
	switch (res->stage) {
	case SLICEJOB_READ:
		fprintf(stderr, "%s: %s\n", cmd, err.msg);
		return rc == ST_ERR_NOMEM ? ST_EXIT_SOFTWARE : ST_EXIT_DATAERR;
	case SLICEJOB_REPAIR:
		if (res->unprintable) {
			fprintf(stderr, "%s: %s: %s; nothing was written\n", cmd, name, err.msg);
			return ST_EXIT_FAILURE;
		}
		fprintf(stderr, "%s: %s: %s\n", cmd, name, err.msg);
		return rc == ST_ERR_ARG ? ST_EXIT_SOFTWARE : st_exit_for(rc);
	default:
		fprintf(stderr, "%s: %s: %s; nothing was written\n", cmd, name, err.msg);
		return slicejob_exit(rc);
	}
}
