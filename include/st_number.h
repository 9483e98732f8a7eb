/*
 * st_number.h - the one locale-independent decimal reader (docs/architecture.md convention
 * 12), shared by every module that reads numbers from untrusted text: mesh
 * files, printer profiles, G-code.
 *
 * Header-only and libc-only, like st_error.h, so repair/, serial/ and host/
 * may all use it.  The token's grammar is checked here; only a validated,
 * bounded copy reaches strtod, and Stratum never calls setlocale, so the
 * decimal point is always '.'.
 */
#ifndef STRATUM_ST_NUMBER_H
#define STRATUM_ST_NUMBER_H

#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

/* Longest accepted number token, in bytes. */
#define ST_NUMBER_MAX 96

enum st_number {
	ST_NUMBER_OK,
	ST_NUMBER_BAD,	     /* not [+-]digits[.digits] (or .digits), or too long */
	ST_NUMBER_NONFINITE, /* grammatical but overflows a double */
};

/* Accept an exponent "e[+-]ddd" (at most 5 digits): STL exporters write
 * them; G-code and profiles do not. */
#define ST_NUMBER_EXPONENT 1u

static inline bool st_is_digit(char c)
{
	return c >= '0' && c <= '9';
}

/*
 * st_parse_double - read s[0..len) as one decimal number into *out.  The
 * whole token must match; no leading or trailing blanks, no hex, no
 * "nan"/"inf".  *out is written only on ST_NUMBER_OK.
 */
static inline enum st_number st_parse_double(const char *s, size_t len, unsigned flags,
					     double *out)
{
	char buf[ST_NUMBER_MAX + 1];
	size_t i = 0, digits = 0;
	char *end;
	double v;

	if (len == 0 || len > ST_NUMBER_MAX)
		return ST_NUMBER_BAD;
	if (s[i] == '+' || s[i] == '-')
		i++;
	for (; i < len && st_is_digit(s[i]); i++)
		digits++;
	if (i < len && s[i] == '.')
		for (i++; i < len && st_is_digit(s[i]); i++)
			digits++;
	if (digits == 0)
		return ST_NUMBER_BAD;
	if ((flags & ST_NUMBER_EXPONENT) && i < len && (s[i] == 'e' || s[i] == 'E')) {
		size_t exp_digits = 0;

		i++;
		if (i < len && (s[i] == '+' || s[i] == '-'))
			i++;
		for (; i < len && st_is_digit(s[i]); i++)
			exp_digits++;
		/* Bounded: "1e+308" fits, "1e0000000000001" does not. */
		if (exp_digits == 0 || exp_digits > 5)
			return ST_NUMBER_BAD;
	}
	if (i != len)
		return ST_NUMBER_BAD;
	memcpy(buf, s, len);
	buf[len] = '\0';
	v = strtod(buf, &end);
	if (end != buf + len)
		return ST_NUMBER_BAD;
	if (!isfinite(v))
		return ST_NUMBER_NONFINITE;
	*out = v;
	return ST_NUMBER_OK;
}

/*
 * st_parse_duration - a slicer's "1d 2h 3m 4s" (any of the parts, in that
 * form: "; estimated printing time = 45m 38s") in seconds, up to the end
 * of s or a newline; -1 when s is not one.
 */
static inline double st_parse_duration(const char *s)
{
	double total = 0, v;
	bool any = false;

	while (*s == ' ')
		s++;
	while (*s && *s != '\n') {
		size_t n = strspn(s, "0123456789");

		if (!n || st_parse_double(s, n, 0, &v) != ST_NUMBER_OK)
			return -1;
		s += n;
		switch (*s++) {
		case 'd': total += v * 86400; break;
		case 'h': total += v * 3600; break;
		case 'm': total += v * 60; break;
		case 's': total += v; break;
		default: return -1;
		}
		any = true;
		while (*s == ' ')
			s++;
	}
	return any ? total : -1;
}

#endif /* STRATUM_ST_NUMBER_H */
