/*
 * progress.h - progress output of long subcommands (docs/architecture.md "Errors, exit
 * codes, output"): a redrawn "[stage] N%" bar on stderr when stderr is a
 * terminal, one plain "stratum CMD: stage" line per stage otherwise.
 *
 * progress_update has the signature of the library progress callbacks
 * (repair_options.progress, slicer_config.progress) and may be called from
 * worker threads: a mutex serialises the drawing.
 */
#ifndef STRATUM_HOST_PROGRESS_H
#define STRATUM_HOST_PROGRESS_H

#include <pthread.h>
#include <stdbool.h>
#include <stddef.h>

struct progress {
	pthread_mutex_t lock;
	const char *cmd;	/* "stratum repair": prefix of the plain lines */
	bool tty;		/* draw a bar; otherwise one line per stage */
	char stage[64];		/* the stage last shown */
	int percent;		/* the percentage last shown, -1 none */
	size_t width;		/* characters of the bar line on screen */
	double t0;		/* monotonic s when the stage began */
};

/*
 * progress_start - set p up for command cmd (a static string), deciding
 * between bar and lines from isatty(stderr).  Returns false when the mutex
 * cannot be created: then show no progress (p must not be used).
 */
bool progress_start(struct progress *p, const char *cmd);

/* progress_update - callback: stage name and 0..1 done; redraws only on
 * change.  The bar shows the stage, its percentage, elapsed time and ETA. */
void progress_update(void *ctx, const char *stage, double done);

/* progress_end - erase the bar so the report starts on a clean line; frees p. */
void progress_end(struct progress *p);

#endif /* STRATUM_HOST_PROGRESS_H */
