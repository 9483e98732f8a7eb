/*
 * pngout.c - a cairo drawing written as PNG (pngout.h).
 */
#include "pngout.h"

#include <errno.h>
#include <string.h>

static cairo_status_t put(void *closure, const unsigned char *data, unsigned int len)
{
	return fwrite(data, 1, len, closure) == len ? CAIRO_STATUS_SUCCESS
						    : CAIRO_STATUS_WRITE_ERROR;
}

int pngout_write(cairo_t *cr, cairo_surface_t *surf, FILE *f, const char *what,
		 const char *nomem, struct st_error *err)
{
	cairo_status_t st = cairo_status(cr);

	if (st == CAIRO_STATUS_SUCCESS) {
		cairo_surface_flush(surf);
		st = cairo_surface_write_to_png_stream(surf, put, f);
	}
	cairo_destroy(cr);
	cairo_surface_destroy(surf);
	if (st == CAIRO_STATUS_WRITE_ERROR)
		return st_error_set(err, ST_ERR_IO, "%s: cannot write the PNG: %s", what,
				    strerror(errno));
	if (st == CAIRO_STATUS_NO_MEMORY)
		return st_error_set(err, ST_ERR_NOMEM, "%s: out of memory%s", what, nomem);
	if (st != CAIRO_STATUS_SUCCESS)
		return st_error_set(err, ST_ERR_INTERNAL, "%s: cairo: %s", what,
				    cairo_status_to_string(st));
	return 0;
}
