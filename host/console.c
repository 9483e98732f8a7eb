/*
 * console.c - the built-in words of `stratum console` (console.h).
 */
#include "console.h"

#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <string.h>
#include <strings.h>

#include "st_number.h"

/* The filaments `preheat NAME` knows, declared once: nozzle and bed as the
 * makers' data sheets commonly give them.  `preheat` alone uses the printer
 * profile's own filament instead. */
static const struct {
	const char *name;
	int nozzle, bed;
} filaments[] = {
    {"PLA", 210, 60}, {"PETG", 240, 80}, {"ABS", 250, 100},
    {"ASA", 255, 100}, {"TPU", 230, 50}, {"PC", 270, 110},
};
#define NFILAMENTS (sizeof(filaments) / sizeof(filaments[0]))

/* Jog feed rates (mm/min): slow enough for any of the profiles' machines. */
static const struct {
	char axis;
	int feed;
} jog_feeds[] = {{'X', 3000}, {'Y', 3000}, {'Z', 600}, {'E', 120}};
#define NJOG (sizeof(jog_feeds) / sizeof(jog_feeds[0]))
#define JOG_MAX_MM 1000.0 /* a longer jog is a typing slip, not a wish */

/* The first max words of text (cut in buf) and their count: every built-in
 * takes fewer than max, so max words mean too many. */
static size_t words(const char *text, char *buf, size_t cap, char **w, size_t max)
{
	size_t n = 0;
	char *save = NULL;

	snprintf(buf, cap, "%s", text);
	for (char *t = strtok_r(buf, " \t\r\n", &save); t && n < max;
	     t = strtok_r(NULL, " \t\r\n", &save))
		w[n++] = t;
	return n;
}

/* Append one G-code line to c (always fits: the built-ins' lines are short). */
static void add(struct console_cmd *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void add(struct console_cmd *c, const char *fmt, ...)
{
	va_list ap;

	va_start(ap, fmt);
	vsnprintf(c->line[c->n++], CONSOLE_LINE_MAX, fmt, ap);
	va_end(ap);
	c->kind = CONSOLE_BUILTIN;
}

static void bad(struct console_cmd *c, const char *msg)
{
	c->kind = CONSOLE_BAD;
	snprintf(c->msg, sizeof(c->msg), "%s", msg);
}

/* home [X] [Y] [Z]: G28 of the axes named, all without. */
static void read_home(char **w, size_t n, struct console_cmd *c)
{
	char axes[8] = "";

	for (size_t i = 1; i < n; i++) {
		char a = (char)toupper((unsigned char)w[i][0]);

		if (w[i][1] || !strchr("XYZ", a) || strchr(axes, a)) {
			bad(c, "usage: home [X] [Y] [Z] (all axes without one)");
			return;
		}
		size_t k = strlen(axes);
		axes[k] = ' ';
		axes[k + 1] = a;
		axes[k + 2] = '\0';
	}
	add(c, "G28%s", axes);
}

/* jog AXIS MM: one relative move, then absolute positions again. */
static void read_jog(char **w, size_t n, struct console_cmd *c)
{
	char a = n == 3 && !w[1][1] ? (char)toupper((unsigned char)w[1][0]) : 0;
	double mm;
	size_t k;

	for (k = 0; k < NJOG && jog_feeds[k].axis != a; k++)
		;
	if (k == NJOG || st_parse_double(w[2], strlen(w[2]), 0, &mm) != ST_NUMBER_OK ||
	    fabs(mm) > JOG_MAX_MM || mm == 0) {
		bad(c, "usage: jog X|Y|Z|E MM (a distance, -1000 to 1000, not 0; E extrudes, "
		       "so only with the nozzle hot)");
		return;
	}
	add(c, "G91");
	add(c, "G1 %c%.3f F%d", a, mm, jog_feeds[k].feed);
	add(c, "G90");
}

/* preheat [NAME]: the filament's temperatures, the profile's without a name. */
static void read_preheat(char **w, size_t n, const struct console_heat *heat,
			 struct console_cmd *c)
{
	int nozzle = heat->nozzle, bed = heat->bed;

	if (n > 2) {
		bad(c, "usage: preheat [PLA|PETG|ABS|ASA|TPU|PC] (the profile's filament without "
		       "a name)");
		return;
	}
	if (n == 2) {
		size_t k;

		for (k = 0; k < NFILAMENTS && strcasecmp(filaments[k].name, w[1]); k++)
			;
		if (k == NFILAMENTS) {
			bad(c, "preheat knows PLA, PETG, ABS, ASA, TPU and PC; 'preheat' alone "
			       "heats for the printer profile's filament, or send M104 S<C> and "
			       "M140 S<C> yourself");
			return;
		}
		nozzle = filaments[k].nozzle;
		bed = filaments[k].bed;
	}
	add(c, "M104 S%d", nozzle);
	add(c, "M140 S%d", bed);
}

void console_read(const char *text, const struct console_heat *heat, struct console_cmd *c)
{
	char buf[256], *w[5];
	size_t n;

	memset(c, 0, sizeof(*c));
	text += strspn(text, " \t");
	if (!*text || *text == ';' || *text == '\r' || *text == '\n')
		return;
	c->kind = CONSOLE_GCODE;
	/* G-code starts with a letter and a number; the words are longer */
	if (strlen(text) >= sizeof(buf) || !isalpha((unsigned char)text[0]) ||
	    !isalpha((unsigned char)text[1]))
		return;
	n = words(text, buf, sizeof(buf), w, 5);
	if (!strcasecmp(w[0], "help")) {
		c->kind = CONSOLE_HELP;
	} else if (!strcasecmp(w[0], "quit") || !strcasecmp(w[0], "exit")) {
		c->kind = n == 1 ? CONSOLE_QUIT : CONSOLE_BAD;
		snprintf(c->msg, sizeof(c->msg), "usage: quit");
	} else if (!strcasecmp(w[0], "home")) {
		read_home(w, n, c);
	} else if (!strcasecmp(w[0], "jog")) {
		read_jog(w, n, c);
	} else if (!strcasecmp(w[0], "preheat")) {
		read_preheat(w, n, heat, c);
	} else if (!strcasecmp(w[0], "cooldown")) {
		if (n > 1)
			bad(c, "usage: cooldown (nozzle and bed heaters off)");
		else {
			add(c, "M104 S0");
			add(c, "M140 S0");
		}
	} else if (!strcasecmp(w[0], "motors")) {
		if (n != 2 || strcasecmp(w[1], "off"))
			bad(c, "usage: motors off");
		else
			add(c, "M84");
	}
}

void console_help(const struct console_heat *heat, FILE *f)
{
	fprintf(f, "Built-in commands (any other line goes to the printer as G-code):\n"
		   "  home [X] [Y] [Z]   home the axes named, all without one (G28)\n"
		   "  jog AXIS MM        move X, Y, Z or E by MM (G91, G1, G90)\n"
		   "  preheat [NAME]     heat nozzle and bed (M104, M140) for NAME:");
	for (size_t k = 0; k < NFILAMENTS; k++)
		fprintf(f, "%s%s %d/%d", k % 3 ? ", " : "\n                     ", filaments[k].name,
			filaments[k].nozzle, filaments[k].bed);
	fprintf(f, "\n"
		   "                     without NAME the profile's filament: %d/%d\n"
		   "  cooldown           heaters off (M104 S0, M140 S0)\n"
		   "  motors off         steppers off (M84)\n"
		   "  help               this text\n"
		   "  quit               leave (the printer keeps its heaters as they are);\n"
		   "                     Ctrl-C stops it safely: heaters and motors off\n",
		heat->nozzle, heat->bed);
}
