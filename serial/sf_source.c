/*
 * sf_source.c - S3G command sources over G-code and X3G files
 * (sf_source.h), for the Sailfish adapter (printer_sailfish.c).
 */
#include <errno.h>
#include <string.h>

#include "sf_source.h"

int sfsrc_gcode_open(struct sfsrc_gcode *g, FILE *f, const char *name,
		     const struct x3g_machine *m, const struct x3g_options *xo,
		     struct st_error *err)
{
	sfsrc_warn_fn warn = g->warn;
	void *warn_ctx = g->warn_ctx;
	void (*edit)(void *, struct gcode_line *) = g->edit;
	void *edit_ctx = g->edit_ctx;
	int rc;

	memset(g, 0, sizeof(*g));
	g->name = name;
	g->warn = warn;
	g->warn_ctx = warn_ctx;
	g->edit = edit;
	g->edit_ctx = edit_ctx;
	g->layer = -1;
	if ((rc = x3g_new(m, xo, &g->t, err)))
		return rc;
	return gcode_reader_new(f, name, &g->r, err);
}

void sfsrc_gcode_close(struct sfsrc_gcode *g)
{
	gcode_reader_free(g->r);
	x3g_free(g->t);
	g->r = NULL;
	g->t = NULL;
}

/* Parse the next line of text (lines ending in '\n') at *pos into line. */
static int text_line(const char *text, size_t len, size_t *pos, struct gcode_line *line,
		     struct st_error *err)
{
	const char *p = text + *pos, *nl = memchr(p, '\n', len - *pos);
	size_t n = nl ? (size_t)(nl - p) : len - *pos;

	*pos += n + (nl != NULL);
	return gcode_parse(p, n, 0, line, err);
}

bool sfsrc_gcode_insert(struct sfsrc_gcode *g, const char *text)
{
	size_t len = strlen(text);

	if (len + 1 > sfsrc_gcode_insert_room(g))
		return false;
	memmove(g->ins, g->ins + g->ins_pos, g->ins_len - g->ins_pos);
	g->ins_len -= g->ins_pos;
	g->ins_pos = 0;
	memcpy(g->ins + g->ins_len, text, len);
	g->ins[g->ins_len + len] = '\n';
	g->ins_len += len + 1;
	return true;
}

size_t sfsrc_gcode_insert_room(const struct sfsrc_gcode *g)
{
	return sizeof(g->ins) - (g->ins_len - g->ins_pos);
}

bool sfsrc_gcode_mid_line(const struct sfsrc_gcode *g)
{
	return g->pos < g->out_len;
}

int sfsrc_gcode_next(void *src, struct s3g_cmd *cmd, struct st_error *err)
{
	struct sfsrc_gcode *g = src;
	struct gcode_line line;
	bool pre = false, ins = false;
	int n, k;

	while (g->pos >= g->out_len) {
		if (g->finished)
			return 0;
		pre = g->pre_pos < g->pre_len;
		ins = !pre && g->ins_pos < g->ins_len;
		if (pre) {
			n = text_line(g->pre, g->pre_len, &g->pre_pos, &line, err);
			n = n < 0 ? n : x3g_translate(g->t, &line, 0, err);
		} else if (ins) {
			struct st_error e;

			/* an operator's line that does not parse must not fail the print */
			n = text_line(g->ins, g->ins_len, &g->ins_pos, &line, &e) ? 0
			    : x3g_translate_aside(g->t, &line, g->line, err);
		} else {
			n = gcode_reader_next(g->r, 0, &line, err);
		}
		if (n < 0)
			return n;
		if (pre || ins) {
			/* commands of the preamble: nothing of the file yet; inserted
			 * ones: no further than the command before them */
		} else if (n == 0) {
			g->finished = true;
			n = x3g_finish(g->t, err);
		} else {
			long l;
			if (gcode_layer_comment(&line, &l, NULL) == GCODE_LAYER_START)
				g->layer = l >= 0 ? l : g->layer + 1;
			if (g->edit)
				g->edit(g->edit_ctx, &line);
			n = x3g_translate(g->t, &line, gcode_reader_line(g->r), err);
		}
		if (n < 0)
			return n;
		g->out_line = pre ? 0 : ins ? g->line : gcode_reader_line(g->r);
		g->out_end = pre ? 0 : ins ? g->end : gcode_reader_bytes(g->r);
		if (g->warn) {
			const struct x3g_warning *w;
			size_t nw = x3g_warnings(g->t, &w);
			if (nw)
				g->warn(g->warn_ctx, g->name, w, nw);
		}
		g->out = x3g_output(g->t, &g->out_len);
		g->pos = 0;
		g->out_inserted = ins;
	}
	k = s3g_action_length(g->out + g->pos, g->out_len - g->pos);
	if (k <= 0 || k > S3G_MAX_PAYLOAD || (size_t)k > g->out_len - g->pos)
		return st_error_set(err, ST_ERR_INTERNAL,
				    "%s: line %llu: the translator wrote command %u, which the "
				    "S3G driver cannot send",
				    g->name, (unsigned long long)g->out_line, g->out[g->pos]);
	cmd->payload = g->out + g->pos;
	cmd->len = (uint8_t)k;
	g->pos += (size_t)k;
	g->prev_line = g->line;
	g->line = g->out_line;
	g->prev_end = g->end;
	g->end = g->out_end;
	g->pulled++;
	g->inserted += g->out_inserted;
	return 1;
}

void sfsrc_x3g_open(struct sfsrc_x3g *x, FILE *f)
{
	memset(x, 0, sizeof(*x));
	x->f = f;
}

int sfsrc_x3g_next(void *src, struct s3g_cmd *cmd, struct st_error *err)
{
	struct sfsrc_x3g *x = src;
	struct x3g_command c;
	int rc;

	if (x->len - x->pos < X3G_PAYLOAD_MAX && !x->eof) {
		memmove(x->buf, x->buf + x->pos, x->len - x->pos);
		x->len -= x->pos;
		x->pos = 0;
		x->len += fread(x->buf + x->len, 1, sizeof(x->buf) - x->len, x->f);
		if (ferror(x->f))
			return st_error_set(err, ST_ERR_IO, "byte %llu: read error: %s",
					    (unsigned long long)x->off, strerror(errno));
		x->eof = feof(x->f);
	}
	if (x->pos == x->len)
		return 0;
	rc = x3g_decode(x->buf + x->pos, x->len - x->pos, x->off, &c, err);
	if (rc < 0)
		return rc;
	if (s3g_action_length(x->buf + x->pos, (size_t)rc) != rc)
		return st_error_set(err, ST_ERR_PARSE,
				    "byte %llu: command %u (%s) is not one Sailfish takes over USB",
				    (unsigned long long)x->off, c.code, c.name);
	cmd->payload = x->buf + x->pos;
	cmd->len = (uint8_t)rc;
	x->pos += (size_t)rc;
	x->prev_off = x->off;
	x->off += (uint64_t)rc;
	x->pulled++;
	return 1;
}

uint64_t sfsrc_done_end(const struct sfsrc_gcode *g, const struct sfsrc_x3g *x, bool x3g,
			uint64_t done)
{
	if (done == 0)
		return 0;
	if (x3g)
		return done >= x->pulled ? x->off : x->prev_off;
	return done >= g->pulled ? g->end : g->prev_end;
}
