/*
 * accplot.c - cusp-height plots and coloured meshes as PNG (accplot.h).
 */
#include "accplot.h"

#include <cairo.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>

#include "pngout.h"

#define FONT_PX 12
#define MARGIN 16
#define TITLE_H 26
#define TICKS_MAX 8 /* labelled ticks on an axis at most */

/* cusp plot, px */
#define PLOT_W 800
#define PLOT_H 600
#define AXIS_L 70 /* room for the Z labels */
#define AXIS_B 46 /* room for the cusp labels */

/* coloured mesh, px */
#define MESH_W 900
#define VIEW_H 560
#define BAR_W 18
#define BAR_AREA 150 /* the colour scale and its labels, right of the view */
#define HIST_H 170
#define VIEW_AZIMUTH (-35.0 * M_PI / 180) /* seen from the front left */
#define VIEW_ELEVATION (25.0 * M_PI / 180)

/* The 1-2-5 step that labels 0 .. hi with at most TICKS_MAX ticks. */
static double tick_step(double hi)
{
	double decade, steps[3] = {1, 2, 5};

	if (!(hi > 0))
		return 1;
	decade = pow(10, floor(log10(hi / TICKS_MAX)));
	for (int i = 0;; i = (i + 1) % 3) {
		double s = steps[i] * decade;
		if (hi / s <= TICKS_MAX)
			return s;
		if (i == 2)
			decade *= 10;
	}
}

/* Blue (0) through cyan, green and yellow to red (1). */
static void scale_colour(double f, double rgb_out[3])
{
	static const double stops[5][3] = {
	    {0.19, 0.30, 0.80}, {0.10, 0.75, 0.85}, {0.20, 0.75, 0.25}, {0.95, 0.85, 0.10},
	    {0.85, 0.10, 0.10}};
	double x = (f < 0 ? 0 : f > 1 ? 1 : f) * 4;
	int i = x >= 4 ? 3 : (int)x;

	for (int c = 0; c < 3; c++)
		rgb_out[c] = stops[i][c] + (x - i) * (stops[i + 1][c] - stops[i][c]);
}

/* A white w x h picture with its title, drawing in black. */
static cairo_t *start(int w, int h, const char *title, cairo_surface_t **surf)
{
	cairo_t *cr = pngout_canvas(w, h, FONT_PX, surf);

	pngout_text(cr, MARGIN, MARGIN + FONT_PX, title ? title : "", 0);
	return cr;
}

/* ---- cusp height against Z ---- */

int accplot_cusp(const struct cusp_report *r, const char *title, const char *path,
		 struct st_error *err)
{
	cairo_surface_t *surf;
	cairo_t *cr = start(PLOT_W, PLOT_H, title, &surf);
	double x0 = AXIS_L, x1 = PLOT_W - MARGIN, y0 = PLOT_H - AXIS_B, y1 = MARGIN + 2 * TITLE_H;
	double ztop = r->nslices ? r->slices[r->nslices - 1].z + r->layer_height / 2 : 1;
	double cmax = r->max > 0 ? r->max * 1.1 : r->layer_height / 2;
	double sx = (x1 - x0) / cmax, sy = (y0 - y1) / ztop;
	char label[64];

	/* axes, ticks and grid */
	cairo_set_line_width(cr, 1);
	for (double v = 0, s = tick_step(cmax); v <= cmax + 1e-12; v += s) {
		pngout_rgb(cr, 0xdddddd);
		cairo_move_to(cr, x0 + v * sx, y0);
		cairo_line_to(cr, x0 + v * sx, y1);
		cairo_stroke(cr);
		pngout_rgb(cr, 0x000000);
		snprintf(label, sizeof(label), "%g", v);
		pngout_text(cr, x0 + v * sx - 8, y0 + 16, label, 0);
	}
	for (double v = 0, s = tick_step(ztop); v <= ztop + 1e-12; v += s) {
		pngout_rgb(cr, 0xdddddd);
		cairo_move_to(cr, x0, y0 - v * sy);
		cairo_line_to(cr, x1, y0 - v * sy);
		cairo_stroke(cr);
		pngout_rgb(cr, 0x000000);
		snprintf(label, sizeof(label), "%g", v);
		pngout_text(cr, x0 - 6, y0 - v * sy + 4, label, 1);
	}
	pngout_rgb(cr, 0x000000);
	cairo_rectangle(cr, x0, y1, x1 - x0, y0 - y1);
	cairo_stroke(cr);
	pngout_text(cr, (x0 + x1) / 2 - 60, PLOT_H - 12, "cusp height, mm", 0);
	cairo_save(cr);
	cairo_translate(cr, 18, (y0 + y1) / 2 + 50);
	cairo_rotate(cr, -M_PI / 2);
	pngout_text(cr, 0, 0, "Z above the bed, mm", 0);
	cairo_restore(cr);
	/* every box, then the layer lines over them */
	cairo_set_source_rgba(cr, 0.45, 0.45, 0.45, 0.35);
	for (size_t i = 0; i < r->nboxes; i++) {
		cairo_rectangle(cr, x0 + r->boxes[i].cusp * sx - 1, y0 - r->boxes[i].z * sy - 1, 2, 2);
		cairo_fill(cr);
	}
	for (int line = 0; line < 2; line++) {
		bool first = true;
		pngout_rgb(cr, line ? 0x2f6fb2 : 0xc0392b);
		cairo_set_line_width(cr, 1.5);
		for (size_t i = 0; i < r->nslices; i++) {
			const struct cusp_slice *s = &r->slices[i];
			if (!s->boxes)
				continue;
			double x = x0 + (line ? s->mean : s->max) * sx, y = y0 - s->z * sy;
			(first ? cairo_move_to : cairo_line_to)(cr, x, y);
			first = false;
		}
		cairo_stroke(cr);
	}
	/* legend: one row under the title, over the plot */
	const char *names[3] = {"layer maximum", "layer mean", "one box (seed 004)"};
	const unsigned colours[3] = {0xc0392b, 0x2f6fb2, 0x999999};
	for (int k = 0; k < 3; k++) {
		double lx = x0 + 170 * k, ly = MARGIN + FONT_PX + 20;
		pngout_rgb(cr, colours[k]);
		cairo_rectangle(cr, lx, ly - 5, 20, k == 2 ? 3 : 2);
		cairo_fill(cr);
		pngout_rgb(cr, 0x000000);
		pngout_text(cr, lx + 26, ly, names[k], 0);
	}
	return pngout_save(cr, surf, path, path, " drawing the picture", err);
}

/* ---- a mesh coloured per facet ---- */

struct facet_depth {
	double depth;
	uint32_t t;
};

static int cmp_depth(const void *x, const void *y)
{
	double a = ((const struct facet_depth *)x)->depth, b = ((const struct facet_depth *)y)->depth;

	return a < b ? -1 : a > b;
}

/* The view: right, up and towards the viewer, unit vectors. */
static void view_axes(double right[3], double up[3], double toward[3])
{
	double ca = cos(VIEW_AZIMUTH), sa = sin(VIEW_AZIMUTH);
	double ce = cos(VIEW_ELEVATION), se = sin(VIEW_ELEVATION);

	toward[0] = -sa * ce, toward[1] = -ca * ce, toward[2] = se;
	right[0] = ca, right[1] = -sa, right[2] = 0;
	/* up = toward x right */
	up[0] = toward[1] * right[2] - toward[2] * right[1];
	up[1] = toward[2] * right[0] - toward[0] * right[2];
	up[2] = toward[0] * right[1] - toward[1] * right[0];
}

static double dot3(const double a[3], const double b[3])
{
	return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* The facets facing the viewer, farthest first. */
static struct facet_depth *visible_facets(const struct mesh *m, const double toward[3],
					  size_t *n)
{
	struct facet_depth *f = malloc((m->ntris ? m->ntris : 1) * sizeof(*f));

	*n = 0;
	if (!f)
		return NULL;
	for (size_t t = 0; t < m->ntris; t++) {
		const double *a = m->verts[m->tris[t][0]], *b = m->verts[m->tris[t][1]],
			     *c = m->verts[m->tris[t][2]];
		double u[3], v[3], nrm[3], mid[3];
		for (int d = 0; d < 3; d++) {
			u[d] = b[d] - a[d];
			v[d] = c[d] - a[d];
			mid[d] = (a[d] + b[d] + c[d]) / 3;
		}
		nrm[0] = u[1] * v[2] - u[2] * v[1];
		nrm[1] = u[2] * v[0] - u[0] * v[2];
		nrm[2] = u[0] * v[1] - u[1] * v[0];
		if (dot3(nrm, toward) <= 0)
			continue; /* its back: hidden on a closed mesh */
		f[*n].depth = dot3(mid, toward);
		f[(*n)++].t = (uint32_t)t;
	}
	qsort(f, *n, sizeof(*f), cmp_depth);
	return f;
}

static void draw_view(cairo_t *cr, const struct mesh *m, const struct accplot_values *val,
		      double vx, double vy, double vw, double vh)
{
	double right[3], up[3], toward[3], lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
	size_t n;
	struct facet_depth *f;

	view_axes(right, up, toward);
	for (size_t i = 0; i < m->nverts; i++) {
		double x = dot3(m->verts[i], right), y = dot3(m->verts[i], up);
		lo[0] = fmin(lo[0], x), hi[0] = fmax(hi[0], x);
		lo[1] = fmin(lo[1], y), hi[1] = fmax(hi[1], y);
	}
	double s = fmin(vw / fmax(hi[0] - lo[0], 1e-9), vh / fmax(hi[1] - lo[1], 1e-9));
	double ox = vx + (vw - s * (hi[0] - lo[0])) / 2 - s * lo[0];
	double oy = vy + (vh - s * (hi[1] - lo[1])) / 2 + s * hi[1];
	if (!(f = visible_facets(m, toward, &n)))
		return;
	cairo_set_line_width(cr, 0.5);
	cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
	for (size_t i = 0; i < n; i++) {
		const uint32_t *c = m->tris[f[i].t];
		double col[3], u[3], v[3], nrm[3], len;
		for (int d = 0; d < 3; d++) {
			u[d] = m->verts[c[1]][d] - m->verts[c[0]][d];
			v[d] = m->verts[c[2]][d] - m->verts[c[0]][d];
		}
		nrm[0] = u[1] * v[2] - u[2] * v[1];
		nrm[1] = u[2] * v[0] - u[0] * v[2];
		nrm[2] = u[0] * v[1] - u[1] * v[0];
		len = sqrt(dot3(nrm, nrm));
		/* lit from the viewer: facets turned away are darker */
		double light = 0.45 + 0.55 * (len > 0 ? dot3(nrm, toward) / len : 0);
		double value = val->value[f[i].t];
		if (value <= val->grey_to)
			col[0] = col[1] = col[2] = 0.8;
		else
			scale_colour(val->vmax > 0 ? value / val->vmax : 0, col);
		cairo_set_source_rgb(cr, col[0] * light, col[1] * light, col[2] * light);
		for (int k = 0; k < 3; k++) {
			double x = ox + s * dot3(m->verts[c[k]], right);
			double y = oy - s * dot3(m->verts[c[k]], up);
			(k ? cairo_line_to : cairo_move_to)(cr, x, y);
		}
		cairo_close_path(cr);
		cairo_fill_preserve(cr); /* the stroke closes hairline gaps */
		if (val->outline)
			cairo_set_source_rgb(cr, col[0] * light * 0.6, col[1] * light * 0.6,
					     col[2] * light * 0.6);
		cairo_stroke(cr);
	}
	free(f);
}

static void draw_scale(cairo_t *cr, const struct accplot_values *v, double x, double y, double h)
{
	char label[80];
	double vmax = v->vmax, step = tick_step(vmax > 0 ? vmax : 1), col[3];

	for (int i = 0; i < (int)h; i++) {
		scale_colour(1.0 - i / h, col);
		cairo_set_source_rgb(cr, col[0], col[1], col[2]);
		cairo_rectangle(cr, x, y + i, BAR_W, 1);
		cairo_fill(cr);
	}
	pngout_rgb(cr, 0x000000);
	for (double t = 0; vmax > 0 && t <= vmax + 1e-12; t += step) {
		snprintf(label, sizeof(label), "%g", t);
		pngout_text(cr, x + BAR_W + 6, y + h - t / vmax * h + 4, label, 0);
	}
	pngout_text(cr, x - 10, y - 10, v->what, 0);
	snprintf(label, sizeof(label), "mm (max %.4g)", vmax);
	pngout_text(cr, x - 10, y + h + 18, label, 0);
	if (v->grey_to >= 0) {
		cairo_set_source_rgb(cr, 0.8, 0.8, 0.8);
		cairo_rectangle(cr, x - 10, y + h + 30, BAR_W, 10);
		cairo_fill(cr);
		pngout_rgb(cr, 0x000000);
		snprintf(label, sizeof(label), "up to %g mm", v->grey_to);
		pngout_text(cr, x + BAR_W - 4, y + h + 40, label, 0);
	}
}

static void draw_hist(cairo_t *cr, const struct accplot_hist *hist, double x, double y, double w,
		      double h)
{
	double top = 0, bw = w / (double)hist->n;
	char label[64];

	for (size_t i = 0; i < hist->n; i++)
		top = fmax(top, hist->share[i]);
	pngout_rgb(cr, 0x000000);
	pngout_text(cr, x, y - 8, "share of both surfaces' area by distance, mm", 0);
	for (size_t i = 0; i < hist->n; i++) {
		double col[3], bh = top > 0 ? hist->share[i] / top * (h - 30) : 0;
		scale_colour(((double)i + 0.5) / (double)hist->n, col);
		cairo_set_source_rgb(cr, col[0], col[1], col[2]);
		cairo_rectangle(cr, x + i * bw + 1, y + h - 20 - bh, bw - 2, bh);
		cairo_fill(cr);
		pngout_rgb(cr, 0x000000);
		snprintf(label, sizeof(label), "%.1f%%", 100 * hist->share[i]);
		pngout_text(cr, x + i * bw + 4, y + h - 24 - bh, label, 0);
		snprintf(label, sizeof(label), "%.3g", hist->bin_width * (double)i);
		pngout_text(cr, x + i * bw, y + h - 4, label, 0);
	}
}

int accplot_mesh(const struct mesh *m, const struct accplot_values *v,
		 const struct accplot_hist *hist, const char *title, const char *path,
		 struct st_error *err)
{
	int h = MARGIN + TITLE_H + VIEW_H + (hist ? HIST_H : 0) + MARGIN;
	cairo_surface_t *surf;
	cairo_t *cr = start(MESH_W, h, title, &surf);
	double vy = MARGIN + TITLE_H, vw = MESH_W - 2 * MARGIN - BAR_AREA;

	draw_view(cr, m, v, MARGIN, vy, vw, VIEW_H);
	draw_scale(cr, v, MESH_W - BAR_AREA + 10, vy + 40, VIEW_H - 120);
	if (hist)
		draw_hist(cr, hist, MARGIN + 20, vy + VIEW_H + 20, MESH_W - 2 * MARGIN - 40,
			  HIST_H - 20);
	return pngout_save(cr, surf, path, path, " drawing the picture", err);
}
