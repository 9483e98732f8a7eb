/*
 * check_x3g.c - serial/x3g.c: the bytes of each translated G-code command,
 * worked out by hand from the s3g command layouts and GPX's arithmetic
 * (docs/protocols.md section 2) for the FlashForge Creator Pro; flavours, tools,
 * warnings.  The decoder and the comparison with gpx are in check_x3g_gpx.c,
 * the translator rig in x3gtest.c.
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
Suite *x3g_suite(void)
{
	Suite *s = suite_create("x3g");
	TCase *tr = tcase_create("translate");

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

	x3g_gpx_tcases(s);
	return s;
}
