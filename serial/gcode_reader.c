/*
 * gcode_reader.c - the streaming G-code line reader and the slicers' layer
 * comments, on top of the line parser of gcode.c (see gcode.h).
 */
#include "gcode.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static bool is_blank(char c)
{
	return c == ' ' || c == '\t';
}

/* ---- slicer layer comments ---- */

/* Number in s[0..n) after trimming blanks; false if it is not one. */
static bool comment_number(const char *s, size_t n, double *v)
{
	while (n > 0 && is_blank(*s))
		s++, n--;
	while (n > 0 && is_blank(s[n - 1]))
		n--;
	return n > 0 && gcode_read_number(s, n, v, NULL) == 0;
}

/* Whole number in s[0..n), blanks trimmed, |n| < 10^9. */
static bool comment_integer(const char *s, size_t n, long *v)
{
	double d;

	for (size_t i = 0; i < n; i++)
		if (s[i] == '.')
			return false;
	if (!comment_number(s, n, &d) || fabs(d) >= 1e9)
		return false;
	*v = (long)d;
	return true;
}

static bool has_prefix(const char *s, size_t n, const char *pre)
{
	size_t k = strlen(pre);

	return n >= k && memcmp(s, pre, k) == 0;
}

bool gcode_layer_follow(const struct gcode_line *line, long *layer, double *z)
{
	long l;
	double zz;
	const enum gcode_layer_mark mark = gcode_layer_comment(line, &l, &zz);

	if (mark == GCODE_LAYER_START)
		*layer = l >= 0 ? l : *layer + 1;
	if (mark != GCODE_LAYER_NONE && !isnan(zz))
		*z = zz;
	return mark == GCODE_LAYER_START;
}

enum gcode_layer_mark gcode_layer_comment(const struct gcode_line *line, long *layer, double *z)
{
	const char *s;
	size_t n;
	long num = -1;
	double height = NAN;
	enum gcode_layer_mark mark = GCODE_LAYER_NONE;

	if (!line || line->letter != 0 || !line->has_comment)
		return GCODE_LAYER_NONE;
	s = line->comment;
	n = line->comment_len;
	while (n > 0 && is_blank(*s))
		s++, n--;
	if (has_prefix(s, n, "LAYER:")) { /* Cura */
		if (comment_integer(s + 6, n - 6, &num))
			mark = GCODE_LAYER_START;
	} else if (n == 12 && memcmp(s, "LAYER_CHANGE", 12) == 0) { /* PrusaSlicer */
		mark = GCODE_LAYER_START;
	} else if (has_prefix(s, n, "Z:")) { /* PrusaSlicer, after ;LAYER_CHANGE */
		if (comment_number(s + 2, n - 2, &height))
			mark = GCODE_LAYER_Z;
	} else if (has_prefix(s, n, "layer ")) { /* Simplify3D: "; layer 1, Z = 0.200" */
		const char *comma = memchr(s, ',', n);
		size_t i;

		if (!comma || !comment_integer(s + 6, (size_t)(comma - s) - 6, &num))
			return GCODE_LAYER_NONE;
		i = (size_t)(comma - s) + 1;
		while (i < n && is_blank(s[i]))
			i++;
		if (i >= n || s[i] != 'Z')
			return GCODE_LAYER_NONE;
		for (i++; i < n && is_blank(s[i]); i++)
			;
		if (i >= n || s[i] != '=' || !comment_number(s + i + 1, n - i - 1, &height))
			return GCODE_LAYER_NONE;
		mark = GCODE_LAYER_START;
	}
	if (mark == GCODE_LAYER_NONE)
		return mark;
	if (layer)
		*layer = num;
	if (z)
		*z = height;
	return mark;
}

/* ---- streaming reader ---- */

#define READER_CHUNK 65536

struct gcode_reader {
	FILE *fp;
	char *name;
	char *chunk; /* READER_CHUNK bytes read ahead */
	size_t chunk_len, chunk_pos;
	char *line; /* GCODE_RAW_MAX bytes */
	uint64_t lineno, bytes;
	bool eof;
	int io_code; /* sticky read error, 0 if none */
	struct st_error io_err;
};

int gcode_reader_new(FILE *fp, const char *name, struct gcode_reader **out, struct st_error *err)
{
	struct gcode_reader *r;

	if (out)
		*out = NULL;
	if (!fp || !out)
		return st_error_set(err, ST_ERR_ARG, "gcode_reader_new: NULL argument");
	if (!name)
		name = "<input>";
	r = calloc(1, sizeof(*r));
	if (!r)
		goto out_nomem;
	r->name = malloc(strlen(name) + 1);
	if (!r->name)
		goto out_free_reader;
	strcpy(r->name, name);
	r->chunk = malloc(READER_CHUNK);
	if (!r->chunk)
		goto out_free_name;
	r->line = malloc(GCODE_RAW_MAX);
	if (!r->line)
		goto out_free_chunk;
	r->fp = fp;
	*out = r;
	return 0;

out_free_chunk:
	free(r->chunk);
out_free_name:
	free(r->name);
out_free_reader:
	free(r);
out_nomem:
	return st_error_set(err, ST_ERR_NOMEM, "%s: out of memory for the G-code reader", name);
}

void gcode_reader_free(struct gcode_reader *r)
{
	if (!r)
		return;
	free(r->line);
	free(r->chunk);
	free(r->name);
	free(r);
}

/* Next byte of input, or -1 at the end or on a (sticky) read error. */
static int reader_byte(struct gcode_reader *r)
{
	if (r->chunk_pos == r->chunk_len) {
		size_t got;

		if (r->eof || r->io_code)
			return -1;
		errno = 0;
		got = fread(r->chunk, 1, READER_CHUNK, r->fp);
		if (got == 0) {
			if (ferror(r->fp)) {
				int e = errno;

				r->io_code = st_error_set(&r->io_err, ST_ERR_IO,
							  "%s: line %llu: read error: %s", r->name,
							  (unsigned long long)(r->lineno + 1),
							  e ? strerror(e) : "unknown error");
			} else {
				r->eof = true;
			}
			return -1;
		}
		r->chunk_len = got;
		r->chunk_pos = 0;
	}
	r->bytes++;
	return (unsigned char)r->chunk[r->chunk_pos++];
}

/* Look at the next byte without taking it (-1 at the end). */
static int reader_peek(struct gcode_reader *r)
{
	int c = reader_byte(r);

	if (c >= 0) {
		r->chunk_pos--;
		r->bytes--;
	}
	return c;
}

int gcode_reader_next(struct gcode_reader *r, unsigned flags, struct gcode_line *line,
		      struct st_error *err)
{
	size_t len = 0;
	bool any = false, overlong = false;
	int c, rc;

	if (!r || !line)
		return st_error_set(err, ST_ERR_ARG, "gcode_reader_next: NULL argument");
	if (r->io_code) {
		if (err)
			*err = r->io_err;
		return r->io_code;
	}
	for (;;) {
		c = reader_byte(r);
		if (c < 0)
			break;
		any = true;
		if (c == '\n')
			break;
		if (c == '\r') {
			if (reader_peek(r) == '\n')
				reader_byte(r);
			break;
		}
		if (len < GCODE_RAW_MAX)
			r->line[len++] = (char)c;
		else
			overlong = true;
	}
	if (r->io_code) {
		if (err)
			*err = r->io_err;
		return r->io_code;
	}
	if (!any)
		return 0;
	r->lineno++;
	if (overlong)
		return st_error_set(
		    err, ST_ERR_PARSE,
		    "%s: line %llu: line longer than %d bytes; it is rejected, not cut", r->name,
		    (unsigned long long)r->lineno, GCODE_RAW_MAX);
	{
		struct st_error perr = {0};

		rc = gcode_parse(r->line, len, flags, line, &perr);
		if (rc)
			return st_error_set(err, rc, "%s: line %llu: %s", r->name,
					    (unsigned long long)r->lineno, perr.msg);
	}
	return 1;
}

uint64_t gcode_reader_line(const struct gcode_reader *r)
{
	return r ? r->lineno : 0;
}

uint64_t gcode_reader_bytes(const struct gcode_reader *r)
{
	return r ? r->bytes : 0;
}
