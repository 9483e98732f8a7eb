/*
 * placeholder_vars.c - the variable tables of the placeholder language
 * (placeholder.h): storage, lookup through parents, and typing a config
 * file's value text the way PrusaSlicer wrote it.
 */
#include "placeholder_int.h"

#include <stdlib.h>
#include <string.h>

#include "st_number.h"
#include "st_grow.h"

struct ph_vars *ph_vars_new(const struct ph_vars *parent)
{
	struct ph_vars *v = calloc(1, sizeof(*v));

	if (v)
		v->parent = parent;
	return v;
}

static void var_clear(struct ph_var *x)
{
	for (size_t k = 0; x->str && k < x->n; k++)
		free(x->str[k]);
	free(x->str);
	free(x->num);
	x->str = NULL;
	x->num = NULL;
	x->n = 0;
}

void ph_vars_free(struct ph_vars *v)
{
	if (!v)
		return;
	for (size_t i = 0; i < v->n; i++) {
		var_clear(&v->v[i]);
		free(v->v[i].name);
	}
	free(v->v);
	free(v);
}

const struct ph_var *ph_vars_find(const struct ph_vars *v, const char *name, size_t len)
{
	for (; v; v = v->parent)
		for (size_t i = 0; i < v->n; i++)
			if (strlen(v->v[i].name) == len && !memcmp(v->v[i].name, name, len))
				return &v->v[i];
	return NULL;
}

bool ph_vars_has(const struct ph_vars *v, const char *name)
{
	return name && ph_vars_find(v, name, strlen(name)) != NULL;
}

struct ph_var *ph_vars_find_own(struct ph_vars *v, const char *name)
{
	for (size_t i = 0; i < v->n; i++)
		if (!strcmp(v->v[i].name, name))
			return &v->v[i];
	return NULL;
}

/* The slot for name in v itself, emptied; NULL when out of memory. */
static struct ph_var *slot(struct ph_vars *v, const char *name)
{
	struct ph_var *x;

	for (size_t i = 0; i < v->n; i++)
		if (!strcmp(v->v[i].name, name)) {
			var_clear(&v->v[i]);
			return &v->v[i];
		}
	struct ph_var *grown = st_grow(v->v, &v->cap, v->n + 1, sizeof(*grown));

	if (!grown)
		return NULL;
	v->v = grown;
	x = &v->v[v->n];
	memset(x, 0, sizeof(*x));
	x->name = strdup(name);
	if (!x->name)
		return NULL;
	v->n++;
	return x;
}

int ph_vars_set_numbers(struct ph_vars *v, const char *name, enum ph_type t, const double *vals,
			size_t n, bool vector, struct st_error *err)
{
	struct ph_var *x;

	if (!v || !name || !*name || (n && !vals) || t == PH_STRING || (!vector && n != 1))
		return st_error_set(err, ST_ERR_ARG, "placeholders: bad variable %s",
				    name ? name : "(null)");
	x = slot(v, name);
	if (!x || !(x->num = malloc((n ? n : 1) * sizeof(double))))
		return st_error_set(err, ST_ERR_NOMEM, "placeholders: out of memory");
	memcpy(x->num, vals, n * sizeof(double));
	x->n = n;
	x->type = t;
	x->vector = vector;
	x->boolish = false;
	return 0;
}

int ph_vars_set_number(struct ph_vars *v, const char *name, enum ph_type t, double val,
		       struct st_error *err)
{
	return ph_vars_set_numbers(v, name, t, &val, 1, false, err);
}

int ph_vars_set_strings(struct ph_vars *v, const char *name, const char *const *vals, size_t n,
			bool vector, struct st_error *err)
{
	struct ph_var *x;

	if (!v || !name || !*name || (n && !vals) || (!vector && n != 1))
		return st_error_set(err, ST_ERR_ARG, "placeholders: bad variable %s",
				    name ? name : "(null)");
	x = slot(v, name);
	if (!x || !(x->str = calloc(n ? n : 1, sizeof(char *))))
		return st_error_set(err, ST_ERR_NOMEM, "placeholders: out of memory");
	x->type = PH_STRING;
	x->vector = vector;
	for (size_t k = 0; k < n; k++) {
		x->str[k] = strdup(vals[k] ? vals[k] : "");
		if (!x->str[k])
			return st_error_set(err, ST_ERR_NOMEM, "placeholders: out of memory");
		x->n = k + 1;
	}
	return 0;
}

/* A list of "quoted";"strings" (escapes already decoded by the reader). */
static int set_quoted(struct ph_vars *v, const char *name, const char *text, size_t len,
		      struct st_error *err)
{
	const char *items[64];
	char *copy = malloc(len + 1), *s;
	size_t n = 0;
	int rc;

	if (!copy)
		return st_error_set(err, ST_ERR_NOMEM, "placeholders: out of memory");
	memcpy(copy, text + 1, len - 2);
	copy[len - 2] = '\0';
	for (s = copy; n < 64;) {
		char *sep = strstr(s, "\";\"");

		items[n++] = s;
		if (!sep)
			break;
		*sep = '\0';
		s = sep + 3;
	}
	rc = ph_vars_set_strings(v, name, items, n, true, err);
	free(copy);
	return rc;
}

int ph_vars_set_config(struct ph_vars *v, const char *name, const char *text,
		       struct st_error *err)
{
	double nums[64];
	size_t n = 0, len = text ? strlen(text) : 0;
	bool real = false, boolish = true;
	const char *s = text;

	if (!text)
		return st_error_set(err, ST_ERR_ARG, "placeholders: no value for %s", name);
	if (len >= 2 && text[0] == '"' && text[len - 1] == '"')
		return set_quoted(v, name, text, len, err);
	while (len && n < 64) {
		const char *comma = strchr(s, ',');
		size_t il = comma ? (size_t)(comma - s) : strlen(s);
		bool pct = il && s[il - 1] == '%';

		while (il && (*s == ' ' || *s == '\t'))
			s++, il--;
		while (il && (s[il - 1] == ' ' || s[il - 1] == '\t'))
			il--;
		if (pct)
			il--;
		if (st_parse_double(s, il, ST_NUMBER_EXPONENT, &nums[n]) != ST_NUMBER_OK)
			break;
		if (pct || memchr(s, '.', il) || memchr(s, 'e', il))
			real = true;
		if (nums[n] != 0 && nums[n] != 1)
			boolish = false;
		n++;
		if (!comma) {
			int rc = ph_vars_set_numbers(v, name, real ? PH_REAL : PH_INT, nums, n, true,
						     err);
			if (rc == 0 && !real && boolish) {
				struct ph_var *x = ph_vars_find_own(v, name);
				x->boolish = true;
			}
			return rc;
		}
		s = comma + 1;
	}
	return ph_vars_set_strings(v, name, &text, 1, false, err);
}
