/*
 * sfcheck.c - Sailfish simulator log checks shared by suites (sfcheck.h).
 */
#include <check.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "profile_x3g.h"
#include "gcode.h"
#include "profile.h"
#include "sfcheck.h"
#include "testutil.h"
#include "x3g.h"

static char sfc_out[1 << 16];

json_t *sfc_reference(const char *gcode, const char *x3g, const char *dec, size_t min)
{
	json_error_t je;
	int rc = tu_run(sfc_out, sizeof(sfc_out), "x3g %s -o %s --printer " SFC_PRINTER, gcode,
			x3g);
	ck_assert_msg(rc == 0, "x3g: exit %d: %s", rc, sfc_out);
	rc = tu_run(sfc_out, sizeof(sfc_out), "x3g --decode %s --json >%s", x3g, dec);
	ck_assert_msg(rc == 0, "x3g --decode: exit %d: %s", rc, sfc_out);
	json_t *o = json_load_file(dec, 0, &je);
	ck_assert_msg(o != NULL, "%s: %s", dec, je.text);
	json_t *cmds = json_incref(json_object_get(o, "commands"));
	json_decref(o);
	ck_assert(json_is_array(cmds));
	ck_assert_uint_ge(json_array_size(cmds), min);
	return cmds;
}

/* A field of a decoded command as an integer. */
static long field(json_t *cmd, const char *name)
{
	json_t *v = json_object_get(json_object_get(cmd, "fields"), name);
	ck_assert_msg(json_is_number(v), "no field %s", name);
	return (long)json_number_value(v);
}

void sfc_check_log(FILE *f, json_t *cmds, bool fields)
{
	char line[512];

	for (size_t i = 0; i < json_array_size(cmds); i++) {
		unsigned long long seq;
		unsigned code;
		json_t *c = json_array_get(cmds, i);

		ck_assert_msg(fgets(line, sizeof(line), f), "only %zu of %zu commands executed", i,
			      json_array_size(cmds));
		ck_assert_msg(sscanf(line, "%llu %u", &seq, &code) == 2, "log line: %s", line);
		ck_assert_uint_eq(seq, i + 1);
		ck_assert_msg(code == json_integer_value(json_object_get(c, "code")),
			      "command %zu: code %u executed, %lld expected", i + 1, code,
			      (long long)json_integer_value(json_object_get(c, "code")));
		const char *p = strstr(line, " X=");
		if (fields && p) {
			long x, y, z, a, b;
			ck_assert_int_eq(sscanf(p, " X=%ld Y=%ld Z=%ld A=%ld B=%ld", &x, &y, &z, &a,
						&b), 5);
			ck_assert_msg(x == field(c, "x") && y == field(c, "y") && z == field(c, "z") &&
					      a == field(c, "a") && b == field(c, "b"),
				      "command %zu: %s", i + 1, line);
		}
		if (fields && code == 155) {
			p = strstr(line, " rate=");
			ck_assert_ptr_nonnull(p);
			ck_assert_int_eq(atol(p + 6), field(c, "dda_rate"));
		}
		if (fields && code == 136 && (p = strstr(line, " value=")))
			ck_assert_int_eq(atol(p + 7), field(c, "value"));
	}
}

/* One S3G command as the simulated Sailfish logs it: code and, for the
 * position commands, the five axes in steps. */
struct sfc_cmd {
	unsigned code;
	long pos[5];
	bool has_pos;
};

static bool sf_has_pos(unsigned code)
{
	return code == 139 || code == 140 || code == 142 || code == 155;
}

/*
 * The commands of `path` translated for the Creator Pro, each with its
 * G-code line; *start gets the index of the first command of line `from`
 * or later.
 */
static size_t sf_translate(const char *path, uint64_t from, struct sfc_cmd **cmds, size_t *start)
{
	struct profile *prof = NULL;
	struct x3g_machine m;
	struct x3g_options xo = {0};
	struct x3g_translator *t;
	struct gcode_reader *r;
	struct gcode_line g;
	struct st_error err = {0};
	size_t n = 0, cap = 0;
	FILE *f = fopen(path, "rb");
	int rc;

	*cmds = NULL;
	*start = SIZE_MAX;
	ck_assert_ptr_nonnull(f);
	ck_assert_int_eq(profile_find(SFC_PRINTER, &prof, &err), 0);
	ck_assert_int_eq(profile_x3g_machine(prof, &m, &xo.flavor, &err), 0);
	ck_assert_int_eq(x3g_new(&m, &xo, &t, &err), 0);
	ck_assert_int_eq(gcode_reader_new(f, path, &r, &err), 0);
	do {
		const uint8_t *b;
		size_t len, pos = 0;

		rc = gcode_reader_next(r, 0, &g, &err);
		ck_assert_msg(rc >= 0, "%s", err.msg);
		ck_assert_int_ge(rc ? x3g_translate(t, &g, gcode_reader_line(r), &err)
				    : x3g_finish(t, &err), 0);
		if (rc && gcode_reader_line(r) >= from && *start == SIZE_MAX)
			*start = n;
		b = x3g_output(t, &len);
		while (pos < len) {
			struct x3g_command c;
			int k = x3g_decode(b + pos, len - pos, 0, &c, &err);
			ck_assert_msg(k > 0, "%s", err.msg);
			if (n == cap) {
				cap = cap ? 2 * cap : 4096;
				*cmds = realloc(*cmds, cap * sizeof(**cmds));
				ck_assert_ptr_nonnull(*cmds);
			}
			(*cmds)[n] = (struct sfc_cmd){.code = c.code, .has_pos = sf_has_pos(c.code)};
			for (int i = 0; i < 5 && (*cmds)[n].has_pos; i++) {
				double v;
				ck_assert(x3g_field_value(&c, (const char[][2]){"x", "y", "z", "a",
									     "b"}[i], &v));
				(*cmds)[n].pos[i] = lround(v);
			}
			n++;
			pos += (size_t)k;
		}
	} while (rc == 1);
	gcode_reader_free(r);
	fclose(f);
	x3g_free(t);
	profile_free(prof);
	return n;
}

/* The simulated Sailfish's log: one command a line, numbered from 1. */
static size_t sf_log_read(const char *path, struct sfc_cmd **cmds, char (**text)[160])
{
	FILE *f = fopen(path, "r");
	char line[512];
	size_t n = 0, cap = 0;

	ck_assert_msg(f != NULL, "%s", path);
	*cmds = NULL;
	*text = NULL;
	while (fgets(line, sizeof(line), f)) {
		unsigned long long seq;
		const char *p;
		struct sfc_cmd c = {0};

		ck_assert_msg(sscanf(line, "%llu %u", &seq, &c.code) == 2, "log: %s", line);
		ck_assert_uint_eq(seq, n + 1);
		if ((c.has_pos = sf_has_pos(c.code))) {
			p = strstr(line, " X=");
			ck_assert_msg(p && sscanf(p, " X=%ld Y=%ld Z=%ld A=%ld B=%ld", &c.pos[0],
						  &c.pos[1], &c.pos[2], &c.pos[3], &c.pos[4]) == 5,
				      "log: %s", line);
		}
		if (n == cap) {
			cap = cap ? 2 * cap : 4096;
			*cmds = realloc(*cmds, cap * sizeof(**cmds));
			*text = realloc(*text, cap * sizeof(**text));
			ck_assert(*cmds && *text);
		}
		line[strcspn(line, "\n")] = '\0';
		snprintf((*text)[n], sizeof((*text)[n]), "%.159s", line);
		(*cmds)[n++] = c;
	}
	fclose(f);
	return n;
}

double sfc_check_resumed(const char *gcode, uint64_t from, const char *log)
{
	char (*text)[160];
	struct sfc_cmd *want, *got;
	size_t nwant, ngot, start, pre;
	double z = NAN;

	ck_assert_uint_gt(from, 0);
	nwant = sf_translate(gcode, from, &want, &start);
	ngot = sf_log_read(log, &got, &text);
	ck_assert_uint_lt(start, nwant);
	ck_assert_uint_gt(ngot, nwant - start);
	/* the file from that line on is exactly what ran after the preamble;
	 * the layer's first move may go where the preamble already put the
	 * nozzle (its Z), a move of no length the translator leaves out */
	pre = ngot - (nwant - start);
	if (got[pre].code != want[start].code && want[start].code == 155 && pre > 0) {
		long at[5] = {0};
		for (size_t i = 0; i < pre; i++)
			if (got[i].code == 155 || got[i].code == 140)
				memcpy(at, got[i].pos, sizeof(at));
		if (!memcmp(at, want[start].pos, 3 * sizeof(at[0]))) {
			start++;
			pre++;
		}
	}
	for (size_t i = 0; i < nwant - start; i++) {
		const struct sfc_cmd *a = &got[pre + i], *b = &want[start + i];
		ck_assert_msg(a->code == b->code, "command %zu after the preamble: executed %s, "
			      "the file gives %u", i, text[pre + i], b->code);
		/* X, Y, Z exact; the extruders within a step: the translator
		 * carries the rounding remainder of extruder steps from move to
		 * move, and the resumed translation starts without the
		 * remainder of the layers before */
		for (int k = 0; k < 5 && a->has_pos; k++)
			ck_assert_msg(labs(a->pos[k] - b->pos[k]) <= (k >= 3),
				      "command %zu after the preamble: "
				      "executed %s, the file gives axis %d = %ld", i, text[pre + i],
				      k, b->pos[k]);
	}
	/* the preamble: bed and nozzle waits, X/Y homed (never Z), a set
	 * position at the layer's Z, the calibrated X/Y home recalled */
	bool bed = false, nozzle = false, home = false, setpos = false, recall = false;
	for (size_t i = 0; i < pre; i++) {
		ck_assert_msg(got[i].code != 131, "homed to a minimum: %s", text[i]);
		if (got[i].code == 132) {
			ck_assert_msg(strstr(text[i], "axes=0x03"), "not X/Y only: %s", text[i]);
			home = true;
		}
		bed |= got[i].code == 141;
		nozzle |= got[i].code == 135 && home;
		recall |= got[i].code == 144 && home && strstr(text[i], "value=0x03");
		if (got[i].code == 140 && !home) {
			setpos = true;
			z = got[i].pos[2] / 400.0;
		}
	}
	ck_assert_msg(bed && nozzle && home && setpos && recall, "preamble: bed wait %d, nozzle "
		      "wait %d, X/Y home %d, set position %d, recall %d", bed, nozzle, home, setpos,
		      recall);
	free(want);
	free(got);
	free(text);
	return z;
}
