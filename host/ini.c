/*
 * ini.c - the key = value reader shared by profiles and the node's
 * configuration (ini.h).
 */
#include "ini.h"

#include <errno.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "st_grow.h"

#define SHOW 40 /* bytes of an offending line quoted in messages */

static bool is_blank(char c)
{
	return c == ' ' || c == '\t';
}

/* Trim blanks from both ends of [*s, *s + *len). */
static void trim(const char **s, size_t *len)
{
	while (*len && is_blank(**s)) {
		(*s)++;
		(*len)--;
	}
	while (*len && is_blank((*s)[*len - 1]))
		(*len)--;
}

void ini_show(char *buf, size_t cap, const char *s, size_t len)
{
	size_t n = len < SHOW ? len : SHOW;
	size_t i, o = 0;

	for (i = 0; i < n && o + 1 < cap; i++)
		buf[o++] = (s[i] == '\n' || s[i] == '\r' || s[i] == '\0') ? ' ' : s[i];
	if (len > n)
		for (i = 0; i < 3 && o + 1 < cap; i++)
			buf[o++] = '.';
	buf[o] = '\0';
}

/* A key is letters, digits and '_'. */
static bool good_key(const char *k, size_t len)
{
	for (size_t i = 0; i < len; i++)
		if (!(k[i] >= '0' && k[i] <= '9') && !(k[i] >= 'a' && k[i] <= 'z') &&
		    !(k[i] >= 'A' && k[i] <= 'Z') && k[i] != '_')
			return false;
	return len > 0;
}

size_t ini_comment_at(const char *s, size_t len)
{
	for (size_t i = 1; i < len; i++)
		if ((s[i] == '#' || s[i] == ';') && is_blank(s[i - 1]))
			return i;
	return len;
}

/* One line without its line end. */
static int one_line(const char *s, size_t len, int line, const char *origin,
		    const struct ini_handler *h, void *ctx, struct st_error *err)
{
	struct ini_entry e = {.line = line};
	char tok[INI_SHOW_MAX];
	const char *eq;

	if (memchr(s, '\0', len))
		return st_error_set(err, ST_ERR_PARSE,
				    "%s: line %d: unexpected NUL byte (binary data in a text file)",
				    origin, line);
	trim(&s, &len);
	if (len == 0 || s[0] == '#' || s[0] == ';')
		return 0;
	if (h->inline_comments) {
		len = ini_comment_at(s, len);
		trim(&s, &len);
	}
	if (s[0] == '[') {
		if (h->section)
			return h->section(ctx, line, s, len, err);
		ini_show(tok, sizeof(tok), s, len);
		return st_error_set(err, ST_ERR_PARSE,
				    "%s: line %d: sections such as '%s' are not supported here",
				    origin, line, tok);
	}
	eq = memchr(s, '=', len);
	if (!eq) {
		ini_show(tok, sizeof(tok), s, len);
		return st_error_set(err, ST_ERR_PARSE,
				    "%s: line %d: expected 'key = value', found '%s'", origin, line,
				    tok);
	}
	e.key = s;
	e.key_len = (size_t)(eq - s);
	trim(&e.key, &e.key_len);
	if (h->skip_bad_keys && e.key_len && !good_key(e.key, e.key_len))
		return 0;
	if (!good_key(e.key, e.key_len)) {
		ini_show(tok, sizeof(tok), e.key, e.key_len);
		return st_error_set(err, ST_ERR_PARSE,
				    "%s: line %d: '%s' is not a valid key (letters, digits and '_')",
				    origin, line, tok);
	}
	e.value = eq + 1;
	e.value_len = (size_t)(s + len - e.value);
	trim(&e.value, &e.value_len);
	return h->entry(ctx, &e, err);
}

int ini_parse(const char *text, size_t len, const char *origin, const struct ini_handler *h,
	      void *ctx, struct st_error *err)
{
	size_t pos = 0;
	int line = 0, rc;

	if (len >= 3 && !memcmp(text, "\xEF\xBB\xBF", 3))
		pos = 3; /* UTF-8 byte order mark */
	while (pos < len) {
		const char *start = text + pos;
		const char *nl = memchr(start, '\n', len - pos);
		size_t n = nl ? (size_t)(nl - start) : len - pos;

		line++;
		pos += n + (nl ? 1 : 0);
		if (n && start[n - 1] == '\r')
			n--;
		if (n > INI_LINE_MAX)
			return st_error_set(err, ST_ERR_PARSE,
					    "%s: line %d is longer than %u bytes; the line is "
					    "rejected, not cut",
					    origin, line, INI_LINE_MAX);
		rc = one_line(start, n, line, origin, h, ctx, err);
		if (rc)
			return rc;
	}
	return 0;
}

int ini_read_file(const char *path, char **text, size_t *len, struct st_error *err)
{
	struct stat st;
	char *buf = NULL;
	size_t n = 0, cap = 0;
	const size_t max = INI_FILE_MAX;
	FILE *f;
	int rc;

	*text = NULL;
	*len = 0;
	if (stat(path, &st) == 0 && S_ISDIR(st.st_mode))
		return st_error_set(err, ST_ERR_IO, "%s: is a directory, not a file", path);
	f = fopen(path, "rb");
	if (!f)
		return st_error_set(err, ST_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
	for (;;) {
		size_t got;

		if (n == cap && st_grow_at((void **)&buf, &cap, n + 16384, 1)) {
			rc = st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", path);
			goto out_close;
		}
		got = fread(buf + n, 1, cap - n, f);
		n += got;
		if (n > max) {
			rc = st_error_set(err, ST_ERR_PARSE,
					  "%s: larger than %zu KiB; this is a text file of a few "
					  "kilobytes",
					  path, max >> 10);
			goto out_close;
		}
		if (got == 0) {
			if (ferror(f)) {
				rc = st_error_set(err, ST_ERR_IO, "%s: read error: %s", path,
						  strerror(errno));
				goto out_close;
			}
			break;
		}
	}
	fclose(f);
	*text = buf;
	*len = n;
	return 0;

out_close:
	fclose(f);
	free(buf);
	return rc;
}
