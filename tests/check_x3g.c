/*
 * check_x3g.c - serial/x3g.c: the bytes of each translated G-code command,
 * worked out by hand from the s3g command layouts and GPX's arithmetic
 * (docs/protocols.md section 2) for the FlashForge Creator Pro; flavours, tools,
 * warnings; the decoder's checks on truncated and unknown input; and, when
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

#define OUT_MAX 4096

/* Bytes of a little-endian int32 / uint16, for writing expected payloads. */
#define LE32(v) (uint8_t)((uint32_t)(v)&0xff), (uint8_t)(((uint32_t)(v) >> 8) & 0xff), \
		(uint8_t)(((uint32_t)(v) >> 16) & 0xff), (uint8_t)(((uint32_t)(v) >> 24) & 0xff)
#define LE16(v) (uint8_t)((v)&0xff), (uint8_t)(((v) >> 8) & 0xff)

struct tr {
	struct x3g_translator *t;
	uint8_t out[OUT_MAX];
	size_t len;
	size_t warnings;
	char warning[X3G_WARNING_MAX];
	uint64_t warning_line;
};

static void tr_open(struct tr *r, enum x3g_flavor flavor)
{
	struct x3g_machine m;
	struct x3g_options opt = {flavor, "part"};
	struct st_error err = {0};

	memset(r, 0, sizeof(*r));
	x3g_machine_fcp(&m);
	ck_assert_msg(x3g_new(&m, &opt, &r->t, &err) == 0, "x3g_new: %s", err.msg);
}

/* Collect the output and the warnings of the last call. */
static void tr_collect(struct tr *r)
{
	const struct x3g_warning *w;
	size_t n, nw = x3g_warnings(r->t, &w);
	const uint8_t *b = x3g_output(r->t, &n);

	ck_assert_uint_le(r->len + n, OUT_MAX);
	memcpy(r->out + r->len, b, n);
	r->len += n;
	if (nw) {
		snprintf(r->warning, sizeof(r->warning), "%s", w[nw - 1].msg);
		r->warning_line = w[nw - 1].line;
	}
	r->warnings += nw;
}

/* Translate each line of text (lines numbered from 1), appending output. */
static void tr_lines(struct tr *r, const char *text)
{
	uint64_t no = 0;

	while (*text) {
		const char *nl = strchr(text, '\n');
		size_t n = nl ? (size_t)(nl - text) : strlen(text);
		struct gcode_line l;
		struct st_error err = {0};

		no++;
		ck_assert_msg(gcode_parse(text, n, 0, &l, &err) == 0, "%.*s: %s", (int)n, text,
			      err.msg);
		ck_assert_int_ge(x3g_translate(r->t, &l, no, &err), 0);
		tr_collect(r);
		text += n + (nl ? 1 : 0);
	}
}

/* Translate text from a fresh translator and compare with want. */
static void expect(enum x3g_flavor flavor, const char *text, const uint8_t *want, size_t n)
{
	struct tr r;

	tr_open(&r, flavor);
	tr_lines(&r, text);
	ck_assert_msg(r.len == n, "\"%s\": %zu bytes, wanted %zu", text, r.len, n);
	for (size_t i = 0; i < n; i++)
		ck_assert_msg(r.out[i] == want[i], "\"%s\": byte %zu is %u, wanted %u", text, i,
			      r.out[i], want[i]);
	ck_assert_msg(r.warnings == 0, "\"%s\": unexpected warning: %s", text, r.warning);
	x3g_free(r.t);
}

#define EXPECT(flavor, text, ...)                                                    \
	do {                                                                         \
		static const uint8_t want_[] = {__VA_ARGS__};                          \
		expect((flavor), (text), want_, sizeof(want_));                      \
	} while (0)
#define RR X3G_FLAVOR_REPRAP
#define MB X3G_FLAVOR_MAKERBOT

/* All five axes at 0 and known, so moves take the 155 path. */
#define ZERO "G92 X0 Y0 Z0 A0 B0\n"
#define ZERO_BYTES 140, LE32(0), LE32(0), LE32(0), LE32(0), LE32(0)

START_TEST(test_simple_commands)
{
	/* 133 delay, uint32 ms */
	EXPECT(RR, "G4 P250", 133, LE32(250));
	/* 136 tool action 3 (nozzle target), payload int16 */
	EXPECT(RR, "M104 S210 T0", 136, 0, 3, 2, LE16(210));
	/* NOZZLE_MAX 280 */
	EXPECT(RR, "M104 S300", 136, 0, 3, 2, LE16(280));
	/* 136 action 31 (platform target) */
	EXPECT(RR, "M140 S60", 136, 0, 31, 2, LE16(60));
	/* RepRap M109: set, then 135 wait (poll 100 ms, no timeout = 65535 s) */
	EXPECT(RR, "M109 S215", 136, 0, 3, 2, LE16(215), 135, 0, LE16(100), LE16(0xffff));
	EXPECT(RR, "M109 S215 P30", 136, 0, 3, 2, LE16(215), 135, 0, LE16(100), LE16(30));
	/* M190: set and 141 wait for the platform */
	EXPECT(RR, "M190 S60", 136, 0, 31, 2, LE16(60), 141, 0, LE16(100), LE16(0xffff));
	/* M116 waits for what was set: the platform, then nozzle B, then A */
	EXPECT(RR, "M140 S50\nM104 S200 T1\nM104 S190 T0\nM116", 136, 0, 31, 2, LE16(50), 136,
	       1, 3, 2, LE16(200), 136, 0, 3, 2, LE16(190), 141, 0, LE16(100), LE16(0xffff),
	       135, 1, LE16(100), LE16(0xffff), 135, 0, LE16(100), LE16(0xffff));
	/* fans: RepRap flavour drives the blower (13), Makerbot the fan (12) */
	EXPECT(RR, "M106", 136, 0, 13, 1, 1);
	EXPECT(RR, "M106 S0", 136, 0, 13, 1, 0);
	EXPECT(RR, "M107", 136, 0, 13, 1, 0);
	EXPECT(MB, "M106 S255", 136, 0, 12, 1, 1);
	EXPECT(MB, "M107", 136, 0, 12, 1, 0);
	EXPECT(RR, "M127", 136, 0, 13, 1, 0);
	/* 137: bit 7 enables; no axes = all five on a two-extruder machine */
	EXPECT(RR, "M17", 137, 0x9f);
	EXPECT(RR, "M18", 137, 0x1f);
	EXPECT(RR, "M84", 137, 0x1f);
	EXPECT(RR, "M18 X Y", 137, 0x03);
	EXPECT(RR, "M17 Z E", 137, 0x84 | 0x08);
	/* 140 set extended position: round(mm x steps/mm) */
	EXPECT(RR, "G92 X10 Y20 Z5 A0 B0", 140, LE32(941), LE32(1882), LE32(2000), LE32(0),
	       LE32(0));
	EXPECT(RR, ZERO "G92 E2", ZERO_BYTES, 140, LE32(0), LE32(0), LE32(0), LE32(193),
	       LE32(0));
	/* M132 -> 144 recall home positions with the axes bitfield */
	EXPECT(RR, "M132 X Y Z A B", 144, 0x1f);
	EXPECT(RR, "M72 P1", 151, 1);
	EXPECT(RR, "M300 S440 P200", 147, LE16(440), LE16(200), 0);
	EXPECT(RR, "M320\nM321", 156, 1, 156, 0);
	/* modes and millimetres write nothing */
	expect(RR, "G21\nG90\nG91\nM82\nM83\nM110 N0\nM400", NULL, 0);
}
END_TEST

START_TEST(test_homing)
{
	/*
	 * 131/132: uint8 axes, uint32 us per step, uint16 timeout 20 s.
	 * X and Y at 2500 mm/min: sqrt(2) mm / 2500 mm/min = 33941.1 us over
	 * 94.117647 steps = 360.6 -> 361.  Z at 1100: 54545.5 us / 400 = 136.4
	 * -> 136; at F100: 600000 / 400 = 1500.
	 */
	EXPECT(RR, "G162 X Y F2500", 132, 0x03, LE32(361), LE16(20));
	EXPECT(RR, "G161 Z F1100", 131, 0x04, LE32(136), LE16(20));
	EXPECT(RR, "G161 Z F100", 131, 0x04, LE32(1500), LE16(20));
	/* no F: the fastest homing rate of the axes named, capped per axis */
	EXPECT(RR, "G161 Z", 131, 0x04, LE32(136), LE16(20));
	/* G28: X and Y to their maximum first, then Z to its minimum */
	EXPECT(RR, "G28", 132, 0x03, LE32(361), LE16(20), 131, 0x04, LE32(136), LE16(20));
	/* X alone at 2500: 24000 us / 94.117647 = 255.0 */
	EXPECT(RR, "G28 X", 132, 0x01, LE32(255), LE16(20));
}
END_TEST

START_TEST(test_moves)
{
	/*
	 * 155: X 10 mm at F600 = 10 mm/s: 941 steps in 1 s -> 941 steps/s;
	 * relative bits A|B (0x18); distance 10.0f = 0x41200000; 10 mm/s x 64.
	 */
	EXPECT(RR, ZERO "G1 X10 F600", ZERO_BYTES, 155, LE32(941), LE32(0), LE32(0), LE32(0),
	       LE32(0), LE32(941), 0x18, LE32(0x41200000), LE16(640));
	/* a bare F keeps the feed rate (F600), as in Marlin */
	EXPECT(RR, ZERO "G1 F600\nG1 X10 F", ZERO_BYTES, 155, LE32(941), LE32(0), LE32(0),
	       LE32(0), LE32(0), LE32(941), 0x18, LE32(0x41200000), LE16(640));
	/* G0 is G1 in GPX: the current feed rate, not the maximum */
	EXPECT(RR, ZERO "G1 F600\nG0 X10", ZERO_BYTES, 155, LE32(941), LE32(0), LE32(0),
	       LE32(0), LE32(0), LE32(941), 0x18, LE32(0x41200000), LE16(640));
	/*
	 * Relative E: 1 mm = 96.2752 steps -> -96 (extruder steps are negated),
	 * the 0.2752 carried; the second mm gives -96.5504 -> -97, so the two
	 * moves total round(192.5504) = 193 steps.
	 */
	EXPECT(RR, ZERO "M83\nG1 X10 E1 F600\nG1 X20 E1", ZERO_BYTES, 155, LE32(941), LE32(0),
	       LE32(0), LE32(-96), LE32(0), LE32(941), 0x18, LE32(0x41200000), LE16(640), 155,
	       LE32(1882), LE32(0), LE32(0), LE32(-97), LE32(0), LE32(941), 0x18,
	       LE32(0x41200000), LE16(640));
	/* absolute E (M82) gives the same deltas */
	EXPECT(RR, ZERO "M82\nG1 X10 E1 F600\nG1 X20 E2", ZERO_BYTES, 155, LE32(941), LE32(0),
	       LE32(0), LE32(-96), LE32(0), LE32(941), 0x18, LE32(0x41200000), LE16(640), 155,
	       LE32(1882), LE32(0), LE32(0), LE32(-97), LE32(0), LE32(941), 0x18,
	       LE32(0x41200000), LE16(640));
	/*
	 * Extruder only, 2 mm at F600 (under A's 1600 mm/min): 193 steps in
	 * 0.2 s = 965 steps/s; distance 2.0f = 0x40000000.
	 */
	EXPECT(RR, ZERO "M83\nG1 E2 F600", ZERO_BYTES, 155, LE32(0), LE32(0), LE32(0),
	       LE32(-193), LE32(0), LE32(965), 0x18, LE32(0x40000000), LE16(640));
	/*
	 * Z over its 1170 mm/min maximum: 1 mm asked at F6000 runs at 1170 =
	 * 19.5 mm/s: 400 steps in 1/19.5 s = 7800 steps/s; 19.5 x 64 = 1248.
	 */
	EXPECT(RR, ZERO "G1 Z1 F6000", ZERO_BYTES, 155, LE32(0), LE32(0), LE32(400), LE32(0),
	       LE32(0), LE32(7800), 0x18, LE32(0x3f800000), LE16(1248));
	/* G91: X, Y, Z relative too: every relative bit set, steps as deltas */
	EXPECT(RR, ZERO "G91\nG1 X10 F600\nG1 X10", ZERO_BYTES, 155, LE32(941), LE32(0),
	       LE32(0), LE32(0), LE32(0), LE32(941), 0x1f, LE32(0x41200000), LE16(640), 155,
	       LE32(941), LE32(0), LE32(0), LE32(0), LE32(0), LE32(941), 0x1f,
	       LE32(0x41200000), LE16(640));
	/* shorter than a step on every axis: nothing (GPX drops it too) */
	EXPECT(RR, ZERO "G1 X0.001 F600", ZERO_BYTES);
	/* G10 P1 offset applied under G54 */
	EXPECT(RR, ZERO "G10 P1 X10\nG54\nG1 X0 F600", ZERO_BYTES, 155, LE32(941), LE32(0),
	       LE32(0), LE32(0), LE32(0), LE32(941), 0x18, LE32(0x41200000), LE16(640));
	/* M220 S50 halves the feed rate */
	EXPECT(RR, ZERO "M220 S50\nG1 X10 F1200", ZERO_BYTES, 155, LE32(941), LE32(0), LE32(0),
	       LE32(0), LE32(0), LE32(941), 0x18, LE32(0x41200000), LE16(640));
}
END_TEST

/* Little-endian int32 at b. */
static int32_t le32_at(const uint8_t *b)
{
	return (int32_t)((uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 |
			 (uint32_t)b[3] << 24);
}

/* G2/G3, which X3G has no command for, become the chords Marlin cuts
 * them into (1 mm): a quarter of radius 10 mm is 15 points on the circle,
 * the last on the target, E spread over them; clockwise back the same. */
START_TEST(test_arcs_in_chords)
{
	static const char *const arcs[] = {"G3 X0 Y10 I-10 J0 E1", "G2 X0 Y10 R10 E1"};
	const double spm = 941 / 10.0; /* X and Y steps per mm (Creator Pro) */

	for (size_t a = 0; a < 2; a++) {
		struct tr r;
		char text[200];
		int points = 0;
		int32_t e = 0;
		size_t at = 21; /* past the G92's 140 */

		snprintf(text, sizeof(text), ZERO "M83\nG1 X10 F600\n%s", arcs[a]);
		tr_open(&r, RR);
		tr_lines(&r, text);
		ck_assert_msg(r.warnings == 0, "%s: %s", arcs[a], r.warning);
		at += 32; /* the G1 */
		for (; at + 32 <= r.len && r.out[at] == 155; at += 32, points++) {
			double x = le32_at(r.out + at + 1) / spm, y = le32_at(r.out + at + 5) / spm;
			double cy = a == 0 ? 0 : 10, cx = a == 0 ? 0 : 10;
			e += le32_at(r.out + at + 13);
			ck_assert_msg(fabs(hypot(x - cx, y - cy) - 10) < 0.02, "%s: point %d at %g %g",
				      arcs[a], points, x, y);
		}
		ck_assert_uint_eq(at, r.len);
		ck_assert_msg(points == 15, "%s: %d points", arcs[a], points);
		ck_assert_int_eq(le32_at(r.out + at - 32 + 1), 0);
		ck_assert_int_eq(le32_at(r.out + at - 32 + 5), 941);
		ck_assert_int_eq(e, -96);
		x3g_free(r.t);
	}
}
END_TEST

START_TEST(test_unknown_positions)
{
	/*
	 * At the start only the extruders are known.  A move naming every
	 * unknown axis is a 139 with absolute steps and a fixed DDA: X at
	 * F600 needs 60e6 / (94.117647 x 600) = 1062.5 -> 1062 us per step,
	 * slower than Z's 250, and than the 35 us floor.
	 */
	EXPECT(RR, "G1 X1 Y1 Z1 F600", 139, LE32(94), LE32(94), LE32(400), LE32(0), LE32(0),
	       LE32(1062));
	/* Z alone: X and Y stay unknown, so 155 with X and Y relative (0) */
	EXPECT(RR, "G1 Z20 F1100", 155, LE32(0), LE32(0), LE32(8000), LE32(0), LE32(0),
	       LE32(7333), 0x1b, LE32(0x41a00000), LE16(1173));
}
END_TEST

START_TEST(test_tools)
{
	/* a tool change with the position known: 134, then a 139 to where
	 * the head is (the firmware applies the offset there), DDA floor 35 */
	EXPECT(RR, ZERO "T1", ZERO_BYTES, 134, 1, 139, LE32(0), LE32(0), LE32(0), LE32(0),
	       LE32(0), LE32(35));
	/* E goes to B on tool 1: 2 mm = 193 steps */
	EXPECT(RR, ZERO "T1\nM83\nG1 E2 F600", ZERO_BYTES, 134, 1, 139, LE32(0), LE32(0),
	       LE32(0), LE32(0), LE32(0), LE32(35), 155, LE32(0), LE32(0), LE32(0), LE32(0),
	       LE32(-193), LE32(965), 0x18, LE32(0x40000000), LE16(640));
	/* no position known: 134 only; selecting the current tool: nothing */
	EXPECT(RR, "T1", 134, 1);
	expect(RR, "T0", NULL, 0);
	EXPECT(RR, "M6 T1", 134, 1);
	/* G10 P2 S: tool 1's active temperature is set on the change */
	EXPECT(RR, "G10 P2 S220\nT1", 136, 1, 3, 2, LE16(220), 134, 1);
	/* RepRap: T on M104 selects the tool for later lines; Makerbot: not */
	EXPECT(RR, "M104 S200 T1\nM104 S190", 136, 1, 3, 2, LE16(200), 136, 1, 3, 2, LE16(190));
	EXPECT(MB, "M104 S200 T1\nM104 S190", 136, 1, 3, 2, LE16(200), 136, 0, 3, 2, LE16(190));
	/* Makerbot M109 sets the platform */
	EXPECT(MB, "M109 S60", 136, 0, 31, 2, LE16(60));
}
END_TEST

START_TEST(test_build_and_messages)
{
	/* M73 P0: 153 (uint32 0, name, NUL), 150 0%, 134 current tool */
	EXPECT(RR, "M73 P0", 153, LE32(0), 'p', 'a', 'r', 't', 0, 150, 0, 0, 134, 0);
	/* progress only goes up; P100 closes the build */
	EXPECT(RR, "M73 P0\nM73 P50\nM73 P40\nM73 P100", 153, LE32(0), 'p', 'a', 'r', 't', 0,
	       150, 0, 0, 134, 0, 150, 50, 0, 150, 100, 0, 154, 0);
	EXPECT(RR, "M136\nM137", 153, LE32(0), 'p', 'a', 'r', 't', 0, 150, 0, 0, 134, 0, 150,
	       100, 0, 154, 0);
	/* 149: options (bit 1 = last part), x, y, timeout, text, NUL */
	EXPECT(RR, "M70 P5 (Hello)", 149, 0x02, 0, 0, 5, 'H', 'e', 'l', 'l', 'o', 0);
	EXPECT(RR, "M70 X2 Y1 ;Hi", 149, 0x03, 2, 1, 0, 'H', 'i', 0);
	/* 25 characters: a row of 20, then 5 with "keep the screen" */
	EXPECT(RR, "M70 (abcdefghijklmnopqrstuvwxy)", 149, 0x00, 0, 0, 0, 'a', 'b', 'c', 'd', 'e',
	       'f', 'g', 'h', 'i', 'j', 'k', 'l', 'm', 'n', 'o', 'p', 'q', 'r', 's', 't', 0, 149,
	       0x03, 0, 0, 0, 'u', 'v', 'w', 'x', 'y', 0);
	/* M71 waits for the button (bit 2) */
	EXPECT(RR, "M71 (Go)", 149, 0x06, 0, 0, 0, 'G', 'o', 0);
}
END_TEST

START_TEST(test_finish_and_m2)
{
	struct tr r;
	struct st_error err = {0};

	/* a file with no build notification still ends one, as gpx does */
	tr_open(&r, RR);
	ck_assert_int_eq(x3g_finish(r.t, &err), 2);
	tr_collect(&r);
	ck_assert_uint_eq(r.len, 5);
	ck_assert_int_eq(memcmp(r.out, (uint8_t[]){150, 100, 0, 154, 0}, 5), 0);
	x3g_free(r.t);

	/* M2 ends it; later lines are ignored with a warning; finish adds nothing */
	tr_open(&r, RR);
	tr_lines(&r, "M2\nG4 P10");
	ck_assert_uint_eq(r.len, 5);
	ck_assert_uint_eq(r.warnings, 1);
	ck_assert_uint_eq(r.warning_line, 2);
	ck_assert_int_eq(x3g_finish(r.t, &err), 0);
	x3g_free(r.t);
}
END_TEST

START_TEST(test_warnings)
{
	static const char *const lines[] = {"M115", "G29", "M117 Hello", "G4", "M104",
					    "T5",   "G2 X1 Y1 I1", "G162 F100", "M132"};
	struct tr r;

	for (size_t i = 0; i < sizeof(lines) / sizeof(lines[0]); i++) {
		tr_open(&r, RR);
		tr_lines(&r, "G21\n; comment\n");
		tr_lines(&r, lines[i]);
		ck_assert_msg(r.len == 0, "%s wrote %zu bytes", lines[i], r.len);
		ck_assert_msg(r.warnings == 1, "%s: %zu warnings", lines[i], r.warnings);
		/* the caller's line number: lines restart at 1 per tr_lines call */
		ck_assert_uint_eq(r.warning_line, 1);
		ck_assert_uint_eq(x3g_warning_total(r.t), 1);
		x3g_free(r.t);
	}
	tr_open(&r, RR);
	tr_lines(&r, "M115");
	ck_assert_msg(strstr(r.warning, "M115"), "message does not name the command: %s",
		      r.warning);
	x3g_free(r.t);
}
END_TEST

/* What Marlin and Prusa's firmware accept but X3G cannot express is warned
 * about, naming the command and the line, as GPX does (issue 18). */
START_TEST(test_firmware_texts)
{
	static const struct {
		const char *line, *warning;
		size_t warnings;
	} cases[] = {
	    {"M115 U3.11.0 ; tell printer latest fw version", "M115 is not supported", 1},
	    {"M862.3 P \"MK3S\" ; printer model check", "M862.3 is not supported", 1},
	    {"M862.1 P0.4", "M862.1 is not supported", 1},
	    {"M117 Bed: 60\xc2\xb0" "C", "M117 is not supported", 1},
	    {"M0 Click to continue", "M0 is not supported", 1},
	    {"M1 Change filament", "M1 is not supported", 1},
	    {"M900 K0.05", "M900 is not supported", 1},
	    {"M73 Q0 S37", "M73 without P", 1},
	    {"G80", "G80 is not supported", 1},
	    {"G29", "G29 is not supported", 1},
	    {"T?", "T? (a Prusa MMU filament command) is not supported", 1},
	    {"Tc", "Tc (a Prusa MMU", 1},
	    /* Klipper's macros, a toolchanger's bare T, text (issue 18) */
	    {"print_start EXTRUDER=215 BED=60", "'print_start EXTRUDER=215 BED=60' is not a G, M", 1},
	    {"BED_MESH_CALIBRATE ; mesh", "'BED_MESH_CALIBRATE' is not a G, M or T command", 1},
	    {"T", "'T' is not a G, M or T command", 1},
	    {"Start printing", "X3G cannot express it", 1},
	    /* GPX: "T1250 cannot select non-existant extruder", then M204 */
	    {"M204 P1250 R1250 T1250", "M204 is not supported", 2},
	};
	struct tr r;

	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		const struct x3g_warning *w;

		tr_open(&r, RR);
		tr_lines(&r, cases[i].line);
		ck_assert_msg(r.len == 0, "%s wrote %zu bytes", cases[i].line, r.len);
		ck_assert_msg(r.warnings == cases[i].warnings, "%s: %zu warnings", cases[i].line,
			      r.warnings);
		ck_assert_msg(strstr(r.warning, cases[i].warning), "%s: %s", cases[i].line,
			      r.warning);
		ck_assert_uint_eq(r.warning_line, 1);
		if (cases[i].warnings == 2) {
			ck_assert_uint_eq(x3g_warnings(r.t, &w), 2);
			ck_assert_msg(strstr(w[0].msg, "T1250: this printer has 2 extruders"), "%s",
				      w[0].msg);
		}
		x3g_free(r.t);
	}
}
END_TEST

START_TEST(test_bad_machine)
{
	struct x3g_machine m;
	struct x3g_translator *t = (void *)1;
	struct st_error err = {0};

	x3g_machine_fcp(&m);
	m.axis[2].steps_per_mm = 0;
	ck_assert_int_eq(x3g_new(&m, NULL, &t, &err), ST_ERR_ARG);
	ck_assert_ptr_null(t);
	ck_assert_ptr_nonnull(strstr(err.msg, "Z steps per mm"));
	x3g_machine_fcp(&m);
	m.extruder_count = 3;
	ck_assert_int_eq(x3g_new(&m, NULL, &t, &err), ST_ERR_ARG);
	x3g_machine_fcp(&m);
	m.axis[3].max_feedrate = NAN;
	ck_assert_int_eq(x3g_new(&m, NULL, &t, &err), ST_ERR_ARG);
	x3g_free(NULL);
}
END_TEST

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

Suite *x3g_suite(void)
{
	Suite *s = suite_create("x3g");
	TCase *tr = tcase_create("translate");
	TCase *dec = tcase_create("decode");
	TCase *gpx = tcase_create("gpx");

	tcase_add_test(tr, test_simple_commands);
	tcase_add_test(tr, test_homing);
	tcase_add_test(tr, test_moves);
	tcase_add_test(tr, test_arcs_in_chords);
	tcase_add_test(tr, test_unknown_positions);
	tcase_add_test(tr, test_tools);
	tcase_add_test(tr, test_build_and_messages);
	tcase_add_test(tr, test_finish_and_m2);
	tcase_add_test(tr, test_warnings);
	tcase_add_test(tr, test_firmware_texts);
	tcase_add_test(tr, test_bad_machine);
	suite_add_tcase(s, tr);

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
	return s;
}
