/*
 * print_estimate.c - the time each layer of a G-code file takes by the
 * slicer's estimate (print_job.h), for the ETA of `stratum print`: the
 * moves planned as Marlin plans them (slicer/estimate.h, the same planner
 * the G-code writer times its own moves with), scaled to the total the
 * file states when it states one (the header's "estimated printing time",
 * else the first M73's minutes), so the ETA starts from the figure the
 * slicer showed.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "estimate.h"
#include "gcwalk.h"
#include "print_job.h"
#include "st_number.h"

#define PRINT_EST_FEED 25.0 /* mm/s before the file's first F (Marlin's default) */

double print_time_comment(const char *c)
{
	static const char key[] = "estimated printing time";
	double s;

	while (*c == ' ')
		c++;
	if (strncmp(c, key, sizeof(key) - 1))
		return NAN;
	c += sizeof(key) - 1;
	/* "(normal mode)" is the one the printer runs; the silent one is not */
	if (!strncmp(c, " (normal mode)", 14))
		c += 14;
	while (*c == ' ')
		c++;
	if (*c != '=' || (s = st_parse_duration(c + 1)) < 0)
		return NAN;
	return s;
}

/* Plan the file's moves; est of each layer = the time before its line. */
static int print_plan(const char *path, struct print_layers *L, double *total)
{
	struct est_limits lim;
	struct est_planner *p = NULL;
	struct gcwalk *w = NULL;
	struct gcwalk_move m;
	struct est_result r;
	struct st_error err = {0};
	double e = 0;
	size_t next = 0;
	int rc = -1;
	FILE *f = fopen(path, "rb");

	if (!f)
		return -1;
	est_limits_init(&lim);
	if (!(p = est_planner_new(&lim, NULL, &err)) || gcwalk_new(f, path, &w, &err))
		goto out;
	while ((rc = gcwalk_next(w, &m, &err)) == 1) {
		struct est_move mv = {m.to[0], m.to[1], m.to[2], e + m.de,
				      m.feed > 0 ? m.feed / 60.0 : PRINT_EST_FEED};

		for (; next < L->n && L->v[next].line <= m.line; next++) {
			est_planner_result(p, &r);
			L->v[next].est = r.time_s;
		}
		e += m.de;
		if (est_planner_add(p, &mv, &err)) {
			rc = -1;
			goto out;
		}
	}
	if (rc < 0)
		goto out;
	est_planner_result(p, &r);
	for (; next < L->n; next++)
		L->v[next].est = r.time_s;
	*total = r.time_s;
	rc = 0;
out:
	gcwalk_free(w);
	est_planner_free(p);
	fclose(f);
	return rc;
}

void print_estimate(const char *path, struct print_layers *L, double stated_s)
{
	double total = 0, k = 1;

	L->est_total = 0;
	if (print_plan(path, L, &total) || !(total > 0))
		return; /* no estimate: the ETA follows the line rate */
	if (stated_s > 0)
		k = stated_s / total;
	for (size_t i = 0; i < L->n; i++)
		L->v[i].est *= k;
	L->est_total = total * k;
}

double print_est_done(const struct print_layers *L, long layer, uint64_t line)
{
	uint64_t l0, l1;
	double e0, e1;

	if (!(L->est_total > 0) || layer < 0 || !L->n)
		return 0;
	if ((size_t)layer >= L->n)
		return L->est_total;
	l0 = L->v[layer].line;
	e0 = L->v[layer].est;
	l1 = (size_t)layer + 1 < L->n ? L->v[layer + 1].line : L->lines;
	e1 = (size_t)layer + 1 < L->n ? L->v[layer + 1].est : L->est_total;
	/* within the layer, in proportion to its lines */
	if (l1 <= l0 || line <= l0)
		return e0;
	return e0 + (e1 - e0) * (double)(fmin((double)(line - l0), (double)(l1 - l0))) /
			    (double)(l1 - l0);
}
