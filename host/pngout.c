/*
 * pngout.c - a cairo drawing written as PNG (pngout.h).
 */
#include "pngout.h"

#include "st_file.h"

#include <errno.h>
#include <string.h>

cairo_t *pngout_canvas(int w, int h, double font_px, cairo_surface_t **surf)
{
	cairo_t *cr;

	*surf = cairo_image_surface_create(CAIRO_FORMAT_RGB24, w, h);
	cr = cairo_create(*surf);
	pngout_rgb(cr, 0xffffff);
	cairo_paint(cr);
	cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
			       CAIRO_FONT_WEIGHT_NORMAL);
	cairo_set_font_size(cr, font_px);
	pngout_rgb(cr, 0x000000);
	return cr;
}

void pngout_rgb(cairo_t *cr, unsigned c)
{
	cairo_set_source_rgb(cr, ((c >> 16) & 0xff) / 255.0, ((c >> 8) & 0xff) / 255.0,
			     (c & 0xff) / 255.0);
}

void pngout_text(cairo_t *cr, double x, double y, const char *s, double align)
{
	cairo_text_extents_t e;

	cairo_text_extents(cr, s, &e);
	cairo_move_to(cr, x - align * e.x_advance, y);
	cairo_show_text(cr, s);
}

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

int pngout_save(cairo_t *cr, cairo_surface_t *surf, const char *path, const char *what,
		const char *nomem, struct st_error *err)
{
	struct st_file_out out;
	int rc = st_file_begin(&out, path, err);

	if (rc) {
		cairo_destroy(cr);
		cairo_surface_destroy(surf);
		return rc;
	}
	if ((rc = pngout_write(cr, surf, out.f, what, nomem, err))) {
		st_file_abort(&out);
		return rc;
	}
	return st_file_commit(&out, err);
}
