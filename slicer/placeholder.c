/*
 * placeholder.c - PrusaSlicer's placeholder language (placeholder.h): a
 * recursive-descent reader of the text that evaluates as it reads, with
 * the precedence of PrusaSlicer's grammar (PlaceholderParser.cpp, itself
 * after C): ?: < or < and < equality and =~ < relational < + - < * / % <
 * unary.
 */
#include "placeholder_int.h"
#include "st_grow.h"

#include <math.h>
#include <regex.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------------------
 * Errors and small helpers
 */

/* "WHAT: line L, column C: message" for byte at of the text. */
int ph_err(const struct ps *p, size_t at, int code, const char *fmt, ...)
{
	char msg[200];
	int line = 1, col = 1;
	va_list ap;

	for (size_t k = 0; k < at && k < p->len; k++, col++)
		if (p->t[k] == '\n')
			line++, col = 0;
	va_start(ap, fmt);
	vsnprintf(msg, sizeof(msg), fmt, ap);
	va_end(ap);
	return st_error_set(p->err, code, "%s: line %d, column %d: %s", p->what, line, col, msg);
}

int ph_buf_add(struct ps *p, struct buf *b, const char *s, size_t n)
{
	if (!b)
		return 0;
	char *grown = n < SIZE_MAX - b->len - 1 ? st_grow(b->p, &b->cap, b->len + n + 1, 1) : NULL;

	if (!grown)
		return ph_err(p, p->i, ST_ERR_NOMEM, "out of memory");
	b->p = grown;
	memcpy(b->p + b->len, s, n);
	b->len += n;
	b->p[b->len] = '\0';
	return 0;
}

static bool is_alpha(char c)
{
	return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_';
}

static bool is_alnum(char c)
{
	return is_alpha(c) || (c >= '0' && c <= '9');
}

void ph_ws(struct ps *p)
{
	while (p->i < p->len &&
	       (p->t[p->i] == ' ' || p->t[p->i] == '\t' || p->t[p->i] == '\n' || p->t[p->i] == '\r'))
		p->i++;
}

/* Length of the identifier at i, 0 when none. */
size_t ph_ident_at(const struct ps *p, size_t i)
{
	size_t k = i;

	if (k >= p->len || !is_alpha(p->t[k]))
		return 0;
	while (k < p->len && is_alnum(p->t[k]))
		k++;
	return k - i;
}

/* The word w at i, as a whole identifier. */
bool ph_word_at(const struct ps *p, size_t i, const char *w)
{
	size_t n = strlen(w);

	return ph_ident_at(p, i) == n && !memcmp(p->t + i, w, n);
}

bool ph_lit(struct ps *p, const char *s)
{
	size_t n = strlen(s);

	ph_ws(p);
	if (p->i + n <= p->len && !memcmp(p->t + p->i, s, n)) {
		p->i += n;
		return true;
	}
	return false;
}

int ph_expect(struct ps *p, const char *s)
{
	if (ph_lit(p, s))
		return 0;
	if (p->i >= p->len)
		return ph_err(p, p->i, ST_ERR_PARSE, "expected '%s' before the end of the text", s);
	return ph_err(p, p->i, ST_ERR_PARSE, "expected '%s', found '%c'", s, p->t[p->i]);
}

void ph_val_free(struct val *v)
{
	if (v->t == PH_STRING)
		free(v->s);
	v->s = NULL;
	v->t = PH_INT;
	v->i = 0;
}

static void val_int(struct val *v, long long i)
{
	ph_val_free(v);
	v->t = PH_INT;
	v->i = i;
	v->boolish = false;
}

static void val_bool(struct val *v, bool b)
{
	ph_val_free(v);
	v->t = PH_BOOL;
	v->i = b;
	v->boolish = false;
}

static void val_real(struct val *v, double d)
{
	ph_val_free(v);
	v->t = PH_REAL;
	v->d = d;
	v->boolish = false;
}

static int val_str(struct ps *p, struct val *v, const char *s, size_t n)
{
	char *c = malloc(n + 1);

	if (!c)
		return ph_err(p, p->i, ST_ERR_NOMEM, "out of memory");
	memcpy(c, s, n);
	c[n] = '\0';
	ph_val_free(v);
	v->t = PH_STRING;
	v->s = c;
	v->boolish = false;
	return 0;
}

static bool numeric(const struct val *v)
{
	return v->t == PH_INT || v->t == PH_REAL;
}

static double as_d(const struct val *v)
{
	return v->t == PH_REAL ? v->d : (double)v->i;
}

/* A bool, or a config's 0/1 standing for one. */
bool ph_truth(const struct val *v, bool *out)
{
	if (v->t == PH_BOOL || (v->t == PH_INT && v->boolish)) {
		*out = v->i != 0;
		return true;
	}
	return false;
}

/* v as PrusaSlicer prints it: {} form (legacy false) or [] form. */
void ph_fmt_val(const struct val *v, bool legacy, char *num, const char **s)
{
	*s = num;
	switch (v->t) {
	case PH_BOOL:
		snprintf(num, PH_NUM, "%s", legacy ? (v->i ? "1" : "0") : (v->i ? "true" : "false"));
		break;
	case PH_INT:
		snprintf(num, PH_NUM, "%lld", v->i);
		break;
	case PH_REAL:
		snprintf(num, PH_NUM, legacy ? "%.15g" : "%g", v->d == 0 ? 0.0 : v->d);
		break;
	case PH_STRING:
		*s = v->s;
		break;
	}
}

/* ---------------------------------------------------------------------------
 * Variables
 */

/* Element idx of x (idx < 0: the current extruder's) into out. */
int ph_var_value(struct ps *p, size_t at, const struct ph_var *x, long long idx,
		     struct val *out)
{
	size_t k;

	/* A config's value typed from its text may be PrusaSlicer's vector of
	 * one: [0] reads it. */
	if (idx > 0 && !x->vector)
		return ph_err(p, at, ST_ERR_UNSUPPORTED, "%s is not a vector; write it without [index]",
			    x->name);
	if (idx >= 0 && (size_t)idx >= x->n)
		return ph_err(p, at, ST_ERR_UNSUPPORTED,
			    "%s[%lld]: index %lld is out of range (%s has %zu value%s)", x->name,
			    idx, idx, x->name, x->n, x->n == 1 ? "" : "s");
	if (x->n == 0)
		return ph_err(p, at, ST_ERR_RANGE, "%s has no value", x->name);
	k = idx >= 0 ? (size_t)idx : p->extruder < x->n ? p->extruder : 0;
	if (!x->vector)
		k = 0;
	if (x->type == PH_STRING)
		return val_str(p, out, x->str[k], strlen(x->str[k]));
	if (x->type == PH_REAL)
		val_real(out, x->num[k]);
	else if (x->type == PH_BOOL)
		val_bool(out, x->num[k] != 0);
	else
		val_int(out, (long long)x->num[k]);
	out->boolish = x->boolish;
	return 0;
}

/* ---------------------------------------------------------------------------
 * Expressions
 */

int ph_cond_expr(struct ps *p, struct val *out);
static int add_expr(struct ps *p, struct val *out);

/* "..." with backslash escapes. */
static int string_lit(struct ps *p, struct val *out)
{
	size_t start = p->i++;
	struct buf b = {0};
	int rc = 0;

	while (p->i < p->len && p->t[p->i] != '"' && rc == 0) {
		if (p->t[p->i] == '\\' && p->i + 1 < p->len)
			p->i++;
		rc = ph_buf_add(p, &b, p->t + p->i++, 1);
	}
	if (rc == 0 && p->i >= p->len)
		rc = ph_err(p, start, ST_ERR_PARSE, "the string has no closing '\"'");
	if (rc == 0) {
		p->i++;
		rc = val_str(p, out, b.p ? b.p : "", b.len);
	}
	free(b.p);
	return rc;
}

/* digits[.digits][e[+-]digits]: an int, or a real with '.' or an exponent. */
static int number_lit(struct ps *p, struct val *out)
{
	size_t start = p->i, k = p->i;
	bool real = false;
	char tmp[PH_NUM];
	char *end;

	while (k < p->len && p->t[k] >= '0' && p->t[k] <= '9')
		k++;
	if (k < p->len && p->t[k] == '.') {
		real = true;
		for (k++; k < p->len && p->t[k] >= '0' && p->t[k] <= '9'; k++)
			;
	}
	if (k < p->len && (p->t[k] == 'e' || p->t[k] == 'E')) {
		size_t e = k + 1;
		if (e < p->len && (p->t[e] == '+' || p->t[e] == '-'))
			e++;
		if (e < p->len && p->t[e] >= '0' && p->t[e] <= '9') {
			real = true;
			for (k = e; k < p->len && p->t[k] >= '0' && p->t[k] <= '9'; k++)
				;
		}
	}
	if (k - start >= sizeof(tmp))
		return ph_err(p, start, ST_ERR_PARSE, "number too long");
	memcpy(tmp, p->t + start, k - start);
	tmp[k - start] = '\0';
	p->i = k;
	if (real) {
		val_real(out, strtod(tmp, &end));
	} else {
		long long v = strtoll(tmp, &end, 10);
		if (v > INT32_MAX)
			return ph_err(p, start, ST_ERR_RANGE, "%s is too large for a whole number", tmp);
		val_int(out, v);
	}
	return 0;
}

/* min, max, int, round, digits, zdigits: the name is at p->i. */
static int function(struct ps *p, const char *name, struct val *out)
{
	size_t at = p->i;
	struct val b = {PH_INT, false, 0, 0, NULL}, c = {PH_INT, false, 0, 0, NULL};
	bool two = !strcmp(name, "min") || !strcmp(name, "max");
	bool dig = !strcmp(name, "digits") || !strcmp(name, "zdigits");
	int rc;

	p->i += strlen(name);
	rc = ph_expect(p, "(");
	if (rc == 0)
		rc = ph_cond_expr(p, out);
	if (rc == 0 && (two || dig)) {
		rc = ph_expect(p, ",");
		if (rc == 0)
			rc = ph_cond_expr(p, &b);
	}
	if (rc == 0 && dig && ph_lit(p, ","))
		rc = ph_cond_expr(p, &c);
	if (rc == 0)
		rc = ph_expect(p, ")");
	if (rc || p->skip)
		goto out;
	if (!numeric(out) || ((two || dig) && !numeric(&b)) || (dig && !numeric(&c))) {
		rc = ph_err(p, at, ST_ERR_RANGE, "%s() takes numbers", name);
	} else if (two) {
		bool lo = as_d(out) < as_d(&b), pick_b = !strcmp(name, "min") ? !lo : lo;
		bool real = out->t == PH_REAL || b.t == PH_REAL;
		double d = pick_b ? as_d(&b) : as_d(out);

		if (real)
			val_real(out, d);
		else
			val_int(out, (long long)d);
	} else if (dig) {
		char num[PH_NUM];
		int w = (int)as_d(&b), dd = (int)as_d(&c);

		if (w < 0 || w > 40 || dd < 0 || dd > 20)
			rc = ph_err(p, at, ST_ERR_RANGE, "%s(): width 0-40 and decimals 0-20", name);
		else {
			snprintf(num, sizeof(num), name[0] == 'z' ? "%0*.*f" : "%*.*f", w, dd,
				 as_d(out));
			rc = val_str(p, out, num, strlen(num));
		}
	} else {
		double d = as_d(out);
		double r = !strcmp(name, "round") ? round(d) : trunc(d);

		if (!(fabs(r) <= INT32_MAX))
			rc = ph_err(p, at, ST_ERR_RANGE, "%s(): %g does not fit a whole number", name, d);
		else
			val_int(out, (long long)r);
	}
out:
	ph_val_free(&b);
	ph_val_free(&c);
	return rc;
}

/* name or name[index]. */
static int variable(struct ps *p, size_t n, struct val *out)
{
	size_t at = p->i;
	const struct ph_var *x;
	long long idx = -1;
	int rc = 0;

	p->i += n;
	if (ph_lit(p, "[")) {
		struct val iv = {PH_INT, false, 0, 0, NULL};

		rc = add_expr(p, &iv);
		if (rc == 0)
			rc = ph_expect(p, "]");
		if (rc == 0 && !p->skip && iv.t != PH_INT)
			rc = ph_err(p, at, ST_ERR_RANGE, "an index must be a whole number");
		if (rc == 0 && iv.i < 0 && !p->skip)
			rc = ph_err(p, at, ST_ERR_RANGE, "negative index %lld", iv.i);
		idx = iv.i;
		ph_val_free(&iv);
		if (rc)
			return rc;
	}
	x = ph_vars_find(p->vars, p->t + at, n);
	if (p->skip) {
		val_int(out, 0);
		return 0;
	}
	if (!x)
		return ph_err(p, at, ST_ERR_PARSE, "unknown placeholder {%.*s}",
			    (int)(n > PH_SHOW ? PH_SHOW : n), p->t + at);
	return ph_var_value(p, at, x, idx, out);
}

static int unary_expr(struct ps *p, struct val *out)
{
	static const char *const funcs[] = {"min", "max", "int", "round", "digits", "zdigits"};
	size_t at, n;
	int rc;
	bool b = false;

	if (++p->depth > PH_DEPTH_MAX)
		return ph_err(p, p->i, ST_ERR_RANGE, "nested too deeply");
	ph_ws(p);
	at = p->i;
	if (at >= p->len) {
		rc = ph_err(p, at, ST_ERR_PARSE, "expected a value before the end of the text");
	} else if (p->t[at] == '(') {
		p->i++;
		rc = ph_cond_expr(p, out);
		if (rc == 0)
			rc = ph_expect(p, ")");
	} else if (p->t[at] == '-' || p->t[at] == '+') {
		p->i++;
		rc = unary_expr(p, out);
		if (rc == 0 && !p->skip && !numeric(out))
			rc = ph_err(p, at, ST_ERR_RANGE, "'%c' needs a number", p->t[at]);
		if (rc == 0 && p->t[at] == '-' && out->t == PH_INT)
			out->i = -out->i;
		else if (rc == 0 && p->t[at] == '-' && out->t == PH_REAL)
			out->d = -out->d;
		out->boolish = false;
	} else if (p->t[at] == '!' || ph_word_at(p, at, "not")) {
		p->i += p->t[at] == '!' ? 1 : 3;
		rc = unary_expr(p, out);
		if (rc == 0 && !p->skip && !ph_truth(out, &b))
			rc = ph_err(p, at, ST_ERR_RANGE, "'not' needs a condition");
		if (rc == 0 && !p->skip)
			val_bool(out, !b);
	} else if (p->t[at] == '"') {
		rc = string_lit(p, out);
	} else if ((p->t[at] >= '0' && p->t[at] <= '9') || p->t[at] == '.') {
		rc = number_lit(p, out);
	} else if (ph_word_at(p, at, "true") || ph_word_at(p, at, "false")) {
		val_bool(out, p->t[at] == 't');
		p->i += p->t[at] == 't' ? 4 : 5;
		rc = 0;
	} else if ((n = ph_ident_at(p, at)) > 0) {
		size_t k;

		for (k = 0; k < sizeof(funcs) / sizeof(funcs[0]); k++)
			if (ph_word_at(p, at, funcs[k]))
				break;
		if (k < sizeof(funcs) / sizeof(funcs[0]))
			rc = function(p, funcs[k], out);
		else
			rc = variable(p, n, out);
	} else {
		rc = ph_err(p, at, ST_ERR_PARSE, "expected a value, found '%c'", p->t[at]);
	}
	p->depth--;
	return rc;
}

/* a OP b for + - * / %; the result in a. */
static int arith(struct ps *p, size_t at, char op, struct val *a, struct val *b)
{
	char na[PH_NUM], nb[PH_NUM];
	const char *sa, *sb;

	if (p->skip) {
		val_int(a, 0);
		return 0;
	}
	if (op == '+' && (a->t == PH_STRING || b->t == PH_STRING)) {
		struct buf cat = {0};
		int rc;

		ph_fmt_val(a, false, na, &sa);
		ph_fmt_val(b, false, nb, &sb);
		rc = ph_buf_add(p, &cat, sa, strlen(sa));
		if (rc == 0)
			rc = ph_buf_add(p, &cat, sb, strlen(sb));
		if (rc == 0)
			rc = val_str(p, a, cat.p ? cat.p : "", cat.len);
		free(cat.p);
		return rc;
	}
	if (!numeric(a) || !numeric(b))
		return ph_err(p, at, ST_ERR_RANGE, "'%c' needs numbers", op);
	if ((op == '/' || op == '%') && (b->t == PH_INT ? b->i == 0 : b->d == 0))
		return ph_err(p, at, ST_ERR_RANGE, "division by zero");
	if (a->t == PH_REAL || b->t == PH_REAL) {
		double x = as_d(a), y = as_d(b);
		val_real(a, op == '+' ? x + y : op == '-' ? x - y : op == '*' ? x * y
			    : op == '/' ? x / y : fmod(x, y));
		return 0;
	}
	{
		long long x = a->i, y = b->i, r;

		r = op == '+' ? x + y : op == '-' ? x - y : op == '*' ? x * y : op == '/' ? x / y : x % y;
		if (r > INT32_MAX || r < INT32_MIN)
			return ph_err(p, at, ST_ERR_RANGE, "whole-number overflow");
		val_int(a, r);
	}
	return 0;
}

/* A left-associative chain of the operators in ops over next's operands. */
static int chain(struct ps *p, struct val *out, const char *ops,
		 int (*next)(struct ps *, struct val *))
{
	int rc = next(p, out);

	while (rc == 0) {
		struct val b = {PH_INT, false, 0, 0, NULL};
		size_t at;
		char op;

		ph_ws(p);
		at = p->i;
		if (at >= p->len || !strchr(ops, p->t[at]) || !p->t[at])
			break;
		op = p->t[p->i++];
		rc = next(p, &b);
		if (rc == 0)
			rc = arith(p, at, op, out, &b);
		ph_val_free(&b);
	}
	return rc;
}

static int mul_expr(struct ps *p, struct val *out)
{
	return chain(p, out, "*/%", unary_expr);
}

static int add_expr(struct ps *p, struct val *out)
{
	return chain(p, out, "+-", mul_expr);
}

/* Compare a with b ('=' '<' '>', invert for != >= <=); the result in a. */
static int compare(struct ps *p, size_t at, char op, bool invert, struct val *a, struct val *b)
{
	bool r, ba, bb;

	if (p->skip) {
		val_bool(a, false);
		return 0;
	}
	if (numeric(a) && numeric(b) && !(a->boolish && b->t == PH_BOOL)) {
		double x = as_d(a), y = as_d(b);
		bool real = a->t == PH_REAL || b->t == PH_REAL;

		r = op == '=' ? (real ? fabs(x - y) < 1e-8 : a->i == b->i) : op == '<' ? x < y : x > y;
	} else if (ph_truth(a, &ba) && ph_truth(b, &bb)) {
		if (op != '=')
			return ph_err(p, at, ST_ERR_RANGE, "conditions can only be compared with == or !=");
		r = ba == bb;
	} else if (a->t == PH_STRING || b->t == PH_STRING) {
		char na[PH_NUM], nb[PH_NUM];
		const char *sa, *sb;
		int c;

		ph_fmt_val(a, false, na, &sa);
		ph_fmt_val(b, false, nb, &sb);
		c = strcmp(sa, sb);
		r = op == '=' ? c == 0 : op == '<' ? c < 0 : c > 0;
	} else {
		return ph_err(p, at, ST_ERR_RANGE, "cannot compare these values");
	}
	val_bool(a, invert ? !r : r);
	return 0;
}

static int rel_expr(struct ps *p, struct val *out)
{
	int rc = add_expr(p, out);

	while (rc == 0) {
		struct val b = {PH_INT, false, 0, 0, NULL};
		size_t at;
		char op;
		bool inv;

		ph_ws(p);
		at = p->i;
		if (ph_lit(p, "<=")) {
			op = '>', inv = true;
		} else if (ph_lit(p, ">=")) {
			op = '<', inv = true;
		} else if (p->i < p->len && (p->t[p->i] == '<' || p->t[p->i] == '>') &&
			   !(p->t[p->i] == '<' && p->i + 1 < p->len && p->t[p->i + 1] == '>')) {
			op = p->t[p->i++], inv = false;
		} else {
			break;
		}
		rc = add_expr(p, &b);
		if (rc == 0)
			rc = compare(p, at, op, inv, out, &b);
		ph_val_free(&b);
	}
	return rc;
}

/* /regex/ matched against the whole of a (=~), or not (!~). */
static int regex_match(struct ps *p, size_t at, bool negate, struct val *a)
{
	struct buf pat = {0};
	size_t start;
	regex_t re;
	int rc = 0, r;

	ph_ws(p);
	start = p->i;
	if (p->i >= p->len || p->t[p->i] != '/')
		return ph_err(p, p->i, ST_ERR_PARSE, "expected a /regular expression/");
	rc = ph_buf_add(p, &pat, "^(", 2);
	for (p->i++; rc == 0 && p->i < p->len && p->t[p->i] != '/'; p->i++) {
		if (p->t[p->i] == '\\' && p->i + 1 < p->len) {
			char c = p->t[++p->i];
			rc = ph_buf_add(p, &pat, c == '/' ? "/" : c == 'd' ? "[0-9]" : c == 'D' ? "[^0-9]" : "\\",
				     c == '/' ? 1 : c == 'd' ? 5 : c == 'D' ? 6 : 1);
			if (rc == 0 && c != '/' && c != 'd' && c != 'D')
				rc = ph_buf_add(p, &pat, &c, 1);
		} else {
			rc = ph_buf_add(p, &pat, p->t + p->i, 1);
		}
	}
	if (rc == 0 && p->i >= p->len)
		rc = ph_err(p, start, ST_ERR_PARSE, "the regular expression has no closing '/'");
	if (rc == 0) {
		p->i++;
		rc = ph_buf_add(p, &pat, ")$", 2);
	}
	if (rc == 0 && !p->skip && a->t != PH_STRING)
		rc = ph_err(p, at, ST_ERR_RANGE, "the left side of %s must be a string",
			  negate ? "!~" : "=~");
	if (rc == 0 && !p->skip) {
		r = regcomp(&re, pat.p, REG_EXTENDED | REG_NOSUB);
		if (r != 0) {
			rc = ph_err(p, start, ST_ERR_PARSE, "bad regular expression");
		} else {
			bool m = regexec(&re, a->s, 0, NULL, 0) == 0;
			regfree(&re);
			val_bool(a, negate ? !m : m);
		}
	}
	if (rc == 0 && p->skip)
		val_bool(a, false);
	free(pat.p);
	return rc;
}

static int eq_expr(struct ps *p, struct val *out)
{
	int rc = rel_expr(p, out);

	while (rc == 0) {
		struct val b = {PH_INT, false, 0, 0, NULL};
		size_t at;
		bool inv;

		ph_ws(p);
		at = p->i;
		if (ph_lit(p, "=~") || ph_lit(p, "!~")) {
			rc = regex_match(p, at, p->t[at] == '!', out);
			continue;
		}
		if (ph_lit(p, "=="))
			inv = false;
		else if (ph_lit(p, "!=") || ph_lit(p, "<>"))
			inv = true;
		else
			break;
		rc = rel_expr(p, &b);
		if (rc == 0)
			rc = compare(p, at, '=', inv, out, &b);
		ph_val_free(&b);
	}
	return rc;
}

/* A chain of and (is_and) or of or. */
static int logic_expr(struct ps *p, struct val *out, bool is_and)
{
	const char *word = is_and ? "and" : "or", *sym = is_and ? "&&" : "||";
	int rc = is_and ? eq_expr(p, out) : logic_expr(p, out, true);

	while (rc == 0) {
		struct val b = {PH_INT, false, 0, 0, NULL};
		size_t at;
		bool x, y;

		ph_ws(p);
		at = p->i;
		if (ph_word_at(p, at, word))
			p->i += strlen(word);
		else if (!ph_lit(p, sym))
			break;
		rc = is_and ? eq_expr(p, &b) : logic_expr(p, &b, true);
		if (rc == 0 && !p->skip) {
			if (!ph_truth(out, &x) || !ph_truth(&b, &y))
				rc = ph_err(p, at, ST_ERR_RANGE, "'%s' needs conditions on both sides",
					  word);
			else
				val_bool(out, is_and ? x && y : x || y);
		}
		ph_val_free(&b);
	}
	return rc;
}

int ph_cond_expr(struct ps *p, struct val *out)
{
	struct val a = {PH_INT, false, 0, 0, NULL}, b = {PH_INT, false, 0, 0, NULL};
	size_t at;
	bool c = false;
	int rc;

	if (++p->depth > PH_DEPTH_MAX)
		return ph_err(p, p->i, ST_ERR_RANGE, "nested too deeply");
	rc = logic_expr(p, out, false);
	ph_ws(p);
	at = p->i;
	if (rc == 0 && ph_lit(p, "?")) {
		rc = ph_cond_expr(p, &a);
		if (rc == 0)
			rc = ph_expect(p, ":");
		if (rc == 0)
			rc = ph_cond_expr(p, &b);
		if (rc == 0 && !p->skip && !ph_truth(out, &c))
			rc = ph_err(p, at, ST_ERR_RANGE, "'?' needs a condition before it");
		if (rc == 0 && !p->skip) {
			ph_val_free(out);
			*out = c ? a : b;
			if (c)
				a.s = NULL, a.t = PH_INT;
			else
				b.s = NULL, b.t = PH_INT;
		}
	}
	ph_val_free(&a);
	ph_val_free(&b);
	p->depth--;
	return rc;
}

