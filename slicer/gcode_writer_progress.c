/*
 * gcode_writer_progress.c - remaining_times: the M73 progress lines (see
 * gcode_writer.h).  The total time is only known once the last move is
 * planned, after the body was generated, so the body records where each
 * line goes and the time planned up to there; the lines are written into
 * the body as it is copied after the header.  Also how an acceleration
 * op is written (default_acceleration and the per-role keys).
 */
#include "gcode_writer_int.h"

#include <errno.h>
#include <math.h>
#include <string.h>

#include "st_grow.h"

int gcodew_progress_mark(struct gcodew *w, bool last)
{
	struct gcodew_m73 *grown;
	struct est_result er;
	off_t off;

	if (!w->s->remaining_times)
		return 0;
	if (fflush(w->body) != 0 || (off = ftello(w->body)) < 0)
		return st_error_set(w->err, ST_ERR_IO, "G-code: temporary file: %s", strerror(errno));
	grown = st_grow(w->m73, &w->m73cap, w->nm73 + 1, sizeof(*grown));
	if (!grown)
		return st_error_set(w->err, ST_ERR_NOMEM, "G-code: out of memory");
	w->m73 = grown;
	est_planner_result(w->est, &er);
	w->m73[w->nm73++] = (struct gcodew_m73){.off = off, .t = er.time_s, .last = last};
	return 0;
}

int gcodew_accel_written(const struct gcodew_settings *s, double v)
{
	int a = (int)floor(v + 0.5), cap = (int)(s->limits.accel_extruding + 0.5);

	/* PrusaSlicer caps it where it writes the limits (Marlin). */
	return s->limits_form != GCODEW_LIMITS_NONE && a > cap ? cap : a;
}

/* Copy n bytes of body to fp, from where body is. */
static int copy_part(FILE *body, FILE *fp, off_t n, struct st_error *err)
{
	char buf[65536];

	while (n > 0) {
		size_t want = n < (off_t)sizeof(buf) ? (size_t)n : sizeof(buf);
		size_t got = fread(buf, 1, want, body);
		if (got == 0)
			break;
		if (fwrite(buf, 1, got, fp) != got)
			return st_error_set(err, ST_ERR_IO, "G-code: write failed: %s", strerror(errno));
		n -= (off_t)got;
	}
	if (ferror(body))
		return st_error_set(err, ST_ERR_IO, "G-code: cannot read back the temporary file: %s",
				    strerror(errno));
	return 0;
}

/* PrusaSlicer 2.5's figures: the percentage floored, the minutes of the
 * rounded seconds floored. */
static void m73_figures(const struct gcodew_m73 *m, double total, int *pct, int *mins)
{
	double left = m->last ? 0 : total - m->t;

	*pct = m->last ? 100 : total > 0 ? (int)(100 * m->t / total) : 0;
	if (*pct > 100)
		*pct = 100;
	*mins = left > 0 ? (int)((left + 0.5) / 60) : 0;
}

int gcodew_copy_body(struct gcodew *w, FILE *fp, double total, struct st_error *err)
{
	off_t at = 0;
	int last_pct = -1, last_mins = -1, rc = 0;

	rewind(w->body);
	for (size_t i = 0; i < w->nm73 && rc == 0; i++) {
		const struct gcodew_m73 *m = &w->m73[i];
		int pct, mins;

		rc = copy_part(w->body, fp, m->off - at, err);
		at = m->off;
		m73_figures(m, total, &pct, &mins);
		if (rc || (!m->last && pct == last_pct && mins == last_mins))
			continue; /* written only when a figure changes, as PrusaSlicer */
		fprintf(fp, "M73 P%d R%d\n", pct, mins);
		if (w->s->remaining_times_silent)
			fprintf(fp, "M73 Q%d S%d\n", pct, mins);
		last_pct = pct;
		last_mins = mins;
	}
	return rc ? rc : copy_part(w->body, fp, (off_t)1 << 62, err);
}
