/*
 * x3gtest.c - the helpers of x3gtest.h.
 */
#include <check.h>
#include <stdio.h>
#include <string.h>

#include "gcode.h"
#include "testutil.h"
#include "x3g.h"
#include "x3gtest.h"

void tr_open(struct tr *r, enum x3g_flavor flavor)
{
	struct x3g_machine m;
	struct x3g_options opt = {flavor, "part"};
	struct st_error err = {0};

	memset(r, 0, sizeof(*r));
	x3g_machine_fcp(&m);
	ck_assert_msg(x3g_new(&m, &opt, &r->t, &err) == 0, "x3g_new: %s", err.msg);
}

/* Collect the output and the warnings of the last call. */
void tr_collect(struct tr *r)
{
	const struct x3g_warning *w;
	size_t n, nw = x3g_warnings(r->t, &w);
	const uint8_t *b = x3g_output(r->t, &n);

	ck_assert_uint_le(r->len + n, OUT_MAX);
	memcpy(r->out + r->len, b, n);
	r->len += n;
	if (nw) {
		snprintf(r->warning, sizeof(r->warning), "%s", w[nw - 1].msg);
		r->warning_line = w[nw - 1].line;
	}
	r->warnings += nw;
}

/* Translate each line of text (lines numbered from 1), appending output. */
void tr_lines(struct tr *r, const char *text)
{
	uint64_t no = 0;

	while (*text) {
		const char *nl = strchr(text, '\n');
		size_t n = nl ? (size_t)(nl - text) : strlen(text);
		struct gcode_line l;
		struct st_error err = {0};

		no++;
		ck_assert_msg(gcode_parse(text, n, 0, &l, &err) == 0, "%.*s: %s", (int)n, text,
			      err.msg);
		ck_assert_int_ge(x3g_translate(r->t, &l, no, &err), 0);
		tr_collect(r);
		text += n + (nl ? 1 : 0);
	}
}

