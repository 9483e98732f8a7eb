/*
 * gcode_impl.h - what the G-code parser (gcode.c) asks of the command
 * tables (gcode_kind.c).  Private to serial/gcode*.c.
 */
#ifndef STRATUM_SERIAL_GCODE_IMPL_H
#define STRATUM_SERIAL_GCODE_IMPL_H

#include <stdbool.h>

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

#endif /* STRATUM_SERIAL_GCODE_IMPL_H */
