/*
 * resume.c - the state of a printer at a byte of a G-code file, and the
 * commands that restore it (resume.h).
 */
#include "resume.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "gcode.h"

/*
 * Relative moves and G92 can add up to positions no G-code line can carry
 * (the parser takes 15 significant digits, gcode.h); the preamble writes
 * them with up to 5 decimals (plus 2 mm of lift), so beyond RESUME_VALUE_MAX
 * its own lines would be refused or, cut at RESUME_LINE_MAX, mean another
 * place.  Refuse such a state instead of writing it.
 */
static int check_writable(const char *path, int64_t end, const struct resume_state *rs,
			  struct st_error *err)
{
	const struct {
		const char *what;
		double v;
	} vals[] = {
		{"X position", rs->x}, {"Y position", rs->y},	  {"Z position", rs->z},
		{"E position", rs->e}, {"feed rate", rs->f},	  {"nozzle target", rs->tool},
		{"bed target", rs->bed}, {"fan speed", rs->fan},
	};

	for (size_t i = 0; i < sizeof(vals) / sizeof(vals[0]); i++)
		if (!(fabs(vals[i].v) < RESUME_VALUE_MAX))
			return st_error_set(err, ST_ERR_RANGE, "%s: byte %lld: the %s is %g, "
							       "beyond the %g a resume can set; "
							       "the job cannot be resumed there",
					    path, (long long)end, vals[i].what, vals[i].v,
					    RESUME_VALUE_MAX);
	return 0;
}

/* Read path up to byte end and work out where the printer was. */
int resume_scan(const char *path, int64_t end, struct resume_state *rs,
		       struct st_error *err)
{
	FILE *f = fopen(path, "rb");
	struct gcode_reader *r;
	struct gcode_line g;
	int rc;

	memset(rs, 0, sizeof(*rs));
	rs->f = 1500;
	if (!f)
		return st_error_set(err, ST_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
	if ((rc = gcode_reader_new(f, path, &r, err))) {
		fclose(f);
		return rc;
	}
	while ((int64_t)gcode_reader_bytes(r) < end && (rc = gcode_reader_next(r, 0, &g, err)) == 1) {
		double v;

		if (g.letter == 'M') {
			if ((g.number == 104 || g.number == 109) && gcode_word_value(&g, 'S', &v))
				rs->tool = v;
			else if ((g.number == 140 || g.number == 190) && gcode_word_value(&g, 'S', &v))
				rs->bed = v;
			else if (g.number == 106)
				rs->fan = gcode_word_value(&g, 'S', &v) ? v : 255;
			else if (g.number == 107)
				rs->fan = 0;
			else if (g.number == 82 || g.number == 83)
				rs->rel_e = g.number == 83;
			continue;
		}
		if (g.letter != 'G')
			continue;
		if (g.number == 90 || g.number == 91) {
			rs->rel_xyz = rs->rel_e = g.number == 91;
		} else if (g.number == 92) {
			if (gcode_word_value(&g, 'X', &v)) rs->x = v;
			if (gcode_word_value(&g, 'Y', &v)) rs->y = v;
			if (gcode_word_value(&g, 'Z', &v)) rs->z = v;
			if (gcode_word_value(&g, 'E', &v)) rs->e = v;
		} else if (g.number == 28) {
			bool all = !gcode_find_word(&g, 'X') && !gcode_find_word(&g, 'Y') &&
				   !gcode_find_word(&g, 'Z');
			if (all || gcode_find_word(&g, 'X')) rs->x = 0;
			if (all || gcode_find_word(&g, 'Y')) rs->y = 0;
			if (all || gcode_find_word(&g, 'Z')) rs->z = 0;
		} else if (g.number >= 0 && g.number <= 3) {
			double *axis[4] = {&rs->x, &rs->y, &rs->z, &rs->e};
			const char *names = "XYZE";

			for (int i = 0; i < 4; i++) {
				bool rel = i == 3 ? rs->rel_e : rs->rel_xyz;

				if (gcode_word_value(&g, names[i], &v))
					*axis[i] = rel ? *axis[i] + v : v;
			}
			if (gcode_word_value(&g, 'F', &v))
				rs->f = v;
			rs->moved = true;
		}
	}
	gcode_reader_free(r);
	fclose(f);
	if (rc < 0)
		return rc;
	rs->z_nozzle = rs->z;
	return check_writable(path, end, rs, err);
}

int resume_locate(const char *path, int64_t offset, int64_t saved, struct resume_state *rs,
		  struct st_error *err)
{
	struct resume_state at;
	int rc = resume_scan(path, offset, rs, err);

	if (rc || saved <= offset)
		return rc;
	if ((rc = resume_scan(path, saved, &at, err)))
		return rc;
	rs->z_nozzle = at.z;
	return 0;
}

#define ADD(...) (n < cap ? (void)snprintf(out[n++], RESUME_LINE_MAX + 1, __VA_ARGS__) : (void)0)

/* Both preambles' end, from line n on: down to Z (down), modes, E (set_e),
 * feed rate, fan.  Returns the line count. */
static size_t resume_finish(const struct resume_state *rs, bool down, bool set_e,
			    char out[][RESUME_LINE_MAX + 1], size_t n, size_t cap)
{
	/* the layer's own Z move follows; never lower into what it printed */
	if (down)
		ADD("G1 Z%.3f F600", fmax(rs->z, rs->z_nozzle));
	ADD("%s", rs->rel_e ? "M83" : "M82");
	if (set_e)
		ADD("G92 E%.5f", rs->rel_e ? 0.0 : rs->e);
	if (rs->rel_xyz)
		ADD("G91");
	ADD("G1 F%.0f", rs->f);
	if (rs->fan > 0)
		ADD("M106 S%.0f", rs->fan);
	return n;
}

/* The restoring commands, in the order resume.h gives and why. */
size_t resume_preamble(const struct resume_state *rs, char out[][RESUME_LINE_MAX + 1],
			      size_t cap)
{
	size_t n = 0;

	if (rs->bed > 0) {
		ADD("M140 S%.0f", rs->bed);
		ADD("M190 S%.0f", rs->bed);
	}
	if (rs->tool > 0)
		ADD("M104 S%.0f", rs->tool);
	ADD("G92 Z%.3f", rs->z_nozzle);
	ADD("G91");
	ADD("G1 Z2 F600");
	ADD("G90");
	ADD("G28 X Y");
	if (rs->tool > 0)
		ADD("M109 S%.0f", rs->tool);
	if (rs->moved)
		ADD("G1 X%.3f Y%.3f F6000", rs->x, rs->y);
	return resume_finish(rs, true, true, out, n, cap);
}

/* The Sailfish form: what resume_preamble does, in the translator's words. */
size_t resume_preamble_x3g(const struct resume_state *rs, char out[][RESUME_LINE_MAX + 1],
			   size_t cap)
{
	size_t n = 0;

	ADD("M73 P0"); /* starts the build, as the file's start G-code did */
	if (rs->bed > 0)
		ADD("M190 S%.0f", rs->bed); /* sets the target too */
	if (rs->tool > 0)
		ADD("M104 S%.0f T0", rs->tool);
	ADD("G90");
	ADD("G92 X0 Y0 Z%.3f A0 B0", rs->z_nozzle);
	ADD("G1 Z%.3f F600", rs->z_nozzle + 2);
	ADD("G28 X Y");
	ADD("M132 X Y");
	if (rs->tool > 0)
		ADD("M133 T0");
	if (rs->moved)
		ADD("G1 X%.3f Y%.3f F6000", rs->x, rs->y);
	/* G92 E in relative mode would be one more set-position of all axes */
	return resume_finish(rs, true, !rs->rel_e, out, n, cap);
}
/* The way back after an operator's commands in a hold. */
size_t resume_return(const struct resume_state *rs, bool set_e, char out[][RESUME_LINE_MAX + 1],
		     size_t cap)
{
	size_t n = 0;

	/* before the file's first move there is no place to go back to */
	if (rs->moved) {
		ADD("G91");
		ADD("G1 Z2 F600");
		ADD("G90");
		ADD("G1 X%.3f Y%.3f F6000", rs->x, rs->y);
	} else {
		ADD("G90");
	}
	return resume_finish(rs, rs->moved, set_e, out, n, cap);
}
#undef ADD

int resume_x3g_text(const char *path, int64_t offset, int64_t saved,
		    char buf[RESUME_TEXT_MAX], struct st_error *err)
{
	char pre[RESUME_LINES][RESUME_LINE_MAX + 1];
	struct resume_state rs;
	size_t n, len = 0;
	int rc = resume_locate(path, offset, saved, &rs, err);

	buf[0] = '\0';
	if (rc)
		return rc;
	n = resume_preamble_x3g(&rs, pre, RESUME_LINES);
	for (size_t i = 0; i < n && len < RESUME_TEXT_MAX; i++)
		len += (size_t)snprintf(buf + len, RESUME_TEXT_MAX - len, "%s\n", pre[i]);
	return 0;
}

int resume_layer_start(const char *path, int64_t pos, int64_t *offset, long *layer,
		       struct st_error *err)
{
	FILE *f = fopen(path, "rb");
	struct gcode_reader *r;
	struct gcode_line g;
	int64_t before = 0;
	long num = -1;
	int rc;

	*offset = 0;
	*layer = -1;
	if (!f)
		return st_error_set(err, ST_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
	if ((rc = gcode_reader_new(f, path, &r, err))) {
		fclose(f);
		return rc;
	}
	/* a layer whose comment starts before pos has its comment line done */
	while ((rc = gcode_reader_next(r, 0, &g, err)) == 1) {
		long l;

		if (gcode_layer_comment(&g, &l, NULL) == GCODE_LAYER_START) {
			num = l >= 0 ? l : num + 1;
			if (*layer >= 0 && before >= pos)
				break;
			*offset = before;
			*layer = num;
		}
		before = (int64_t)gcode_reader_bytes(r);
	}
	gcode_reader_free(r);
	fclose(f);
	if (rc < 0)
		return rc;
	if (*layer < 0)
		return st_error_set(err, ST_ERR_PARSE, "%s has no layer comments; cannot tell "
				    "where to resume", path);
	return 0;
}
