/*
 * x3g.h - G-code to X3G translation for Sailfish (Makerbot family) printers,
 * and the decoder that cuts an X3G byte stream back into commands.
 *
 * X3G is a file of S3G action-command payloads (docs/protocols.md section 2):
 * a command byte, then little-endian fields.  The translator follows the
 * reference translator GPX (markwal/GPX src/gpx/gpx.c, machine "fcp") so
 * that its output matches `gpx -m fcp` command for command: moves become
 * 155 "queue extended point x3g" (absolute steps for X, Y, Z, relative
 * steps for the extruders, a DDA rate in steps/s, the distance as float32 and
 * the feed rate in mm/s x 64), or 139 "queue extended point" with a fixed
 * DDA when the position of a moved axis is unknown (after homing, M132).
 *
 * The translator is fed one parsed line at a time (serial/gcode.h); each call
 * leaves the bytes of zero or more commands in the translator's output buffer
 * and zero or more warnings (unsupported commands, missing parameters), each
 * with the caller's line number.  Library code never prints; the caller
 * shows the warnings.  Nothing is global; distinct translators may be used
 * from distinct threads.
 *
 * This header does not depend on host/: host fills struct x3g_machine from
 * the printer profile.
 */
#ifndef STRATUM_SERIAL_X3G_H
#define STRATUM_SERIAL_X3G_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "gcode.h"
#include "st_error.h"

/* Longest S3G payload the Mightyboard accepts (bytes), and so the longest
 * command in an X3G file. */
#define X3G_PAYLOAD_MAX 32
/* Longest build name written in command 153 (GPX cuts at 24 characters). */
#define X3G_BUILD_NAME_MAX 24
/* Longest warning text (bytes, NUL included). */
#define X3G_WARNING_MAX 160
/* Warnings kept per translated line; further ones are counted only. */
#define X3G_WARNINGS_PER_LINE 4

/* Which end of an axis its endstop is at (GPX ENDSTOP_IS_MIN/MAX). */
enum x3g_endstop {
	X3G_ENDSTOP_MIN = 0,
	X3G_ENDSTOP_MAX = 1,
};

/* Command dialect: GPX -r (RepRap, GPX's default) or -g (Makerbot/RepG).
 * They differ in M106/M107 (blower "valve" vs heatsink fan), M109 (set and
 * wait for the nozzle vs set the platform) and whether T on a command line
 * selects the tool for the following lines (RepRap) or only that line. */
enum x3g_flavor {
	X3G_FLAVOR_REPRAP = 0,
	X3G_FLAVOR_MAKERBOT,
};

/* One motion axis of the machine definition. */
struct x3g_axis {
	double steps_per_mm;	/* > 0 */
	double max_feedrate;	/* mm/min, > 0 */
	double home_feedrate;	/* mm/min, > 0 (X, Y, Z only) */
	enum x3g_endstop endstop; /* X, Y, Z only */
};

/* The machine definition (GPX `Machine`): X, Y, Z, then extruders A, B. */
struct x3g_machine {
	struct x3g_axis axis[5];   /* X Y Z A B; B unused with one extruder */
	int extruder_count;	   /* 1 or 2 */
	bool heated_platform;	   /* the platform heater hangs off tool 0 */
	unsigned home_timeout;	   /* s, written in 131/132; GPX uses 20 */
};

/* x3g_machine_fcp - GPX's "fcp" (FlashForge Creator Pro = r1d) definition. */
void x3g_machine_fcp(struct x3g_machine *m);

/* Translation options. */
struct x3g_options {
	enum x3g_flavor flavor;
	/* Name in the build start notification (153), cut to
	 * X3G_BUILD_NAME_MAX; NULL gives "Stratum". */
	const char *build_name;
};

/* A warning about one input line; nothing was written for what it names. */
struct x3g_warning {
	uint64_t line; /* the caller's line number (from 1) */
	char msg[X3G_WARNING_MAX];
};

struct x3g_translator;

/*
 * x3g_new - a translator for machine m.
 * @m:   checked: extruder count 1-2, steps and feed rates > 0 and finite.
 * @opt: may be NULL (RepRap flavour, default build name).
 * Returns 0 and *out, or ST_ERR_ARG (a bad machine, the message names the
 * field) or ST_ERR_NOMEM; *out is NULL on error.  Free with x3g_free.
 */
int x3g_new(const struct x3g_machine *m, const struct x3g_options *opt,
	    struct x3g_translator **out, struct st_error *err);

/* x3g_free - free a translator; NULL is allowed. */
void x3g_free(struct x3g_translator *t);

/*
 * x3g_translate - translate one parsed line.
 * @line:   from gcode_parse / gcode_reader_next.
 * @lineno: the file line number, used in warnings.
 * Clears the previous call's output and warnings, then appends the commands
 * of this line (x3g_output) and its warnings (x3g_warnings).  Comment-only
 * lines produce nothing; after M2 every further line is ignored (a warning
 * says so once).
 * Returns the number of commands written (>= 0), or ST_ERR_NOMEM.
 */
int x3g_translate(struct x3g_translator *t, const struct gcode_line *line, uint64_t lineno,
		  struct st_error *err);

/*
 * x3g_translate_aside - x3g_translate of a line from outside the file (an
 * operator's command during a print): its T word, unless the line is a
 * tool change, names the tool for that line only, as Marlin reads M104 T1,
 * so the file's following lines keep their tool in either flavour.
 */
int x3g_translate_aside(struct x3g_translator *t, const struct gcode_line *line, uint64_t lineno,
			struct st_error *err);

/*
 * x3g_finish - the end of the input: closes the build (150 at 100 % and 154
 * build end) unless M2, M137 or M73 P100 already did.  Returns the number of
 * commands written, output and warnings as x3g_translate.
 */
int x3g_finish(struct x3g_translator *t, struct st_error *err);

/* x3g_output - the bytes written by the last call (*len may be 0).  Owned by
 * the translator, valid until the next call. */
const uint8_t *x3g_output(const struct x3g_translator *t, size_t *len);

/* x3g_warnings - the warnings of the last call; returns their number. */
size_t x3g_warnings(const struct x3g_translator *t, const struct x3g_warning **out);

/* x3g_build_name - "dir/name.ext" -> "name": the build name GPX gives a file. */
void x3g_build_name(const char *path, char *name, size_t cap);

/* x3g_warning_total - every warning so far, those not kept included. */
uint64_t x3g_warning_total(const struct x3g_translator *t);

/* ---- decoding ------------------------------------------------------------ */

#define X3G_FIELDS_MAX 10
#define X3G_TEXT_MAX X3G_PAYLOAD_MAX

/* One decoded field.  Integers and float32 values are all exact in a double. */
struct x3g_field {
	const char *name; /* static, e.g. "x", "dda_rate", "distance" */
	double value;
};

/* One command of an X3G stream. */
struct x3g_command {
	uint8_t code;	  /* S3G command number, 129-158 */
	const char *name; /* static, e.g. "queue extended point x3g" */
	uint64_t offset;  /* where it starts in the stream (bytes) */
	size_t length;	  /* bytes, command byte included */
	size_t nfields;
	struct x3g_field fields[X3G_FIELDS_MAX];
	bool has_text; /* 149 display message, 153 build start */
	char text[X3G_TEXT_MAX + 1];
};

/*
 * x3g_decode - decode the command at the start of (buf, len).
 * @offset: buf's position in the whole stream, for cmd->offset and messages.
 * Every length is checked against len: a command cut short, an unknown
 * command byte, a tool action whose stated length does not fit, or a string
 * without its NUL within X3G_PAYLOAD_MAX bytes is ST_ERR_PARSE with a message
 * naming the byte offset.  Returns the command's length (> 0), 0 when len is
 * 0, or a negative class; *cmd is filled only on success.
 */
int x3g_decode(const uint8_t *buf, size_t len, uint64_t offset, struct x3g_command *cmd,
	       struct st_error *err);

/* x3g_field_value - the value of the field called name, or false. */
bool x3g_field_value(const struct x3g_command *cmd, const char *name, double *value);

/*
 * x3g_format - one line describing cmd ("155 queue extended point x3g:
 * x=100 y=-3 ..."), NUL-terminated in out (cut to cap).  Returns the length
 * that would have been written, as snprintf.
 */
int x3g_format(const struct x3g_command *cmd, char *out, size_t cap);

#endif /* STRATUM_SERIAL_X3G_H */
