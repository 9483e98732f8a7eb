/*
 * console.h - the words of `stratum console` (host/cmd_console.c): one
 * typed line read as a built-in (home, jog, preheat, cooldown, motors off,
 * help, quit) and the G-code lines it stands for, or as G-code to send as
 * typed.  Pure: no printer, nothing printed, so the suite tests every word.
 */
#ifndef STRATUM_HOST_CONSOLE_H
#define STRATUM_HOST_CONSOLE_H

#include <stddef.h>
#include <stdio.h>

#define CONSOLE_LINES_MAX 3 /* G-code lines of the longest built-in (jog) */
#define CONSOLE_LINE_MAX 96

/* What a typed line is. */
enum console_kind {
	CONSOLE_EMPTY = 0, /* blank or a comment alone: nothing to do */
	CONSOLE_GCODE,	   /* not a built-in: line[0] is the text to send as typed */
	CONSOLE_BUILTIN,   /* line[0..n) are the G-code lines to send, in order */
	CONSOLE_HELP,
	CONSOLE_QUIT,
	CONSOLE_BAD,	   /* a built-in used wrongly: msg says how to use it */
};

struct console_cmd {
	enum console_kind kind;
	size_t n;
	char line[CONSOLE_LINES_MAX][CONSOLE_LINE_MAX];
	char msg[200];
};

/* The temperatures `preheat` alone uses: the printer profile's filament. */
struct console_heat {
	int nozzle, bed; /* degC */
};

/*
 * console_read - what text (one line, no newline) asks for; heat is the
 * profile's filament for `preheat` without a name.  Built-in words are
 * matched whatever their case; G-code (text of 1 to CONSOLE_LINE_MAX - 1
 * bytes) is left to the printer's own check.  Always fills c.
 */
void console_read(const char *text, const struct console_heat *heat, struct console_cmd *c);

/* console_help - the built-ins and the filaments preheat knows, for `help`. */
void console_help(const struct console_heat *heat, FILE *f);

#endif /* STRATUM_HOST_CONSOLE_H */
