/*
 * st_append.h - the one way to build a message in a fixed buffer piece by
 * piece (lists joined with ", ", fields one after another), header-only
 * like st_error.h: each piece is appended after the text already there and
 * cut where the buffer ends, so no caller counts lengths by hand.
 */
#ifndef STRATUM_ST_APPEND_H
#define STRATUM_ST_APPEND_H

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/*
 * st_appendf - append printf text to the NUL-terminated text in buf (cap
 * bytes), truncating quietly; a full buffer stays as it is.
 */
static inline void st_appendf(char *buf, size_t cap, const char *fmt, ...)
	__attribute__((format(printf, 3, 4)));

static inline void st_appendf(char *buf, size_t cap, const char *fmt, ...)
{
	size_t len = strnlen(buf, cap);
	va_list ap;

	if (len + 1 >= cap)
		return;
	va_start(ap, fmt);
	vsnprintf(buf + len, cap - len, fmt, ap);
	va_end(ap);
}

#endif /* STRATUM_ST_APPEND_H */
