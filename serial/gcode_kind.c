/*
 * gcode_kind.c - what a G-code command is: its kind, whether it takes a
 * text or numbers only (docs/errors.md "G-code input"), and the word
 * look-ups of gcode.h.
 */
#include "gcode.h"
#include "gcode_impl.h"

/* Marlin string-argument commands: the rest of the line is one string. */
bool gcode_takes_string(char letter, int number)
{
	if (letter != 'M')
		return false;
	switch (number) {
	case 23:
	case 28:
	case 30:
	case 32:
	case 117:
	case 118:
	case 928:
	case 862: /* Prusa print checks: M862.3 P "MK3S" quotes the model name */
		return true;
	default:
		return false;
	}
}

/* The kind of a command (letter 0 = no command). */
enum gcode_kind gcode_classify(char letter, int n)
{
	if (letter == 0 || letter == '@')
		return GCODE_KIND_HOST_ONLY;
	if (letter == GCODE_LETTER_TEXT)
		return GCODE_KIND_TEXT_COMMAND;
	if (letter == 'T')
		return GCODE_KIND_TOOL_CHANGE;
	if (letter == 'G') {
		switch (n) {
		case 0:
		case 1:
		case 2:
		case 3:
		case 5:
			return GCODE_KIND_MOTION;
		case 4:
			return GCODE_KIND_DWELL;
		case 28:
			return GCODE_KIND_HOME;
		case 29:
		case 30:
		case 31:
		case 32:
		case 33:
		case 34:
		case 35:
		case 38:
		case 80:
			return GCODE_KIND_PROBE;
		case 92:
			return GCODE_KIND_SET_POSITION;
		case 20:
		case 21:
		case 90:
		case 91:
			return GCODE_KIND_MODE;
		default:
			return GCODE_KIND_OTHER;
		}
	}
	switch (n) { /* M */
	case 0:
	case 1:
	case 226:
	case 600:
		return GCODE_KIND_USER_WAIT;
	case 6:
		return GCODE_KIND_TOOL_CHANGE;
	case 48:
		return GCODE_KIND_PROBE;
	case 82:
	case 83:
		return GCODE_KIND_MODE;
	case 104:
	case 140:
	case 141:
		return GCODE_KIND_TEMP_SET;
	case 109:
	case 116:
	case 190:
	case 191:
		return GCODE_KIND_TEMP_WAIT;
	case 106:
	case 107:
		return GCODE_KIND_FAN;
	case 400:
		return GCODE_KIND_FINISH_MOVES;
	case 108:
	case 112:
	case 410:
	case 524:
	case 876:
		return GCODE_KIND_EMERGENCY;
	case 110:
		return GCODE_KIND_LINE_NUMBER;
	case 105:
	case 114:
	case 115:
	case 119:
	case 155:
		return GCODE_KIND_REPORT;
	case 73:
	case 117:
	case 118:
		return GCODE_KIND_MESSAGE;
	default:
		return GCODE_KIND_OTHER;
	}
}

/* Commands whose numbers move the machine, heat it or set how it moves:
 * their words must all be numbers (or bare letters), since the firmware
 * would read a prefix of anything else ("X1.2.3" as X1.2).  Every other
 * M command may end in text, as Marlin reads it (M0 Click to continue,
 * M115 U3.11.0), and that text is passed on as written. */
bool gcode_needs_numbers(char letter, int n)
{
	if (letter != 'M')
		return true; /* G, T: motion, probing, tools */
	switch (gcode_classify(letter, n)) {
	case GCODE_KIND_OTHER:
	case GCODE_KIND_REPORT:
	case GCODE_KIND_MESSAGE:
		break;
	case GCODE_KIND_USER_WAIT:
		return n == 226 || n == 600; /* a pin wait; a filament change that moves */
	default:
		return true;
	}
	switch (n) {
	case 3: /* spindle or laser power */
	case 4:
	case 5:
	case 42: /* set a pin */
	case 92: /* steps per mm */
	case 200:
	case 201:
	case 202:
	case 203:
	case 204:
	case 205:
	case 206:
	case 207:
	case 208:
	case 209:
	case 218: /* tool offsets */
	case 220: /* feed rate % */
	case 221: /* flow % */
	case 290: /* babystep */
	case 301: /* PID */
	case 302: /* cold extrusion */
	case 303:
	case 304:
	case 851: /* probe offset */
	case 900: /* linear advance */
	case 906: /* motor currents */
	case 907:
	case 913:
	case 914:
		return true;
	default:
		return false;
	}
}

static const char *const kind_names[GCODE_KIND_COUNT_] = {
    [GCODE_KIND_OTHER] = "other",
    [GCODE_KIND_HOST_ONLY] = "host_only",
    [GCODE_KIND_MOTION] = "motion",
    [GCODE_KIND_DWELL] = "dwell",
    [GCODE_KIND_HOME] = "home",
    [GCODE_KIND_PROBE] = "probe",
    [GCODE_KIND_SET_POSITION] = "set_position",
    [GCODE_KIND_MODE] = "mode",
    [GCODE_KIND_TEMP_SET] = "temp_set",
    [GCODE_KIND_TEMP_WAIT] = "temp_wait",
    [GCODE_KIND_FAN] = "fan",
    [GCODE_KIND_TOOL_CHANGE] = "tool_change",
    [GCODE_KIND_FINISH_MOVES] = "finish_moves",
    [GCODE_KIND_USER_WAIT] = "user_wait",
    [GCODE_KIND_EMERGENCY] = "emergency",
    [GCODE_KIND_LINE_NUMBER] = "line_number",
    [GCODE_KIND_REPORT] = "report",
    [GCODE_KIND_MESSAGE] = "message",
    [GCODE_KIND_TEXT_COMMAND] = "text_command",
};

const char *gcode_kind_name(enum gcode_kind kind)
{
	if ((int)kind < 0 || kind >= GCODE_KIND_COUNT_)
		return "unknown";
	return kind_names[kind];
}

bool gcode_is_blocking(enum gcode_kind kind)
{
	switch (kind) {
	case GCODE_KIND_DWELL:
	case GCODE_KIND_HOME:
	case GCODE_KIND_PROBE:
	case GCODE_KIND_TEMP_WAIT:
	case GCODE_KIND_FINISH_MOVES:
	case GCODE_KIND_USER_WAIT:
	case GCODE_KIND_TEXT_COMMAND:
		return true;
	default:
		return false;
	}
}

const struct gcode_word *gcode_find_word(const struct gcode_line *line, char letter)
{
	if (!line)
		return NULL;
	if (letter >= 'a' && letter <= 'z')
		letter = (char)(letter - 'a' + 'A');
	for (size_t i = 0; i < line->nwords && i < GCODE_WORDS_MAX; i++)
		if (line->words[i].letter == letter)
			return &line->words[i];
	return NULL;
}

bool gcode_word_value(const struct gcode_line *line, char letter, double *value)
{
	const struct gcode_word *w = gcode_find_word(line, letter);

	if (!w || !w->has_value)
		return false;
	if (value)
		*value = w->value;
	return true;
}
