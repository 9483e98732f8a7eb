/*
 * gcode_impl.h - what the G-code parser (gcode.c) asks of the command
 * tables (gcode_kind.c) and of the number reader (gcode_number.c).  Private to serial/gcode*.c.
 */
#ifndef STRATUM_SERIAL_GCODE_IMPL_H
#define STRATUM_SERIAL_GCODE_IMPL_H

#include <stdbool.h>
#include <stddef.h>

#include "gcode.h"

/* The kind of a command (letter 0 = no command, '@' = host command). */
enum gcode_kind gcode_classify(char letter, int number);

/* True for Marlin's string-argument commands and Prusa's M862.x: the rest
 * of the line is one text. */
bool gcode_takes_string(char letter, int number);

/* True for the commands that take numbers only, never a text: every G and
 * T command and the M commands whose numbers heat, move or set how the
 * machine moves. */
bool gcode_needs_numbers(char letter, int number);

/* Characters of a token quoted in a message. */
#define GCODE_QUOTE_MAX 24

enum num_status {
	NUM_OK = 0,
	NUM_SYNTAX,	/* not [+-]digits[.digits] */
	NUM_TOO_LONG,	/* more than GCODE_NUMBER_MAX characters */
	NUM_TOO_PRECISE /* more than NUM_SIG_MAX significant digits or 22 decimals */
};

/* gcode_scan_number - [+-]digits[.digits] into *value, correctly rounded;
 * no locale, no exponent. */
enum num_status gcode_scan_number(const char *s, size_t n, double *value);

/* gcode_num_reason - why a number was refused, as the tail of a message. */
const char *gcode_num_reason(enum num_status st);

#endif /* STRATUM_SERIAL_GCODE_IMPL_H */
