/*
 * gcode.c - G-code line parser (the number reader and checksums are in
 * gcode_number.c, the command tables in gcode_kind.c, the streaming reader
 * and the layer comments in gcode_reader.c).  See
 * gcode.h for the accepted syntax; every read below is checked against the
 * line's end.
 */
#include "gcode.h"
#include "gcode_impl.h"

#include <stdlib.h>
#include <string.h>

/* ---- the line parser ---- */

struct parser {
	const char *buf;
	size_t len; /* line ending removed */
	size_t pos;
	struct gcode_line *l;
	struct st_error *err;
};

static bool is_blank(char c)
{
	return c == ' ' || c == '\t';
}

static bool is_alpha(char c)
{
	return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z');
}

static bool is_digit(char c)
{
	return c >= '0' && c <= '9';
}

static char upper(char c)
{
	return (c >= 'a' && c <= 'z') ? (char)(c - 'a' + 'A') : c;
}

/* End of the token that starts at pos, for quoting it in a message. */
static size_t token_end(const struct parser *p, size_t pos)
{
	size_t e = pos;

	while (e < p->len && e - pos < GCODE_QUOTE_MAX && !is_blank(p->buf[e]) &&
	       p->buf[e] != ';' && p->buf[e] != '(' && p->buf[e] != '*' &&
	       (unsigned char)p->buf[e] >= 0x20 && (unsigned char)p->buf[e] < 0x7f)
		e++;
	return e;
}

/* Fail with "column C: 'TOKEN' <what>", quoting the token at pos. */
static int fail_token(const struct parser *p, size_t pos, const char *what)
{
	size_t e = token_end(p, pos);

	return st_error_set(p->err, ST_ERR_PARSE, "column %zu: '%.*s' %s", pos + 1, (int)(e - pos),
			    p->buf + pos, what);
}

/* Refuse a byte of the command part that is not printable ASCII. */
static int check_ascii(const struct parser *p, size_t pos)
{
	unsigned char c = (unsigned char)p->buf[pos];

	if (c >= 0x80)
		return st_error_set(p->err, ST_ERR_PARSE,
				    "column %zu: non-ASCII byte 0x%02x; G-code commands are ASCII",
				    pos + 1, c);
	return 0;
}

/* Append to the cleaned text; refuse a command that grows too long. */
static int text_put(struct parser *p, const char *s, size_t n)
{
	struct gcode_line *l = p->l;

	if (n > GCODE_LINE_MAX - l->text_len)
		return st_error_set(p->err, ST_ERR_PARSE,
				    "command longer than %d characters (comments excluded); "
				    "it is rejected, not cut",
				    GCODE_LINE_MAX);
	memcpy(l->text + l->text_len, s, n);
	l->text_len += n;
	l->text[l->text_len] = '\0';
	return 0;
}

/* Keep comment text (possibly in part) in dst of GCODE_COMMENT_MAX + 1. */
static void keep_comment(char *dst, size_t *dlen, bool *trunc, const char *s, size_t n)
{
	size_t room = GCODE_COMMENT_MAX - *dlen;

	if (n > room) {
		n = room;
		*trunc = true;
	}
	memcpy(dst + *dlen, s, n);
	*dlen += n;
	dst[*dlen] = '\0';
}

/* Skip blanks and "( ... )" comments, keeping the comments' text. */
static int skip_space(struct parser *p)
{
	struct gcode_line *l = p->l;

	while (p->pos < p->len) {
		char c = p->buf[p->pos];
		size_t open, s, e;

		if (is_blank(c)) {
			p->pos++;
			continue;
		}
		if (c != '(')
			break;
		open = p->pos;
		e = open + 1;
		while (e < p->len && p->buf[e] != ')')
			e++;
		if (e >= p->len)
			return st_error_set(
			    p->err, ST_ERR_PARSE,
			    "column %zu: unterminated '(' comment; close it with ')'", open + 1);
		for (s = open + 1; s < e && is_blank(p->buf[s]); s++)
			;
		{
			size_t t = e;

			while (t > s && is_blank(p->buf[t - 1]))
				t--;
			if (l->has_paren && t > s)
				keep_comment(l->paren, &l->paren_len, &l->paren_truncated, " ", 1);
			if (t > s || !l->has_paren)
				keep_comment(l->paren, &l->paren_len, &l->paren_truncated,
					     p->buf + s, t - s);
		}
		l->has_paren = true;
		p->pos = e + 1;
	}
	return 0;
}

/* Read up to maxd decimal digits at pos into *v; returns how many (0 = none).
 * A longer run of digits is reported as maxd + 1. */
static size_t read_digits(const struct parser *p, size_t pos, size_t maxd, unsigned long *v)
{
	size_t n = 0;
	unsigned long acc = 0;

	while (pos + n < p->len && is_digit(p->buf[pos + n])) {
		if (n == maxd)
			return maxd + 1;
		acc = acc * 10 + (unsigned long)(p->buf[pos + n] - '0');
		n++;
	}
	*v = acc;
	return n;
}

/* True if the byte at pos may end a number or a command number. */
static bool at_delimiter(const struct parser *p, size_t pos)
{
	char c;

	if (pos >= p->len)
		return true;
	c = p->buf[pos];
	return is_blank(c) || c == ';' || c == '(' || c == '*' || is_alpha(c);
}

/* Parse "*<cs>" at pos and check only blanks or comments follow. */
static int parse_checksum(struct parser *p)
{
	size_t star = p->pos, q = star + 1, nd;
	unsigned long v = 0;
	int rc;

	while (q < p->len && is_blank(p->buf[q]))
		q++;
	nd = read_digits(p, q, 3, &v);
	if (nd == 0 || nd > 3 || v > 255 || !at_delimiter(p, q + nd) ||
	    (q + nd < p->len && is_alpha(p->buf[q + nd])))
		return st_error_set(p->err, ST_ERR_PARSE,
				    "column %zu: '*' must be followed by a checksum from 0 to 255",
				    star + 1);
	p->pos = q + nd;
	rc = skip_space(p);
	if (rc)
		return rc;
	if (p->pos < p->len && p->buf[p->pos] != ';')
		return st_error_set(p->err, ST_ERR_PARSE,
				    "column %zu: text after the checksum; the checksum must end "
				    "the command",
				    p->pos + 1);
	p->l->has_checksum = true;
	p->l->checksum = (uint8_t)v;
	p->l->checksum_computed = 0; /* set by the caller, which knows the start */
	return (int)star;
}

/* Parse "[N<n>]" at the start of the command part. */
static int parse_line_number(struct parser *p)
{
	size_t col = p->pos, nd;
	unsigned long v = 0;

	nd = read_digits(p, col + 1, 10, &v);
	if (nd == 0)
		return st_error_set(p->err, ST_ERR_PARSE,
				    "column %zu: N without a number; the line number is "
				    "N followed by digits",
				    col + 1);
	if (nd > 10 || v > 2147483647UL)
		return fail_token(p, col, "is out of range; line numbers go from 0 to 2147483647");
	if (!at_delimiter(p, col + 1 + nd))
		return fail_token(p, col, "is not a line number");
	p->l->has_line_number = true;
	p->l->line_number = (long)v;
	p->pos = col + 1 + nd;
	return skip_space(p);
}

/* Does the G, M or T at p->pos start a command, as Marlin's parser reads
 * it: a number follows (blanks allowed), or one of the Prusa MMU's T?, Tx,
 * Tc?  Otherwise ("START_PRINT", "TURN_OFF_HEATERS", a bare "T") Marlin
 * takes the line for an unknown command. */
static bool starts_command(const struct parser *p)
{
	size_t q = p->pos + 1;

	while (q < p->len && is_blank(p->buf[q]))
		q++;
	if (q < p->len && is_digit(p->buf[q]))
		return true;
	return upper(p->buf[p->pos]) == 'T' && q < p->len && memchr("?xc", p->buf[q], 3) &&
	       (q + 1 >= p->len || is_blank(p->buf[q + 1]) || p->buf[q + 1] == ';' ||
		p->buf[q + 1] == '*');
}

/* Parse the command letter and number: G1, M104, T0, G29.1. */
static int parse_command(struct parser *p)
{
	struct gcode_line *l = p->l;
	size_t col = p->pos, q = col + 1, nd;
	unsigned long v = 0, sub = 0;
	char letter = upper(p->buf[col]), tmp[24];
	int w;

	while (q < p->len && is_blank(p->buf[q]))
		q++;
	nd = read_digits(p, q, 5, &v);
	if (nd == 0) {
		/* Prusa MMU (starts_command let no other through): T? lets the
		 * user pick the filament, Tx and Tc load it in two steps (Prusa
		 * firmware and Marlin's PRUSA_MMU2 read these) */
		tmp[0] = 'T';
		tmp[1] = p->buf[q];
		l->letter = 'T';
		l->number = -1;
		l->subcode = -1;
		l->has_string = true;
		l->string_off = 1;
		p->pos = q + 1;
		return text_put(p, tmp, 2);
	}
	if (nd > 5)
		return fail_token(p, col, "has a command number over 5 digits");
	q += nd;
	l->letter = letter;
	l->number = (int)v;
	l->subcode = -1;
	if (q < p->len && p->buf[q] == '.' && letter != 'T') {
		size_t sd = read_digits(p, q + 1, 3, &sub);

		if (sd == 0 || sd > 3)
			return fail_token(p, col, "is not a command (bad subcode after '.')");
		l->subcode = (int)sub;
		q += 1 + sd;
	}
	if (!at_delimiter(p, q))
		return fail_token(p, col, "is not a command");
	if (l->subcode >= 0)
		w = snprintf(tmp, sizeof(tmp), "%c%d.%d", letter, l->number, l->subcode);
	else
		w = snprintf(tmp, sizeof(tmp), "%c%d", letter, l->number);
	p->pos = q;
	return text_put(p, tmp, (size_t)w);
}

/* Refuse a '*' left inside a text once its checksum is taken off: Marlin's
 * parser ends the command at the first '*' and Prusa's firmware computes
 * the checksum up to it, so the text would be cut or the line resent for
 * ever (docs/errors.md "G-code input"). */
static int check_no_star(const struct parser *p, size_t s, size_t e)
{
	const char *star = memchr(p->buf + s, '*', e - s);
	/* the command's name: the cleaned one, or a text command's first token */
	const char *cmd = p->l->text_len ? p->l->text : p->buf + s;
	size_t n = p->l->text_len ? p->l->text_len : token_end(p, s) - s;
	const char *sp = memchr(cmd, ' ', n);

	if (!star)
		return 0;
	return st_error_set(p->err, ST_ERR_PARSE,
			    "column %zu: '*' inside the text of %.*s; the firmware takes '*' for "
			    "the start of the checksum and would cut the text there, so remove it",
			    (size_t)(star - p->buf) + 1, (int)(sp ? (size_t)(sp - cmd) : n), cmd);
}

/* Rest of a string-argument command (or '@' host command, or the text that
 * ends a command which takes text) up to ';', as written: any byte but
 * control bytes, UTF-8 included. */
static int parse_string(struct parser *p, size_t first)
{
	struct gcode_line *l = p->l;
	size_t s = p->pos, end = s, e, d;
	int rc;

	while (s < p->len && is_blank(p->buf[s]))
		s++;
	while (end < p->len && p->buf[end] != ';')
		end++;
	/* A trailing "*<digits>" is the checksum. */
	e = end;
	while (e > s && is_blank(p->buf[e - 1]))
		e--;
	d = e;
	while (d > s && e - d < 4 && is_digit(p->buf[d - 1]))
		d--;
	if (l->letter != '@' && d < e && e - d <= 3 && d > s && p->buf[d - 1] == '*') {
		unsigned long v = 0;

		read_digits(p, d, 3, &v);
		if (v > 255)
			return st_error_set(p->err, ST_ERR_PARSE,
					    "column %zu: '*' must be followed by a checksum "
					    "from 0 to 255",
					    d);
		l->has_checksum = true;
		l->checksum = (uint8_t)v;
		l->checksum_computed = gcode_checksum(p->buf + first, d - 1 - first);
		e = d - 1;
	}
	while (e > s && is_blank(p->buf[e - 1]))
		e--;
	if (l->letter != '@' && (rc = check_no_star(p, s, e)))
		return rc;
	if (l->letter != '@' && l->text_len > 0 && e > s && (rc = text_put(p, " ", 1)))
		return rc;
	l->string_off = l->letter == '@' ? 1 : l->text_len;
	l->has_string = true;
	if ((rc = text_put(p, p->buf + s, e - s)))
		return rc;
	p->pos = end;
	return 0;
}

/* How a word at p->pos reads. */
enum word_status {
	WORD_OK = 0,
	WORD_TWICE,	/* its letter was given before */
	WORD_BAD_NUMBER, /* the letter is followed by something that is not a number */
	WORD_RUN_ON,	/* a bare letter run into more letters or symbols ("Click") */
};

/* Read one word "L[value]" at p->pos into the next slot of p->l->words
 * without taking it; *end is where the word ends, *num why a number failed.
 * In a command that takes numbers only (strict) a bare letter is a word
 * whatever follows (G28XY is G28 X Y; what follows is checked next); in
 * one that may end in text, it must stand alone ("Click" is text). */
static enum word_status scan_word(struct parser *p, bool strict, size_t *end,
				  enum num_status *num)
{
	struct gcode_line *l = p->l;
	size_t col = p->pos, q = col + 1, ne;
	char letter = upper(p->buf[col]);
	struct gcode_word *wd = &l->words[l->nwords];

	*num = NUM_OK;
	if (gcode_find_word(l, letter))
		return WORD_TWICE;
	wd->letter = letter;
	wd->column = (uint32_t)(col + 1);
	wd->has_value = false;
	wd->value = 0;
	while (q < p->len && is_blank(p->buf[q]))
		q++;
	if (q < p->len &&
	    (is_digit(p->buf[q]) || p->buf[q] == '.' || p->buf[q] == '+' || p->buf[q] == '-')) {
		ne = q;
		if (p->buf[ne] == '+' || p->buf[ne] == '-')
			ne++;
		while (ne < p->len && (is_digit(p->buf[ne]) || p->buf[ne] == '.'))
			ne++;
		*num = gcode_scan_number(p->buf + q, ne - q, &wd->value);
		if (*num != NUM_OK || !at_delimiter(p, ne))
			return WORD_BAD_NUMBER;
		wd->has_value = true;
		*end = ne;
		return WORD_OK;
	}
	*end = col + 1;
	if (!strict && (!at_delimiter(p, col + 1) || (col + 1 < p->len && is_alpha(p->buf[col + 1]))))
		return WORD_RUN_ON;
	return WORD_OK;
}

/* Take the word scan_word just read (ending at end) into the line. */
static int take_word(struct parser *p, size_t end)
{
	struct gcode_line *l = p->l;
	const struct gcode_word *wd = &l->words[l->nwords];
	size_t vs = wd->column; /* index just after the letter */
	int rc;

	if ((rc = text_put(p, " ", 1)) || (rc = text_put(p, &wd->letter, 1)))
		return rc;
	if (wd->has_value) {
		while (is_blank(p->buf[vs]))
			vs++;
		if ((rc = text_put(p, p->buf + vs, end - vs)))
			return rc;
	}
	l->nwords++;
	p->pos = end;
	return 0;
}

/* The error for a word scan_word refused, in a command that takes numbers
 * only. */
static int word_error(const struct parser *p, enum word_status st, enum num_status num)
{
	const struct gcode_line *l = p->l;
	size_t col = p->pos, e = token_end(p, col);
	char letter = upper(p->buf[col]);

	if (st == WORD_TWICE)
		return st_error_set(p->err, ST_ERR_PARSE,
				    "column %zu: '%c' appears twice (first at column %u); "
				    "give each letter once",
				    col + 1, letter, (unsigned)gcode_find_word(l, letter)->column);
	if (e < p->len && (unsigned char)p->buf[e] >= 0x80)
		return check_ascii(p, e); /* "S60°C": the degree sign is the trouble */
	return st_error_set(p->err, ST_ERR_PARSE, "column %zu: '%.*s' is not a number%s",
			    col + 1, (int)(e - col), p->buf + col, gcode_num_reason(num));
}

/* The words of the command, up to ';', the checksum or (for a command that
 * takes text) the first token that is not a word, which starts the text. */
static int parse_words(struct parser *p, size_t first)
{
	struct gcode_line *l = p->l;
	bool strict = l->letter == 0 || gcode_needs_numbers(l->letter, l->number);
	/* Start of the blank-separated token being read, and the line then. */
	size_t tok = p->pos, tok_words = l->nwords, tok_text = l->text_len;
	int rc;

	for (;;) {
		size_t before = p->pos, end = 0;
		enum num_status num;
		enum word_status st;
		char c;

		while (p->pos < p->len && is_blank(p->buf[p->pos]))
			p->pos++;
		if (!strict && p->pos < p->len && p->buf[p->pos] == '(' &&
		    !memchr(p->buf + p->pos, ')', p->len - p->pos)) {
			if (p->pos != before) {
				tok = p->pos;
				tok_words = l->nwords;
				tok_text = l->text_len;
			}
			goto text; /* an unclosed '(' in a text is text */
		}
		if ((rc = skip_space(p)))
			return rc;
		if (p->pos != before) {
			tok = p->pos;
			tok_words = l->nwords;
			tok_text = l->text_len;
		}
		if (p->pos >= p->len || p->buf[p->pos] == ';')
			return 0;
		c = p->buf[p->pos];
		if (c == '*') {
			size_t star;

			rc = parse_checksum(p);
			if (rc < 0)
				return rc;
			star = (size_t)rc;
			l->checksum_computed = gcode_checksum(p->buf + first, star - first);
			return 0;
		}
		if (is_alpha(c)) {
			if (l->letter == 0)
				return fail_token(p, p->pos,
						  "is not a command; a line starts with G, M or T");
			st = scan_word(p, strict, &end, &num);
			if (st == WORD_OK) {
				if ((rc = take_word(p, end)))
					return rc;
				continue;
			}
			if (strict && st != WORD_RUN_ON)
				return word_error(p, st, num);
		}
		if (strict) {
			if ((rc = check_ascii(p, p->pos)))
				return rc;
			if (is_digit(c) || c == '.' || c == '+' || c == '-')
				return fail_token(p, p->pos, "has no word letter in front");
			return st_error_set(p->err, ST_ERR_PARSE,
					    "column %zu: unexpected character '%c'", p->pos + 1, c);
		}
		break;
	}
text:
	/* The text starts with the token that is not a word, as written. */
	l->nwords = tok_words;
	l->text_len = tok_text;
	l->text[l->text_len] = '\0';
	p->pos = tok;
	return parse_string(p, first);
}

/* The whole line into p->l; returns 0 or a negative class. */
static int parse_line(struct parser *p, unsigned flags)
{
	struct gcode_line *l = p->l;
	size_t first;
	int rc;

	/* Control bytes are refused everywhere, comments included. */
	for (size_t i = 0; i < p->len; i++) {
		unsigned char c = (unsigned char)p->buf[i];

		if ((c < 0x20 && c != '\t') || c == 0x7f)
			return st_error_set(p->err, ST_ERR_PARSE,
					    "column %zu: control byte 0x%02x; a G-code line holds "
					    "printable ASCII and tabs only",
					    i + 1, c);
	}
	while (p->pos < p->len && is_blank(p->buf[p->pos]))
		p->pos++;
	first = p->pos;
	if ((rc = skip_space(p)))
		return rc;
	if (p->pos < p->len && upper(p->buf[p->pos]) == 'N' && (rc = parse_line_number(p)))
		return rc;

	if (p->pos < p->len && p->buf[p->pos] != ';' && p->buf[p->pos] != '*') {
		char c = upper(p->buf[p->pos]);

		if ((rc = check_ascii(p, p->pos)))
			return rc;
		if (c == '@' && !l->has_line_number) {
			l->letter = '@';
			if ((rc = text_put(p, "@", 1)))
				return rc;
			p->pos++;
			/* the name follows '@' directly */
			if ((rc = parse_string(p, first)))
				return rc;
			if (l->text_len == 1)
				return st_error_set(p->err, ST_ERR_PARSE,
						    "column %zu: '@' without a host command name",
						    first + 1);
		} else if ((c == 'G' || c == 'M' || c == 'T') && starts_command(p)) {
			if ((rc = parse_command(p)))
				return rc;
		} else if (l->has_line_number && !is_blank(p->buf[p->pos - 1])) {
			/* "N12x G1": Marlin skips N12x up to the blank and runs G1 */
			return fail_token(p, p->pos, "is not a command");
		} else if (is_alpha(c) && !memchr("GMT", c, 3) && p->pos + 1 < p->len &&
			   memchr("0123456789+-.", p->buf[p->pos + 1], 13)) {
			/* a word with no command: with Marlin's GCODE_MOTION_MODES
			 * "X10 Y10" moves, and no reader here would see the move
			 * (a signed "T-1" is a tool command to RepRapFirmware and
			 * Marlin's switching toolheads, unknown to the others) */
			return fail_token(p, p->pos,
					  "is not a command; a line starts with G, M or T (or a "
					  "macro name)");
		} else if (is_alpha(c) || c == '_') {
			/* Klipper's extended commands and macros, a bare T, text:
			 * Marlin answers "Unknown command", Klipper runs them */
			l->letter = GCODE_LETTER_TEXT;
		} else {
			return fail_token(p, p->pos,
					  "is not a command; a line starts with a letter");
		}
	}

	if (gcode_takes_string(l->letter, l->number) || l->letter == GCODE_LETTER_TEXT) {
		if ((rc = parse_string(p, first)))
			return rc;
	} else if (l->letter != '@' && (rc = parse_words(p, first))) {
		return rc;
	}

	/* The ';' comment runs to the end of the line. */
	if (p->pos < p->len && p->buf[p->pos] == ';') {
		size_t s = p->pos + 1, e = p->len;

		while (e > s && is_blank(p->buf[e - 1]))
			e--;
		l->has_comment = true;
		keep_comment(l->comment, &l->comment_len, &l->comment_truncated, p->buf + s, e - s);
	}

	/* Parameters that must have a value.  A bare F on a move keeps the
	 * feed rate, as in Marlin (its G0-G3 take F only when above 0; Cura's
	 * JGAurora A6 start G-code has `G1 Z15.0 F`). */
	if (l->letter == 'G' && l->number <= 5 && l->number != -1) {
		for (size_t i = 0; i < l->nwords; i++)
			if (!l->words[i].has_value && !(l->words[i].letter == 'F' && l->number != 4))
				return st_error_set(p->err, ST_ERR_PARSE,
						    "column %u: '%c' without a value; G%d needs a "
						    "number after each letter",
						    (unsigned)l->words[i].column,
						    l->words[i].letter, l->number);
	}

	if (!l->has_string)
		l->string_off = l->text_len;
	l->kind = gcode_classify(l->letter, l->number);
	l->checksum_ok = true;
	if (l->has_checksum && l->checksum != l->checksum_computed) {
		if (!(flags & GCODE_PARSE_KEEP_BAD_CHECKSUM))
			return st_error_set(p->err, ST_ERR_PARSE,
					    "checksum %u does not match %u computed from the line; "
					    "the line was damaged",
					    (unsigned)l->checksum, (unsigned)l->checksum_computed);
		l->checksum_ok = false;
	}
	return 0;
}

int gcode_parse(const char *buf, size_t len, unsigned flags, struct gcode_line *out,
		struct st_error *err)
{
	struct gcode_line tmp;
	struct parser p;
	int rc;

	if (!out || (!buf && len > 0))
		return st_error_set(err, ST_ERR_ARG, "gcode_parse: NULL argument");
	if (!buf)
		buf = "";
	if (len > 0 && buf[len - 1] == '\n')
		len--;
	if (len > 0 && buf[len - 1] == '\r')
		len--;
	if (len > GCODE_RAW_MAX)
		return st_error_set(err, ST_ERR_PARSE,
				    "line longer than %d bytes; it is rejected, not cut",
				    GCODE_RAW_MAX);
	memset(&tmp, 0, sizeof(tmp));
	tmp.number = -1;
	tmp.subcode = -1;
	p.buf = buf;
	p.len = len;
	p.pos = 0;
	p.l = &tmp;
	p.err = err;
	rc = parse_line(&p, flags);
	if (rc)
		return rc;
	*out = tmp;
	return 0;
}
