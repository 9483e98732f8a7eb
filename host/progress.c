/*
 * progress.c - progress bar or plain progress lines on stderr (progress.h).
 */
#include "progress.h"
#include "st_clock.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

/* Monotonic clock, seconds. */
static double progress_now(void)
{
	return st_mono_s();
}

bool progress_start(struct progress *p, const char *cmd)
{
	memset(p, 0, sizeof(*p));
	p->percent = -1;
	p->cmd = cmd;
	if (pthread_mutex_init(&p->lock, NULL))
		return false;
	p->tty = isatty(STDERR_FILENO);
	return true;
}

/* Redraw only when the stage or the whole percentage changed. */
void progress_update(void *ctx, const char *stage, double done)
{
	struct progress *p = ctx;
	int percent;
	bool new_stage;

	if (!stage)
		stage = "";
	percent = isfinite(done) ? (int)(done * 100.0) : 0;
	if (percent < 0)
		percent = 0;
	if (percent > 100)
		percent = 100;
	pthread_mutex_lock(&p->lock);
	new_stage = strncmp(p->stage, stage, sizeof(p->stage) - 1) != 0;
	if (new_stage)
		p->t0 = progress_now();
	if (p->tty && (new_stage || percent != p->percent)) {
		double el = progress_now() - p->t0;
		char eta[32] = "";
		int n;

		if (done > 0.01 && done < 1)
			snprintf(eta, sizeof(eta), " ETA %.0f s", el / done - el);
		n = fprintf(stderr, "\r[%.*s] %d%% %.1f s%s", (int)(sizeof(p->stage) - 1), stage,
			    percent, el, eta);
		/* Blank what is left of a longer previous line. */
		for (size_t w = n > 0 ? (size_t)n - 1 : 0; w < p->width; w++)
			fputc(' ', stderr);
		if (n > 0 && (size_t)n - 1 > p->width)
			p->width = (size_t)n - 1;
		fflush(stderr);
	} else if (!p->tty && new_stage) {
		fprintf(stderr, "%s: %s\n", p->cmd, stage);
	}
	if (new_stage)
		snprintf(p->stage, sizeof(p->stage), "%s", stage);
	p->percent = percent;
	pthread_mutex_unlock(&p->lock);
}

void progress_end(struct progress *p)
{
	if (p->tty && p->width) {
		fputc('\r', stderr);
		for (size_t w = 0; w < p->width; w++)
			fputc(' ', stderr);
		fputc('\r', stderr);
		fflush(stderr);
	}
	pthread_mutex_destroy(&p->lock);
}
