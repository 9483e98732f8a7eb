/*
 * gcode.h - the one G-code parser of Stratum (docs/architecture.md item 5), shared by
 * the sender, the X3G translator, the estimator and the simulated printers.
 *
 * A line is read from (buf, len) with no NUL required.  It is checked as a
 * whole before anything is returned: a rejected line leaves the output
 * struct untouched (STYLE rule 6), and a line that is too long is rejected,
 * never cut.  The syntax accepted follows Marlin's reader
 * (Marlin/src/gcode/queue.cpp, parser.cpp):
 *
 *   [N<line>] <command> [<words>] [*<checksum>] [;<comment>]
 *
 * - command: G<n>, M<n> or T<n> (letters in either case; G and M may carry
 *   a subcode, G29.1), the Prusa MMU tool commands T?, Tx and Tc, or an
 *   OctoPrint-style host command "@name args";
 * - a line whose first token is not such a command but starts with a letter
 *   or '_' (Klipper's extended commands and macros, "START_PRINT
 *   EXTRUDER=215", "BED_MESH_CALIBRATE", a bare "T", a text "Start ...")
 *   is a text command (letter GCODE_LETTER_TEXT): the rest of the line, as
 *   written, up to ';' or the checksum, is its text.  Marlin's parser marks
 *   such a line '?' and answers it with echo:Unknown command: "..." and ok;
 *   Klipper runs it.  It has no words, so nothing reads a move from it;
 * - words: a letter A-Z, then optionally a number; "G28 X" gives a word
 *   with no value.  Spaces between words are optional (G1X10Y-2.5);
 * - numbers: [+-]digits[.digits] or [+-].digits, at most 15 significant
 *   digits; no exponent, hexadecimal, NaN or infinity.  "X1E3" is read as the
 *   two words X1 and E3, exactly as Marlin and grbl read it;
 * - ';' starts a comment that runs to the end of the line, everywhere,
 *   M117 included (Marlin does the same); "( ... )" comments are removed
 *   anywhere except inside a text;
 * - the checksum is the XOR of every byte from the first non-blank byte of
 *   the line up to the '*', written in decimal (docs/protocols.md section 1);
 * - string-argument commands (M23, M28, M30, M32, M117, M118, M928,
 *   Prusa's M862.x print checks and '@' host commands) keep the rest of the
 *   line, up to ';' or the checksum, as one text;
 * - any other M command may end in text, as Marlin reads it: the first
 *   blank-separated token that is not a word (a bare letter run into more
 *   letters as in "M0 Click to continue", a value that is not a number as
 *   in "M115 U3.11.0", a letter given twice, a quote, a non-ASCII byte)
 *   starts a text that runs, as written, to ';' or the checksum.  The
 *   exceptions are the M commands whose numbers heat, move or set how the
 *   machine moves (temperatures, fans, M82/M83, M92, M200-M209, M220/M221,
 *   M851, M900 ...), which like every G and T command take words only: a
 *   word there that is not a number is refused, never passed on for the
 *   firmware to read a prefix of;
 * - a text may hold any byte except control bytes, UTF-8 included, but no
 *   '*' (Marlin's parser ends a command at its first '*', so the text would
 *   be cut); the command part outside texts is ASCII.  Control bytes are
 *   refused everywhere except tab, comments included: they break the
 *   line protocol (NUL ends a line early, 0x08 erases a byte in Marlin).
 *   See docs/errors.md "G-code input" for every refusal and its reason.
 *
 * Nothing here allocates except gcode_reader_new; nothing is global.  All
 * functions are thread-safe on distinct objects.
 */
#ifndef STRATUM_SERIAL_GCODE_H
#define STRATUM_SERIAL_GCODE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "st_error.h"

/* Longest command text accepted, comments, line number and checksum removed
 * (bytes).  Marlin's own limit (MAX_CMD_SIZE = 96 for the whole numbered
 * line) is the Marlin driver's business, not the parser's. */
#define GCODE_LINE_MAX 256
/* Longest raw line accepted, comments included (bytes, line ending
 * excluded).  Slicers write long configuration comments. */
#define GCODE_RAW_MAX 65536
/* Comment text kept in struct gcode_line (bytes); longer comments are
 * kept in part and flagged, since comments are never sent. */
#define GCODE_COMMENT_MAX 255
/* At most one word per letter, so 26 words. */
#define GCODE_WORDS_MAX 26
/* Longest number token, sign and point included (characters). */
#define GCODE_NUMBER_MAX 24

/* struct gcode_line.letter of a text command (Marlin's own mark for a line
 * without a command letter). */
#define GCODE_LETTER_TEXT '?'

/* What a line does, as far as a host needs to know. */
enum gcode_kind {
	GCODE_KIND_OTHER = 0,	 /* any other command: forward it */
	GCODE_KIND_HOST_ONLY,	 /* empty, comment-only or '@' host command: never send */
	GCODE_KIND_MOTION,	 /* G0 G1 G2 G3 G5 */
	GCODE_KIND_DWELL,	 /* G4 */
	GCODE_KIND_HOME,	 /* G28 */
	GCODE_KIND_PROBE,	 /* G29-G35, G38, G80, M48: probing and levelling */
	GCODE_KIND_SET_POSITION, /* G92 */
	GCODE_KIND_MODE,	 /* G20 G21 G90 G91 M82 M83: units and positioning */
	GCODE_KIND_TEMP_SET,	 /* M104 M140 M141 */
	GCODE_KIND_TEMP_WAIT,	 /* M109 M190 M191 M116 */
	GCODE_KIND_FAN,		 /* M106 M107 */
	GCODE_KIND_TOOL_CHANGE,	 /* T<n>, M6 */
	GCODE_KIND_FINISH_MOVES, /* M400 */
	GCODE_KIND_USER_WAIT,	 /* M0 M1 M226 M600: waits for a person or a pin */
	GCODE_KIND_EMERGENCY,	 /* M108 M112 M410 M524 M876: Marlin's emergency parser */
	GCODE_KIND_LINE_NUMBER,	 /* M110: protocol command */
	GCODE_KIND_REPORT,	 /* M105 M114 M115 M119 M155 */
	GCODE_KIND_MESSAGE,	 /* M73 M117 M118 */
	GCODE_KIND_TEXT_COMMAND, /* not G/M/T: a Klipper macro, text; forward as written */
	GCODE_KIND_COUNT_
};

/* One parameter word. */
struct gcode_word {
	char letter;	 /* 'A'-'Z', upper case */
	bool has_value;	 /* false for a bare letter such as the X of "G28 X" */
	double value;	 /* 0 when !has_value */
	uint32_t column; /* where the letter is in the raw line, from 1 (bytes) */
};

/* A parsed line.  Plain value type: copy it freely. */
struct gcode_line {
	char letter; /* 'G', 'M', 'T', '@' (host command), GCODE_LETTER_TEXT
		      * (text command) or 0 (no command) */
	int number;  /* command number, -1 if letter is 0 or '@', and for the
		      * Prusa MMU tool commands T?, Tx and Tc (the '?', 'x' or
		      * 'c' is then the string) */
	int subcode; /* digits after '.', G29.1 -> 1; -1 if none */
	enum gcode_kind kind;

	size_t nwords; /* words in order of appearance, letters all distinct */
	struct gcode_word words[GCODE_WORDS_MAX];

	bool has_line_number;
	long line_number; /* N<n> before the command, 0-2147483647 */

	bool has_checksum;
	uint8_t checksum;	   /* as written after '*' */
	uint8_t checksum_computed; /* XOR from the first non-blank byte to '*' */
	bool checksum_ok;	   /* false only with GCODE_PARSE_KEEP_BAD_CHECKSUM */

	/* Cleaned command: upper-case command and words separated by single
	 * spaces, numbers as written, then the text if any, as written; no line
	 * number, checksum or comment.  Empty for comment-only lines.  Ready for
	 * gcode_format_numbered. */
	char text[GCODE_LINE_MAX + 1];
	size_t text_len;
	/* For string-argument commands and commands that end in text: text +
	 * string_off is the text as written (may be empty for the former);
	 * string_off == text_len for all other lines. */
	size_t string_off;
	bool has_string;

	/* The first ';' comment, without the ';' and trailing blanks. */
	bool has_comment;
	bool comment_truncated; /* longer than GCODE_COMMENT_MAX, kept in part */
	char comment[GCODE_COMMENT_MAX + 1];
	size_t comment_len;
	/* Text of all "( ... )" comments, joined by single spaces. */
	bool has_paren;
	bool paren_truncated;
	char paren[GCODE_COMMENT_MAX + 1];
	size_t paren_len;
};

/* gcode_parse flags. */
enum {
	/* Accept a line whose checksum does not match, with checksum_ok false,
	 * instead of failing: for simulated firmware, which must answer the
	 * way Marlin does, and for diagnostics. */
	GCODE_PARSE_KEEP_BAD_CHECKSUM = 1u << 0,
};

/*
 * gcode_parse - check and parse one line.
 * @buf, @len: the line; it may end in "\n", "\r\n" or "\r", or in nothing.
 *             Any other CR or LF inside is an error.  No NUL is needed.
 * @flags:     0 or GCODE_PARSE_KEEP_BAD_CHECKSUM.
 * @out:       filled on success only.
 * @err:       may be NULL; on failure filled with ST_ERR_PARSE (or ST_ERR_ARG
 *             for a NULL buf with len > 0 or a NULL out) and a message
 *             naming the column (from 1, in bytes) and what was wrong; see
 *             docs/errors.md "G-code input".
 * Returns 0 or a negative ST_ERR_* class.
 */
int gcode_parse(const char *buf, size_t len, unsigned flags, struct gcode_line *out,
		struct st_error *err);

/*
 * gcode_read_number - the locale-independent number reader, on its own.
 * The whole of (buf, len) must be one number: [+-]digits[.digits] or
 * [+-].digits, at most GCODE_NUMBER_MAX characters and 15 significant digits.
 * The value is correctly rounded.  Returns 0 and sets *value, or
 * ST_ERR_PARSE (then *value is unchanged) with a message in err (may be NULL).
 */
int gcode_read_number(const char *buf, size_t len, double *value, struct st_error *err);

/* gcode_checksum - XOR of the n bytes at s (Marlin's line checksum). */
uint8_t gcode_checksum(const char *s, size_t n);

/*
 * gcode_format_numbered - write "N<n> <cmd>*<cs>" and a NUL into out, where
 * <cs> is gcode_checksum of "N<n> <cmd>", as Marlin expects.
 * @n:   0-2147483647.
 * @cmd: a cleaned command (struct gcode_line.text): non-empty, no control
 *       byte but tab, no ';' or '*' (bytes 0x80-0xff are allowed: UTF-8
 *       texts).  No line ending is added.
 * Returns the length written (> 0, NUL excluded), ST_ERR_ARG for a bad n or
 * cmd, or ST_ERR_RANGE if out (cap bytes) is too small; out is then "" when
 * cap > 0.
 */
int gcode_format_numbered(char *out, size_t cap, long n, const char *cmd);

/* gcode_kind_name - stable lower-case name of a kind ("motion", "temp_wait"
 * ...) for logs and --json; "unknown" for values out of range. */
const char *gcode_kind_name(enum gcode_kind kind);

/* gcode_is_blocking - true for kinds whose "ok" may take long (G4, G28,
 * probing, M109/M190/M191/M116, M400, M0/M1/M600, and text commands, since
 * a Klipper macro such as START_PRINT heats, homes and probes), so a driver
 * extends its time-out instead of resending. */
bool gcode_is_blocking(enum gcode_kind kind);

/* gcode_find_word - the word with this letter (either case), or NULL. */
const struct gcode_word *gcode_find_word(const struct gcode_line *line, char letter);

/* gcode_word_value - true and *value set if the letter is present with a
 * value; false (value untouched) otherwise. */
bool gcode_word_value(const struct gcode_line *line, char letter, double *value);

/* What a slicer comment says about layers. */
enum gcode_layer_mark {
	GCODE_LAYER_NONE = 0,
	/* A new layer starts: Cura ";LAYER:<n>" (layer = n, may be negative
	 * for raft layers), PrusaSlicer/SuperSlicer/OrcaSlicer ";LAYER_CHANGE"
	 * (layer = -1), Simplify3D/Slic3r "; layer <n>, Z = <z>". */
	GCODE_LAYER_START,
	/* The Z of the layer just started, PrusaSlicer ";Z:<z>" (the line after
	 * ";LAYER_CHANGE"): not a new layer, so counting STARTs counts layers. */
	GCODE_LAYER_Z,
};

/*
 * gcode_layer_comment - recognise the layer comments of common slicers.
 * Only comment-only lines count.  On GCODE_LAYER_START or GCODE_LAYER_Z sets
 * *layer (-1 if the comment has no number) and *z (NAN if it has no height);
 * either pointer may be NULL.  On GCODE_LAYER_NONE they are unchanged.
 */
enum gcode_layer_mark gcode_layer_comment(const struct gcode_line *line, long *layer, double *z);

/*
 * gcode_layer_follow - keep a streamer's running layer and Z up to date:
 * a layer comment with a number sets *layer, one without counts it on, a
 * height sets *z.  Returns true when line starts a layer.
 */
bool gcode_layer_follow(const struct gcode_line *line, long *layer, double *z);

/*
 * gcode_reader - streaming reader over a FILE*, for `stratum send` and the
 * X3G translator.  Bounded memory (about 2 x GCODE_RAW_MAX bytes).  Lines may
 * end in "\n", "\r\n" or "\r", mixed; the last line needs no ending.
 */
struct gcode_reader;

/*
 * gcode_reader_new - a reader over fp, which stays the caller's (not closed
 * by gcode_reader_free).  @name is used in messages ("FILE: line N: ...")
 * and copied; NULL means "<input>".  Returns 0 or ST_ERR_ARG/ST_ERR_NOMEM;
 * *out is NULL on error.
 */
int gcode_reader_new(FILE *fp, const char *name, struct gcode_reader **out, struct st_error *err);

/* gcode_reader_free - free the reader; NULL is allowed. */
void gcode_reader_free(struct gcode_reader *r);

/*
 * gcode_reader_next - read and parse the next line (flags as gcode_parse).
 * Returns 1 with *line filled, 0 at the end of input, or a negative class
 * with err filled as "NAME: line N: ..." (N from 1).  After ST_ERR_PARSE the
 * reader is at the start of the following line, so a caller may go on;
 * after ST_ERR_IO every further call fails the same way.
 */
int gcode_reader_next(struct gcode_reader *r, unsigned flags, struct gcode_line *line,
		      struct st_error *err);

/* gcode_reader_line - file line number (from 1) of the line last returned
 * or rejected; 0 before the first call. */
uint64_t gcode_reader_line(const struct gcode_reader *r);

/* gcode_reader_bytes - bytes consumed so far, line endings included. */
uint64_t gcode_reader_bytes(const struct gcode_reader *r);

#endif /* STRATUM_SERIAL_GCODE_H */
