/*
 * ini.h - the one reader of Stratum's `key = value` files: printer profiles
 * (profile.h, flat, PrusaSlicer's syntax) and the farm node's configuration
 * (host/serve/, with [sections]).  Both therefore agree on every quirk:
 *
 *   - a UTF-8 byte order mark at the start is skipped;
 *   - lines end in LF or CRLF; a line longer than INI_LINE_MAX bytes is
 *     rejected, never cut; a NUL byte anywhere in a line is rejected; a
 *     file larger than INI_FILE_MAX is refused;
 *   - blanks (space, tab) around keys and values are dropped;
 *   - a line starting with '#' or ';' is a comment;
 *   - after a value, a '#' or ';' that follows a blank starts a comment
 *     (ini_comment_at) where the caller asks for it: on every line with
 *     inline_comments (the node's configuration), or in the values of the
 *     keys it knows are not text (profiles: numbers, lists, choices; see
 *     profile_check.c).  Profiles keep it in text values: their G-code
 *     holds ' ;' and ' #' (PrusaSlicer's own bundles have start_gcode = ;
 *     # # # START Header...) and cutting there would drop G-code silently.
 *     A '#' or ';' that does not follow a blank (API keys, URLs, colours,
 *     "a";"b" lists) is always part of the value;
 *   - a line starting with '[' is a section line, handed to the caller;
 *   - every other line is KEY = VALUE, KEY of letters, digits and '_'; the
 *     value is everything after the first '=' (may be empty).
 *
 * The reader does not decode escapes or look for duplicate keys: what a
 * value means and where it may appear is the caller's business.
 *
 * Errors: "ORIGIN: line N: ..." in the caller's struct st_error, class
 * ST_ERR_PARSE for syntax, or whatever a callback returns.
 * Thread safety: no state outside the arguments.
 */
#ifndef STRATUM_HOST_INI_H
#define STRATUM_HOST_INI_H

#include <stdbool.h>
#include <stddef.h>

#include "st_error.h"

#define INI_LINE_MAX 65536u		  /* bytes per line, line end excluded */
#define INI_FILE_MAX (16u * 1024 * 1024) /* these files are a few KiB; refuse absurd ones */

/* One KEY = VALUE line, trimmed; the pointers are into the caller's text. */
struct ini_entry {
	int line; /* from 1 */
	const char *key, *value;
	size_t key_len, value_len;
};

/* What the caller does with each line; a non-zero return stops the read. */
struct ini_handler {
	/* @text, @len: the whole trimmed line, '[' included.  NULL: section
	 * lines are refused as "sections are not supported". */
	int (*section)(void *ctx, int line, const char *text, size_t len, struct st_error *err);
	int (*entry)(void *ctx, const struct ini_entry *e, struct st_error *err);
	/* true: a '#' or ';' after a blank ends the line (section and key
	 * lines); so "key = #x" has an empty value. */
	bool inline_comments;
	/* true: a key line whose key is not letters, digits and '_' is
	 * skipped (PrusaSlicer's own configs and bundles: its reader skips
	 * keys it does not know, such as "top solid_infill_speed" in Prusa's
	 * 2.5.5 bundle, a setting of neither tool); false: refused.  An
	 * empty key is refused either way. */
	bool skip_bad_keys;
};

/*
 * ini_parse - read text[0..len) line by line and call h for each section
 * and key line.
 * @origin: the file name for messages.  Returns 0, ST_ERR_PARSE (err set),
 * or the first non-zero callback return.
 */
int ini_parse(const char *text, size_t len, const char *origin, const struct ini_handler *h,
	      void *ctx, struct st_error *err);

/*
 * ini_read_file - the whole file into a new buffer (free with free()).
 * A file larger than INI_FILE_MAX is refused (ST_ERR_PARSE, "larger than
 * N KiB").  Returns 0, ST_ERR_IO (cannot open or read, or a directory),
 * ST_ERR_PARSE or ST_ERR_NOMEM; *text is NULL on error.
 */
int ini_read_file(const char *path, char **text, size_t *len, struct st_error *err);

/*
 * ini_comment_at - where an inline comment starts in s[0..len): the first
 * '#' or ';' after a blank (not at 0), else len.  Blanks before it are the
 * caller's to trim.
 */
size_t ini_comment_at(const char *s, size_t len);

/*
 * ini_show - copy at most 40 bytes of s[0..len) into buf for a message,
 * line breaks and NULs as blanks, "..." when cut.
 */
void ini_show(char *buf, size_t cap, const char *s, size_t len);

#define INI_SHOW_MAX 44 /* buffer size for ini_show */

#endif /* STRATUM_HOST_INI_H */
