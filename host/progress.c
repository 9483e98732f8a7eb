/*
 * progress.c - progress bar or plain progress lines on stderr (progress.h).
 */
#include "progress.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

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
	if (p->tty && (new_stage || percent != p->percent)) {
		int n = fprintf(stderr, "\r[%.*s] %d%%", (int)(sizeof(p->stage) - 1), stage,
				percent);
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
