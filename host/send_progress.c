/*
 * send_progress.c - the progress line of `stratum send` and `stratum
 * print` while a printer runs (send.h): fitted to the terminal, layers
 * counted from 1, the ETA from the slicer's estimate corrected by the
 * measured pace when the print has one.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "progress.h"
#include "send.h"
#include "st_append.h"
#include "st_clock.h"

#define SEND_HEATING_BAND 3.0 /* degC below target: still heating */

void send_progress_start(struct send_progress *p)
{
	memset(p, 0, sizeof(*p));
	p->cmd = "stratum send";
	p->tag = "send";
	p->tty = isatty(STDERR_FILENO);
	p->last_decile = -1;
	p->pace0 = 1;
	p->t0 = st_mono_s();
}

/* Wall seconds left, or NAN when nothing tells yet. */
static double send_left(struct send_progress *p, double frac, double now)
{
	double el = now - p->t0;

	if (p->est_total > 0) {
		if (p->est_done > 0 && !p->t_moving)
			p->t_moving = now;
		return progress_eta(p->est_done, fmax(p->est_total - p->est_done, 0),
				    p->t_moving ? now - p->t_moving : 0, p->pace0);
	}
	return frac > 0.01 && frac < 1 ? el / frac - el : NAN;
}

size_t send_progress_line(struct send_progress *p, const struct printer_progress *v, double now,
			  size_t cols, char *out, size_t cap)
{
	double frac = v->total ? (double)v->done / (double)v->total : 1.0, left;
	char tag[40], pct[8], layer[48] = "", count[64], temps[64] = "", el[24], eta[32] = "";
	bool heating = (v->tool && v->tool_actual < v->tool_target - SEND_HEATING_BAND) ||
		       (v->bed && v->bed_actual < v->bed_target - SEND_HEATING_BAND);

	tag[0] = '\0';
	if (p->tag)
		snprintf(tag, sizeof(tag), "[%s]", p->tag);
	snprintf(pct, sizeof(pct), "%3d%%", (int)(fmin(fmax(frac, 0), 1) * 100));
	if (v->layer >= 0 && p->layers)
		snprintf(layer, sizeof(layer), "layer %ld/%zu", v->layer + 1, p->layers);
	else if (v->layer >= 0)
		snprintf(layer, sizeof(layer), "layer %ld", v->layer + 1);
	snprintf(count, sizeof(count), "%s %llu/%llu", v->unit ? v->unit : "line",
		 (unsigned long long)v->done, (unsigned long long)v->total);
	if (v->tool)
		st_appendf(temps, sizeof(temps), "T %.0f/%.0f", v->tool_actual, v->tool_target);
	if (v->bed)
		st_appendf(temps, sizeof(temps), "%sB %.0f/%.0f", temps[0] ? " " : "",
			   v->bed_actual, v->bed_target);
	progress_hms(el, sizeof(el), now - p->t0);
	strcat(el, " elapsed");
	left = send_left(p, frac, now);
	if (isfinite(left) && frac < 1) {
		char hms[16];
		progress_hms(hms, sizeof(hms), left);
		snprintf(eta, sizeof(eta), "ETA %s", hms);
	}
	const struct progress_field f[] = {
	    {tag, 3},	{pct, 0},
	    {layer, 1}, {count, 2},
	    {temps, heating ? 1 : 5}, /* while heating they are the news */
	    {el, 4},	{eta, 0},
	    {v->paused ? "(paused)" : "", 0},
	};
	return progress_fit(out, cap, cols, f, sizeof(f) / sizeof(f[0]));
}

void send_progress_show(struct send_progress *p, const struct printer_progress *v)
{
	double frac = v->total ? (double)v->done / (double)v->total : 1.0;
	char line[512];
	size_t n;

	if (p->tty) {
		n = send_progress_line(p, v, st_mono_s(), progress_columns(STDERR_FILENO), line,
				       sizeof(line));
		progress_redraw(line, n, &p->width);
		return;
	}
	int decile = (int)(frac * 10);
	if (decile != p->last_decile) {
		p->last_decile = decile;
		const char *tag = p->tag;

		/* a log line: every field, the command's name for a tag */
		p->tag = NULL;
		send_progress_line(p, v, st_mono_s(), sizeof(line), line, sizeof(line));
		p->tag = tag;
		fprintf(stderr, "%s: %s\n", p->cmd, line);
	}
}

void send_progress_end(struct send_progress *p)
{
	if (p->tty)
		fputc('\n', stderr);
}
