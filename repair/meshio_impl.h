/*
 * meshio_impl.h - private to repair/meshio*.c, stlio.c and objoff.c: the
 * byte source every reader parses from (a file read in 64 KiB chunks, or a
 * caller's buffer), the bounded line/token reader for the text formats, the
 * number readers, and error helpers that prefix the file name.
 *
 * One code path for files and buffers: a buffer is simply a source whose
 * single window is the whole buffer and that never refills.
 */
#ifndef STRATUM_REPAIR_MESHIO_IMPL_H
#define STRATUM_REPAIR_MESHIO_IMPL_H

#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "mesh.h"
#include "meshio.h"
#include "st_error.h"
#include "st_number.h"

/* File reads go through a window of this many bytes (memory budget). */
#define MIO_CHUNK 65536
/* Longest accepted text line, without its line break, in bytes. */
#define MIO_LINE_MAX 4096
/* Longest accepted number token ("-1.2345678901234567e-305" is 24). */
#define MIO_NUM_MAX ST_NUMBER_MAX

/* A byte source: a file read in chunks or a buffer in memory. */
struct mio_src {
	FILE *f;		  /* NULL when reading from memory */
	const char *name;	  /* for messages */
	const unsigned char *p;	  /* next unread byte of the window */
	const unsigned char *end; /* end of the window */
	unsigned char *chunk;	  /* file mode: MIO_CHUNK bytes */
	uint64_t off;		  /* input offset of p, bytes */
	uint64_t size;		  /* total input size, bytes */
	int read_errno;		  /* errno of a failed read, 0 if none */
	struct st_error *err;	  /* caller's, may be NULL */
};

/* A line/token reader over a source for the text formats. */
struct mio_text {
	struct mio_src *s;
	char line[MIO_LINE_MAX + 2]; /* current line, NUL-terminated */
	size_t len;		     /* its length */
	size_t pos;		     /* tokenizer position in line */
	uint64_t lineno;	     /* 1-based number of the current line */
	bool eof;		     /* no more lines */
};

/* Number reader results. */
enum mio_num {
	MIO_NUM_OK,
	MIO_NUM_BAD,	   /* not a decimal number */
	MIO_NUM_NONFINITE, /* "nan", "inf" or a value that overflows double */
};

/*
 * mio_fill - make sure the window holds unread bytes.  Returns the number
 * available (>0), 0 at end of input, or ST_ERR_IO with s->read_errno set.
 */
long mio_fill(struct mio_src *s);

/* mio_read - copy up to n bytes to dst; returns the count (short at end). */
size_t mio_read(struct mio_src *s, void *dst, size_t n);

/* Report a read error (s->read_errno) at byte off; returns ST_ERR_IO. */
int mio_read_error(struct mio_src *s, uint64_t off);

/*
 * mio_err - fill s->err with "NAME: " + the formatted text and return code.
 * Every message of the readers goes through here so each starts with the
 * file name.
 */
int mio_err(struct mio_src *s, int code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* mio_verr_line - mio_err as "NAME: ENTRY line N: text" (a 3MF entry's
 * line), the text from fmt and ap. */
int mio_verr_line(struct mio_src *s, int code, const char *entry, unsigned long line,
		  const char *fmt, va_list ap) __attribute__((format(printf, 5, 0)));

/* Rewrap a builder error (berr, unprefixed) as "NAME: line N: ..." or byte. */
int mio_builder_error(struct mio_src *s, const char *unit, uint64_t where,
		      const struct st_error *berr);

/* mio_text_init - start reading lines from s (strips a UTF-8 BOM). */
void mio_text_init(struct mio_text *t, struct mio_src *s);

/*
 * mio_next_line - read the next line into t->line (line break and a
 * trailing CR removed).  Returns 1, 0 at end of input, or a negative class
 * with the error filled (line too long, NUL byte, read error).
 */
int mio_next_line(struct mio_text *t);

/*
 * mio_token - next whitespace-separated token of the current line, NUL-
 * terminated in place; NULL when the line has no more.  *len gets its length.
 */
char *mio_token(struct mio_text *t, size_t *len);

/*
 * mio_next_token - like mio_token but reads further lines as needed (for
 * token-stream formats such as ASCII STL).  Returns the token or NULL at end
 * of input; *rc is 0 or the negative class of a line error.
 */
char *mio_next_token(struct mio_text *t, size_t *len, int *rc);

/* Case-insensitive comparison of a token with an ASCII keyword. */
bool mio_keyword(const char *tok, const char *kw);

/*
 * mio_parse_double - read a decimal number: [+-] digits [. digits]
 * [(e|E) [+-] digits], at most MIO_NUM_MAX characters and 5 exponent digits.
 * No hexadecimal, no "nan"/"inf" words (reported as MIO_NUM_NONFINITE).
 */
enum mio_num mio_parse_double(const char *tok, size_t len, double *v);

/* mio_parse_int - [+-] up to 18 digits; false if not such a token. */
bool mio_parse_int(const char *tok, size_t len, long long *v);

/* Printable copy of a token for messages (quoted, shortened, '?' for bytes). */
const char *mio_tokstr(const char *tok, char *buf, size_t cap);

/* The format readers: parse everything from s into *out (NULL on error). */
int stlio_read_binary(struct mio_src *s, struct mesh **out);
int stlio_read_ascii(struct mio_src *s, struct mesh **out);
int objoff_read_obj(struct mio_src *s, struct mesh **out);
int objoff_read_off(struct mio_src *s, struct mesh **out);
/* 3MF (threemf.c): the zip is s's file by name, or s's whole buffer; info may be NULL. */
int threemf_read(struct mio_src *s, struct mesh **out, struct meshio_info *info);

/* threemf_text - the text of the 3MF's entry (a Metadata/ file) or NULL
 * when it has none (meshio_3mf_config, meshio_3mf_layer_profile). */
int threemf_text(struct mio_src *s, const char *entry, char **text);
/* threemf_layer_profile - object's layer height profile and how many objects
 * have one (meshio_3mf_layer_profile; threemf_profile.c);
 * threemf_parse_layer_profile - the same from the entry's text (NULL: none). */
int threemf_parse_layer_profile(struct mio_src *s, const char *text, size_t object, double **zh,
				size_t *pairs, size_t *profiles);
int threemf_layer_profile(struct mio_src *s, size_t object, double **zh, size_t *pairs,
			  size_t *profiles);

/* True if the first window shows a binary STL: size == 84 + 50 * count. */
bool stlio_binary_size_matches(const struct mio_src *s);

/*
 * stlio_binary_size_error - the size-arithmetic failure for a file that should
 * be binary STL ("header says N triangles (needs X bytes) but the file has
 * Y bytes", or too short for the header).  Returns ST_ERR_PARSE.
 */
int stlio_binary_size_error(struct mio_src *s);

/* stlio_write - the STL writer behind meshio_write_stl. */
int stlio_write(const char *path, const struct mesh *m, enum meshio_format fmt,
		struct st_error *err);

#endif /* STRATUM_REPAIR_MESHIO_IMPL_H */
