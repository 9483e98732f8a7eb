/*
 * pngout.h - what every cairo picture host/ writes as PNG (the layer
 * previews, the layer-height plot, the accuracy plots) shares: a white
 * canvas with the font set, colours as 0xRRGGBB, aligned text, and the
 * end: check what cairo drew, write it as PNG, free the drawing, and say
 * what went wrong.
 */
#ifndef STRATUM_HOST_PNGOUT_H
#define STRATUM_HOST_PNGOUT_H

#include <cairo.h>
#include <stdio.h>

#include "st_error.h"

/* pngout_canvas - a white w x h picture (*surf) and its context, drawing
 * in black with the sans-serif font at font_px. */
cairo_t *pngout_canvas(int w, int h, double font_px, cairo_surface_t **surf);

/* pngout_rgb - draw in colour c, 0xRRGGBB. */
void pngout_rgb(cairo_t *cr, unsigned c);

/* pngout_text - s with its base line at y, from x (align 0), centred on x
 * (0.5) or ending at x (1). */
void pngout_text(cairo_t *cr, double x, double y, const char *s, double align);

/*
 * pngout_write - what was drawn on cr (a context on surf) into f as PNG;
 * cr and surf are freed either way.  0, or ST_ERR_IO ("WHAT: cannot write
 * the PNG: REASON"), ST_ERR_NOMEM ("WHAT: out of memoryNOMEM", nomem being
 * e.g. " drawing 800 x 600 px" or "") or ST_ERR_INTERNAL ("WHAT: cairo:
 * REASON") in err.
 */
int pngout_write(cairo_t *cr, cairo_surface_t *surf, FILE *f, const char *what,
		 const char *nomem, struct st_error *err);

/* pngout_save - pngout_write into the file path, atomically (st_file.h):
 * path is replaced only by a whole picture. */
int pngout_save(cairo_t *cr, cairo_surface_t *surf, const char *path, const char *what,
		const char *nomem, struct st_error *err);

#endif /* STRATUM_HOST_PNGOUT_H */
