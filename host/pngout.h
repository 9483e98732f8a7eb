/*
 * pngout.h - the end of every cairo picture host/ writes as PNG (the layer
 * previews, the layer-height plot, the accuracy plots): check what cairo
 * drew, write it as PNG, free the drawing, and say what went wrong.
 */
#ifndef STRATUM_HOST_PNGOUT_H
#define STRATUM_HOST_PNGOUT_H

#include <cairo.h>
#include <stdio.h>

#include "st_error.h"

/*
 * pngout_write - what was drawn on cr (a context on surf) into f as PNG;
 * cr and surf are freed either way.  0, or ST_ERR_IO ("WHAT: cannot write
 * the PNG: REASON"), ST_ERR_NOMEM ("WHAT: out of memoryNOMEM", nomem being
 * e.g. " drawing 800 x 600 px" or "") or ST_ERR_INTERNAL ("WHAT: cairo:
 * REASON") in err.
 */
int pngout_write(cairo_t *cr, cairo_surface_t *surf, FILE *f, const char *what,
		 const char *nomem, struct st_error *err);

#endif /* STRATUM_HOST_PNGOUT_H */
