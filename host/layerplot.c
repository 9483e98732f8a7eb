/*
 * layerplot.c - the layer-height profile as a PNG (layerplot.h).
 */
#include "layerplot.h"

#include <cairo.h>
#include <math.h>
#include <stdio.h>

#include "pngout.h"

#define MARGIN_LEFT 70.0
#define MARGIN_RIGHT 20.0
#define MARGIN_TOP 40.0
#define MARGIN_BOTTOM 50.0
#define FONT_PX 13.0
#define TICKS 6 /* about this many labelled ticks per axis */

/* The data's frame and the plot area in px. */
struct frame {
	double z0, z1, h0, h1;
	double left, right, top, bottom;
};

static double px_x(const struct frame *f, double z)
{
	return f->left + (z - f->z0) / (f->z1 - f->z0) * (f->right - f->left);
}

static double px_y(const struct frame *f, double h)
{
	return f->bottom - (h - f->h0) / (f->h1 - f->h0) * (f->bottom - f->top);
}

/* A round tick step (1, 2 or 5 times a power of ten) giving about TICKS ticks. */
static double tick_step(double range)
{
	double raw = range / TICKS, p = pow(10.0, floor(log10(raw)));

	return raw <= p ? p : raw <= 2 * p ? 2 * p : raw <= 5 * p ? 5 * p : 10 * p;
}

static void draw_axes(cairo_t *cr, const struct frame *f)
{
	double zs = tick_step(f->z1 - f->z0), hs = tick_step(f->h1 - f->h0);
	char buf[32];

	cairo_set_source_rgb(cr, 0, 0, 0);
	cairo_set_line_width(cr, 1.0);
	cairo_rectangle(cr, f->left, f->top, f->right - f->left, f->bottom - f->top);
	cairo_stroke(cr);
	for (double z = ceil(f->z0 / zs) * zs; z <= f->z1 + 1e-9; z += zs) {
		cairo_move_to(cr, px_x(f, z), f->bottom);
		cairo_line_to(cr, px_x(f, z), f->bottom + 5);
		cairo_stroke(cr);
		snprintf(buf, sizeof(buf), "%g", z);
		pngout_text(cr, px_x(f, z), f->bottom + 5 + FONT_PX, buf, 0.5);
	}
	for (double h = ceil(f->h0 / hs) * hs; h <= f->h1 + 1e-9; h += hs) {
		cairo_move_to(cr, f->left - 5, px_y(f, h));
		cairo_line_to(cr, f->left, px_y(f, h));
		cairo_stroke(cr);
		snprintf(buf, sizeof(buf), "%g", h);
		pngout_text(cr, f->left - 8, px_y(f, h) + FONT_PX / 3, buf, 1.0);
	}
	pngout_text(cr, (f->left + f->right) / 2, f->bottom + 10 + 2 * FONT_PX, "Z (mm)", 0.5);
	cairo_save(cr);
	cairo_translate(cr, 18, (f->top + f->bottom) / 2);
	cairo_rotate(cr, -M_PI / 2);
	pngout_text(cr, 0, 0, "layer height (mm)", 0.5);
	cairo_restore(cr);
}

/* The dashed line of a bound, when set and inside the frame. */
static void draw_bound(cairo_t *cr, const struct frame *f, double h)
{
	static const double dash[] = {6.0, 4.0};

	if (!(h > f->h0 && h < f->h1))
		return;
	cairo_save(cr);
	cairo_set_source_rgb(cr, 0.8, 0.2, 0.2);
	cairo_set_dash(cr, dash, 2, 0);
	cairo_move_to(cr, f->left, px_y(f, h));
	cairo_line_to(cr, f->right, px_y(f, h));
	cairo_stroke(cr);
	cairo_restore(cr);
}

static void draw_layers(cairo_t *cr, const struct frame *f, const struct layer_span *l, size_t n,
			size_t raft)
{
	cairo_set_line_width(cr, 2.0);
	for (size_t i = 0; i < n; i++) {
		if (i == 0 || i == raft)
			cairo_stroke(cr); /* the raft and the part in their colours */
		if (i < raft)
			cairo_set_source_rgb(cr, 0.55, 0.55, 0.55);
		else
			cairo_set_source_rgb(cr, 0.1, 0.3, 0.8);
		if (i == 0 || i == raft)
			cairo_move_to(cr, px_x(f, l[i].z - l[i].height), px_y(f, l[i].height));
		else
			cairo_line_to(cr, px_x(f, l[i].z - l[i].height), px_y(f, l[i].height));
		cairo_line_to(cr, px_x(f, l[i].z), px_y(f, l[i].height));
	}
	cairo_stroke(cr);
}

int layerplot_write(const char *path, const struct layer_span *l, size_t n,
		    const struct layerplot_opts *o, struct st_error *err)
{
	struct frame fr = {.left = MARGIN_LEFT,
			   .right = LAYERPLOT_WIDTH - MARGIN_RIGHT,
			   .top = MARGIN_TOP,
			   .bottom = LAYERPLOT_HEIGHT - MARGIN_BOTTOM};
	cairo_surface_t *surf;
	cairo_t *cr;

	if (!l || !n)
		return st_error_set(err, ST_ERR_ARG, "layer plot: no layers to plot");
	fr.z1 = l[n - 1].z;
	for (size_t i = 0; i < n; i++)
		fr.h1 = fmax(fr.h1, l[i].height);
	fr.h1 = fmax(fr.h1, o->max_height) * 1.1;
	if (!(fr.z1 > fr.z0))
		fr.z1 = fr.z0 + 1.0;
	cr = pngout_canvas(LAYERPLOT_WIDTH, LAYERPLOT_HEIGHT, FONT_PX, &surf);
	draw_axes(cr, &fr);
	draw_bound(cr, &fr, o->min_height);
	draw_bound(cr, &fr, o->max_height);
	draw_layers(cr, &fr, l, n, o->raft_layers);
	if (o->title) {
		cairo_set_source_rgb(cr, 0, 0, 0);
		pngout_text(cr, MARGIN_LEFT, MARGIN_TOP - 14, o->title, 0.0);
	}
	return pngout_save(cr, surf, path, "layer plot", "", err);
}
