/*
 * progress.c - the redrawn progress line or plain progress lines on
 * stderr (progress.h), and the width, time and ETA helpers the print
 * and send line shares.
 */
#include "progress.h"
#include "st_clock.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <time.h>
#include <unistd.h>

#define PROGRESS_REDRAW_S 0.1  /* at most this often from the callbacks */
#define PROGRESS_TICK_S 0.5    /* the ticker's redraw period */
#define PROGRESS_ETA_AFTER_S 2 /* a phase's ETA once it has run this long */
#define PROGRESS_QUIET_S 0.3   /* nothing drawn before: a quick run stays clean */

size_t progress_columns(int fd)
{
	struct winsize ws;
	const char *env = getenv("COLUMNS");
	long c;

	if (!ioctl(fd, TIOCGWINSZ, &ws) && ws.ws_col > 0)
		return ws.ws_col;
	if (env && (c = strtol(env, NULL, 10)) > 0 && c < 10000)
		return (size_t)c;
	return 80;
}

size_t progress_fit(char *out, size_t cap, size_t cols, const struct progress_field *f,
		    size_t n)
{
	size_t room = cols > 1 ? cols - 1 : 1, len;
	int drop = 0;

	if (!cap)
		return 0;
	for (size_t i = 0; i < n; i++)
		if (f[i].drop > drop)
			drop = f[i].drop;
	if (room > cap - 1)
		room = cap - 1;
	/* Leave out fields from the highest drop level down until it fits. */
	for (int keep = drop;; keep--) {
		len = 0;
		out[0] = '\0';
		for (size_t i = 0; i < n; i++) {
			if (!f[i].text || !f[i].text[0] || f[i].drop > keep)
				continue;
			int w = snprintf(out + len, cap - len, "%s%s", len ? " " : "", f[i].text);
			if (w < 0)
				break;
			len = len + (size_t)w < cap ? len + (size_t)w : cap - 1;
		}
		if (len <= room || keep <= 0)
			break;
	}
	if (len > room) { /* the kept fields alone are too long: cut */
		len = room;
		out[len] = '\0';
	}
	return len;
}

void progress_redraw(const char *line, size_t n, size_t *width)
{
	fprintf(stderr, "\r%s", line);
	/* Blank what is left of a longer previous line, and come back. */
	for (size_t w = n; w < *width; w++)
		fputc(' ', stderr);
	if (*width > n) {
		fputc('\r', stderr);
		fputs(line, stderr);
	}
	*width = n;
	fflush(stderr);
}

void progress_hms(char *out, size_t cap, double s)
{
	if (!isfinite(s) || s < 0 || s > 1e9) {
		snprintf(out, cap, "-:--:--");
		return;
	}
	long t = lround(s);
	snprintf(out, cap, "%ld:%02ld:%02ld", t / 3600, t / 60 % 60, t % 60);
}

double progress_eta(double est_done, double est_left, double wall, double pace0)
{
	double total = est_done + est_left, trust, pace;

	if (!(pace0 > 0))
		pace0 = 1;
	if (est_left <= 0)
		return 0;
	if (!(est_done > 0) || !(wall > 0))
		return est_left / pace0;
	/* Full trust in the measured pace after a tenth of the print or ten
	 * minutes of it, whichever is less; before that, a blend. */
	trust = est_done / fmin(0.1 * total, 600.0);
	if (trust > 1)
		trust = 1;
	pace = trust * (est_done / wall) + (1 - trust) * pace0;
	return est_left / pace;
}

/* Monotonic clock, seconds. */
static double progress_now(void)
{
	return st_mono_s();
}

/* Length of the phase's identity: its name up to the first digit. */
static size_t progress_key(const char *stage)
{
	return strcspn(stage, "0123456789");
}

/* Redraw the line (p->lock held). */
static void progress_draw(struct progress *p, double now)
{
	char pct[16] = "", el[32], eta[40] = "", stage[sizeof(p->stage) + 64], line[512];
	double pel = now - p->t0;
	struct progress_field f[4];
	size_t n;

	snprintf(stage, sizeof(stage), "%s%s", p->prefix ? p->prefix : "", p->stage);
	if (p->done > 0) /* a phase that reports no fraction shows none */
		snprintf(pct, sizeof(pct), "%d%%", p->permille / 10);
	snprintf(el, sizeof(el), "%.1f s", now - p->t_start);
	/* Only a phase that has run a while and moved tells its pace. */
	if (pel >= PROGRESS_ETA_AFTER_S && p->done >= 0.02 && p->done < 1) {
		char hms[16];
		progress_hms(hms, sizeof(hms), pel * (1 - p->done) / p->done);
		snprintf(eta, sizeof(eta), "ETA %s", hms);
	}
	f[0] = (struct progress_field){stage, 0};
	f[1] = (struct progress_field){pct, 0};
	f[2] = (struct progress_field){el, 2};
	f[3] = (struct progress_field){eta, 1};
	n = progress_fit(line, sizeof(line), progress_columns(STDERR_FILENO), f, 4);
	progress_redraw(line, n, &p->width);
	p->t_drawn = now;
}

/* The ticker: redraw every PROGRESS_TICK_S while a phase is shown. */
static void *progress_tick(void *arg)
{
	struct progress *p = arg;

	pthread_mutex_lock(&p->lock);
	while (!p->stop) {
		struct timespec ts;
		double now = progress_now();

		if (p->stage[0] && now - p->t_start >= PROGRESS_QUIET_S &&
		    now - p->t_drawn >= PROGRESS_TICK_S - 0.01)
			progress_draw(p, now);
		clock_gettime(CLOCK_REALTIME, &ts);
		ts.tv_nsec += (long)(PROGRESS_TICK_S * 1e9);
		ts.tv_sec += ts.tv_nsec / 1000000000L;
		ts.tv_nsec %= 1000000000L;
		pthread_cond_timedwait(&p->wake, &p->lock, &ts);
	}
	pthread_mutex_unlock(&p->lock);
	return NULL;
}

bool progress_start(struct progress *p, const char *cmd)
{
	memset(p, 0, sizeof(*p));
	p->permille = -1;
	p->cmd = cmd;
	if (pthread_mutex_init(&p->lock, NULL))
		return false;
	if (pthread_cond_init(&p->wake, NULL)) {
		pthread_mutex_destroy(&p->lock);
		return false;
	}
	p->tty = isatty(STDERR_FILENO);
	p->t_start = p->t0 = progress_now();
	/* Without a ticker the line still moves at each callback. */
	p->ticking = p->tty && !pthread_create(&p->ticker, NULL, progress_tick, p);
	return true;
}

void progress_update(void *ctx, const char *stage, double done)
{
	struct progress *p = ctx;
	size_t key;
	int permille;
	bool new_stage;
	double now = progress_now();

	if (!stage)
		stage = "";
	permille = isfinite(done) ? (int)(done * 1000.0) : 0;
	if (permille < 0)
		permille = 0;
	if (permille > 1000)
		permille = 1000;
	key = progress_key(stage);
	pthread_mutex_lock(&p->lock);
	new_stage = progress_key(p->stage) != key || strncmp(p->stage, stage, key) != 0;
	if (new_stage)
		p->t0 = now;
	snprintf(p->stage, sizeof(p->stage), "%s", stage);
	p->done = isfinite(done) ? done : 0;
	if (p->tty && now - p->t_start >= PROGRESS_QUIET_S &&
	    (new_stage || (permille != p->permille && now - p->t_drawn >= PROGRESS_REDRAW_S))) {
		p->permille = permille;
		progress_draw(p, now);
	} else if (!p->tty && new_stage) {
		fprintf(stderr, "%s: %s%s\n", p->cmd, p->prefix ? p->prefix : "", stage);
	}
	p->permille = permille;
	pthread_mutex_unlock(&p->lock);
}

void progress_end(struct progress *p)
{
	if (p->ticking) {
		pthread_mutex_lock(&p->lock);
		p->stop = true;
		pthread_cond_signal(&p->wake);
		pthread_mutex_unlock(&p->lock);
		pthread_join(p->ticker, NULL);
	}
	if (p->tty && p->width) {
		fputc('\r', stderr);
		for (size_t w = 0; w < p->width; w++)
			fputc(' ', stderr);
		fputc('\r', stderr);
		fflush(stderr);
	}
	pthread_cond_destroy(&p->wake);
	pthread_mutex_destroy(&p->lock);
}
