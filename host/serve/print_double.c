/*
 * print_double.c - the test double behind `port = test-instant` (print.h),
 * on the printer table of serial/printer.h:
 * it "prints" a G-code file by reading it line by line through our parser,
 * so a file that is not G-code fails as it would on a printer, reports the
 * byte position as progress, takes temperatures from M104/M109/M140/M190 as
 * reached at once, and waits out G4 dwells (which lets tests hold a print
 * in progress).  It never touches a port.  A testing aid only.
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "gcode.h"
#include "print.h"
#include "printer.h"

#define DOUBLE_DWELL_MAX_MS 60000 /* longest G4 honoured, ms */
#define DOUBLE_WAIT_MS 10	  /* request poll while holding or dwelling, ms */

struct double_state {
	char name[NODE_NAME_MAX];
	struct printer_progress temps; /* as the last job set them */
};

static int double_open(const struct printer_options *o, void **state, struct st_error *err)
{
	struct double_state *s = calloc(1, sizeof(*s));

	if (!s)
		return st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", printer_name(o));
	snprintf(s->name, sizeof(s->name), "%s", printer_name(o));
	*state = s;
	return 0;
}

static void double_close(void *state)
{
	free(state);
}

/* Temperatures a line sets, reached at once. */
static void apply_temps(const struct gcode_line *l, struct printer_progress *p)
{
	if (l->letter != 'M')
		return;
	if (l->number == 104 || l->number == 109) {
		p->tool = true;
		gcode_word_value(l, 'S', &p->tool_target);
		p->tool_actual = p->tool_target;
	} else if (l->number == 140 || l->number == 190) {
		p->bed = true;
		gcode_word_value(l, 'S', &p->bed_target);
		p->bed_actual = p->bed_target;
	}
}

/* Sleep ms milliseconds. */
static void sleep_ms(long ms)
{
	struct timespec t = {ms / 1000, (ms % 1000) * 1000000L};

	nanosleep(&t, NULL);
}

/*
 * Hold while the hook says so, for up to dwell_ms besides (0: no dwell).
 * Returns PRINTER_GO to go on, else the request that ends the print.
 */
static enum printer_control wait_requests(const struct printer_job *job,
					  struct printer_progress *p, long dwell_ms)
{
	for (;;) {
		enum printer_control c = job->control ? job->control(job->ctx) : PRINTER_GO;

		if (c == PRINTER_CANCEL || c == PRINTER_STOP)
			return c;
		if (p->paused != (c == PRINTER_HOLD)) {
			p->paused = c == PRINTER_HOLD;
			if (job->progress)
				job->progress(job->ctx, p);
		}
		if (c != PRINTER_HOLD && dwell_ms <= 0)
			return PRINTER_GO;
		sleep_ms(DOUBLE_WAIT_MS);
		if (c != PRINTER_HOLD)
			dwell_ms -= DOUBLE_WAIT_MS;
	}
}

/* Read job's file line by line from its offset: each line parses. */
static int double_run(struct double_state *s, const struct printer_job *job,
		      struct printer_result *res, struct printer_file_info *info,
		      struct st_error *err)
{
	FILE *f = fopen(job->path, "rb");
	char *line = NULL;
	size_t cap = 0;
	ssize_t n;
	long lineno = 0;
	int64_t pos = job->offset;
	int rc = 0;

	if (!f)
		return st_error_set(err, ST_ERR_IO, "%s: cannot open: %s", job->path, strerror(errno));
	if (fseeko(f, (off_t)job->offset, SEEK_SET)) {
		rc = st_error_set(err, ST_ERR_IO, "%s: cannot read: %s", job->path, strerror(errno));
		goto out_close;
	}
	while ((n = getline(&line, &cap, f)) > 0) {
		struct gcode_line l;
		double ms = 0, secs = 0; /* a dwell: G4 P and S */
		enum printer_control c;

		lineno++;
		if (gcode_parse(line, (size_t)n, 0, &l, err)) {
			char why[sizeof(err->msg)];

			snprintf(why, sizeof(why), "%s", err->msg);
			rc = job->offset ? st_error_set(err, ST_ERR_PARSE, "%s: byte %lld: %s",
							job->path, (long long)pos, why)
					 : st_error_set(err, ST_ERR_PARSE, "%s: line %ld: %s",
							job->path, lineno, why);
			goto out_free;
		}
		pos += n;
		if (info) { /* the check: count, nothing else */
			info->commands += l.text_len > 0;
			continue;
		}
		if (l.letter == 'G' && l.number == 4) {
			gcode_word_value(&l, 'P', &ms);
			gcode_word_value(&l, 'S', &secs);
		}
		apply_temps(&l, &s->temps);
		res->last = s->temps;
		res->last.filepos = pos;
		res->last.line = job->first_line + (uint64_t)lineno;
		res->last.layer = -1;
		if (job->progress)
			job->progress(job->ctx, &res->last);
		c = wait_requests(job, &res->last,
				  (long)fmin(ms + 1000 * secs, DOUBLE_DWELL_MAX_MS));
		if (c != PRINTER_GO) {
			res->end = c == PRINTER_STOP ? PRINTER_END_STOPPED : PRINTER_END_CANCELLED;
			goto out_free;
		}
	}
	if (ferror(f))
		rc = st_error_set(err, ST_ERR_IO, "%s: read error at byte %lld", job->path,
				  (long long)pos);
	if (info)
		info->lines = (uint64_t)lineno;
out_free:
	free(line);
out_close:
	fclose(f);
	return rc;
}

static int double_check(const struct printer_options *o, const struct printer_job *job,
			printer_warn_fn warn, void *warn_ctx, struct printer_file_info *info,
			struct st_error *err)
{
	(void)o;
	(void)warn;
	(void)warn_ctx;
	return double_run(NULL, job, NULL, info, err);
}

static int double_stream(void *state, const struct printer_job *job, struct printer_result *res,
			 struct st_error *err)
{
	int rc;

	res->last.filepos = job->offset;
	rc = double_run(state, job, res, NULL, err);
	if (rc)
		res->end = PRINTER_END_FAILED;
	return rc;
}

static int double_command(void *state, const char *text, char *reply, size_t cap,
			  struct st_error *err)
{
	struct double_state *s = state;
	struct gcode_line l;
	int rc = gcode_parse(text, strlen(text), 0, &l, err);

	if (reply && cap)
		snprintf(reply, cap, "ok\n");
	if (!rc) /* a target set between jobs is reached at once, as in a print */
		apply_temps(&l, &s->temps);
	return rc;
}

static int double_poll(void *state, struct printer_progress *t, struct st_error *err)
{
	struct double_state *s = state;

	(void)err;
	*t = s->temps;
	return 0;
}

const struct printer_ops node_double_ops = {
	.name = "test-instant",
	.can_resume = true,
	.open = double_open,
	.close = double_close,
	.check = double_check,
	.stream = double_stream,
	.command = double_command,
	.poll = double_poll,
};
