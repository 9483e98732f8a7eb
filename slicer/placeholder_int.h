/*
 * placeholder_int.h - what placeholder.c (expressions), placeholder_text.c
 * (text, {if} blocks, [legacy]) and placeholder_vars.c share;
 * nothing else includes it.  The contract is placeholder.h.
 */
#ifndef STRATUM_SLICER_PLACEHOLDER_INT_H
#define STRATUM_SLICER_PLACEHOLDER_INT_H

#include <stdbool.h>
#include <stddef.h>

#include "placeholder.h"

/* One variable: n numbers or n strings. */
struct ph_var {
	char *name;
	enum ph_type type;
	bool vector;  /* per extruder: may be indexed */
	bool boolish; /* typed from a config's 0/1: may serve as a condition */
	size_t n;
	double *num;  /* PH_BOOL, PH_INT, PH_REAL */
	char **str;   /* PH_STRING */
};

struct ph_vars {
	const struct ph_vars *parent;
	struct ph_var *v;
	size_t n, cap;
};

/* The variable name[0..len) in v or its parents, or NULL. */
const struct ph_var *ph_vars_find(const struct ph_vars *v, const char *name, size_t len);

/* The variable name in v itself (not its parents), or NULL. */
struct ph_var *ph_vars_find_own(struct ph_vars *v, const char *name);

#define PH_DEPTH_MAX 200 /* nesting of parentheses, ifs and unary operators */
#define PH_SHOW 48	 /* bytes of a name quoted in messages */
#define PH_NUM 64	 /* a formatted number */

/* A value during evaluation; s is owned. */
struct val {
	enum ph_type t;
	bool boolish;
	long long i; /* PH_INT, and PH_BOOL as 0/1 */
	double d;    /* PH_REAL */
	char *s;     /* PH_STRING */
};

struct buf {
	char *p;
	size_t len, cap;
};

struct ps {
	const char *t, *what;
	size_t len, i;
	const struct ph_vars *vars;
	size_t extruder;
	struct st_error *err;
	bool skip; /* in a branch not taken: syntax only */
	int depth;
};

/* "WHAT: line L, column C: message" for byte at of the text. */
int ph_err(const struct ps *p, size_t at, int code, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
/* Append n bytes to b (NULL: dropped, a branch not taken). */
int ph_buf_add(struct ps *p, struct buf *b, const char *s, size_t n);
void ph_ws(struct ps *p);			       /* skip blanks and line ends */
size_t ph_ident_at(const struct ps *p, size_t i);      /* identifier length at i, or 0 */
bool ph_word_at(const struct ps *p, size_t i, const char *w); /* w as a whole word at i */
bool ph_lit(struct ps *p, const char *s);	       /* s next (after blanks): read it */
int ph_expect(struct ps *p, const char *s);	       /* s next, or an error */
void ph_val_free(struct val *v);
/* v as PrusaSlicer prints it: {} form, or [] (legacy) form; *s may point into num. */
void ph_fmt_val(const struct val *v, bool legacy, char *num, const char **s);
bool ph_truth(const struct val *v, bool *out); /* a bool, or a config's 0/1 */
/* Element idx of x (idx < 0: the current extruder's). */
int ph_var_value(struct ps *p, size_t at, const struct ph_var *x, long long idx, struct val *out);
/* A whole expression, ?: included. */
int ph_cond_expr(struct ps *p, struct val *out);

#endif /* STRATUM_SLICER_PLACEHOLDER_INT_H */
