/*
 * placeholder_text.c - the text level of the placeholder language
 * (placeholder.h): plain text copied, {expression} printed, {if} blocks,
 * PrusaSlicer's legacy [key] forms; the expressions are placeholder.c's.
 */
#include "placeholder_int.h"

#include <stdlib.h>
#include <string.h>

enum stop { STOP_END, STOP_ELSIF, STOP_ELSE, STOP_ENDIF };

static int text_block(struct ps *p, struct buf *out, enum stop *stop, size_t *stop_at);

/* A condition of {if} or {elsif}, up to its '}'. */
static int condition(struct ps *p, size_t at, bool *c)
{
	struct val v = {PH_INT, false, 0, 0, NULL};
	int rc = ph_cond_expr(p, &v);

	if (rc == 0)
		rc = ph_expect(p, "}");
	if (rc == 0 && !p->skip && !ph_truth(&v, c))
		rc = ph_err(p, at, ST_ERR_RANGE, "{if} and {elsif} need a condition");
	ph_val_free(&v);
	return rc;
}

/* {if c}...{elsif c}...{else}...{endif}; "if" at at is read. */
static int if_block(struct ps *p, size_t at, struct buf *out)
{
	bool taken = false, outer = p->skip, c = false, in_else = false;
	enum stop stop;
	size_t stop_at;
	int rc;

	if (++p->depth > PH_DEPTH_MAX)
		return ph_err(p, at, ST_ERR_RANGE, "{if} nested too deeply");
	rc = condition(p, at, &c);
	while (rc == 0) {
		bool active = !outer && !taken && (in_else || c);

		p->skip = outer || !active;
		rc = text_block(p, active ? out : NULL, &stop, &stop_at);
		p->skip = outer;
		if (rc)
			break;
		taken = taken || active;
		if (stop == STOP_END) {
			rc = ph_err(p, at, ST_ERR_PARSE, "{if} has no {endif}");
		} else if (stop == STOP_ENDIF) {
			rc = ph_expect(p, "}");
			break;
		} else if (in_else) {
			rc = ph_err(p, stop_at, ST_ERR_PARSE, "{%s} after {else}",
				  stop == STOP_ELSE ? "else" : "elsif");
		} else if (stop == STOP_ELSE) {
			in_else = true;
			rc = ph_expect(p, "}");
		} else {
			p->skip = outer || taken;
			rc = condition(p, stop_at, &c);
			p->skip = outer;
		}
	}
	p->depth--;
	return rc;
}

/* [key], [key_N] or [key[index_var]] at p->i ('[' included); false when
 * the text there is not one of these (it is then copied as it is). */
static int legacy(struct ps *p, struct buf *out, bool *done)
{
	size_t at = p->i, n = ph_ident_at(p, at + 1), k = at + 1 + n, idx_n = 0;
	const struct ph_var *x;
	struct val v = {PH_INT, false, 0, 0, NULL};
	long long idx = -1;
	char num[PH_NUM];
	const char *s;
	int rc;

	*done = false;
	if (n == 0 || k >= p->len)
		return 0;
	if (p->t[k] == '[') {
		idx_n = ph_ident_at(p, k + 1);
		if (idx_n == 0 || k + 1 + idx_n + 1 >= p->len || p->t[k + 1 + idx_n] != ']' ||
		    p->t[k + 2 + idx_n] != ']')
			return 0;
	} else if (p->t[k] != ']') {
		return 0;
	}
	*done = true;
	x = ph_vars_find(p->vars, p->t + at + 1, n);
	if (!x && idx_n == 0) {
		size_t us = n;
		const char *name = p->t + at + 1;

		while (us > 0 && name[us - 1] >= '0' && name[us - 1] <= '9')
			us--;
		if (us > 1 && us < n && name[us - 1] == '_') {
			const struct ph_var *base = ph_vars_find(p->vars, name, us - 1);
			if (base && base->vector) {
				idx = strtoll(name + us, NULL, 10);
				if (!p->skip && (size_t)idx >= base->n)
					return ph_err(p, at, ST_ERR_UNSUPPORTED,
						    "[%.*s]: extruder index %lld is out of range "
						    "(%.*s has %zu value%s); use [%.*s_0]",
						    (int)n, name, idx, (int)(us - 1), name, base->n,
						    base->n == 1 ? "" : "s", (int)(us - 1), name);
				x = base;
			}
		}
	}
	if (idx_n) {
		const struct ph_var *ix = ph_vars_find(p->vars, p->t + k + 1, idx_n);
		if (!ix && !p->skip)
			return ph_err(p, k + 1, ST_ERR_PARSE, "unknown placeholder %.*s", (int)idx_n,
				    p->t + k + 1);
		if (ix && (ix->type != PH_INT || ix->n == 0) && !p->skip)
			return ph_err(p, k + 1, ST_ERR_RANGE, "an index must be a whole number");
		idx = ix ? (long long)ix->num[0] : 0;
		k += idx_n + 2;
	}
	p->i = k + 1;
	if (p->skip)
		return 0;
	if (!x)
		return ph_err(p, at, ST_ERR_PARSE, "unknown placeholder [%.*s]",
			    (int)(n > PH_SHOW ? PH_SHOW : n), p->t + at + 1);
	if (idx >= 0 && !x->vector)
		return ph_err(p, at, ST_ERR_PARSE, "unknown placeholder [%.*s]", (int)n, p->t + at + 1);
	rc = ph_var_value(p, at, x, idx, &v);
	if (rc == 0) {
		ph_fmt_val(&v, true, num, &s);
		rc = ph_buf_add(p, out, s, strlen(s));
	}
	ph_val_free(&v);
	return rc;
}

/* Text up to the end or to an {elsif}, {else} or {endif} (its keyword read). */
static int text_block(struct ps *p, struct buf *out, enum stop *stop, size_t *stop_at)
{
	static const char *const stops[] = {"elsif", "else", "endif"};

	while (p->i < p->len) {
		size_t at = p->i, k;
		char c = p->t[at];
		int rc;

		if (c == '[') {
			bool done;

			rc = legacy(p, out, &done);
			if (rc)
				return rc;
			if (done)
				continue;
		} else if (c == '{') {
			struct val v = {PH_INT, false, 0, 0, NULL};
			char num[PH_NUM];
			const char *s;

			p->i++;
			ph_ws(p);
			for (k = 0; k < 3; k++)
				if (ph_word_at(p, p->i, stops[k])) {
					*stop = (enum stop)(k + 1);
					*stop_at = at;
					p->i += strlen(stops[k]);
					return 0;
				}
			if (ph_word_at(p, p->i, "if")) {
				p->i += 2;
				rc = if_block(p, at, out);
				if (rc)
					return rc;
				continue;
			}
			rc = ph_cond_expr(p, &v);
			if (rc == 0)
				rc = ph_expect(p, "}");
			if (rc == 0 && !p->skip) {
				ph_fmt_val(&v, false, num, &s);
				rc = ph_buf_add(p, out, s, strlen(s));
			}
			ph_val_free(&v);
			if (rc)
				return rc;
			continue;
		}
		for (k = at + 1; k < p->len && p->t[k] != '[' && p->t[k] != '{'; k++)
			;
		rc = ph_buf_add(p, out, p->t + at, k - at);
		if (rc)
			return rc;
		p->i = k;
	}
	*stop = STOP_END;
	*stop_at = p->len;
	return 0;
}

int ph_expand(const char *text, const char *what, const struct ph_vars *vars, size_t extruder,
	      char **out, struct st_error *err)
{
	struct ps p = {0};
	struct buf b = {0};
	enum stop stop;
	size_t stop_at;
	int rc;

	if (out)
		*out = NULL;
	if (!text || !out)
		return st_error_set(err, ST_ERR_ARG, "placeholders: no text or output");
	p.t = text;
	p.len = strlen(text);
	p.what = what ? what : "custom G-code";
	p.vars = vars;
	p.extruder = extruder;
	p.err = err;
	rc = text_block(&p, &b, &stop, &stop_at);
	if (rc == 0 && stop != STOP_END)
		rc = ph_err(&p, stop_at, ST_ERR_PARSE, "{%s} without {if}",
			  stop == STOP_ELSIF ? "elsif" : stop == STOP_ELSE ? "else" : "endif");
	if (rc == 0)
		rc = ph_buf_add(&p, &b, "", 0);
	if (rc) {
		free(b.p);
		return rc;
	}
	*out = b.p;
	return 0;
}

int ph_eval_bool(const char *expr, const char *what, const struct ph_vars *vars, bool *out,
		 struct st_error *err)
{
	struct ps p = {0};
	struct val v = {PH_INT, false, 0, 0, NULL};
	int rc;

	if (!expr || !out)
		return st_error_set(err, ST_ERR_ARG, "placeholders: no expression or output");
	p.t = expr;
	p.len = strlen(expr);
	p.what = what ? what : "condition";
	p.vars = vars;
	p.err = err;
	rc = ph_cond_expr(&p, &v);
	ph_ws(&p);
	if (rc == 0 && p.i < p.len)
		rc = ph_err(&p, p.i, ST_ERR_PARSE, "unexpected '%c' after the condition", p.t[p.i]);
	if (rc == 0 && !ph_truth(&v, out))
		rc = ph_err(&p, 0, ST_ERR_RANGE, "not a condition");
	ph_val_free(&v);
	return rc;
}
