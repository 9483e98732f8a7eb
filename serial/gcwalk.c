/*
 * gcwalk.c - moves of a G-code file with absolute positions (gcwalk.h).
 */
#include "gcwalk.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gcode.h"

struct gcwalk {
	struct gcode_reader *r;
	char *name;
	double pos[3], e; /* mm */
	double feed;	  /* mm/min */
	bool abs_xyz, abs_e;
	char type[GCODE_COMMENT_MAX + 1];
	long layer;
	double layer_z, layer_height;
	double filament_diameter;
};

int gcwalk_new(FILE *fp, const char *name, struct gcwalk **out, struct st_error *err)
{
	struct gcwalk *w;
	int rc;

	if (out)
		*out = NULL;
	if (!fp || !out)
		return st_error_set(err, ST_ERR_ARG, "gcwalk: gcwalk_new needs a file and out");
	w = calloc(1, sizeof(*w));
	if (!w || !(w->name = strdup(name ? name : "<input>"))) {
		free(w);
		return st_error_set(err, ST_ERR_NOMEM, "gcwalk: out of memory");
	}
	rc = gcode_reader_new(fp, w->name, &w->r, err);
	if (rc) {
		gcwalk_free(w);
		return rc;
	}
	w->abs_xyz = w->abs_e = true;
	w->layer = -1;
	w->layer_z = w->layer_height = NAN;
	*out = w;
	return 0;
}

void gcwalk_free(struct gcwalk *w)
{
	if (!w)
		return;
	gcode_reader_free(w->r);
	free(w->name);
	free(w);
}

double gcwalk_filament_diameter(const struct gcwalk *w)
{
	return w->filament_diameter;
}

long gcwalk_layer_marks(const struct gcwalk *w)
{
	return w->layer + 1;
}

/* Skip blanks from c, not beyond end. */
static const char *skip_blanks(const char *c, const char *end)
{
	while (c < end && (*c == ' ' || *c == '\t'))
		c++;
	return c;
}

/* "; KEY = V[,V...]" or ";KEY:V" (sep): true and *v set for a number > 0. */
static bool comment_number(const struct gcode_line *l, const char *key, char sep, double *v)
{
	const char *c = l->comment, *end = l->comment + l->comment_len;
	size_t klen = strlen(key);

	c = skip_blanks(c, end);
	if ((size_t)(end - c) <= klen || memcmp(c, key, klen))
		return false;
	c = skip_blanks(c + klen, end);
	if (c == end || *c != sep)
		return false;
	c = skip_blanks(c + 1, end);
	const char *num = c;
	while (c < end && *c != ',' && *c != ' ')
		c++;
	double d;
	if (gcode_read_number(num, (size_t)(c - num), &d, NULL) || !(d > 0.0))
		return false;
	*v = d;
	return true;
}

/* A comment-only line: feature type, layer marks, header values. */
static void walk_comment(struct gcwalk *w, const struct gcode_line *l)
{
	long n;
	double z, v;

	if (!strncmp(l->comment, "TYPE:", 5)) {
		memcpy(w->type, l->comment + 5, l->comment_len - 5 + 1);
		return;
	}
	switch (gcode_layer_comment(l, &n, &z)) {
	case GCODE_LAYER_START:
		w->layer++;
		w->layer_z = z;
		w->layer_height = NAN;
		return;
	case GCODE_LAYER_Z:
		w->layer_z = z;
		return;
	default:
		break;
	}
	if (comment_number(l, "HEIGHT", ':', &v))
		w->layer_height = v;
	else if (w->filament_diameter == 0.0 && comment_number(l, "filament_diameter", '=', &v))
		w->filament_diameter = v;
}

/* A mode or G92/G28 line; 0 or an error. */
static int walk_state(struct gcwalk *w, const struct gcode_line *l, struct st_error *err)
{
	static const char axes[3] = {'X', 'Y', 'Z'};
	int g = l->number;
	double v;

	if (l->letter == 'M' && (g == 82 || g == 83)) {
		w->abs_e = g == 82;
	} else if (l->letter != 'G') {
		return 0;
	} else if (g == 20) {
		return st_error_set(err, ST_ERR_UNSUPPORTED,
				    "%s: line %llu: G20 (inches) is not supported; slice in mm",
				    w->name, (unsigned long long)gcode_reader_line(w->r));
	} else if (g == 90 || g == 91) {
		/* Marlin: G90/G91 set E's mode too; a later M82/M83 overrides. */
		w->abs_xyz = w->abs_e = g == 90;
	} else if (g == 28) {
		w->pos[0] = w->pos[1] = w->pos[2] = 0.0;
	} else if (g == 92) {
		for (int a = 0; a < 3; a++)
			if (gcode_word_value(l, axes[a], &v))
				w->pos[a] = v;
		if (gcode_word_value(l, 'E', &v))
			w->e = v;
	}
	return 0;
}

/* A G0-G3 line into m; 0 or an error. */
static int walk_move(struct gcwalk *w, const struct gcode_line *l, struct gcwalk_move *m,
		     struct st_error *err)
{
	static const char axes[3] = {'X', 'Y', 'Z'};
	unsigned long long line = (unsigned long long)gcode_reader_line(w->r);
	double v, to[3], e = w->e;

	for (int a = 0; a < 3; a++) {
		to[a] = w->pos[a];
		if (gcode_word_value(l, axes[a], &v))
			to[a] = w->abs_xyz ? v : w->pos[a] + v;
		if (fabs(to[a]) > GCWALK_COORD_MAX)
			return st_error_set(err, ST_ERR_RANGE, "%s: line %llu: position beyond +-%g mm",
					    w->name, line, GCWALK_COORD_MAX);
	}
	if (gcode_word_value(l, 'E', &v))
		e = w->abs_e ? v : w->e + v;
	if (gcode_word_value(l, 'F', &v))
		w->feed = v;
	bool moves = to[0] != w->pos[0] || to[1] != w->pos[1];
	if (l->number >= 2 && e > w->e && moves)
		return st_error_set(err, ST_ERR_UNSUPPORTED,
				    "%s: line %llu: extruding arcs (G2/G3) are not supported; "
				    "turn arc fitting off in the slicer",
				    w->name, line);
	*m = (struct gcwalk_move){.g = l->number,
				  .de = e - w->e,
				  .feed = w->feed,
				  .type = w->type,
				  .layer = w->layer,
				  .layer_z = w->layer_z,
				  .layer_height = w->layer_height,
				  .line = line};
	memcpy(m->from, w->pos, sizeof(m->from));
	memcpy(m->to, to, sizeof(m->to));
	memcpy(w->pos, to, sizeof(w->pos));
	w->e = e;
	return 0;
}

int gcwalk_next(struct gcwalk *w, struct gcwalk_move *m, struct st_error *err)
{
	struct gcode_line l;
	int rc;

	while ((rc = gcode_reader_next(w->r, 0, &l, err)) == 1) {
		if (l.letter == 0) {
			if (l.has_comment)
				walk_comment(w, &l);
			continue;
		}
		bool motion = l.letter == 'G' && l.number >= 0 && l.number <= 3;
		rc = motion ? walk_move(w, &l, m, err) : walk_state(w, &l, err);
		if (rc)
			return rc;
		if (motion)
			return 1;
	}
	return rc;
}
