/*
 * gcinfo.c - what a G-code file says of itself, for /api/job and the file
 * entries (node_int.h): the slicer's print-time estimate and filament, as
 * PrusaSlicer and Stratum write them ("; estimated printing time = 1h 2m
 * 3s", "; filament used [mm] = 810.5", "... [cm3] = 5.36") or Cura does
 * (";TIME:1188", ";Filament used: 0.81m"), and the M73 R marks (minutes
 * left) that give the time left at a byte of the file.  Read once per file
 * and kept per printer until the file changes.
 */
#include <stdio.h>
#include <sys/types.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "gcode.h"
#include "node_int.h"
#include "st_grow.h"
#include "st_number.h"

#define GCINFO_HEAD (64 << 10)  /* bytes read at the start for a summary */
#define GCINFO_TAIL (256 << 10) /* and at the end (PrusaSlicer's footer, config after it) */

/* The number at the start of s (digits and one '.'), or -1. */
static double lead_number(const char *s)
{
	size_t n = 0;
	double v;

	while (s[n] == ' ')
		s++;
	while ((s[n] >= '0' && s[n] <= '9') || s[n] == '.')
		n++;
	return st_parse_double(s, n, 0, &v) == ST_NUMBER_OK ? v : -1;
}

/* After "prefix" at the start of line, or NULL. */
static const char *after(const char *line, const char *prefix)
{
	size_t n = strlen(prefix);

	return strncmp(line, prefix, n) ? NULL : line + n;
}

/* Read one comment or M73 line of the file at offset pos into g. */
static int take_line(struct node_gcode_info *g, const char *line, int64_t pos, size_t *cap)
{
	const char *v;

	while (*line == ' ' || *line == '\t')
		line++;
	if (!strncmp(line, "M73 ", 4)) {
		const char *r = strstr(line, " R");
		const char *semi = strchr(line, ';');
		double m;

		if (!r || (semi && r > semi) || (m = lead_number(r + 2)) < 0)
			return 0;
		struct node_gcode_mark *mk = st_grow(g->marks, cap, g->nmarks + 1, sizeof(*mk));
		if (!mk)
			return -1;
		g->marks = mk;
		mk[g->nmarks].pos = pos;
		mk[g->nmarks++].left_s = m * 60;
		return 0;
	}
	if (*line != ';')
		return 0;
	if ((v = after(line, "; estimated printing time (normal mode) = ")) ||
	    (v = after(line, "; estimated printing time = ")))
		g->time_s = st_parse_duration(v);
	else if ((v = after(line, ";TIME:")))
		g->time_s = lead_number(v);
	else if ((v = after(line, "; filament used [mm] = ")))
		g->filament_mm = lead_number(v);
	else if ((v = after(line, "; filament used [cm3] = ")))
		g->filament_cm3 = lead_number(v);
	else if ((v = after(line, ";Filament used: ")) && lead_number(v) >= 0)
		g->filament_mm = lead_number(v) * 1000; /* Cura: metres */
	return 0;
}

/* Read the lines of path from byte from to byte to (-1: the end) into g;
 * a line cut at from is skipped. */
static void read_lines(FILE *f, int64_t from, int64_t to, struct node_gcode_info *g, size_t *cap)
{
	char *line = NULL;
	size_t len = 0;
	int64_t pos = from;
	ssize_t got;

	if (fseeko(f, from, SEEK_SET))
		return;
	if (from > 0 && (got = getline(&line, &len, f)) > 0)
		pos += got; /* the rest of a line begun before from */
	while ((to < 0 || pos < to) && (got = getline(&line, &len, f)) > 0) {
		if (take_line(g, line, pos, cap))
			break;
		pos += got;
	}
	free(line);
}

/* Read the file at path into g: whole with marks (the M73 marks are all
 * through it), else its head and tail only. */
static void read_info(const char *path, struct node_gcode_info *g, bool marks)
{
	FILE *f = fopen(path, "r");
	size_t cap = 0;

	g->time_s = g->filament_mm = g->filament_cm3 = -1;
	if (!f)
		return;
	if (marks || g->size <= GCINFO_HEAD + GCINFO_TAIL) {
		read_lines(f, 0, -1, g, &cap);
	} else {
		read_lines(f, 0, GCINFO_HEAD, g, &cap);
		read_lines(f, g->size - GCINFO_TAIL, -1, g, &cap);
	}
	if (!marks) {
		free(g->marks);
		g->marks = NULL;
		g->nmarks = 0;
	}
	fclose(f);
}

void node_gcode_summary(const char *path, struct node_gcode_estimate *out)
{
	struct node_gcode_info g = {0};
	struct stat st;

	out->time_s = out->filament_mm = out->filament_cm3 = out->left_s = -1;
	if (node_file_kind(path) != 'g' || stat(path, &st))
		return;
	g.size = st.st_size;
	read_info(path, &g, false);
	out->time_s = g.time_s;
	out->filament_mm = g.filament_mm;
	out->filament_cm3 = g.filament_cm3;
}

void node_gcode_estimate(struct node_printer *p, const char *path, int64_t filepos,
			 struct node_gcode_estimate *out)
{
	struct node_gcode_info *g = &p->gc;
	struct stat st;

	out->time_s = out->filament_mm = out->filament_cm3 = out->left_s = -1;
	if (!path || !path[0] || node_file_kind(path) != 'g' || stat(path, &st))
		return;
	pthread_mutex_lock(&p->gc_mu);
	if (strcmp(g->path, path) || g->mtime != st.st_mtime || g->size != st.st_size) {
		free(g->marks);
		memset(g, 0, sizeof(*g));
		snprintf(g->path, sizeof(g->path), "%s", path);
		g->mtime = st.st_mtime;
		g->size = st.st_size;
		read_info(path, g, true);
	}
	out->time_s = g->time_s;
	out->filament_mm = g->filament_mm;
	out->filament_cm3 = g->filament_cm3;
	/* the last mark the stream has passed; before the first, the whole time */
	for (size_t i = 0; i < g->nmarks && g->marks[i].pos < filepos; i++)
		out->left_s = g->marks[i].left_s;
	if (out->left_s < 0 && g->nmarks && filepos >= 0)
		out->left_s = g->marks[0].left_s;
	pthread_mutex_unlock(&p->gc_mu);
}

void node_gcode_info_free(struct node_gcode_info *g)
{
	free(g->marks);
	memset(g, 0, sizeof(*g));
}

bool node_gcode_moved(const char *path, int64_t upto, int64_t commands)
{
	FILE *f;
	struct gcode_reader *r = NULL;
	struct gcode_line g;
	bool moved = false;
	int64_t seen = 0;
	int rc = 1;

	if (upto <= 0 && commands <= 0)
		return false; /* nothing went to the printer */
	if (node_file_kind(path) != 'g' || !(f = fopen(path, "rb")))
		return true;
	if (gcode_reader_new(f, path, &r, NULL)) {
		fclose(f);
		return true;
	}
	/* a command counts when its line starts before upto, or it is one of
	 * the first commands sent (lines with no command are not sent) */
	while (!moved && ((int64_t)gcode_reader_bytes(r) < upto || seen < commands) &&
	       (rc = gcode_reader_next(r, 0, &g, NULL)) == 1) {
		if (g.kind == GCODE_KIND_HOST_ONLY || !g.text_len)
			continue;
		seen++;
		switch (g.kind) {
		case GCODE_KIND_MOTION:
		case GCODE_KIND_HOME:
		case GCODE_KIND_PROBE:
		case GCODE_KIND_TOOL_CHANGE:
		case GCODE_KIND_USER_WAIT:
			moved = true;
			break;
		default:
			break;
		}
	}
	gcode_reader_free(r);
	fclose(f);
	return moved || rc < 0;
}
