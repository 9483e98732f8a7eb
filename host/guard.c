/*
 * guard.c - refuse G-code sliced for another printer (guard.h).
 */
#include "guard.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

#include "gcwalk.h"

/* The first move of a file that leaves the bed. */
struct off_bed {
	unsigned long long line; /* 0: none */
	double x, y, z;
	bool too_high;		 /* extrudes above max_print_height */
};

/* Does m leave prof's bed?  Fills o when it does. */
static bool leaves_bed(const struct profile *prof, const struct gcwalk_move *m,
		       struct off_bed *o)
{
	const double t = GUARD_BED_TOLERANCE;
	bool moves_xy = m->to[0] != m->from[0] || m->to[1] != m->from[1];
	bool high = moves_xy && m->de > 0 && m->to[2] > prof->max_print_height + t;

	/* Only X/Y moves are judged: a Z lift or a retraction where the start
	 * G-code left the nozzle is not a move off the bed. */
	if (!high && (!moves_xy || (m->to[0] >= prof->bed_min_x - t && m->to[0] <= prof->bed_max_x + t &&
	    m->to[1] >= prof->bed_min_y - t && m->to[1] <= prof->bed_max_y + t)))
		return false;
	*o = (struct off_bed){.line = (unsigned long long)m->line, .x = m->to[0], .y = m->to[1],
			      .z = m->to[2], .too_high = high};
	return true;
}

/* Rule 1 of guard.h: does the header name another printer? */
static int check_printer(const char *path, const struct gcwalk_header *h,
			 const struct profile *prof, struct st_error *err)
{
	const char *ours = profile_printer_name(prof);
	const char *theirs = h->printer_settings_id[0] ? h->printer_settings_id : h->printer_model;

	if (h->printer_model[0] && prof->printer_model[0]) {
		if (!strcmp(h->printer_model, prof->printer_model))
			return 0;
		return st_error_set(err, ST_ERR_RANGE,
				    "%s was sliced for printer '%.60s' (printer_model %.24s), not "
				    "for '%.60s' (printer_model %.24s); slice it for this printer, "
				    "or pass --force",
				    path, theirs, h->printer_model, ours, prof->printer_model);
	}
	if (h->stratum && h->printer_settings_id[0] && strcmp(h->printer_settings_id, ours))
		return st_error_set(err, ST_ERR_RANGE,
				    "%s was sliced for printer '%.60s', not for '%.60s'; slice it "
				    "for this printer, or pass --force",
				    path, h->printer_settings_id, ours);
	return 0;
}

/* Rule 2: the nozzle the file was sliced for. */
static int check_nozzle(const char *path, const struct gcwalk_header *h,
			const struct profile *prof, struct st_error *err)
{
	double ours = prof->nozzle_diameter[0];

	if (h->nozzle_diameter == 0.0 || fabs(h->nozzle_diameter - ours) <= GUARD_NOZZLE_TOLERANCE)
		return 0;
	return st_error_set(err, ST_ERR_RANGE,
			    "%s was sliced for a %g mm nozzle; printer '%.60s' has %g mm "
			    "(nozzle_diameter); slice it for this printer, or pass --force",
			    path, h->nozzle_diameter, profile_printer_name(prof), ours);
}

/* Rule 3: o is the first move off the bed. */
static int refuse_off_bed(const char *path, const struct off_bed *o, const struct profile *prof,
			  struct st_error *err)
{
	if (o->too_high)
		return st_error_set(err, ST_ERR_RANGE,
				    "%s: line %llu: extrudes at Z %g mm, above printer '%.60s''s "
				    "max_print_height of %g mm; slice it for this printer, or pass "
				    "--force",
				    path, o->line, o->z, profile_printer_name(prof),
				    prof->max_print_height);
	return st_error_set(err, ST_ERR_RANGE,
			    "%s: line %llu: the move to X %g Y %g leaves the bed of printer "
			    "'%.60s' (X %g to %g, Y %g to %g mm); slice it for this printer, or "
			    "pass --force",
			    path, o->line, o->x, o->y, profile_printer_name(prof), prof->bed_min_x,
			    prof->bed_max_x, prof->bed_min_y, prof->bed_max_y);
}

int guard_check_file(const char *path, const char *name, const struct profile *prof,
		     struct st_error *err)
{
	struct off_bed any = {0}, printed = {0}, o;
	struct gcwalk *w = NULL;
	struct gcwalk_move m;
	struct st_error walk_err = {0};
	FILE *fp = fopen(path, "rb");
	int rc;

	if (!fp)
		return st_error_set(err, ST_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
	if (name)
		path = name;
	if ((rc = gcwalk_new(fp, path, &w, err)))
		goto out_close;
	/* On to the end: PrusaSlicer's header is its last lines.  A line the
	 * walker refuses is skipped (the sender's own check judges it). */
	while ((rc = gcwalk_next(w, &m, &walk_err)) != 0) {
		if (rc == ST_ERR_IO || rc == ST_ERR_NOMEM || rc == ST_ERR_ARG) {
			*err = walk_err;
			goto out_free;
		}
		if (rc < 0 || printed.line || !leaves_bed(prof, &m, &o))
			continue;
		if (!any.line)
			any = o;
		/* PrusaSlicer labels the printer's own start and end G-code (a
		 * park position off the print area) ";TYPE:Custom" */
		if (m.layer >= 0 && strcmp(m.type, "Custom"))
			printed = o;
	}
	const struct gcwalk_header *h = gcwalk_header(w);
	if ((rc = check_printer(path, h, prof, err)) || (rc = check_nozzle(path, h, prof, err)))
		goto out_free;
	o = gcwalk_layer_marks(w) > 0 ? printed : any;
	rc = o.line ? refuse_off_bed(path, &o, prof, err) : 0;
out_free:
	gcwalk_free(w);
out_close:
	fclose(fp);
	return rc;
}

/* The exit status of a failed guard_check_file: 2 for a refusal, else by class. */
static int guard_exit_status(int rc)
{
	return rc == ST_ERR_RANGE ? ST_EXIT_USAGE : st_exit_for(rc);
}

int guard_cli(const char *cmd, const char *path, const struct profile *prof, bool force)
{
	struct st_error err = {0};
	int rc = guard_check_file(path, NULL, prof, &err);

	if (rc == ST_ERR_RANGE && force) {
		fprintf(stderr, "%s: warning: %s; going on: --force\n", cmd, err.msg);
		return 0;
	}
	if (rc)
		fprintf(stderr, "%s: %s\n", cmd, err.msg);
	return rc ? guard_exit_status(rc) : 0;
}
