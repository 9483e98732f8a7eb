/*
 * profile_keys.c - key typing: the parsers of every value type and the
 * typing of one key into its struct profile field (profile_int.h); the
 * binding of keys to fields is in profile_bind.c.
 *
 * Numbers are read with our own grammar, [+-]digits[.digits][e[+-]digits]
 * (the exponent because PrusaSlicer writes one, e.g. bed_shape points at
 * 5.51091e-15; no hexadecimal, no decimal comma), and only a validated copy
 * is handed to strtod; the program never calls setlocale, so the C
 * locale's '.' applies.
 */
#include "profile_int.h"

#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "ini.h"
#include "st_append.h"
#include "st_number.h"

/* Locale-independent character classes. */
static bool is_digit(char c)
{
	return c >= '0' && c <= '9';
}

/* Value of a hex digit, or -1. */
static int hex_value(char c)
{
	if (c >= '0' && c <= '9')
		return c - '0';
	if (c >= 'a' && c <= 'f')
		return c - 'a' + 10;
	if (c >= 'A' && c <= 'F')
		return c - 'A' + 10;
	return -1;
}

/* s[0..len) as a decimal number; false if it is not one. */
static bool parse_number(const char *s, size_t len, double *out)
{
	return st_parse_double(s, len, ST_NUMBER_EXPONENT, out) == ST_NUMBER_OK;
}

/* [+-]digits, at most 18 digits, into *out. */
static bool parse_integer(const char *s, size_t len, long long *out)
{
	size_t i = 0;
	long long v = 0;
	bool neg = false;

	if (len && (s[0] == '+' || s[0] == '-')) {
		neg = s[0] == '-';
		i++;
	}
	if (i == len || len - i > 18)
		return false;
	for (; i < len; i++) {
		if (!is_digit(s[i]))
			return false;
		v = v * 10 + (s[i] - '0');
	}
	*out = neg ? -v : v;
	return true;
}

/* 0, 1, false, true. */
static bool parse_bool(const char *s, size_t len, bool *out)
{
	if ((len == 1 && s[0] == '1') || (len == 4 && !memcmp(s, "true", 4))) {
		*out = true;
		return true;
	}
	if ((len == 1 && s[0] == '0') || (len == 5 && !memcmp(s, "false", 5))) {
		*out = false;
		return true;
	}
	return false;
}

/*
 * Split value on ',' into at most cap trimmed items.  Returns the count, or
 * ST_ERR_PARSE (error set) when there are more than cap or one is empty.
 */
int prof_split_list(struct loader *L, const struct profile_kv *kv, struct item *items, size_t cap)
{
	const char *s = kv->value;
	size_t n = 0;

	for (;;) {
		const char *comma = strchr(s, ',');
		size_t len = comma ? (size_t)(comma - s) : strlen(s);
		const char *t = s;

		prof_trim(&t, &len);
		if (len == 0) {
			return prof_key_error(L, kv, NULL, ST_ERR_PARSE, "%s",
					 n == 0 && !comma
					     ? "no value given"
					     : "empty value in the comma-separated list");
		}
		if (n == cap) {
			return prof_key_error(L, kv, NULL, ST_ERR_PARSE,
					 "too many values in the list (at most %zu)", cap);
		}
		items[n].s = t;
		items[n].len = len;
		n++;
		if (!comma)
			break;
		s = comma + 1;
	}
	return (int)n;
}

/* Name the n-th item in a message when the list has more than one. */
static void item_where(char *buf, size_t cap, int i, int n)
{
	if (n > 1)
		snprintf(buf, cap, "value %d of %d, ", i + 1, n);
	else
		buf[0] = '\0';
}

/* A number item checked against decl's range; i of n names it in messages. */
static int prof_number_item(struct loader *L, const struct profile_kv *kv,
			    const struct setting *decl, const struct item *it, int i, int n,
			    double *out)
{
	char tok[INI_SHOW_MAX], where[48], range[96];

	item_where(where, sizeof(where), i, n);
	if (!parse_number(it->s, it->len, out)) {
		ini_show(tok, sizeof(tok), it->s, it->len);
		return prof_key_error(L, kv, NULL, ST_ERR_PARSE,
				 "%s'%s' is not a number (write digits with an optional sign and "
				 "'.', e.g. 0.4)",
				 where, tok);
	}
	if (!setting_in_range(decl, *out)) {
		setting_range_text(decl, range, sizeof(range));
		ini_show(tok, sizeof(tok), it->s, it->len);
		return prof_key_error(L, kv, NULL, ST_ERR_RANGE, "%s%s is out of range (must be %s)",
				 where, tok, range);
	}
	return 0;
}

/* Read a whole-number item and check it against d's range. */
static int int_item(struct loader *L, const struct profile_kv *kv, const struct key_def *d,
		    const struct item *it, int i, int n, int *out)
{
	char tok[INI_SHOW_MAX], where[48], range[96];
	long long v;

	item_where(where, sizeof(where), i, n);
	if (!parse_integer(it->s, it->len, &v)) {
		ini_show(tok, sizeof(tok), it->s, it->len);
		return prof_key_error(L, kv, NULL, ST_ERR_PARSE, "%s'%s' is not a whole number", where,
				 tok);
	}
	if (!setting_in_range(prof_decl(d), (double)v)) {
		setting_range_text(prof_decl(d), range, sizeof(range));
		return prof_key_error(L, kv, NULL, ST_ERR_RANGE, "%s%lld is out of range (must be %s)",
				 where, v, range);
	}
	*out = (int)v;
	return 0;
}

/* Read a bool item. */
static int bool_item(struct loader *L, const struct profile_kv *kv, const struct item *it, int i,
		     int n, bool *out)
{
	char tok[INI_SHOW_MAX], where[48];

	item_where(where, sizeof(where), i, n);
	if (!parse_bool(it->s, it->len, out)) {
		ini_show(tok, sizeof(tok), it->s, it->len);
		return prof_key_error(L, kv, NULL, ST_ERR_PARSE, "%sexpected 0 or 1, found '%s'", where,
				 tok);
	}
	return 0;
}

/* Read "XxY" into a point, both coordinates within d's range. */
static int point_item(struct loader *L, const struct profile_kv *kv, const struct key_def *d,
		      const struct item *it, int i, int n, struct profile_point *out)
{
	char tok[INI_SHOW_MAX], where[48], range[96];
	const char *x = memchr(it->s, 'x', it->len);
	struct item a, b;

	item_where(where, sizeof(where), i, n);
	ini_show(tok, sizeof(tok), it->s, it->len);
	if (!x)
		return prof_key_error(L, kv, NULL, ST_ERR_PARSE,
				 "%s'%s' is not a point XxY (e.g. 227x148)", where, tok);
	a.s = it->s;
	a.len = (size_t)(x - it->s);
	b.s = x + 1;
	b.len = it->len - a.len - 1;
	prof_trim(&a.s, &a.len);
	prof_trim(&b.s, &b.len);
	if (!parse_number(a.s, a.len, &out->x) || !parse_number(b.s, b.len, &out->y))
		return prof_key_error(L, kv, NULL, ST_ERR_PARSE,
				 "%s'%s' is not a point XxY of two numbers (e.g. 227x148)", where,
				 tok);
	if (!setting_in_range(prof_decl(d), out->x) || !setting_in_range(prof_decl(d), out->y)) {
		setting_range_text(prof_decl(d), range, sizeof(range));
		return prof_key_error(L, kv, NULL, ST_ERR_RANGE,
				 "%spoint %s is out of range (coordinates must be %s)", where, tok,
				 range);
	}
	return 0;
}

/* Where the extruder count came from, for messages. */
static void ec_source(const struct loader *L, char *buf, size_t cap)
{
	if (L->ec_kv)
		snprintf(buf, cap, "%s on line %d", L->ec_key, L->ec_kv->line);
	else
		snprintf(buf, cap, "the default");
}

/*
 * A per-extruder list (or a list whose first value is used) must hold one
 * value or one per extruder.
 */
static int check_count(struct loader *L, const struct profile_kv *kv, const struct key_def *d,
		       int n)
{
	char src[96];
	int ec = L->p->extruder_count;

	if (prof_decl(d)->shape == SETTING_LIMITS) {
		if (n > 2)
			return prof_key_error(L, kv, NULL, ST_ERR_RANGE,
					 "has %d values; machine limits take 1 or 2 "
					 "(normal, stealth)",
					 n);
		return 0;
	}
	if (n == 1 || n == ec)
		return 0;
	ec_source(L, src, sizeof(src));
	return prof_key_error(L, kv, NULL, ST_ERR_RANGE,
			 "has %d values but the printer has %d extruder%s (%s); give one value "
			 "for all or one per extruder",
			 n, ec, ec == 1 ? "" : "s", src);
}

/* Match s against a table of names; index or -1. */
static int name_index(const char *const *names, size_t count, const char *s)
{
	for (size_t i = 0; i < count; i++)
		if (!strcmp(names[i], s))
			return (int)i;
	return -1;
}

/* kv's value is none of decl's names: the error, naming them all. */
static int not_one_of(struct loader *L, const struct profile_kv *kv, const struct setting *decl)
{
	char tok[INI_SHOW_MAX], names[256] = "";

	ini_show(tok, sizeof(tok), kv->value, strlen(kv->value));
	for (size_t i = 0; i < decl->nnames; i++)
		st_appendf(names, sizeof(names), "%s%s", i ? ", " : "", decl->names[i]);
	return prof_key_error(L, kv, NULL, ST_ERR_PARSE, "'%s' is not one of %s", tok, names);
}

/* usb_ids: a list of VVVV:PPPP, 4 hex digits each; empty = none. */
static int apply_usb(struct loader *L, const struct profile_kv *kv)
{
	struct item items[PROFILE_MAX_USB_IDS];
	struct profile *p = L->p;
	char tok[INI_SHOW_MAX];
	int n;

	p->usb_id_count = 0;
	if (kv->value[0] == '\0')
		return 0;
	n = prof_split_list(L, kv, items, PROFILE_MAX_USB_IDS);
	if (n < 0)
		return n;
	for (int i = 0; i < n; i++) {
		const char *s = items[i].s;
		unsigned vid = 0, pid = 0;
		bool ok = items[i].len == 9 && s[4] == ':';

		for (int j = 0; ok && j < 9; j++) {
			int h = j == 4 ? 0 : hex_value(s[j]);
			if (h < 0)
				ok = false;
			else if (j < 4)
				vid = vid * 16 + (unsigned)h;
			else if (j > 4)
				pid = pid * 16 + (unsigned)h;
		}
		if (!ok) {
			ini_show(tok, sizeof(tok), s, items[i].len);
			return prof_key_error(L, kv, NULL, ST_ERR_PARSE,
					 "'%s' is not a USB id VVVV:PPPP (4 hex digits each, e.g. "
					 "2c99:0002)",
					 tok);
		}
		p->usb_ids[i].vid = (uint16_t)vid;
		p->usb_ids[i].pid = (uint16_t)pid;
	}
	p->usb_id_count = (size_t)n;
	return 0;
}

/* bed_shape: at least 3 points XxY enclosing some area. */
static int apply_bed(struct loader *L, const struct profile_kv *kv, const struct key_def *d)
{
	struct profile *p = L->p;
	struct item *items = NULL;
	struct profile_point *pts = NULL;
	double area = 0;
	int n, i, rc;

	items = calloc(PROFILE_MAX_BED_POINTS, sizeof(*items));
	if (!items)
		return prof_key_error(L, kv, NULL, ST_ERR_NOMEM, "out of memory");
	n = prof_split_list(L, kv, items, PROFILE_MAX_BED_POINTS);
	if (n < 0) {
		rc = n;
		goto out_free_items;
	}
	if (n < 3) {
		rc = prof_key_error(L, kv, NULL, ST_ERR_PARSE,
			       "a bed polygon needs at least 3 points XxY, found %d (e.g. "
			       "0x0,227x0,227x148,0x148)",
			       n);
		goto out_free_items;
	}
	pts = calloc((size_t)n, sizeof(*pts));
	if (!pts) {
		rc = prof_key_error(L, kv, NULL, ST_ERR_NOMEM, "out of memory");
		goto out_free_items;
	}
	for (i = 0; i < n; i++) {
		rc = point_item(L, kv, d, &items[i], i, n, &pts[i]);
		if (rc)
			goto out_free_pts;
	}
	for (i = 0; i < n; i++) {
		const struct profile_point *a = &pts[i], *b = &pts[(i + 1) % n];
		area += a->x * b->y - b->x * a->y;
	}
	if (fabs(area) / 2 < 1.0) {
		rc = prof_key_error(L, kv, NULL, ST_ERR_RANGE,
			       "the bed polygon encloses no area (its points are on a line)");
		goto out_free_pts;
	}
	free(p->bed_shape);
	p->bed_shape = pts;
	p->bed_points = (size_t)n;
	free(items);
	return 0;

out_free_pts:
	free(pts);
out_free_items:
	free(items);
	return rc;
}

/*
 * The first of PrusaSlicer's per-filament strings "a";"b" (escapes already
 * decoded), cut in place: the value is owned by the profile's key list.  A
 * value without the quotes is one string.
 */
static const char *first_string(char *v)
{
	size_t n = strlen(v);
	char *sep;

	if (n < 2 || v[0] != '"' || v[n - 1] != '"')
		return v;
	v[n - 1] = '\0';
	sep = strstr(v + 1, "\";\"");
	if (sep)
		*sep = '\0';
	return v + 1;
}

/* The sign-and-number part of "N%" or "N", with *pct telling which. */
static int pct_or_number(struct loader *L, const struct profile_kv *kv, double *v, bool *pct)
{
	const char *s = kv->value;
	size_t len = strlen(s);
	char tok[INI_SHOW_MAX];

	*pct = len && s[len - 1] == '%';
	if (*pct)
		len--;
	if (!parse_number(s, len, v)) {
		ini_show(tok, sizeof(tok), kv->value, strlen(kv->value));
		return prof_key_error(L, kv, NULL, ST_ERR_PARSE,
				 "'%s' is not a number or a percentage (e.g. 0.2 or 150%%)", tok);
	}
	return 0;
}


int prof_apply_key(struct loader *L, const struct key_def *d, const struct profile_kv *kv,
		     struct pending *pend)
{
	struct profile *p = L->p;
	const struct setting *decl = prof_decl(d);
	void *field = (char *)p + d->off;
	struct item items[PROFILE_MAX_EXTRUDERS];
	struct item one = {kv->value, strlen(kv->value)};
	char tok[INI_SHOW_MAX], range[96];
	int n, i, rc, idx;
	double v;
	bool pct, per_extruder;
	size_t size;

	if (!*kv->value && d->type != KT_STRING && d->type != KT_FIRST_STRING && d->type != KT_USB)
		return prof_key_error(L, kv, NULL, ST_ERR_PARSE,
				 "no value given (write one or remove the line)");
	switch (d->type) {
	case KT_STRING:
		*(const char **)field = kv->value;
		return 0;
	case KT_FIRST_STRING:
		*(const char **)field = first_string(kv->value);
		return 0;
	case KT_DOUBLE:
		prof_trim(&one.s, &one.len);
		return prof_number_item(L, kv, decl, &one, 0, 1, (double *)field);
	case KT_INT:
	case KT_EXTRUDERS:
		prof_trim(&one.s, &one.len);
		return int_item(L, kv, d, &one, 0, 1, (int *)field);
	case KT_BOOL:
		prof_trim(&one.s, &one.len);
		return bool_item(L, kv, &one, 0, 1, (bool *)field);
	case KT_EX_DOUBLE:
	case KT_EX_INT:
	case KT_EX_POINT:
	case KT_FIRST_DOUBLE:
	case KT_FIRST_INT:
	case KT_FIRST_BOOL:
		n = prof_split_list(L, kv, items, PROFILE_MAX_EXTRUDERS);
		if (n < 0)
			return n;
		/* Every item is checked; a per-extruder key keeps each, a FIRST key its first. */
		per_extruder = d->type == KT_EX_DOUBLE || d->type == KT_EX_INT ||
			       d->type == KT_EX_POINT;
		size = d->type == KT_EX_DOUBLE || d->type == KT_FIRST_DOUBLE ? sizeof(double)
		       : d->type == KT_EX_INT || d->type == KT_FIRST_INT     ? sizeof(int)
		       : d->type == KT_EX_POINT				     ? sizeof(struct profile_point)
										     : sizeof(bool);
		for (i = 0; i < n; i++) {
			union {
				double d;
				int i;
				bool b;
				struct profile_point pt;
			} item;

			if (d->type == KT_EX_DOUBLE || d->type == KT_FIRST_DOUBLE)
				rc = prof_number_item(L, kv, decl, &items[i], i, n, &item.d);
			else if (d->type == KT_EX_INT || d->type == KT_FIRST_INT)
				rc = int_item(L, kv, d, &items[i], i, n, &item.i);
			else if (d->type == KT_EX_POINT)
				rc = point_item(L, kv, d, &items[i], i, n, &item.pt);
			else /* KT_FIRST_BOOL */
				rc = bool_item(L, kv, &items[i], i, n, &item.b);
			if (rc)
				return rc;
			if (per_extruder || i == 0)
				memcpy((char *)field + (per_extruder ? (size_t)i * size : 0), &item, size);
		}
		rc = check_count(L, kv, d, n);
		if (rc)
			return rc;
		/* One value applies to every extruder. */
		for (i = n; per_extruder && n == 1 && i < p->extruder_count; i++)
			memcpy((char *)field + (size_t)i * size, field, size);
		return 0;
	case KT_FIRST_HEIGHT:
	case KT_WIDTH:
	case KT_NUM_PCT:
		rc = pct_or_number(L, kv, &v, &pct);
		if (rc)
			return rc;
		if (pct) {
			if (!(v >= 0 && v <= 1000) || (v == 0 && d->type == KT_FIRST_HEIGHT))
				return prof_key_error(
				    L, kv, NULL, ST_ERR_RANGE,
				    "%s is out of range (a percentage must be %s)", kv->value,
				    d->type != KT_FIRST_HEIGHT ? "between 0% and 1000%"
							       : "more than 0% and at most 1000%");
		} else if (!setting_in_range(prof_decl(d), v)) {
			setting_range_text(prof_decl(d), range, sizeof(range));
			return prof_key_error(L, kv, NULL, ST_ERR_RANGE,
					 "%s is out of range (must be %s, or a percentage)",
					 kv->value, range);
		}
		if (d->type == KT_FIRST_HEIGHT) {
			pend->flh_pct = pct;
			pend->flh = v;
		} else if (d->type == KT_WIDTH) {
			pend->width_pct = pct;
			pend->width = v;
		} else {
			*(struct profile_pct *)field = (struct profile_pct){v, pct};
		}
		return 0;
	case KT_DENSITY:
		if (decl->shape == SETTING_FIRST) { /* a list per extruder: its first value */
			struct profile_kv first = *kv;
			char buf[64];

			n = prof_split_list(L, kv, items, PROFILE_MAX_EXTRUDERS);
			if (n < 0)
				return n;
			rc = check_count(L, kv, d, n);
			if (rc)
				return rc;
			snprintf(buf, sizeof(buf), "%.*s", (int)items[0].len, items[0].s);
			first.value = buf;
			rc = pct_or_number(L, &first, &v, &pct);
		} else {
			rc = pct_or_number(L, kv, &v, &pct);
		}
		if (rc)
			return rc;
		if (!pct)
			v *= 100; /* a bare number is a fraction, as in Slic3r */
		if (!setting_in_range(prof_decl(d), v))
			return prof_key_error(L, kv, NULL, ST_ERR_RANGE,
					 "%s is out of range (must be %g%% to %g%%, or a fraction "
					 "%g to 1)",
					 kv->value, prof_decl(d)->min, prof_decl(d)->max,
					 prof_decl(d)->min / 100);
		*(double *)field = v;
		return 0;
	case KT_PROTOCOL:
		idx = name_index(decl->names, decl->nnames, kv->value);
		if (idx < 0) {
			ini_show(tok, sizeof(tok), kv->value, strlen(kv->value));
			return prof_key_error(L, kv, NULL, ST_ERR_PARSE,
					 "expected marlin or sailfish, found '%s'", tok);
		}
		p->protocol = (enum profile_protocol)idx;
		return 0;
	case KT_FLAVOR:
		idx = name_index(decl->names, decl->nnames, kv->value);
		if (idx < 0 && !strcmp(kv->value, "marlinfirmware"))
			idx = PROFILE_FLAVOR_MARLIN2; /* PrusaSlicer 2.4 alpha's name */
		if (idx < 0)
			return not_one_of(L, kv, decl);
		p->gcode_flavor = (enum profile_flavor)idx;
		return 0;
	case KT_CHOICE:
		idx = name_index(decl->names, decl->nnames, kv->value);
		if (idx < 0 && !strcmp(d->key, "fill_pattern") && !strcmp(kv->value, "monotonous"))
			idx = 1; /* PrusaSlicer's old name of monotonic */
		if (idx < 0 && !strcmp(d->key, "support_material_style") &&
		    !strcmp(kv->value, "organic"))
			return prof_key_error(L, kv, NULL, ST_ERR_PARSE,
					 "'organic' (PrusaSlicer 2.6's tree supports) is not "
					 "supported; use grid or snug");
		if (idx < 0)
			return not_one_of(L, kv, decl);
		*(const char **)field = decl->names[idx];
		return 0;
	case KT_HOME:
		if (!strcmp(kv->value, "min") || !strcmp(kv->value, "max")) {
			*(enum profile_home *)field =
			    kv->value[1] == 'i' ? PROFILE_HOME_MIN : PROFILE_HOME_MAX;
			return 0;
		}
		ini_show(tok, sizeof(tok), kv->value, strlen(kv->value));
		return prof_key_error(L, kv, NULL, ST_ERR_PARSE, "expected min or max, found '%s'", tok);
	case KT_BAUD: {
		long long b;

		if (!parse_integer(kv->value, strlen(kv->value), &b)) {
			ini_show(tok, sizeof(tok), kv->value, strlen(kv->value));
			return prof_key_error(L, kv, NULL, ST_ERR_PARSE, "'%s' is not a whole number",
					 tok);
		}
		size_t nrates;
		const long *rates = settings_baud_rates(&nrates);
		char list[256] = "";

		for (size_t k = 0; k < nrates; k++)
			if (rates[k] == b) {
				p->baudrate = (long)b;
				return 0;
			}
		for (size_t k = 0; k < nrates; k++)
			st_appendf(list, sizeof(list), "%s%ld", k ? ", " : "", rates[k]);
		return prof_key_error(L, kv, NULL, ST_ERR_RANGE,
				      "%lld is not a standard baud rate (use one of %s)", b, list);
	}
	case KT_USB:
		return apply_usb(L, kv);
	case KT_BED:
		return apply_bed(L, kv, d);
	}
	return prof_key_error(L, kv, NULL, ST_ERR_INTERNAL, "no parser for this key");
}
