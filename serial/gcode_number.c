/*
 * gcode_number.c - the G-code number reader, Marlin's line checksum and
 * numbered lines (gcode.h); the line parser (gcode.c) reads its numbers
 * here too.  Every read is checked against the token's end.
 */
#include "gcode.h"
#include "gcode_impl.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Significant digits the number reader keeps exactly (10^15 < 2^53). */
#define NUM_SIG_MAX 15
/* Powers of ten that are exact doubles. */
static const double pow10_exact[] = {
    1e0,  1e1,	1e2,  1e3,  1e4,  1e5,	1e6,  1e7,  1e8,  1e9,	1e10, 1e11,
    1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
};
#define POW10_MAX ((int)(sizeof(pow10_exact) / sizeof(pow10_exact[0])) - 1)

/* Why a number was refused, as the tail of a message. */
const char *gcode_num_reason(enum num_status st)
{
	switch (st) {
	case NUM_TOO_LONG:
		return " (longer than 24 characters)";
	case NUM_TOO_PRECISE:
		return " (more than 15 significant digits or 22 decimals)";
	default:
		return "";
	}
}

/* Convert [+-]digits[.digits] exactly as written; no locale, no exponent. */
enum num_status gcode_scan_number(const char *s, size_t n, double *value)
{
	size_t i = 0, digits = 0;
	uint64_t mant = 0;
	int sig = 0, frac = 0, zeros = 0;
	bool neg = false, dot = false;
	double v;

	if (n > GCODE_NUMBER_MAX)
		return NUM_TOO_LONG;
	if (i < n && (s[i] == '+' || s[i] == '-'))
		neg = s[i++] == '-';
	for (; i < n; i++) {
		char c = s[i];

		if (c == '.') {
			if (dot)
				return NUM_SYNTAX;
			dot = true;
			continue;
		}
		if (c < '0' || c > '9')
			return NUM_SYNTAX;
		digits++;
		if (dot && c == '0') {
			zeros++; /* trailing fraction zeros change nothing */
			continue;
		}
		if (!dot && mant == 0 && c == '0')
			continue; /* leading zero */
		for (; zeros > 0; zeros--) {
			if (mant != 0 && ++sig > NUM_SIG_MAX)
				return NUM_TOO_PRECISE;
			mant *= 10;
			frac++;
		}
		if (++sig > NUM_SIG_MAX)
			return NUM_TOO_PRECISE;
		mant = mant * 10 + (uint64_t)(c - '0');
		if (dot)
			frac++;
	}
	if (digits == 0)
		return NUM_SYNTAX;
	if (frac > POW10_MAX)
		return NUM_TOO_PRECISE;
	/* Both operands are exact doubles, so one division rounds correctly. */
	v = (double)mant / pow10_exact[frac];
	*value = neg ? -v : v;
	return NUM_OK;
}

int gcode_read_number(const char *buf, size_t len, double *value, struct st_error *err)
{
	enum num_status st;
	double v = 0;

	if (!buf || !value)
		return st_error_set(err, ST_ERR_ARG, "gcode_read_number: NULL argument");
	st = gcode_scan_number(buf, len, &v);
	if (st != NUM_OK)
		return st_error_set(err, ST_ERR_PARSE, "'%.*s' is not a number%s",
				    (int)(len < GCODE_QUOTE_MAX ? len : GCODE_QUOTE_MAX), buf,
				    gcode_num_reason(st));
	*value = v;
	return 0;
}

uint8_t gcode_checksum(const char *s, size_t n)
{
	uint8_t cs = 0;

	for (size_t i = 0; i < n; i++)
		cs ^= (uint8_t)s[i];
	return cs;
}

int gcode_format_numbered(char *out, size_t cap, long n, const char *cmd)
{
	char head[16];
	size_t hlen, clen, need;
	uint8_t cs;
	int w;

	if (out && cap > 0)
		out[0] = '\0';
	if (!out || !cmd || n < 0 || n > 2147483647L)
		return ST_ERR_ARG;
	clen = strlen(cmd);
	if (clen == 0 || clen > GCODE_LINE_MAX)
		return ST_ERR_ARG;
	for (size_t i = 0; i < clen; i++) {
		unsigned char c = (unsigned char)cmd[i];

		if ((c < 0x20 && c != '\t') || c == 0x7f || c == ';' || c == '*')
			return ST_ERR_ARG;
	}
	w = snprintf(head, sizeof(head), "N%ld ", n);
	if (w < 0 || (size_t)w >= sizeof(head))
		return ST_ERR_ARG;
	hlen = (size_t)w;
	cs = (uint8_t)(gcode_checksum(head, hlen) ^ gcode_checksum(cmd, clen));
	need = hlen + clen + 1 + (cs >= 100 ? 3 : cs >= 10 ? 2 : 1);
	if (need + 1 > cap)
		return ST_ERR_RANGE;
	memcpy(out, head, hlen);
	memcpy(out + hlen, cmd, clen);
	snprintf(out + hlen + clen, cap - hlen - clen, "*%u", (unsigned)cs);
	return (int)need;
}
