/*
 * pvdraw.c - layer preview pictures (pvdraw.h): one layout, two back ends
 * (SVG text by hand, PNG through cairo).
 */
#include "pvdraw.h"

#include <cairo.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "commands.h"
#include "pngout.h"
#include "st_file.h"

#define MARGIN 16	/* px around everything */
#define TITLE_H 24	/* px, the title line */
#define FONT_PX 12	/* px, text size */
#define ROW_H 18	/* px, one legend row */
#define COL_W 190	/* px, one legend column */
#define SWATCH_W 22	/* px */
#define SCALE_H 30	/* px, the scale bar row */
#define TALL_MAX 2.0	/* the drawing is at most this many times as tall as wide */
#define TRAVEL_PX 1.0	/* px, travel stroke */
#define OUTLINE_PX 1.5	/* px, model section stroke */
#define DASH_ON 4.0	/* px */
#define DASH_OFF 3.0	/* px */
#define LEGEND_MAX (PREVIEW_FEATURES + 1)

/* Feature colours, 0xRRGGBB, in enum preview_feature order. */
static const unsigned colours[PREVIEW_FEATURES] = {
	0x2a9d8f, /* skirt/brim: teal */
	0x43a047, /* support: green */
	0xb03029, /* sparse infill: dark red */
	0x8e44ad, /* solid infill/skin: purple */
	0x2f6fb2, /* bridge: blue */
	0xc71585, /* gap fill/thin wall: magenta */
	0xe0b000, /* inner perimeter: amber */
	0xff6f20, /* outer perimeter: orange */
	0x8a8a8a, /* other: grey */
	0x3949ab, /* travel: indigo (drawn thin, dashed, translucent) */
};
#define OUTLINE_COLOUR 0x000000
#define TRAVEL_ALPHA 0.6

/* Where things go, px. */
struct layout {
	int w, h;
	double s;	  /* px per mm */
	double tx, ty;	  /* px of the point (0, 0) mm; y grows downwards */
	double clip[4];	  /* x, y, w, h of the drawing: travels to far away are cut */
	double legend_y;  /* top of the legend */
	int cols;
	size_t nleg;
	int leg[LEGEND_MAX]; /* features, or -1 for the model outline */
	double bar_mm;	  /* scale bar length */
	double bar_y;
	char title[512];
};

bool pvdraw_format_of(const char *path, enum pvdraw_format *f)
{
	if (path && cmd_has_ext(path, ".svg"))
		*f = PVDRAW_SVG;
	else if (path && cmd_has_ext(path, ".png"))
		*f = PVDRAW_PNG;
	else
		return false;
	return true;
}

/* The largest 1-2-5 length whose bar fits in max_px. */
static double nice_length(double s, double max_px)
{
	double best = 0.01;

	for (double decade = 0.01; decade <= 1e4; decade *= 10)
		for (int k = 0; k < 3; k++) {
			double l = decade * (k == 0 ? 1 : k == 1 ? 2 : 5);
			if (l * s <= max_px)
				best = l;
		}
	return best;
}

static int layout(const struct preview *pv, const struct pvdraw_opts *o, struct layout *l,
		  struct st_error *err)
{
	double fw = pv->max[0] - pv->min[0], fh = pv->max[1] - pv->min[1];

	memset(l, 0, sizeof(*l));
	if (o->width_px < PVDRAW_WIDTH_MIN || o->width_px > PVDRAW_WIDTH_MAX)
		return st_error_set(err, ST_ERR_ARG, "preview: width %d px is outside %d..%d",
				    o->width_px, PVDRAW_WIDTH_MIN, PVDRAW_WIDTH_MAX);
	if (!(fw > 0.0) || !(fh > 0.0) || !isfinite(fw) || !isfinite(fh))
		return st_error_set(err, ST_ERR_ARG, "preview: nothing to frame");
	double dw = o->width_px - 2 * MARGIN;
	l->s = dw / fw;
	if (fh * l->s > TALL_MAX * dw)
		l->s = TALL_MAX * dw / fh;
	double dh = fh * l->s;
	l->w = o->width_px;
	/* Centre the drawing horizontally when the height limited the scale. */
	l->tx = MARGIN + (dw - fw * l->s) / 2 - pv->min[0] * l->s;
	l->ty = MARGIN + TITLE_H + pv->max[1] * l->s;
	for (int f = 0; f < PREVIEW_FEATURES; f++)
		if (pv->count[f])
			l->leg[l->nleg++] = f;
	if (pv->has_model)
		l->leg[l->nleg++] = -1;
	l->cols = (int)(dw / COL_W);
	if (l->cols < 1)
		l->cols = 1;
	int rows = (int)((l->nleg + (size_t)l->cols - 1) / (size_t)l->cols);
	l->clip[0] = MARGIN;
	l->clip[1] = MARGIN + TITLE_H;
	l->clip[2] = dw;
	l->clip[3] = ceil(dh);
	l->legend_y = MARGIN + TITLE_H + ceil(dh) + MARGIN;
	l->bar_y = l->legend_y + rows * ROW_H + 8;
	l->h = (int)ceil(l->bar_y + SCALE_H + MARGIN);
	l->bar_mm = nice_length(l->s, dw / 4);
	snprintf(l->title, sizeof(l->title), "layer %zu of %zu, Z %.3g mm, %.3g mm high%s%s",
		 pv->layer, pv->layers, pv->z, pv->height, o->title ? " - " : "",
		 o->title ? o->title : "");
	return 0;
}

int pvdraw_size(const struct preview *pv, const struct pvdraw_opts *o, int *w, int *h,
		struct st_error *err)
{
	struct layout l;
	int rc = layout(pv, o, &l, err);

	if (rc)
		return rc;
	*w = l.w;
	*h = l.h;
	return 0;
}

int pvdraw_to_px(const struct preview *pv, const struct pvdraw_opts *o, double x, double y,
		 double *px, double *py, struct st_error *err)
{
	struct layout l;
	int rc = layout(pv, o, &l, err);

	if (rc)
		return rc;
	*px = l.tx + x * l.s;
	*py = l.ty - y * l.s;
	return 0;
}

/* Legend text of entry k. */
static void legend_text(const struct preview *pv, int e, char *buf, size_t cap)
{
	if (e < 0)
		snprintf(buf, cap, "model section (%zu)", pv->noutline);
	else
		snprintf(buf, cap, "%s (%zu)", preview_feature_name((enum preview_feature)e),
			 pv->count[e]);
}

static void legend_pos(const struct layout *l, size_t k, double *x, double *y)
{
	*x = MARGIN + (double)(k % (size_t)l->cols) * COL_W;
	*y = l->legend_y + (double)(k / (size_t)l->cols) * ROW_H;
}

/* ---- SVG ---- */

/* Text with XML's five special characters escaped. */
static void svg_text(FILE *f, const char *s)
{
	for (; *s; s++) {
		const char *ent = *s == '&' ? "&amp;" : *s == '<' ? "&lt;" : *s == '>' ? "&gt;"
				: *s == '"' ? "&quot;" : *s == '\'' ? "&apos;" : NULL;
		if (ent)
			fputs(ent, f);
		else /* control bytes are not allowed in XML 1.0 */
			fputc((unsigned char)*s < 0x20 ? '?' : *s, f);
	}
}

static void svg_path(FILE *f, const struct preview_path *p, bool own_width)
{
	fputs("<path", f);
	if (own_width)
		fprintf(f, " stroke-width=\"%.4f\"", p->width);
	fputs(" d=\"", f);
	for (size_t k = 0; k < p->n; k++)
		fprintf(f, "%s%.3f %.3f", k == 0 ? "M" : " L", p->xy[2 * k], p->xy[2 * k + 1]);
	fputs(p->closed ? " Z\"/>\n" : "\"/>\n", f);
}

/* The picture as SVG into f (left open); 0, ST_ERR_ARG (as pvdraw_size) or ST_ERR_IO. */
static int pvdraw_svg(const struct preview *pv, const struct pvdraw_opts *o, FILE *f,
		      struct st_error *err)
{
	struct layout l;
	char text[128];
	int rc = layout(pv, o, &l, err);

	if (rc)
		return rc;
	fprintf(f,
		"<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
		"<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" "
		"viewBox=\"0 0 %d %d\" font-family=\"sans-serif\" font-size=\"%d\">\n<title>",
		l.w, l.h, l.w, l.h, FONT_PX);
	svg_text(f, l.title);
	fprintf(f, "</title>\n<rect width=\"%d\" height=\"%d\" fill=\"#ffffff\"/>\n", l.w, l.h);
	fprintf(f, "<text x=\"%d\" y=\"%d\">", MARGIN, MARGIN + FONT_PX);
	svg_text(f, l.title);
	/* Paths in G-code mm: y up, stroke widths in mm. */
	fprintf(f,
		"</text>\n<defs><clipPath id=\"frame\"><rect x=\"%.0f\" y=\"%.0f\" width=\"%.0f\" "
		"height=\"%.0f\"/></clipPath></defs>\n<g clip-path=\"url(#frame)\">\n"
		"<g id=\"layer\" transform=\"translate(%.3f %.3f) scale(%.6f %.6f)\" "
		"fill=\"none\" stroke-linecap=\"round\" stroke-linejoin=\"round\">\n",
		l.clip[0], l.clip[1], l.clip[2], l.clip[3], l.tx, l.ty, l.s, -l.s);
	for (int ft = 0; ft < PREVIEW_FEATURES; ft++) {
		if (!pv->count[ft])
			continue;
		fprintf(f, "<g id=\"%s\" stroke=\"#%06x\"", preview_feature_id(ft), colours[ft]);
		if (ft == PREVIEW_TRAVEL)
			fprintf(f,
				" stroke-width=\"%.4f\" stroke-dasharray=\"%.4f %.4f\" "
				"stroke-opacity=\"%.2f\"",
				TRAVEL_PX / l.s, DASH_ON / l.s, DASH_OFF / l.s, TRAVEL_ALPHA);
		fputs(">\n", f);
		for (size_t i = 0; i < pv->n; i++)
			if (pv->paths[i].feature == (enum preview_feature)ft)
				svg_path(f, &pv->paths[i], ft != PREVIEW_TRAVEL);
		fputs("</g>\n", f);
	}
	if (pv->noutline) {
		fprintf(f, "<g id=\"model-outline\" stroke=\"#%06x\" stroke-width=\"%.4f\">\n",
			OUTLINE_COLOUR, OUTLINE_PX / l.s);
		for (size_t i = 0; i < pv->noutline; i++)
			svg_path(f, &pv->outline[i], false);
		fputs("</g>\n", f);
	}
	fputs("</g>\n</g>\n<g id=\"legend\">\n", f);
	for (size_t k = 0; k < l.nleg; k++) {
		double x, y;
		int e = l.leg[k];
		legend_pos(&l, k, &x, &y);
		legend_text(pv, e, text, sizeof(text));
		fprintf(f, "<rect x=\"%.0f\" y=\"%.0f\" width=\"%d\" height=\"8\" fill=\"#%06x\"/>",
			x, y + 5, SWATCH_W, e < 0 ? OUTLINE_COLOUR : colours[e]);
		fprintf(f, "<text x=\"%.0f\" y=\"%.0f\">", x + SWATCH_W + 6, y + 13);
		svg_text(f, text);
		fputs("</text>\n", f);
	}
	double bx = MARGIN, bl = l.bar_mm * l.s, by = l.bar_y + 10;
	fprintf(f,
		"</g>\n<g id=\"scale-bar\" stroke=\"#000000\" stroke-width=\"2\">\n"
		"<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>"
		"<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>"
		"<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>\n"
		"<text x=\"%.1f\" y=\"%.1f\" stroke=\"none\">%g mm</text>\n</g>\n</svg>\n",
		bx, by, bx + bl, by, bx, by - 5, bx, by + 5, bx + bl, by - 5, bx + bl, by + 5,
		bx + bl + 8, by + 4, l.bar_mm);
	if (ferror(f))
		return st_error_set(err, ST_ERR_IO, "preview: cannot write the SVG: %s",
				    strerror(errno));
	return 0;
}

/* ---- PNG ---- */

static void set_colour(cairo_t *cr, unsigned c, double alpha)
{
	cairo_set_source_rgba(cr, ((c >> 16) & 0xff) / 255.0, ((c >> 8) & 0xff) / 255.0,
			      (c & 0xff) / 255.0, alpha);
}

/* Stroke one path in mm (the current transform maps mm to px). */
static void cairo_path_mm(cairo_t *cr, const struct preview_path *p, double width)
{
	cairo_new_path(cr);
	for (size_t k = 0; k < p->n; k++)
		(k ? cairo_line_to : cairo_move_to)(cr, p->xy[2 * k], p->xy[2 * k + 1]);
	if (p->closed)
		cairo_close_path(cr);
	cairo_set_line_width(cr, width);
	cairo_stroke(cr);
}

static void draw_layer(cairo_t *cr, const struct preview *pv, const struct layout *l)
{
	double dash[2] = {DASH_ON / l->s, DASH_OFF / l->s};

	cairo_save(cr);
	cairo_rectangle(cr, l->clip[0], l->clip[1], l->clip[2], l->clip[3]);
	cairo_clip(cr);
	cairo_translate(cr, l->tx, l->ty);
	cairo_scale(cr, l->s, -l->s);
	cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
	cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
	for (int ft = 0; ft < PREVIEW_FEATURES; ft++) {
		bool travel = ft == PREVIEW_TRAVEL;
		set_colour(cr, colours[ft], travel ? TRAVEL_ALPHA : 1.0);
		cairo_set_dash(cr, dash, travel ? 2 : 0, 0);
		for (size_t i = 0; i < pv->n; i++) {
			const struct preview_path *p = &pv->paths[i];
			if (p->feature != (enum preview_feature)ft)
				continue;
			/* A bead thinner than a pixel still shows. */
			cairo_path_mm(cr, p, travel ? TRAVEL_PX / l->s : fmax(p->width, 1.0 / l->s));
		}
	}
	cairo_set_dash(cr, NULL, 0, 0);
	set_colour(cr, OUTLINE_COLOUR, 1.0);
	for (size_t i = 0; i < pv->noutline; i++)
		cairo_path_mm(cr, &pv->outline[i], OUTLINE_PX / l->s);
	cairo_restore(cr);
}

static void draw_furniture(cairo_t *cr, const struct preview *pv, const struct layout *l)
{
	char text[128];

	pngout_rgb(cr, 0x000000);
	pngout_text(cr, MARGIN, MARGIN + FONT_PX, l->title, 0);
	for (size_t k = 0; k < l->nleg; k++) {
		double x, y;
		int e = l->leg[k];
		legend_pos(l, k, &x, &y);
		set_colour(cr, e < 0 ? OUTLINE_COLOUR : colours[e], 1.0);
		cairo_rectangle(cr, x, y + 5, SWATCH_W, 8);
		cairo_fill(cr);
		pngout_rgb(cr, 0x000000);
		legend_text(pv, e, text, sizeof(text));
		pngout_text(cr, x + SWATCH_W + 6, y + 13, text, 0);
	}
	double bx = MARGIN, bl = l->bar_mm * l->s, by = l->bar_y + 10;
	cairo_set_line_width(cr, 2);
	cairo_move_to(cr, bx, by);
	cairo_line_to(cr, bx + bl, by);
	cairo_move_to(cr, bx, by - 5);
	cairo_line_to(cr, bx, by + 5);
	cairo_move_to(cr, bx + bl, by - 5);
	cairo_line_to(cr, bx + bl, by + 5);
	cairo_stroke(cr);
	snprintf(text, sizeof(text), "%g mm", l->bar_mm);
	pngout_text(cr, bx + bl + 8, by + 4, text, 0);
}

/* The picture as PNG into f (left open); 0, ST_ERR_ARG, ST_ERR_IO, ST_ERR_NOMEM or
 * ST_ERR_INTERNAL (cairo refused). */
static int pvdraw_png(const struct preview *pv, const struct pvdraw_opts *o, FILE *f,
		      struct st_error *err)
{
	struct layout l;
	cairo_surface_t *surf;
	cairo_t *cr;
	char nomem[64];
	int rc = layout(pv, o, &l, err);

	if (rc)
		return rc;
	cr = pngout_canvas(l.w, l.h, FONT_PX, &surf);
	draw_layer(cr, pv, &l);
	draw_furniture(cr, pv, &l);
	snprintf(nomem, sizeof(nomem), " drawing %d x %d px", l.w, l.h);
	return pngout_write(cr, surf, f, "preview", nomem, err);
}

/* ---- the file ---- */

int pvdraw_write(const struct preview *pv, const struct pvdraw_opts *o, const char *path,
		 struct st_error *err)
{
	enum pvdraw_format fmt;
	struct st_file_out out;
	int rc;

	if (!pvdraw_format_of(path, &fmt))
		return st_error_set(err, ST_ERR_ARG, "%s: the picture must end in .svg or .png",
				    path ? path : "(no path)");
	if ((rc = st_file_begin(&out, path, err)))
		return rc;
	rc = fmt == PVDRAW_SVG ? pvdraw_svg(pv, o, out.f, err) : pvdraw_png(pv, o, out.f, err);
	if (rc) {
		st_file_abort(&out);
		return rc;
	}
	return st_file_commit(&out, err);
}
