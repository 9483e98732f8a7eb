/*
 * meshio_src.c - the byte source, bounded line and token reader, number
 * readers and error helpers shared by the mesh readers (meshio_impl.h).
 *
 * Numbers: the token grammar is validated here, then the token is copied to
 * a bounded local buffer and converted with strtod.  strtod is correctly
 * rounded (so ASCII STL written with %.17g round-trips exactly) but reads
 * the decimal point of the current locale; Stratum never calls setlocale, so
 * the "C" locale holds.  Should a future caller change LC_NUMERIC, strtod
 * would stop at the '.', the full-consumption check below fails and the
 * token is reported as malformed: never a silently different value.
 */
#include "meshio_impl.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

long mio_fill(struct mio_src *s)
{
	size_t n;

	if (s->p < s->end)
		return (long)(s->end - s->p);
	if (!s->f)
		return 0;
	errno = 0;
	n = fread(s->chunk, 1, MIO_CHUNK, s->f);
	if (n == 0) {
		if (ferror(s->f)) {
			s->read_errno = errno ? errno : EIO;
			return ST_ERR_IO;
		}
		return 0;
	}
	s->p = s->chunk;
	s->end = s->chunk + n;
	return (long)n;
}

size_t mio_read(struct mio_src *s, void *dst, size_t n)
{
	unsigned char *d = dst;
	size_t done = 0;

	while (done < n) {
		long avail = mio_fill(s);
		size_t k;

		if (avail <= 0)
			break;
		k = (size_t)avail < n - done ? (size_t)avail : n - done;
		memcpy(d + done, s->p, k);
		s->p += k;
		s->off += k;
		done += k;
	}
	return done;
}

int mio_err(struct mio_src *s, int code, const char *fmt, ...)
{
	char text[256];
	va_list ap;

	va_start(ap, fmt);
	vsnprintf(text, sizeof(text), fmt, ap);
	va_end(ap);
	return st_error_set(s->err, code, "%s: %s", s->name, text);
}

int mio_verr_line(struct mio_src *s, int code, const char *entry, unsigned long line,
		  const char *fmt, va_list ap)
{
	char text[256];

	vsnprintf(text, sizeof(text), fmt, ap);
	return mio_err(s, code, "%s line %lu: %s", entry, line, text);
}

int mio_read_error(struct mio_src *s, uint64_t off)
{
	return mio_err(s, ST_ERR_IO, "byte %llu: read error: %s", (unsigned long long)off,
		       strerror(s->read_errno ? s->read_errno : EIO));
}

int mio_builder_error(struct mio_src *s, const char *unit, uint64_t where,
		      const struct st_error *berr)
{
	return mio_err(s, berr->code, "%s %llu: %s", unit, (unsigned long long)where, berr->msg);
}

void mio_text_init(struct mio_text *t, struct mio_src *s)
{
	memset(t, 0, sizeof(*t));
	t->s = s;
}

int mio_next_line(struct mio_text *t)
{
	struct mio_src *s = t->s;
	size_t len = 0;
	bool got = false;

	t->len = 0;
	t->pos = 0;
	t->line[0] = '\0';
	if (t->eof)
		return 0;
	for (;;) {
		long avail = mio_fill(s);
		const unsigned char *nl;
		size_t k;

		if (avail < 0)
			return mio_read_error(s, s->off);
		if (avail == 0)
			break;
		if (!got) {
			got = true;
			t->lineno++;
		}
		nl = memchr(s->p, '\n', (size_t)avail);
		k = nl ? (size_t)(nl - s->p) : (size_t)avail;
		/* One byte of slack for a CR before the LF. */
		if (len + k > MIO_LINE_MAX + 1)
			return mio_err(
			    s, ST_ERR_PARSE,
			    "line %llu is longer than %d bytes; is this a text mesh file?",
			    (unsigned long long)t->lineno, MIO_LINE_MAX);
		memcpy(t->line + len, s->p, k);
		len += k;
		k += nl ? 1 : 0;
		s->p += k;
		s->off += k;
		if (nl)
			break;
	}
	if (!got) {
		t->eof = true;
		return 0;
	}
	if (len && t->line[len - 1] == '\r')
		len--;
	if (len > MIO_LINE_MAX)
		return mio_err(s, ST_ERR_PARSE,
			       "line %llu is longer than %d bytes; is this a text mesh file?",
			       (unsigned long long)t->lineno, MIO_LINE_MAX);
	if (memchr(t->line, '\0', len))
		return mio_err(s, ST_ERR_PARSE,
			       "line %llu: unexpected NUL byte (binary data in a text mesh file)",
			       (unsigned long long)t->lineno);
	/* A UTF-8 byte order mark some editors put in front of text. */
	if (t->lineno == 1 && len >= 3 && !memcmp(t->line, "\xef\xbb\xbf", 3)) {
		memmove(t->line, t->line + 3, len - 3);
		len -= 3;
	}
	t->line[len] = '\0';
	t->len = len;
	return 1;
}

/* Token separators within a line (the line break is already gone). */
static bool is_space(char c)
{
	return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
}

char *mio_token(struct mio_text *t, size_t *len)
{
	size_t start;

	while (t->pos < t->len && is_space(t->line[t->pos]))
		t->pos++;
	if (t->pos >= t->len)
		return NULL;
	start = t->pos;
	while (t->pos < t->len && !is_space(t->line[t->pos]))
		t->pos++;
	*len = t->pos - start;
	if (t->pos < t->len)
		t->line[t->pos++] = '\0';
	return t->line + start;
}

char *mio_next_token(struct mio_text *t, size_t *len, int *rc)
{
	*rc = 0;
	for (;;) {
		char *tok = mio_token(t, len);
		int r;

		if (tok)
			return tok;
		r = mio_next_line(t);
		if (r <= 0) {
			*rc = r;
			return NULL;
		}
	}
}

/* tolower for ASCII only, so the locale never matters. */
static char ascii_lower(char c)
{
	return c >= 'A' && c <= 'Z' ? (char)(c - 'A' + 'a') : c;
}

/* Case-insensitive ASCII prefix test, independent of the locale. */
static bool prefix_ci(const char *s, size_t len, const char *pre)
{
	size_t n = strlen(pre);

	if (len < n)
		return false;
	for (size_t i = 0; i < n; i++)
		if (ascii_lower(s[i]) != ascii_lower(pre[i]))
			return false;
	return true;
}

bool mio_keyword(const char *tok, const char *kw)
{
	size_t n = strlen(tok);

	return n == strlen(kw) && prefix_ci(tok, n, kw);
}

/* isdigit without the locale. */
static bool is_digit(char c)
{
	return c >= '0' && c <= '9';
}

/*
 * The spellings printf implementations use for NaN and infinity: "nan",
 * "nan(...)", "inf", "infinity" and MSVC's "1.#INF", "1.#QNAN", "-1.#IND".
 */
static bool nonfinite_word(const char *tok, size_t len)
{
	if (len && (tok[0] == '+' || tok[0] == '-')) {
		tok++;
		len--;
	}
	if ((len == 3 && (prefix_ci(tok, len, "nan") || prefix_ci(tok, len, "inf"))) ||
	    (len == 8 && prefix_ci(tok, len, "infinity")))
		return true;
	if (len > 4 && prefix_ci(tok, len, "nan(") && tok[len - 1] == ')')
		return true;
	return prefix_ci(tok, len, "1.#inf") || prefix_ci(tok, len, "1.#ind") ||
	       prefix_ci(tok, len, "1.#qnan") || prefix_ci(tok, len, "1.#snan");
}

enum mio_num mio_parse_double(const char *tok, size_t len, double *v)
{
	if (nonfinite_word(tok, len))
		return MIO_NUM_NONFINITE;
	switch (st_parse_double(tok, len, ST_NUMBER_EXPONENT, v)) {
	case ST_NUMBER_OK:
		return MIO_NUM_OK;
	case ST_NUMBER_NONFINITE:
		return MIO_NUM_NONFINITE;
	default:
		return MIO_NUM_BAD;
	}
}

bool mio_parse_int(const char *tok, size_t len, long long *v)
{
	size_t i = 0;
	bool neg = false;
	long long x = 0;

	if (len && (tok[0] == '+' || tok[0] == '-')) {
		neg = tok[0] == '-';
		i++;
	}
	if (i == len || len - i > 18)
		return false;
	for (; i < len; i++) {
		if (!is_digit(tok[i]))
			return false;
		x = x * 10 + (tok[i] - '0');
	}
	*v = neg ? -x : x;
	return true;
}

const char *mio_tokstr(const char *tok, char *buf, size_t cap)
{
	const size_t show = 24;
	size_t n = strlen(tok), o = 0;

	if (cap < show + 6)
		return "?";
	buf[o++] = '\'';
	for (size_t i = 0; i < n && i < show; i++) {
		unsigned char c = (unsigned char)tok[i];
		buf[o++] = c >= 0x20 && c < 0x7f ? (char)c : '?';
	}
	if (n > show) {
		memcpy(buf + o, "...", 3);
		o += 3;
	}
	buf[o++] = '\'';
	buf[o] = '\0';
	return buf;
}

/* Here, not in meshio.c, so the readers and the writer (stlio.c) can name a
 * format without depending on the format dispatch that calls them. */
const char *meshio_format_name(enum meshio_format fmt)
{
	switch (fmt) {
	case MESHIO_AUTO:
		return "auto-detected";
	case MESHIO_STL_BINARY:
		return "binary STL";
	case MESHIO_STL_ASCII:
		return "ASCII STL";
	case MESHIO_OBJ:
		return "OBJ";
	case MESHIO_OFF:
		return "OFF";
	case MESHIO_3MF:
		return "3MF";
	}
	return "unknown format";
}
