/*
 * st_error.h - the one project-wide error type and exit-code table.
 *
 * Header-only and libc-only so that every module (repair, slicer, serial,
 * host) may include it without depending on one another.  Library code fills
 * a caller-supplied struct st_error and returns a negative class; only host/
 * prints messages and chooses the process exit status.
 */
#ifndef STRATUM_ST_ERROR_H
#define STRATUM_ST_ERROR_H

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* Return classes: 0 = OK, negative = error class, positive = counts. */
enum st_status {
	ST_OK = 0,
	ST_ERR_ARG = -1,	 /* caller passed something invalid */
	ST_ERR_IO = -2,		 /* the OS refused: open, read, write, rename */
	ST_ERR_PARSE = -3,	 /* input data malformed (bad STL, bad .ini) */
	ST_ERR_RANGE = -4,	 /* value outside its allowed range */
	ST_ERR_NOMEM = -5,	 /* allocation failed or size overflowed */
	ST_ERR_UNSUPPORTED = -6, /* valid but not something we handle */
	ST_ERR_INTERNAL = -7,	 /* a bug or a library exception */
};

/* Process exit statuses (docs/architecture.md "Errors, exit codes, output"). */
enum st_exit {
	ST_EXIT_OK = 0,
	ST_EXIT_FAILURE = 1,	/* the job ran but its answer is "no" */
	ST_EXIT_USAGE = 2,
	ST_EXIT_DATAERR = 65,	/* bad input data */
	ST_EXIT_UNAVAILABLE = 69, /* printer unavailable */
	ST_EXIT_SOFTWARE = 70,	/* internal error */
	ST_EXIT_INTERRUPTED = 130,
};

/*
 * Filled by library code on failure.  msg is one complete sentence that
 * names what failed and where (file, byte offset or line), so host/ can
 * print it unchanged.  code is the enum st_status class.
 */
struct st_error {
	int code;
	char msg[256];
};

/*
 * Set err (if not NULL) to code and a printf-style message; returns code.
 * The arguments may include err->msg itself (wrapping the cause in context):
 * the text is formatted aside first, as vsnprintf into the buffer it reads
 * from is undefined and garbles the message.
 */
static inline int st_error_set(struct st_error *err, int code, const char *fmt, ...)
	__attribute__((format(printf, 3, 4)));

static inline int st_error_set(struct st_error *err, int code, const char *fmt, ...)
{
	if (err) {
		char text[sizeof(err->msg)];
		va_list ap;
		va_start(ap, fmt);
		vsnprintf(text, sizeof(text), fmt, ap);
		va_end(ap);
		err->code = code;
		memcpy(err->msg, text, sizeof(text));
	}
	return code;
}

/* Map a library error class to the exit status the CLI should use. */
static inline int st_exit_for(int code)
{
	switch (code) {
	case ST_OK:
		return ST_EXIT_OK;
	case ST_ERR_PARSE:
	case ST_ERR_RANGE:
	case ST_ERR_UNSUPPORTED:
		return ST_EXIT_DATAERR;
	case ST_ERR_ARG:
		return ST_EXIT_USAGE;
	case ST_ERR_IO:
		return ST_EXIT_DATAERR;
	default:
		return ST_EXIT_SOFTWARE;
	}
}

#endif /* STRATUM_ST_ERROR_H */
