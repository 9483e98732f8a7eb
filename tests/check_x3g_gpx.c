/*
 * check_x3g_gpx.c - serial/x3g.c, part of the x3g suite (check_x3g.c): the
 * decoder's fields and its checks on truncated and unknown input, and, when
 * Debian's gpx is installed, a command-by-command comparison with
 * `gpx -m fcp` on a hand-written Sailfish file, on a sliced part and on
 * PrusaSlicer's MK3S output, plus `stratum x3g` end to end.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gcode.h"
#include "suites.h"
#include "testutil.h"
#include "x3g.h"
#include "x3gtest.h"

START_TEST(test_decode_fields)
{
	static const uint8_t b[] = {155, LE32(941), LE32(-2), LE32(8000), LE32(-96), LE32(0),
				    LE32(941), 0x18, LE32(0x41200000), LE16(640),
				    136, 1, 3, 2, LE16(215),
				    149, 0x02, 0, 0, 5, 'H', 'i', 0,
				    153, LE32(0), 'p', 0};
	struct x3g_command c;
	struct st_error err = {0};
	double v;
	int n;

	n = x3g_decode(b, sizeof(b), 100, &c, &err);
	ck_assert_int_eq(n, 32);
	ck_assert_uint_eq(c.code, 155);
	ck_assert_uint_eq(c.offset, 100);
	ck_assert_uint_eq(c.length, 32);
	ck_assert(x3g_field_value(&c, "y", &v) && v == -2);
	ck_assert(x3g_field_value(&c, "a", &v) && v == -96);
	ck_assert(x3g_field_value(&c, "distance", &v) && v == 10.0);
	ck_assert(x3g_field_value(&c, "feedrate_x64", &v) && v == 640);
	ck_assert(!x3g_field_value(&c, "nope", &v));
	n = x3g_decode(b + 32, sizeof(b) - 32, 32, &c, &err);
	ck_assert_int_eq(n, 6);
	ck_assert(x3g_field_value(&c, "tool", &v) && v == 1);
	ck_assert(x3g_field_value(&c, "value", &v) && v == 215);
	n = x3g_decode(b + 38, sizeof(b) - 38, 38, &c, &err);
	ck_assert_int_eq(n, 8);
	ck_assert(c.has_text);
	ck_assert_str_eq(c.text, "Hi");
	n = x3g_decode(b + 46, sizeof(b) - 46, 46, &c, &err);
	ck_assert_int_eq(n, 7);
	ck_assert_str_eq(c.text, "p");
	ck_assert_int_eq(x3g_decode(b, 0, 0, &c, &err), 0);
}
END_TEST

/* decode must fail with ST_ERR_PARSE and name byte `at` in its message. */
static void decode_bad(const uint8_t *b, size_t n, uint64_t at, const char *needle)
{
	struct x3g_command c;
	struct st_error err = {0};
	char want[32];

	memset(&c, 0x5a, sizeof(c));
	ck_assert_int_eq(x3g_decode(b, n, at, &c, &err), ST_ERR_PARSE);
	snprintf(want, sizeof(want), "byte %llu", (unsigned long long)at);
	ck_assert_msg(strstr(err.msg, want), "'%s' not in: %s", want, err.msg);
	ck_assert_msg(strstr(err.msg, needle), "'%s' not in: %s", needle, err.msg);
	ck_assert_uint_eq(c.code, 0x5a); /* untouched */
}

START_TEST(test_decode_errors)
{
	static const uint8_t move[] = {155, LE32(941), LE32(0), LE32(8000), LE32(-96), LE32(0),
				       LE32(941), 0x18, LE32(0x41200000), LE16(640)};
	static const uint8_t big_tool[] = {136, 0, 3, 40, 0, 0};
	static const uint8_t short_tool[] = {136, 0, 3, 2, 0xd2};
	uint8_t msg[40];

	/* every cut of a full command is refused, never read past */
	for (size_t n = 1; n < sizeof(move); n++) {
		char want[64];
		snprintf(want, sizeof(want), "needs 32 bytes but the data ends after %zu", n);
		decode_bad(move, n, 7, want);
	}
	decode_bad((const uint8_t[]){200, 0}, 2, 12, "200 is not an X3G action command");
	decode_bad((const uint8_t[]){10, 0}, 2, 0, "is not an X3G action command");
	decode_bad(big_tool, sizeof(big_tool), 3, "at most 32");
	decode_bad(short_tool, sizeof(short_tool), 3, "ends after");
	/* text without its NUL: cut short, or longer than a packet */
	decode_bad((const uint8_t[]){149, 2, 0, 0, 5, 'H', 'i'}, 7, 0, "ends after");
	memset(msg, 'x', sizeof(msg));
	msg[0] = 149;
	decode_bad(msg, sizeof(msg), 9, "NUL");
}
END_TEST

/* The translator's output cut back into commands covers every byte. */
START_TEST(test_decode_roundtrip)
{
	struct tr r;
	struct x3g_command c;
	struct st_error err = {0};
	size_t pos = 0, count = 0;
	int n;

	tr_open(&r, RR);
	tr_lines(&r, "M73 P0\nG28\nG92 X0 Y0 Z0 A0 B0\nM104 S200 T1\nM190 S60\nM116\n"
		     "G1 X10 Y5 E1 F1200\nT1\nG1 X20 E3\nM70 P2 (Printing a test part)\n"
		     "M106\nG4 P100\nM18\nM73 P100");
	while (pos < r.len && (n = x3g_decode(r.out + pos, r.len - pos, pos, &c, &err)) > 0) {
		pos += (size_t)n;
		count++;
	}
	ck_assert_msg(pos == r.len, "stopped at %zu of %zu: %s", pos, r.len, err.msg);
	ck_assert_uint_ge(count, 20);
	x3g_free(r.t);
}
END_TEST

/* ---- comparison with gpx ------------------------------------------------- */

/* Read a whole file; NULL when it cannot. */
static uint8_t *slurp(const char *path, size_t *len)
{
	FILE *f = fopen(path, "rb");
	uint8_t *b;
	long n;

	if (!f)
		return NULL;
	fseek(f, 0, SEEK_END);
	n = ftell(f);
	fseek(f, 0, SEEK_SET);
	b = malloc(n > 0 ? (size_t)n : 1);
	*len = b ? fread(b, 1, (size_t)n, f) : 0;
	fclose(f);
	return b;
}

static bool near(double a, double b, double rel)
{
	return fabs(a - b) <= rel * fmax(fabs(a), fabs(b)) + 1e-9;
}

/*
 * Decode both files and compare command by command: same codes in the same
 * order, equal fields, except rates and distances within 1 %.  Returns the
 * number of commands compared.
 */
static size_t compare_x3g(const char *ours, const char *theirs)
{
	size_t la, lb, pa = 0, pb = 0, count = 0;
	uint8_t *a = slurp(ours, &la), *b = slurp(theirs, &lb);
	struct st_error err = {0};

	ck_assert_msg(a && b, "cannot read %s or %s", ours, theirs);
	while (pa < la && pb < lb) {
		struct x3g_command ca, cb;
		int na = x3g_decode(a + pa, la - pa, pa, &ca, &err);
		int nb;

		ck_assert_msg(na > 0, "%s: %s", ours, err.msg);
		nb = x3g_decode(b + pb, lb - pb, pb, &cb, &err);
		ck_assert_msg(nb > 0, "%s: %s", theirs, err.msg);
		ck_assert_msg(ca.code == cb.code, "command %zu: ours %u (byte %zu), gpx %u (byte %zu)",
			      count, ca.code, pa, cb.code, pb);
		ck_assert_uint_eq(ca.nfields, cb.nfields);
		for (size_t i = 0; i < ca.nfields; i++) {
			const char *f = ca.fields[i].name;
			bool rate = !strcmp(f, "dda_rate") || !strcmp(f, "dda_us") ||
				    !strcmp(f, "feedrate_x64") || !strcmp(f, "distance");
			double x = ca.fields[i].value, y = cb.fields[i].value;

			ck_assert_msg(rate ? near(x, y, 0.01) : x == y,
				      "command %zu (%u, gpx byte %zu): %s is %.9g, gpx %.9g", count,
				      ca.code, pb, f, x, y);
		}
		ck_assert_msg(!strcmp(ca.text, cb.text), "command %zu: text '%s', gpx '%s'", count,
			      ca.text, cb.text);
		pa += (size_t)na;
		pb += (size_t)nb;
		count++;
	}
	ck_assert_msg(pa == la && pb == lb, "ours has %zu bytes left, gpx %zu", la - pa, lb - pb);
	free(a);
	free(b);
	return count;
}

static bool have_gpx(void)
{
	if (system("command -v gpx >/dev/null 2>&1") == 0)
		return true;
	printf("x3g: gpx is not installed ('make deps' installs it); comparison skipped\n");
	return false;
}

/* Translate in with gpx and with stratum (same output base name, so the
 * build names agree) and compare. */
static size_t against_gpx(const char *in, const char *base)
{
	char cmd[4096], out[4096], ours[512], theirs[512];
	int rc;

	snprintf(ours, sizeof(ours), "%s", tu_path("ours"));
	snprintf(theirs, sizeof(theirs), "%s", tu_path("gpx"));
	snprintf(cmd, sizeof(cmd), "mkdir -p '%s' '%s'", ours, theirs);
	ck_assert_int_eq(system(cmd), 0);
	/* -I: no ~/.gpx.ini or ./gpx.ini, GPX's own defaults only */
	snprintf(cmd, sizeof(cmd), "gpx -I -q -m fcp '%s' '%s/%s.x3g' >/dev/null 2>&1", in, theirs,
		 base);
	ck_assert_int_eq(system(cmd), 0);
	/* --force: the translation is compared, whatever printer the file was
	 * sliced for (the guard: tests/check_guard.c) */
	rc = tu_run(out, sizeof(out),
		    "x3g '%s' -o '%s/%s.x3g' --printer flashforge-creator-pro --force", in, ours,
		    base);
	ck_assert_msg(rc == 0, "stratum x3g failed (%d): %s", rc, out);
	snprintf(ours + strlen(ours), sizeof(ours) - strlen(ours), "/%s.x3g", base);
	snprintf(theirs + strlen(theirs), sizeof(theirs) - strlen(theirs), "/%s.x3g", base);
	return compare_x3g(ours, theirs);
}

/* A Sailfish-flavour file using what the translator supports, both tools. */
static const char sailfish_gcode[] =
    "; hand-written Sailfish G-code\n"
    "M73 P0\n"
    "M140 S60 T0\n"
    "M104 S220 T0\n"
    "M104 S215 T1\n"
    "G21\nG90\nM82\n"
    "G162 X Y F2500\n"
    "G161 Z F1100\n"
    "G92 X118 Y72.5 Z0 A0 B0\n"
    "G1 Z5 F1100\n"
    "G161 Z F100\n"
    "M132 X Y Z A B\n"
    "G1 Z20 F1100\n"
    "G1 X-100 Y-70 F6000\n"
    "M190 S60\n"
    "M109 S220 T0\n"
    "M116\n"
    "M70 P5 (Stratum test)\n"
    "G1 Z0.3 F1100\n"
    "G92 E0\n"
    "G1 X100 Y-70 E20 F1200\n"
    "G1 X90 Y-72 F6000\n"
    "M106 S255\n"
    "G1 X10.5 Y3.25 E21.2 F1800\n"
    "G1 X-10.5 Y3.25 E22.4\n"
    "G1 E21.4 F1800\n"
    "G0 X0 Y0 Z0.6 F9000\n"
    "G1 E22.4 F1800\n"
    "M73 P25\n"
    "T1\n"
    "G92 E0\n"
    "G1 X5 Y5 E1.5 F1500\n"
    "G91\n"
    "G1 X2 Y-3 E0.4\n"
    "G1 Z0.2 F600\n"
    "G90\n"
    "M83\n"
    "G1 X-5 Y5 E0.7 F2400\n"
    "G4 P500\n"
    "T0\n"
    "G1 X20 Y20 E1 F3000\n"
    "M73 P80\n"
    "M107\n"
    "M104 S0 T0\n"
    "M104 S0 T1\n"
    "M140 S0 T0\n"
    "G1 Z150 F1100\n"
    "G162 X Y F2500\n"
    "M18\n"
    "M73 P100\n";

START_TEST(test_gpx_handwritten)
{
	const char *in = tu_path("sailfish.gcode");

	if (!have_gpx())
		return;
	tu_write_str(in, sailfish_gcode);
	ck_assert_uint_ge(against_gpx(in, "sailfish"), 40);
}
END_TEST

START_TEST(test_gpx_sliced)
{
	char out[4096];
	const char *gc = tu_path("bracket.gcode");
	size_t n;
	int rc;

	if (!have_gpx())
		return;
	rc = tu_run(out, sizeof(out),
		    "slice docs/examples/bracket.stl -o '%s' --printer flashforge-creator-pro", gc);
	ck_assert_msg(rc == 0, "slice failed (%d): %s", rc, out);
	n = against_gpx(gc, "bracket");
	ck_assert_uint_ge(n, 1000);
}
END_TEST

/* PrusaSlicer 2.5's own G-code for the MK3S translates (with --force: it is
 * for another printer), with its Prusa-only commands warned about, as GPX
 * translates it. */
START_TEST(test_gpx_prusaslicer)
{
	char out[1 << 16];
	const char *x3g = tu_path("mk3s.x3g");
	int rc;

	rc = tu_run(out, sizeof(out),
		    "x3g tests/data/prusaslicer-mk3s-cube.gcode -o '%s' --printer "
		    "flashforge-creator-pro --force",
		    x3g);
	ck_assert_msg(rc == 0, "stratum x3g failed (%d): %.2000s", rc, out);
	ck_assert_msg(strstr(out, "prusaslicer-mk3s-cube.gcode:23: warning: M115 is not supported"),
		      "%.2000s", out);
	ck_assert_msg(strstr(out, "prusaslicer-mk3s-cube.gcode:21: warning: M862.3"), "%.2000s", out);
	ck_assert_msg(strstr(out, "1058 lines"), "%.2000s", out);
	if (!have_gpx())
		return;
	/* GPX writes M115 as a host query (27, which a file cannot answer);
	 * this translator warns instead (test_warnings), so that line is left
	 * out of the comparison */
	{
		FILE *in = fopen("tests/data/prusaslicer-mk3s-cube.gcode", "r");
		const char *copy = tu_path("mk3s.gcode");
		FILE *o = fopen(copy, "w");
		static char line[1 << 16];

		ck_assert(in && o);
		while (fgets(line, sizeof(line), in))
			fputs(strncmp(line, "M115 ", 5) ? line : ";M115 left out\n", o);
		fclose(in);
		ck_assert_int_eq(fclose(o), 0);
		ck_assert_uint_ge(against_gpx(copy, "mk3s"), 500);
	}
}
END_TEST

/* ---- stratum x3g end to end --------------------------------------------- */

START_TEST(test_cli)
{
	char out[8192];
	const char *in = tu_path("cli.gcode"), *x3g = tu_path("cli.x3g");
	const char *bad = tu_path("bad.gcode"), *none = tu_path("none.x3g");
	const char *cut = tu_path("cut.x3g");
	size_t len;
	uint8_t *b;
	int rc;

	tu_write_str(in, "M73 P0\nG92 X0 Y0 Z0 A0 B0\nM117 hello\nG1 X10 F600\n");
	rc = tu_run(out, sizeof(out), "x3g '%s' -o '%s' --printer flashforge-creator-pro", in,
		    x3g);
	ck_assert_msg(rc == 0, "%s", out);
	ck_assert_msg(strstr(out, "cli.gcode:3: warning: M117"), "%s", out);
	ck_assert_msg(strstr(out, "4 lines"), "%s", out);
	ck_assert_msg(strstr(out, "1 warnings"), "%s", out);
	rc = tu_run(out, sizeof(out), "x3g --decode '%s'", x3g);
	ck_assert_msg(rc == 0, "%s", out);
	ck_assert_msg(strstr(out, "153 build start notification") &&
			  strstr(out, "cli\"") && strstr(out, "155 queue extended point x3g: "
								   "x=941"),
		      "%s", out);
	rc = tu_run(out, sizeof(out), "x3g '%s' -o '%s' --printer flashforge-creator-pro --json",
		    in, x3g);
	ck_assert_msg(rc == 0 && strstr(out, "\"commands\": 7") && strstr(out, "\"line\": 3"),
		      "%s", out);

	/* a bad line: 65, file and line named, no output left behind */
	tu_write_str(bad, "G1 X10\nG1 X1..2\n");
	rc = tu_run(out, sizeof(out), "x3g '%s' -o '%s' --printer flashforge-creator-pro", bad,
		    none);
	ck_assert_int_eq(rc, 65);
	ck_assert_msg(strstr(out, "bad.gcode: line 2"), "%s", out);
	ck_assert(!tu_file_exists(none));

	/* usage and a printer that does not speak X3G */
	ck_assert_int_eq(tu_run(out, sizeof(out), "x3g '%s'", in), 2);
	ck_assert_int_eq(tu_run(out, sizeof(out), "x3g '%s' -o '%s' --printer generic-marlin", in,
				none),
			 2);
	ck_assert_msg(strstr(out, "sailfish"), "%s", out);
	ck_assert_int_eq(tu_run(out, sizeof(out), "x3g '%s' -o '%s' --printer "
						  "flashforge-creator-pro --flavor klipper",
				in, none),
			 2);
	ck_assert(!tu_file_exists(none));

	/* --decode of a cut file names the offset of the cut command */
	b = slurp(x3g, &len);
	ck_assert_ptr_nonnull(b);
	tu_write(cut, b, len - 3);
	free(b);
	rc = tu_run(out, sizeof(out), "x3g --decode '%s'", cut);
	ck_assert_int_eq(rc, 65);
	ck_assert_msg(strstr(out, "byte "), "%s", out);
}
END_TEST

void x3g_gpx_tcases(Suite *s)
{
	TCase *dec = tcase_create("decode");
	TCase *gpx = tcase_create("gpx");

	tcase_add_test(dec, test_decode_fields);
	tcase_add_test(dec, test_decode_errors);
	tcase_add_test(dec, test_decode_roundtrip);
	suite_add_tcase(s, dec);

	tcase_set_timeout(gpx, 120);
	tcase_add_test(gpx, test_gpx_handwritten);
	tcase_add_test(gpx, test_gpx_sliced);
	tcase_add_test(gpx, test_gpx_prusaslicer);
	tcase_add_test(gpx, test_cli);
	suite_add_tcase(s, gpx);
}
