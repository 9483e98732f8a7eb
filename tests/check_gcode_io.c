/*
 * check_gcode_io.c - serial/gcode.c, part of the gcode suite (check_gcode.c):
 * the streaming reader on real files (PrusaSlicer's output, the texts the
 * send suite streams) and on bad ones, and randomized robustness tests.
 */
#include <check.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gcode.h"
#include "gcodetest.h"
#include "suites.h"

/* Every command line of FILE, in order, as gcode_reader reads it. */
static size_t read_all(const char *path, struct gcode_line *lines, size_t cap, size_t *total)
{
	FILE *fp = fopen(path, "rb");
	struct gcode_reader *r;
	struct st_error err = {0};
	struct gcode_line l;
	size_t n = 0;
	int rc;

	ck_assert_msg(fp != NULL, "%s: not found (run from the source tree)", path);
	ck_assert_int_eq(gcode_reader_new(fp, path, &r, &err), 0);
	while ((rc = gcode_reader_next(r, 0, &l, &err)) == 1)
		if (l.text_len > 0 && n < cap)
			lines[n++] = l;
	ck_assert_msg(rc == 0, "%s", err.msg);
	*total = (size_t)gcode_reader_line(r);
	gcode_reader_free(r);
	fclose(fp);
	return n;
}

/* PrusaSlicer 2.5's G-code for the MK3S (a 20 mm cube, first three layers
 * and the end): every line reads, and each command is the line as written,
 * comment and trailing blanks removed, since PrusaSlicer writes the words
 * single-spaced. */
START_TEST(test_prusaslicer_file)
{
	static struct gcode_line lines[2048];
	static const char path[] = "tests/data/prusaslicer-mk3s-cube.gcode";
	static char raw[GCODE_RAW_MAX + 2];
	size_t total, n = read_all(path, lines, 2048, &total), k = 0;
	bool m115 = false, m862 = false, g80 = false;
	FILE *fp = fopen(path, "rb");

	ck_assert_uint_eq(total, 1058);
	while (fgets(raw, sizeof(raw), fp)) {
		char *semi = strchr(raw, ';');
		size_t len = semi ? (size_t)(semi - raw) : strlen(raw);

		while (len > 0 && strchr(" \t\r\n", raw[len - 1]))
			len--;
		if (len == 0)
			continue;
		raw[len] = '\0';
		ck_assert_uint_lt(k, n);
		ck_assert_msg(!strcmp(lines[k].text, raw), "command %zu: '%s', the file says '%s'", k,
			      lines[k].text, raw);
		m115 |= !strcmp(raw, "M115 U3.11.0");
		m862 |= !strcmp(raw, "M862.3 P \"MK3S\"");
		g80 |= !strcmp(raw, "G80");
		k++;
	}
	fclose(fp);
	ck_assert_uint_eq(k, n);
	ck_assert(m115 && m862 && g80);
}
END_TEST

/* tests/data/firmware-texts.gcode (what the send suite streams): every line
 * reads, the last one has no line ending. */
START_TEST(test_firmware_texts_file)
{
	static struct gcode_line lines[64];
	size_t total, n = read_all("tests/data/firmware-texts.gcode", lines, 64, &total);

	ck_assert_uint_eq(total, 26);
	ck_assert_uint_eq(n, 23);
	ck_assert_str_eq(lines[0].text, "M115 U3.11.0");
	ck_assert_str_eq(lines[6].text, "M117 Bed: 60\xc2\xb0" "C");
	ck_assert_str_eq(lines[9].text, "M0 Click to continue");
	ck_assert_str_eq(lines[10].text, "M1 Change filament");
	ck_assert_str_eq(lines[n - 1].text, "M117 Done");
}
END_TEST

/* A temporary file holding len bytes, rewound. */
static FILE *temp_with(const char *data, size_t len)
{
	FILE *fp = tmpfile();

	ck_assert_ptr_nonnull(fp);
	ck_assert_uint_eq(fwrite(data, 1, len, fp), len);
	rewind(fp);
	return fp;
}

START_TEST(test_reader)
{
	static const char data[] = "G28\r\nG1 X1\n;comment\rM104 S200\n\n  \r\nG1 Y2";
	static const struct {
		uint64_t line;
		const char *text;
		enum gcode_kind kind;
	} want[] = {
	    {1, "G28", GCODE_KIND_HOME},     {2, "G1 X1", GCODE_KIND_MOTION},
	    {3, "", GCODE_KIND_HOST_ONLY},   {4, "M104 S200", GCODE_KIND_TEMP_SET},
	    {5, "", GCODE_KIND_HOST_ONLY},   {6, "", GCODE_KIND_HOST_ONLY},
	    {7, "G1 Y2", GCODE_KIND_MOTION},
	};
	FILE *fp = temp_with(data, sizeof(data) - 1);
	struct gcode_reader *r = NULL;
	struct st_error err = {0};
	struct gcode_line l;

	ck_assert_int_eq(gcode_reader_new(fp, "part.gcode", &r, &err), 0);
	ck_assert_uint_eq(gcode_reader_line(r), 0);
	for (size_t i = 0; i < sizeof(want) / sizeof(want[0]); i++) {
		int rc = gcode_reader_next(r, 0, &l, &err);

		ck_assert_msg(rc == 1, "line %zu: %d %s", i + 1, rc, err.msg);
		ck_assert_uint_eq(gcode_reader_line(r), want[i].line);
		ck_assert_str_eq(l.text, want[i].text);
		ck_assert_int_eq(l.kind, want[i].kind);
	}
	ck_assert_int_eq(gcode_reader_next(r, 0, &l, &err), 0);
	ck_assert_int_eq(gcode_reader_next(r, 0, &l, &err), 0);
	ck_assert_uint_eq(gcode_reader_bytes(r), sizeof(data) - 1);
	gcode_reader_free(r);
	fclose(fp);

	/* Empty input, trailing newline, NULL arguments. */
	fp = temp_with("", 0);
	ck_assert_int_eq(gcode_reader_new(fp, NULL, &r, &err), 0);
	ck_assert_int_eq(gcode_reader_next(r, 0, &l, &err), 0);
	ck_assert_uint_eq(gcode_reader_line(r), 0);
	gcode_reader_free(r);
	fclose(fp);
	fp = temp_with("G28\n", 4);
	ck_assert_int_eq(gcode_reader_new(fp, NULL, &r, &err), 0);
	ck_assert_int_eq(gcode_reader_next(r, 0, &l, &err), 1);
	ck_assert_int_eq(gcode_reader_next(r, 0, &l, &err), 0);
	ck_assert_uint_eq(gcode_reader_line(r), 1);
	gcode_reader_free(r);
	fclose(fp);
	gcode_reader_free(NULL);
	r = (struct gcode_reader *)&err;
	ck_assert_int_eq(gcode_reader_new(NULL, "x", &r, &err), ST_ERR_ARG);
	ck_assert_ptr_null(r);
	ck_assert_int_eq(gcode_reader_next(NULL, 0, &l, &err), ST_ERR_ARG);
}
END_TEST

START_TEST(test_reader_errors)
{
	/* line 2: command too long; line 4: raw line too long; line 5: bad
	 * number; the reader goes on after each. */
	size_t cap = 2 * GCODE_RAW_MAX, n = 0;
	char *data = malloc(cap);
	FILE *fp;
	struct gcode_reader *r = NULL;
	struct st_error err = {0};
	struct gcode_line l;

	ck_assert_ptr_nonnull(data);
	n += (size_t)snprintf(data + n, cap - n, "G28\nM117 ");
	memset(data + n, 'm', 300);
	n += 300;
	n += (size_t)snprintf(data + n, cap - n, "\r\nG1 X1\n;");
	memset(data + n, 'c', GCODE_RAW_MAX + 10);
	n += GCODE_RAW_MAX + 10;
	n += (size_t)snprintf(data + n, cap - n, "\nG1 X1.2.3\nM400");
	fp = temp_with(data, n);
	free(data);

	ck_assert_int_eq(gcode_reader_new(fp, "big.gcode", &r, &err), 0);
	ck_assert_int_eq(gcode_reader_next(r, 0, &l, &err), 1);
	ck_assert_str_eq(l.text, "G28");

	ck_assert_int_eq(gcode_reader_next(r, 0, &l, &err), ST_ERR_PARSE);
	ck_assert_msg(strstr(err.msg, "big.gcode: line 2: command longer than 256"), "%s", err.msg);
	ck_assert_str_eq(l.text, "G28"); /* untouched */

	ck_assert_int_eq(gcode_reader_next(r, 0, &l, &err), 1);
	ck_assert_str_eq(l.text, "G1 X1");
	ck_assert_uint_eq(gcode_reader_line(r), 3);

	ck_assert_int_eq(gcode_reader_next(r, 0, &l, &err), ST_ERR_PARSE);
	ck_assert_msg(strstr(err.msg, "big.gcode: line 4: line longer than 65536 bytes"), "%s",
		      err.msg);

	ck_assert_int_eq(gcode_reader_next(r, 0, &l, &err), ST_ERR_PARSE);
	ck_assert_msg(strstr(err.msg, "big.gcode: line 5: column 4: 'X1.2.3' is not a number"),
		      "%s", err.msg);

	ck_assert_int_eq(gcode_reader_next(r, 0, &l, &err), 1);
	ck_assert_int_eq(l.kind, GCODE_KIND_FINISH_MOVES);
	ck_assert_uint_eq(gcode_reader_line(r), 6);
	ck_assert_int_eq(gcode_reader_next(r, 0, &l, &err), 0);
	ck_assert_uint_eq(gcode_reader_bytes(r), n);
	gcode_reader_free(r);
	fclose(fp);
}
END_TEST

/* xorshift64: a fixed, portable pseudo-random sequence. */
static uint64_t rnd(uint64_t *s)
{
	*s ^= *s << 13;
	*s ^= *s >> 7;
	*s ^= *s << 17;
	return *s;
}

START_TEST(test_random)
{
	static const char alphabet[] = "GMTNXYZEFSPgmx0123456789.-+ \t;()*@\r\n";
	static const char *const tokens[] = {
	    "G1",   "G28", "M104", "M117",  "T0", "N5 ",  "@",	  " ", " ",  "\t",  "X1.5",
	    "Y-2",  "E.5", "Z",	   "F1800", "S",  "(p)",  "(",	  ")", ";c", "*12", "*",
	    "\r\n", "1e3", "-",	   ".",	    "a",  "\xff", "M110", "N", "0",
	    /* the paths of commands that end in a text */
	    "M0",   "M115", "U3.11.0", "Click", "\"q\"", "\xc2\xb0", "T?", "M862.3",
	};
	uint64_t seed = 0x5eed5eed12345678ULL;
	char buf[320], out[GCODE_LINE_MAX + 32];
	int accepted = 0;

	for (int iter = 0; iter < 10000; iter++) {
		size_t len = (size_t)(rnd(&seed) % sizeof(buf));
		int mode = (int)(rnd(&seed) % 4); /* 0 raw bytes, 1 characters, 2-3 tokens */
		struct gcode_line l, again;
		struct st_error err = {0};
		int rc;

		if (mode >= 2) {
			size_t ntok = (size_t)(rnd(&seed) % 12);

			len = 0;
			for (size_t t = 0; t < ntok; t++) {
				const char *tok =
				    tokens[rnd(&seed) % (sizeof(tokens) / sizeof(tokens[0]))];
				size_t tl = strlen(tok);

				if (len + tl > sizeof(buf))
					break;
				memcpy(buf + len, tok, tl);
				len += tl;
			}
		} else {
			for (size_t i = 0; i < len; i++)
				buf[i] = mode == 0 ? (char)(rnd(&seed) & 0xff)
						   : alphabet[rnd(&seed) % (sizeof(alphabet) - 1)];
		}
		/* Exact-size heap copy so ASan sees any read past the end. */
		{
			char *copy = malloc(len ? len : 1);

			ck_assert_ptr_nonnull(copy);
			memcpy(copy, buf, len);
			memset(&l, 0, sizeof(l));
			rc = gcode_parse(copy, len, 0, &l, &err);
			free(copy);
		}
		if (rc != 0) {
			ck_assert_int_eq(rc, ST_ERR_PARSE);
			ck_assert_msg(err.msg[0] != '\0', "empty message");
			continue;
		}
		accepted++;
		ck_assert_uint_le(l.text_len, GCODE_LINE_MAX);
		ck_assert_uint_eq(strlen(l.text), l.text_len);
		ck_assert_uint_le(l.nwords, GCODE_WORDS_MAX);
		ck_assert_uint_le(l.string_off, l.text_len);
		ck_assert(l.kind >= 0 && l.kind < GCODE_KIND_COUNT_);
		/* What was accepted survives a resend with a new number. */
		if (l.text_len > 0 && l.letter != '@') {
			int n = gcode_format_numbered(out, sizeof(out), iter, l.text);

			ck_assert_msg(n > 0, "cannot format '%s'", l.text);
			rc = gcode_parse(out, (size_t)n, 0, &again, &err);
			ck_assert_msg(rc == 0, "'%s' from '%s': %s", out, l.text, err.msg);
			ck_assert_str_eq(again.text, l.text);
			ck_assert_int_eq(again.kind, l.kind);
			ck_assert_uint_eq(again.nwords, l.nwords);
			ck_assert_uint_eq(again.string_off, l.string_off);
		}
	}
	/* The generator must exercise the accepting paths too. */
	ck_assert_int_gt(accepted, 1000);
}
END_TEST

/* Random well-formed lines: the values come back exactly. */
START_TEST(test_random_values)
{
	uint64_t seed = 0x0123456789abcdefULL;

	for (int iter = 0; iter < 2000; iter++) {
		char line[128];
		long ip = (long)(rnd(&seed) % 100000);
		long fp = (long)(rnd(&seed) % 100000);
		bool neg = rnd(&seed) & 1;
		double want, got;
		struct gcode_line l;

		snprintf(line, sizeof(line), "G1 X%s%ld.%05ld", neg ? "-" : "", ip, fp);
		want = strtod(line + 4, NULL); /* C locale in the tests */
		parse_ok(line, &l);
		ck_assert(gcode_word_value(&l, 'X', &got));
		ck_assert_msg(got == want, "%s read as %.17g, strtod %.17g", line, got, want);
	}
}
END_TEST


void gcode_io_tcases(Suite *s)
{
	TCase *io = tcase_create("io");
	TCase *fuzz = tcase_create("fuzz");

	tcase_add_test(io, test_reader);
	tcase_add_test(io, test_reader_errors);
	tcase_add_test(io, test_prusaslicer_file);
	tcase_add_test(io, test_firmware_texts_file);
	suite_add_tcase(s, io);

	tcase_add_test(fuzz, test_random);
	tcase_add_test(fuzz, test_random_values);
	tcase_set_timeout(fuzz, 60);
	suite_add_tcase(s, fuzz);
}
