/*
 * thumbnail.c - G-code thumbnails of the part (thumbnail.h): the mesh
 * drawn with cairo back to front, encoded as PNG, then base64 (libcrypto).
 */
#include "thumbnail.h"

#include <cairo.h>
#include <math.h>
#include <openssl/evp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "st_grow.h"

/* The view: turned about Z so the front right corner faces the camera,
 * then looked at from this far above the horizon, degrees. */
#define THUMB_YAW_DEG (-45.0)
#define THUMB_PITCH_DEG 30.0
/* Share of each side left empty around the part. */
#define THUMB_MARGIN 0.04
/* PrusaSlicer's base64 lines. */
#define THUMB_LINE_CHARS 78
/* The part's colour (Prusa orange), and how much of it unlit faces keep. */
#define THUMB_R 0.93
#define THUMB_G 0.42
#define THUMB_B 0.13
#define THUMB_AMBIENT 0.35

int thumb_parse(const char *spec, struct thumb_size out[THUMB_SIZES_MAX], size_t *n,
		struct st_error *err)
{
	const char *p = spec ? spec : "";

	*n = 0;
	while (*p == ' ' || *p == ',')
		p++;
	while (*p) {
		char *end;
		long w = strtol(p, &end, 10), h = 0;
		bool ok = end != p && *end == 'x';

		if (ok) {
			const char *q = end + 1;
			h = strtol(q, &end, 10);
			ok = end != q && w >= 1 && w <= THUMB_SIDE_MAX && h >= 1 && h <= THUMB_SIDE_MAX;
		}
		while (ok && *end == ' ')
			end++;
		if (!ok || (*end && *end != ',') || *n == THUMB_SIZES_MAX)
			return st_error_set(err, ST_ERR_RANGE,
					    "'%.64s': each size is WxH (1 to %d px a side), at most %d "
					    "separated by commas, e.g. 160x120",
					    spec, THUMB_SIDE_MAX, THUMB_SIZES_MAX);
		out[(*n)++] = (struct thumb_size){(int)w, (int)h};
		p = end;
		while (*p == ' ' || *p == ',')
			p++;
	}
	return 0;
}

/* A triangle as seen: its corners on the view plane and its distance. */
struct seen {
	double x[3], y[3]; /* view plane, mm, y up */
	double depth;	   /* mean distance along the view, larger nearer */
	double shade;	   /* 0..1 */
};

static int by_depth(const void *a, const void *b)
{
	double da = ((const struct seen *)a)->depth, db = ((const struct seen *)b)->depth;

	return (da > db) - (da < db);
}

/* The triangles of m facing the camera, farthest first; *n of them. */
static struct seen *view(const struct mesh *m, size_t *n)
{
	double yaw = THUMB_YAW_DEG * M_PI / 180, pitch = THUMB_PITCH_DEG * M_PI / 180;
	double cy = cos(yaw), sy = sin(yaw), cp = cos(pitch), sp = sin(pitch);
	/* toward the camera, in the mesh's frame */
	double cam[3] = {-cp * sy, -cp * cy, sp};
	struct seen *s = m->ntris ? malloc(m->ntris * sizeof(*s)) : NULL;

	*n = 0;
	for (size_t t = 0; s && t < m->ntris; t++) {
		const double *v[3] = {m->verts[m->tris[t][0]], m->verts[m->tris[t][1]],
				      m->verts[m->tris[t][2]]};
		double e1[3], e2[3], nv[3], len, facing;
		struct seen *o = &s[*n];

		for (int k = 0; k < 3; k++) {
			e1[k] = v[1][k] - v[0][k];
			e2[k] = v[2][k] - v[0][k];
		}
		nv[0] = e1[1] * e2[2] - e1[2] * e2[1];
		nv[1] = e1[2] * e2[0] - e1[0] * e2[2];
		nv[2] = e1[0] * e2[1] - e1[1] * e2[0];
		len = sqrt(nv[0] * nv[0] + nv[1] * nv[1] + nv[2] * nv[2]);
		facing = len > 0 ? (nv[0] * cam[0] + nv[1] * cam[1] + nv[2] * cam[2]) / len : 0;
		if (facing <= 0)
			continue; /* a back face (or no face): the closed part hides it */
		o->depth = 0;
		for (int k = 0; k < 3; k++) {
			double x = v[k][0] * cy - v[k][1] * sy, y = v[k][0] * sy + v[k][1] * cy;
			o->x[k] = x;
			o->y[k] = v[k][2] * cp + y * sp;
			o->depth += (-y * cp + v[k][2] * sp) / 3;
		}
		o->shade = THUMB_AMBIENT + (1 - THUMB_AMBIENT) * facing;
		(*n)++;
	}
	if (s)
		qsort(s, *n, sizeof(*s), by_depth);
	return s;
}

/* A growing byte buffer for cairo's PNG writer. */
struct bytes {
	unsigned char *p;
	size_t n, cap;
	bool failed;
};

static cairo_status_t put_bytes(void *ctx, const unsigned char *data, unsigned int len)
{
	struct bytes *b = ctx;
	unsigned char *grown = st_grow(b->p, &b->cap, b->n + len, 1);

	if (!grown) {
		b->failed = true;
		return CAIRO_STATUS_WRITE_ERROR;
	}
	b->p = grown;
	memcpy(b->p + b->n, data, len);
	b->n += len;
	return CAIRO_STATUS_SUCCESS;
}

/* The n seen triangles drawn into a w x h PNG, fitted with the margin. */
static int draw_png(const struct seen *s, size_t n, int w, int h, struct bytes *png,
		    struct st_error *err)
{
	double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY, scale;
	cairo_surface_t *sf = cairo_image_surface_create(CAIRO_FORMAT_ARGB32, w, h);
	cairo_t *cr = cairo_create(sf);
	int rc = 0;

	for (size_t i = 0; i < n; i++)
		for (int k = 0; k < 3; k++) {
			x0 = fmin(x0, s[i].x[k]);
			x1 = fmax(x1, s[i].x[k]);
			y0 = fmin(y0, s[i].y[k]);
			y1 = fmax(y1, s[i].y[k]);
		}
	scale = fmin(w * (1 - 2 * THUMB_MARGIN) / fmax(x1 - x0, 1e-9),
		     h * (1 - 2 * THUMB_MARGIN) / fmax(y1 - y0, 1e-9));
	/* the part's middle at the picture's, y down */
	cairo_translate(cr, w / 2.0, h / 2.0);
	cairo_scale(cr, scale, -scale);
	cairo_translate(cr, -(x0 + x1) / 2, -(y0 + y1) / 2);
	cairo_set_line_width(cr, 0.5 / scale); /* closes the seams between faces */
	cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
	for (size_t i = 0; i < n; i++) {
		cairo_move_to(cr, s[i].x[0], s[i].y[0]);
		cairo_line_to(cr, s[i].x[1], s[i].y[1]);
		cairo_line_to(cr, s[i].x[2], s[i].y[2]);
		cairo_close_path(cr);
		cairo_set_source_rgb(cr, THUMB_R * s[i].shade, THUMB_G * s[i].shade,
				     THUMB_B * s[i].shade);
		cairo_fill_preserve(cr);
		cairo_stroke(cr);
	}
	cairo_surface_flush(sf);
	if (cairo_status(cr) != CAIRO_STATUS_SUCCESS ||
	    cairo_surface_write_to_png_stream(sf, put_bytes, png) != CAIRO_STATUS_SUCCESS)
		rc = png->failed ? st_error_set(err, ST_ERR_NOMEM, "thumbnails: out of memory")
				 : st_error_set(err, ST_ERR_INTERNAL,
						"thumbnails: cairo could not draw a %dx%d picture", w,
						h);
	cairo_destroy(cr);
	cairo_surface_destroy(sf);
	return rc;
}

/* Append the block of one picture (thumbnail.h) to text. */
static int add_block(struct bytes *text, const struct bytes *png, int w, int h,
		     struct st_error *err)
{
	size_t b64 = 4 * ((png->n + 2) / 3);
	unsigned char *enc = malloc(b64 + 1);
	char line[128];
	int rc = 0;

	if (!enc)
		return st_error_set(err, ST_ERR_NOMEM, "thumbnails: out of memory");
	EVP_EncodeBlock(enc, png->p, (int)png->n);
	snprintf(line, sizeof(line), ";\n; thumbnail begin %dx%d %zu\n", w, h, b64);
	rc = put_bytes(text, (const unsigned char *)line, (unsigned)strlen(line));
	for (size_t at = 0; !rc && at < b64; at += THUMB_LINE_CHARS) {
		size_t k = b64 - at < THUMB_LINE_CHARS ? b64 - at : THUMB_LINE_CHARS;
		rc = put_bytes(text, (const unsigned char *)"; ", 2) ||
		     put_bytes(text, enc + at, (unsigned)k) ||
		     put_bytes(text, (const unsigned char *)"\n", 1);
	}
	if (!rc)
		rc = put_bytes(text, (const unsigned char *)"; thumbnail end\n;\n", 18);
	free(enc);
	return rc ? st_error_set(err, ST_ERR_NOMEM, "thumbnails: out of memory") : 0;
}

int thumb_block(const struct mesh *m, const char *spec, char **out, struct st_error *err)
{
	struct thumb_size sz[THUMB_SIZES_MAX];
	struct bytes text = {0};
	struct seen *s;
	size_t n, ns;
	int rc = thumb_parse(spec, sz, &n, err);

	*out = NULL;
	if (rc || !n || !m || !m->ntris)
		return rc;
	s = view(m, &ns);
	if (!s)
		return st_error_set(err, ST_ERR_NOMEM, "thumbnails: out of memory for %zu triangles",
				    m->ntris);
	for (size_t i = 0; i < n && !rc; i++) {
		struct bytes png = {0};
		rc = draw_png(s, ns, sz[i].w, sz[i].h, &png, err);
		if (!rc)
			rc = add_block(&text, &png, sz[i].w, sz[i].h, err);
		free(png.p);
	}
	free(s);
	if (!rc && put_bytes(&text, (const unsigned char *)"", 1))
		rc = st_error_set(err, ST_ERR_NOMEM, "thumbnails: out of memory");
	if (rc) {
		free(text.p);
		return rc;
	}
	*out = (char *)text.p;
	return 0;
}
