/*
 * sf_source.h - the S3G command sources of the Sailfish adapter
 * (printer_sailfish.c): a G-code file translated to X3G one line at a time
 * (serial/x3g.h), or an X3G file cut into commands with x3g_decode.  Each
 * is an s3g_source_fn for s3g_stream_pull (serial/s3g.h), and each keeps
 * where in its file the commands it handed out came from, so a caller can
 * tell how far a print got.
 *
 * Nothing here prints: translator warnings go to the caller's callback.
 */
#ifndef STRATUM_SERIAL_SF_SOURCE_H
#define STRATUM_SERIAL_SF_SOURCE_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "gcode.h"
#include "s3g.h"
#include "st_error.h"
#include "x3g.h"

/* Host version sent with the version query; Sailfish answers 0 below 39
 * (Host.cc), and RepG sends 40. */
#define SFSRC_HOST_VERSION 40
#define SFSRC_X3G_CHUNK 8192 /* X3G bytes read at a time */
#define SFSRC_INSERT_MAX 4096 /* inserted G-code text waiting (bytes) */

/* Called with the warnings of each translated line (n >= 1). */
typedef void (*sfsrc_warn_fn)(void *ctx, const char *name, const struct x3g_warning *w,
			      size_t n);

/* A command source over a G-code file: read a line, translate, hand out
 * the line's commands one by one. */
struct sfsrc_gcode {
	struct gcode_reader *r;
	struct x3g_translator *t;
	const char *name;
	sfsrc_warn_fn warn;	  /* may be NULL */
	void *warn_ctx;
	const uint8_t *out;	  /* this line's commands */
	size_t out_len, pos;
	uint64_t out_line;	  /* the line they came from */
	uint64_t out_end;	  /* bytes read once that line was (its end) */
	bool out_inserted;	  /* that line was sfsrc_gcode_insert's */
	bool finished;		  /* x3g_finish done */
	uint64_t line, prev_line; /* lines of the last two commands handed out */
	uint64_t end, prev_end;	  /* their lines' ends (bytes from the reader's start) */
	uint64_t pulled;	  /* commands handed out */
	long layer;		  /* from the slicer's layer comments, -1 unknown */
	/* G-code lines ('\n' after each) translated before the file's (a
	 * resume preamble), set after sfsrc_gcode_open; their commands count
	 * as line 0, end 0 (nothing of the file done) */
	const char *pre;
	size_t pre_len, pre_pos;
	/* G-code lines ('\n' after each) translated before the file's next
	 * line, after the line under way (sfsrc_gcode_insert: an operator's
	 * commands); their commands keep the line and end of the command
	 * before them, so progress stands still */
	char ins[SFSRC_INSERT_MAX];
	size_t ins_len, ins_pos;
	uint64_t inserted; /* commands of inserted lines handed out */
	/* called with each of the file's lines before it is translated (the
	 * operator's temperature offsets); may be NULL */
	void (*edit)(void *ctx, struct gcode_line *line);
	void *edit_ctx;
};

/* A command source over an X3G file, read in chunks. */
struct sfsrc_x3g {
	FILE *f;
	uint8_t buf[SFSRC_X3G_CHUNK];
	size_t pos, len;
	uint64_t off;	   /* file offset of buf[pos]: the end of the last command */
	uint64_t prev_off; /* the end of the command before it */
	uint64_t pulled;   /* commands handed out */
	bool eof;
};

/*
 * sfsrc_gcode_open - a source over f (open, positioned where reading
 * starts; stays the caller's), translating for machine m with options xo
 * (build name pointer kept).  name is for messages and must outlive g.
 * Returns 0, ST_ERR_ARG (a bad machine) or ST_ERR_NOMEM; close with
 * sfsrc_gcode_close either way.
 */
int sfsrc_gcode_open(struct sfsrc_gcode *g, FILE *f, const char *name,
		     const struct x3g_machine *m, const struct x3g_options *xo,
		     struct st_error *err);

/* sfsrc_gcode_close - free the reader and translator (zeroed g is fine). */
void sfsrc_gcode_close(struct sfsrc_gcode *g);

/* sfsrc_gcode_next - s3g_source_fn over a struct sfsrc_gcode. */
int sfsrc_gcode_next(void *src, struct s3g_cmd *cmd, struct st_error *err);

/*
 * sfsrc_gcode_insert - translate the G-code line text (no '\n') with the
 * file's translator, so with its position and modes, before the file's
 * next line.  A line that does not parse is dropped.  Returns false, with
 * nothing kept, when the text waiting would pass SFSRC_INSERT_MAX.
 */
bool sfsrc_gcode_insert(struct sfsrc_gcode *g, const char *text);

/* sfsrc_gcode_insert_room - bytes sfsrc_gcode_insert takes now ('\n' included). */
size_t sfsrc_gcode_insert_room(const struct sfsrc_gcode *g);

/* sfsrc_gcode_mid_line - whether commands of a line (the file's, or a
 * preamble's or inserted one) are still to be handed out. */
bool sfsrc_gcode_mid_line(const struct sfsrc_gcode *g);

/* sfsrc_x3g_open - a source over f from its current position (0 assumed). */
void sfsrc_x3g_open(struct sfsrc_x3g *x, FILE *f);

/* sfsrc_x3g_next - s3g_source_fn over a struct sfsrc_x3g: every command must
 * decode and be one the firmware takes over USB (x3g_decode also knows the
 * old 129/130, which it does not). */
int sfsrc_x3g_next(void *src, struct s3g_cmd *cmd, struct st_error *err);

/*
 * sfsrc_done_end - where the file was done after "done" of the commands
 * handed out were taken by the printer (s3g status confirmed + skipped; the
 * stream pulls at most one command ahead): the end, in bytes, of the line
 * (G-code) or command (X3G) of the last one taken; 0 if none.  x3g picks
 * the source; the other may be NULL.
 */
uint64_t sfsrc_done_end(const struct sfsrc_gcode *g, const struct sfsrc_x3g *x, bool x3g,
			uint64_t done);

#endif /* STRATUM_SERIAL_SF_SOURCE_H */
