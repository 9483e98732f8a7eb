/*
 * threemf_profile.c - the layer height profiles a PrusaSlicer project keeps
 * (docs/slicing.md "A 3MF's layer height profile"): one line per object
 * whose layers were edited with the variable layer height tool,
 * `object_id=N|z;h;z;h;...`, N counting the project's objects from 1 and
 * each pair a Z above the object's bottom and the layer height there (mm).
 *
 * Untrusted input: the entry is read within threemf_text's bound, every
 * number through st_parse_double, and a line that does not parse is an
 * error naming the entry and the line rather than a profile half-used.
 */
#include "meshio_impl.h"
#include "st_grow.h"
#include "st_number.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The line's error: "NAME: ENTRY line N: what", as the model's. */
static int profile_err(struct mio_src *s, size_t line, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static int profile_err(struct mio_src *s, size_t line, const char *fmt, ...)
{
	va_list ap;
	int rc;

	va_start(ap, fmt);
	rc = mio_verr_line(s, ST_ERR_PARSE, MESHIO_3MF_LAYER_PROFILE_ENTRY, line, fmt, ap);
	va_end(ap);
	return rc;
}

/* The object number of a line "object_id=N|...": N, or 0 when malformed;
 * *rest is what follows the bar. */
static size_t line_object(const char *line, const char *end, const char **rest)
{
	static const char key[] = "object_id=";
	size_t id = 0;
	const char *p = line + sizeof(key) - 1;

	if ((size_t)(end - line) < sizeof(key) || memcmp(line, key, sizeof(key) - 1))
		return 0;
	for (; p < end && *p >= '0' && *p <= '9'; p++) {
		if (id > 100000000)
			return 0;
		id = id * 10 + (size_t)(*p - '0');
	}
	if (p == end || *p != '|')
		return 0;
	*rest = p + 1;
	return id;
}

/* Parse the values of one line (between p and end) into a new array. */
static int line_values(struct mio_src *s, size_t lineno, const char *p, const char *end,
		       double **zh, size_t *pairs)
{
	size_t n = 0, cap = 0;
	double *v = NULL;

	while (p < end) {
		const char *q = memchr(p, ';', (size_t)(end - p));
		size_t len = (size_t)((q ? q : end) - p);
		double x;

		if (st_parse_double(p, len, ST_NUMBER_EXPONENT, &x) != ST_NUMBER_OK) {
			free(v);
			return profile_err(s, lineno, "value %zu (\"%.*s\") is not a number", n + 1,
					   (int)(len > 40 ? 40 : len), p);
		}
		if (n == cap) {
			double *g = st_grow(v, &cap, n + 1, sizeof(*v));

			if (!g) {
				free(v);
				return mio_err(s, ST_ERR_NOMEM, "out of memory for a layer profile");
			}
			v = g;
		}
		v[n++] = x;
		p = q ? q + 1 : end;
	}
	if (n < 4 || n % 2) {
		free(v);
		return profile_err(s, lineno, "%zu values; a profile is pairs of Z and height, "
					      "at least two",
				   n);
	}
	for (size_t i = 0; i < n; i += 2) {
		if (v[i] < 0 || (i && v[i] < v[i - 2])) {
			double z = v[i];

			free(v);
			return profile_err(s, lineno, "Z %g mm (pair %zu) is below the one before it "
						      "or below 0",
					   z, i / 2 + 1);
		}
		if (!(v[i + 1] > 0)) {
			double h = v[i + 1];

			free(v);
			return profile_err(s, lineno, "layer height %g mm (pair %zu) is not above 0", h,
					   i / 2 + 1);
		}
	}
	*zh = v;
	*pairs = n / 2;
	return 0;
}

int threemf_parse_layer_profile(struct mio_src *s, const char *text, size_t object, double **zh,
				size_t *pairs, size_t *profiles)
{
	size_t lineno = 0, found = 0;
	int rc = 0;

	*zh = NULL;
	*pairs = 0;
	for (const char *line = text; !rc && line && *line;) {
		const char *nl = strchr(line, '\n'), *end = nl ? nl : line + strlen(line), *rest;
		const char *next = nl ? nl + 1 : end; /* before end drops a '\r' */
		size_t id;

		lineno++;
		if (end > line && end[-1] == '\r')
			end--;
		if (end == line) { /* blank lines, as at the end of the file */
			line = next;
			continue;
		}
		id = line_object(line, end, &rest);
		if (!id)
			rc = profile_err(s, lineno, "not of the form object_id=N|z;h;...");
		else if (id == object && *zh)
			rc = profile_err(s, lineno, "a second profile for object %zu", id);
		else if (id == object)
			rc = line_values(s, lineno, rest, end, zh, pairs);
		else {
			double *other = NULL;
			size_t n;

			/* every line is checked, so a broken file is found whichever
			 * object is sliced */
			rc = line_values(s, lineno, rest, end, &other, &n);
			free(other);
		}
		found++;
		line = next;
	}
	if (rc) {
		free(*zh);
		*zh = NULL;
		*pairs = 0;
	} else if (profiles) {
		*profiles = found;
	}
	return rc;
}

int threemf_layer_profile(struct mio_src *s, size_t object, double **zh, size_t *pairs,
			  size_t *profiles)
{
	char *text = NULL;
	int rc = threemf_text(s, MESHIO_3MF_LAYER_PROFILE_ENTRY, &text);

	if (!rc)
		rc = threemf_parse_layer_profile(s, text, object, zh, pairs, profiles);
	free(text);
	return rc;
}
