/*
 * settings.h - every printer and slicer setting, declared once: name, type,
 * range, default, unit and help.  The profile loader (host/profile.h) types
 * and range-checks a profile's keys with these declarations, the G-code
 * writer (gcode_writer.h) checks its settings against the same ranges, and
 * docs/printers.md's key tables are generated from them (settings_write_doc,
 * `stratum printers --keys`), so a value the loader accepts is one the slicer
 * accepts.
 *
 * Lives in slicer/ because the slicer is the lowest layer that needs it;
 * host/ includes it, slicer/ never includes host/.
 *
 * Thread safety: the table is const; every function only reads it.
 */
#ifndef STRATUM_SLICER_SETTINGS_H
#define STRATUM_SLICER_SETTINGS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

#include "st_error.h"

/* What a value looks like in a profile file. */
enum setting_type {
	SETTING_STRING,	       /* any text, C escapes decoded */
	SETTING_NUMBER,	       /* [+-]digits[.digits] */
	SETTING_INT,	       /* [+-]digits */
	SETTING_BOOL,	       /* 0, 1, false, true */
	SETTING_POINT,	       /* XxY, both coordinates in range */
	SETTING_NUMBER_OR_PCT, /* a number in range, or N% (0-1000%) */
	SETTING_PERCENT,       /* N% 0-100, or a fraction 0-1 */
	SETTING_CHOICE,	       /* one of names[] */
	SETTING_BAUD,	       /* one of settings_baud_rates() */
	SETTING_USB_IDS,       /* VVVV:PPPP list, may be empty */
	SETTING_POLYGON,       /* 3 or more points XxY enclosing an area */
};

/* How many values a key takes. */
enum setting_shape {
	SETTING_ONE = 0,      /* one value */
	SETTING_PER_EXTRUDER, /* a comma list: one value for all, or one per extruder */
	SETTING_FIRST,	      /* a list is accepted (per filament in PrusaSlicer); the first is used */
	SETTING_LIMITS,	      /* machine limit: 1 or 2 values (normal, stealth); the first is used */
};

#define SETTING_GT_MIN 1u      /* the minimum itself is not allowed */
#define SETTING_SAILFISH 2u    /* matters for sailfish printers only */

/* One setting.  Ranges apply to every value of a list (and to both
 * coordinates of a point); a default is written in file syntax, except
 * for strings, which are the text itself. */
struct setting {
	const char *name;  /* PrusaSlicer's key where it has one */
	enum setting_type type;
	enum setting_shape shape;
	double min, max;   /* numeric range (unused for strings and choices) */
	unsigned flags;	   /* SETTING_* */
	const char *unit;  /* "mm", "mm/s", "C" ... or "" */
	const char *dflt;  /* NULL: derived from other keys, help says how */
	const char *sailfish_dflt; /* the default on a sailfish printer; NULL: as dflt */
	const char *const *names;  /* SETTING_CHOICE: the accepted names */
	size_t nnames;
	const char *group; /* non-NULL starts a group (profile output, docs) */
	const char *help;  /* one line for the docs; "" when the name says it */
};

/* settings_count / settings_at - the table in declaration order. */
size_t settings_count(void);
const struct setting *settings_at(size_t i);

/* settings_find - the declaration of name, or NULL. */
const struct setting *settings_find(const char *name);

/*
 * setting_pct_of - the key a percentage of s is of (PrusaSlicer's
 * ratio_over: external_perimeter_speed -> perimeter_speed), or NULL when s
 * takes no percentage or its help says what it is of.
 */
const char *setting_pct_of(const struct setting *s);

/* setting_in_range - v inside s's range (minimum excluded with SETTING_GT_MIN). */
bool setting_in_range(const struct setting *s, double v);

/*
 * setting_range_text - the range as one phrase ("between 0 and 50 mm",
 * "more than 0 and at most 1000 mm/s") for messages and the docs.
 */
void setting_range_text(const struct setting *s, char *buf, size_t cap);

/*
 * setting_default_number - the declared default of a numeric, whole-number,
 * percentage or bool setting (sailfish: the sailfish default); a percentage
 * default ("50%") of a number-or-percentage key is resolved against the
 * default of the key it is of (setting_pct_of), a percentage key's is its
 * percent.
 * Returns false when name is not declared or has no numeric default.
 */
bool setting_default_number(const char *name, bool sailfish, double *out);

/*
 * setting_check - refuse v for name unless finite and inside the declared
 * range.  @what prefixes the message ("G-code settings").
 * Returns 0, ST_ERR_RANGE ("WHAT: NAME = V is out of range (must be ...)"),
 * or ST_ERR_INTERNAL when name is not declared.
 */
int setting_check(const char *what, const char *name, double v, struct st_error *err);

/* The standard baud rates SETTING_BAUD accepts, ascending. */
const long *settings_baud_rates(size_t *count);

/*
 * settings_write_doc - the key tables of docs/printers.md: one Markdown
 * table per group (key, type, range, default, meaning).  The text between
 * the markers in the doc must equal this output (tests/check_profile.c).
 * Returns 0 or ST_ERR_IO when the stream fails.
 */
int settings_write_doc(FILE *f);

#endif /* STRATUM_SLICER_SETTINGS_H */
