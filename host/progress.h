/*
 * progress.h - progress output of long subcommands (docs/architecture.md "Errors, exit
 * codes, output"): a redrawn line on stderr when stderr is a terminal, one
 * plain "stratum CMD: phase" line per phase otherwise.
 *
 * Phases are named as sentences ("repairing the mesh: cutting 1832
 * triangles") and their fraction is of that phase alone; the line shows the
 * command's elapsed time, and an ETA only once the phase has run long
 * enough for one to mean something.  Every redrawn line fits the
 * terminal's width (a longer one wraps, and each redraw becomes a new
 * line).
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
	const char *prefix;	/* before each phase ("repairing the mesh: "), may be NULL */
	bool tty;		/* redraw one line; otherwise one line per phase */
	char stage[96];		/* the phase last shown */
	int permille;		/* the fraction last shown (0.1 % steps), -1 none */
	size_t width;		/* characters of the line on screen */
	double t_start;		/* monotonic s at progress_start */
	double t0;		/* monotonic s when the phase began */
	double t_drawn;		/* when the line was last drawn */
	double done;		/* the fraction last given */
	/* A ticker redraws the line while a long step reports nothing, so the
	 * elapsed time goes on (a frozen line reads as a hung program). */
	pthread_t ticker;
	pthread_cond_t wake;
	bool ticking, stop;
};

/*
 * progress_start - set p up for command cmd (a static string), deciding
 * between a redrawn line and plain lines from isatty(stderr).  Returns
 * false when the mutex cannot be created: then show no progress (p must
 * not be used).
 */
bool progress_start(struct progress *p, const char *cmd);

/* progress_update - callback: phase and 0..1 of it done; redraws at most
 * every 0.1 s (and on a new phase).  The phase is its name up to the
 * first digit, so counts in it ("slicing layer 12 of 80") do not restart it. */
void progress_update(void *ctx, const char *stage, double done);

/* progress_end - erase the line so the report starts on a clean line; frees p. */
void progress_end(struct progress *p);

/* ---- shared with the print and send line (host/send_progress.c) ---- */

/* progress_columns - the width of the terminal on fd (TIOCGWINSZ), else
 * $COLUMNS, else 80. */
size_t progress_columns(int fd);

/* One field of a progress line; the least wanted go first when it is too
 * long: fields of the highest drop level are left out first. */
struct progress_field {
	const char *text; /* "" or NULL: not shown */
	int drop;	  /* 0: kept to the last */
};

/*
 * progress_fit - join the fields with single spaces into out (cap bytes)
 * in at most cols - 1 characters (the last column would wrap on some
 * terminals), leaving out whole fields from the highest drop level down,
 * and cutting what is still too long.  Returns the length written.
 */
size_t progress_fit(char *out, size_t cap, size_t cols, const struct progress_field *f,
		    size_t n);

/* progress_redraw - draw line (n characters) over the one on screen,
 * *width characters long, blanking its tail; *width becomes n. */
void progress_redraw(const char *line, size_t n, size_t *width);

/* progress_hms - s seconds as h:mm:ss ("0:03:12", "45:38:00" past a day);
 * "-:--:--" when s is not a finite non-negative figure. */
void progress_hms(char *out, size_t cap, double s);

/*
 * progress_eta - wall seconds left in a print estimated at est_left more
 * seconds of printing, when est_done estimated seconds were printed in
 * wall seconds since the first move: the estimate divided by the pace,
 * where the pace (estimated seconds per wall second) starts as pace0 (1
 * on a real printer, the simulator's speed-up) and moves to the measured
 * pace as the printed part grows to a tenth of the print or ten minutes.
 */
double progress_eta(double est_done, double est_left, double wall, double pace0);

#endif /* STRATUM_HOST_PROGRESS_H */
