/*
 * placeholder.h - PrusaSlicer's placeholder (macro) language for custom
 * G-code: start, end, before/after layer change, toolchange and filament
 * G-code, as PrusaSlicer 2.5's PlaceholderParser evaluates it:
 *
 *   [key] [key_N] [key[index_var]]   legacy expansion (a vector gives the
 *                                    current extruder's value);
 *   {expression}                     any expression below, printed;
 *   {if c}...{elsif c}...{else}...{endif}   nested freely;
 *   expressions: numbers (int, real), "strings", true/false, key,
 *     key[expr], + - * / % (string + anything concatenates), == != <> < >
 *     <= >=, =~ /regex/ and !~ /regex/ (whole-string match, '.' matches a
 *     line break), and && or || not !, c ? a : b, ( ), min(a,b), max(a,b),
 *     int(x), round(x), digits(x,n[,d]), zdigits(x,n[,d]).
 *
 * Types follow PrusaSlicer: int / int stays whole, a real prints as %g
 * (ostream's default), a bool as true/false in {} and 1/0 in [].  Where a
 * profile's key has no declared type, a whole number 0 or 1 may also serve
 * as a condition (PrusaSlicer's bools are written 0/1).  Stricter than
 * PrusaSlicer in one place: an index past a vector's end is refused, not
 * silently read as element 0.  Branches not taken are checked for syntax
 * only.  docs/slicing.md lists the standard variables the G-code writer
 * sets.
 *
 * Errors name the text, line and column: "start_gcode: line 3, column 12:
 * unknown variable 'foo'" (ST_ERR_PARSE for syntax and unknown names,
 * ST_ERR_RANGE for type errors, division by zero and overflow,
 * ST_ERR_UNSUPPORTED for an index past a vector's end).
 *
 * Thread safety: a struct ph_vars is read-only during ph_expand; distinct
 * tables are independent.
 */
#ifndef STRATUM_SLICER_PLACEHOLDER_H
#define STRATUM_SLICER_PLACEHOLDER_H

#include <stdbool.h>
#include <stddef.h>

#include "st_error.h"

enum ph_type {
	PH_BOOL,
	PH_INT,
	PH_REAL,
	PH_STRING,
};

/* A table of variables; lookups that miss go on to its parent. */
struct ph_vars;

/* ph_vars_new - an empty table over parent (NULL: none; not owned, must
 * outlive the table).  NULL when out of memory. */
struct ph_vars *ph_vars_new(const struct ph_vars *parent);

/* ph_vars_free - NULL is fine. */
void ph_vars_free(struct ph_vars *v);

/*
 * ph_vars_set_numbers - set name to n numbers of type t (PH_BOOL, PH_INT
 * or PH_REAL; a bool is 0 or 1).  vector: a per-extruder list (indexable),
 * else n must be 1.  Replaces an earlier value of name in this table.
 * Returns 0, ST_ERR_ARG or ST_ERR_NOMEM.
 */
int ph_vars_set_numbers(struct ph_vars *v, const char *name, enum ph_type t, const double *vals,
			size_t n, bool vector, struct st_error *err);

/* ph_vars_set_number - one scalar number. */
int ph_vars_set_number(struct ph_vars *v, const char *name, enum ph_type t, double val,
		       struct st_error *err);

/* ph_vars_set_strings - name to n strings (copied); vector as above. */
int ph_vars_set_strings(struct ph_vars *v, const char *name, const char *const *vals, size_t n,
			bool vector, struct st_error *err);

/*
 * ph_vars_set_config - name from a config file's value text, typed as
 * PrusaSlicer wrote it: "a";"b" is a list of strings, a comma list of
 * numbers a vector, N% a real, a whole number an int that may serve as a
 * bool, a real a real, anything else a string.
 */
int ph_vars_set_config(struct ph_vars *v, const char *name, const char *text,
		       struct st_error *err);

/* ph_vars_has - name is set in v or a parent. */
bool ph_vars_has(const struct ph_vars *v, const char *name);

/*
 * ph_expand - the text with every placeholder replaced.
 * @what: names the text in messages ("start_gcode").
 * @extruder: the current extruder, for vectors read without an index.
 * On success *out is a new string (free()); on error NULL and err set.
 */
int ph_expand(const char *text, const char *what, const struct ph_vars *vars, size_t extruder,
	      char **out, struct st_error *err);

/*
 * ph_eval_bool - evaluate one boolean expression (PrusaSlicer's
 * compatible_printers_condition): *out is its value.  Errors as ph_expand.
 */
int ph_eval_bool(const char *expr, const char *what, const struct ph_vars *vars, bool *out,
		 struct st_error *err);

#endif /* STRATUM_SLICER_PLACEHOLDER_H */
