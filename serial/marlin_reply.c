/*
 * marlin_reply.c - marlin_parse_reply: one reply line of Marlin 2.1 (ok,
 * Resend, errors, busy, temperatures, M115 and Cap: lines, host actions).
 * Works on (line, len) alone; no NUL is needed.
 */
#include <ctype.h>
#include <stddef.h>
#include <string.h>

#include "marlin.h"

/* Case-insensitive substring test on (s, len). */
static bool has_ci(const char *s, size_t len, const char *needle)
{
	size_t k = strlen(needle);
	for (size_t i = 0; i + k <= len; i++) {
		size_t j = 0;
		while (j < k && tolower((unsigned char)s[i + j]) == tolower((unsigned char)needle[j]))
			j++;
		if (j == k)
			return true;
	}
	return false;
}

static bool starts(const char *s, size_t len, const char *prefix)
{
	size_t k = strlen(prefix);
	return len >= k && !memcmp(s, prefix, k);
}

/* A whole non-negative decimal at p (< end); false if none. */
static bool read_long(const char *p, const char *end, long *v, const char **after)
{
	long x = 0;
	const char *q = p;
	while (q < end && *q == ' ')
		q++;
	if (q >= end || !isdigit((unsigned char)*q))
		return false;
	while (q < end && isdigit((unsigned char)*q) && x < 1000000000000L)
		x = x * 10 + (*q++ - '0');
	*v = x;
	if (after)
		*after = q;
	return true;
}

/* A number token [p, end) through the project's number reader. */
static bool read_num(const char *p, const char *end, double *v)
{
	return end > p && gcode_read_number(p, (size_t)(end - p), v, NULL) == 0;
}

/* Parse "T:210.00 /210.00 B:60.0 /60.0 T0:.. C:.. @:0 W:?" into st; true
 * if any heater was found. */
static bool parse_temps(const char *s, size_t len, struct marlin_status *st)
{
	const char *p = s, *end = s + len;
	bool any = false, wait = false;
	while (p < end) {
		while (p < end && *p == ' ')
			p++;
		const char *t = p;
		while (p < end && *p != ' ')
			p++;
		const char *colon = memchr(t, ':', (size_t)(p - t));
		if (!colon)
			continue;
		struct marlin_temp *h = NULL;
		size_t nl = (size_t)(colon - t);
		if (nl == 1 && t[0] == 'T') {
			h = &st->tool[0];
		} else if (nl >= 2 && t[0] == 'T' && isdigit((unsigned char)t[1])) {
			long i;
			if (read_long(t + 1, colon, &i, NULL) && i < MARLIN_MAX_TOOLS)
				h = &st->tool[i];
		} else if (nl == 1 && t[0] == 'B') {
			h = &st->bed;
		} else if (nl == 1 && t[0] == 'C') {
			h = &st->chamber;
		} else if (nl == 1 && t[0] == 'W') {
			wait = true;
			continue;
		}
		if (!h || !read_num(colon + 1, p, &h->actual))
			continue;
		h->present = true;
		any = true;
		/* the target follows as " /210.00" */
		const char *q = p;
		while (q < end && *q == ' ')
			q++;
		if (q < end && *q == '/') {
			const char *e = ++q;
			while (e < end && *e != ' ')
				e++;
			if (read_num(q, e, &h->target))
				p = e;
		}
	}
	if (any)
		st->heating_wait = wait;
	return any;
}

/* Does (s, len) look like a temperature report ("T:", "T0:", "B:" first)? */
static bool looks_like_temps(const char *s, size_t len)
{
	while (len && *s == ' ') {
		s++;
		len--;
	}
	if (len >= 2 && (s[0] == 'T' || s[0] == 'B' || s[0] == 'C') && s[1] == ':')
		return true;
	return len >= 3 && s[0] == 'T' && isdigit((unsigned char)s[1]) && s[2] == ':';
}

/* Copy the text after key up to stop (or the end) into out. */
static void copy_field(const char *s, size_t len, const char *key, const char *stop, char *out,
		       size_t cap)
{
	size_t k = strlen(key);
	for (size_t i = 0; i + k <= len; i++) {
		if (memcmp(s + i, key, k))
			continue;
		const char *b = s + i + k, *e = s + len;
		for (const char *q = b; stop && q + strlen(stop) <= s + len; q++)
			if (!memcmp(q, stop, strlen(stop))) {
				e = q;
				break;
			}
		size_t n = (size_t)(e - b);
		if (n >= cap)
			n = cap - 1;
		memcpy(out, b, n);
		out[n] = '\0';
		return;
	}
}

/* Apply one "Cap:NAME:v" line to caps. */
static void parse_cap(const char *s, size_t len, struct marlin_caps *caps)
{
	static const struct {
		const char *name;
		size_t off;
	} tab[] = {
		{"ADVANCED_OK", offsetof(struct marlin_caps, advanced_ok)},
		{"EMERGENCY_PARSER", offsetof(struct marlin_caps, emergency_parser)},
		{"AUTOREPORT_TEMP", offsetof(struct marlin_caps, autoreport_temp)},
		{"HOST_ACTION_COMMANDS", offsetof(struct marlin_caps, host_action_commands)},
		{"PROMPT_SUPPORT", offsetof(struct marlin_caps, prompt_support)},
		{"EEPROM", offsetof(struct marlin_caps, eeprom)},
		{"SDCARD", offsetof(struct marlin_caps, sdcard)},
		{"THERMAL_PROTECTION", offsetof(struct marlin_caps, thermal_protection)},
		{"ARCS", offsetof(struct marlin_caps, arcs)},
		{"PROGRESS", offsetof(struct marlin_caps, progress)},
	};
	const char *name = s + 4, *end = s + len;
	const char *colon = memchr(name, ':', (size_t)(end - name));
	if (!colon || colon + 1 >= end)
		return;
	size_t nl = (size_t)(colon - name);
	bool on = colon[1] == '1';
	for (size_t i = 0; i < sizeof(tab) / sizeof(tab[0]); i++)
		if (strlen(tab[i].name) == nl && !memcmp(tab[i].name, name, nl)) {
			bool *f = (bool *)((char *)caps + tab[i].off);
			/* ADVANCED_OK seen in a reply stays known whatever M115 says */
			*f = i == 0 ? (*f || on) : on;
		}
}

enum marlin_reply_kind marlin_parse_reply(const char *line, size_t len, struct marlin_reply *r,
					  struct marlin_status *st, struct marlin_caps *caps)
{
	struct marlin_status dummy;
	memset(r, 0, sizeof(*r));
	if (!st) {
		memset(&dummy, 0, sizeof(dummy));
		st = &dummy;
	}
	while (len && (line[len - 1] == '\r' || line[len - 1] == ' ' || line[len - 1] == '\n'))
		len--;
	const char *end = line + len;

	if (starts(line, len, "ok") && (len == 2 || line[2] == ' ')) {
		r->kind = MARLIN_REPLY_OK;
		if (looks_like_temps(line + 2, len - 2)) {
			r->has_temps = parse_temps(line + 2, len - 2, st);
			return r->kind;
		}
		for (const char *p = line + 2; p < end;) {
			while (p < end && *p == ' ')
				p++;
			if (p >= end)
				break;
			char c = *p;
			long v;
			const char *after;
			if ((c == 'N' || c == 'P' || c == 'B') && read_long(p + 1, end, &v, &after) &&
			    (after == end || *after == ' ')) {
				if (c == 'N') {
					r->has_n = true;
					r->n = v;
				} else if (c == 'P') {
					r->has_p = true;
					r->p = v;
				} else {
					r->has_b = true;
					r->b = v;
				}
				p = after;
			} else {
				while (p < end && *p != ' ')
					p++;
			}
		}
		return r->kind;
	}
	if (starts(line, len, "Resend:") || starts(line, len, "rs ")) {
		const char *p = line + (line[0] == 'R' ? 7 : 3);
		while (p < end && (*p == ' ' || *p == 'N'))
			p++;
		if (read_long(p, end, &r->resend, NULL)) {
			r->kind = MARLIN_REPLY_RESEND;
			return r->kind;
		}
		return r->kind = MARLIN_REPLY_OTHER;
	}
	if (starts(line, len, "Error:") || starts(line, len, "!!")) {
		if (has_ci(line, len, "checksum mismatch") || has_ci(line, len, "line number") ||
		    has_ci(line, len, "no checksum"))
			r->kind = MARLIN_REPLY_LINE_ERROR;
		else if (has_ci(line, len, "halted") || has_ci(line, len, "kill") ||
			 has_ci(line, len, "thermal runaway") || has_ci(line, len, "mintemp") ||
			 has_ci(line, len, "maxtemp") || has_ci(line, len, "heating failed") ||
			 has_ci(line, len, "thermal malfunction") ||
			 has_ci(line, len, "printer stopped") || starts(line, len, "!!"))
			r->kind = MARLIN_REPLY_FATAL;
		else
			r->kind = MARLIN_REPLY_ERROR;
		return r->kind;
	}
	if (starts(line, len, "echo:busy:") || starts(line, len, "busy:"))
		return r->kind = MARLIN_REPLY_BUSY;
	if (starts(line, len, "echo:Unknown command") || starts(line, len, "echo: Unknown command"))
		return r->kind = MARLIN_REPLY_UNKNOWN_CMD;
	if (len == 5 && !memcmp(line, "start", 5))
		return r->kind = MARLIN_REPLY_START;
	if (starts(line, len, "//action:")) {
		const char *p = line + 9, *e = p;
		while (e < end && *e != ' ')
			e++;
		size_t n = (size_t)(e - p);
		if (n >= sizeof(r->action))
			n = sizeof(r->action) - 1;
		memcpy(r->action, p, n);
		r->action[n] = '\0';
		return r->kind = MARLIN_REPLY_ACTION;
	}
	if (starts(line, len, "FIRMWARE_NAME:")) {
		if (caps) {
			caps->m115 = true;
			copy_field(line, len, "FIRMWARE_NAME:", " SOURCE_CODE_URL:",
				   caps->firmware_name, sizeof(caps->firmware_name));
			if (has_ci(caps->firmware_name, strlen(caps->firmware_name),
				   " PROTOCOL_VERSION:"))
				copy_field(line, len, "FIRMWARE_NAME:", " PROTOCOL_VERSION:",
					   caps->firmware_name, sizeof(caps->firmware_name));
			copy_field(line, len, "MACHINE_TYPE:", " EXTRUDER_COUNT:",
				   caps->machine_type, sizeof(caps->machine_type));
			/* (line, len) need not end in a NUL: search within len only */
			const char *ec = NULL;
			for (size_t i = 0; !ec && i + 15 <= len; i++)
				if (!memcmp(line + i, "EXTRUDER_COUNT:", 15))
					ec = line + i;
			long v;
			if (ec && read_long(ec + 15, end, &v, NULL) && v < 64)
				caps->extruder_count = (int)v;
		}
		return r->kind = MARLIN_REPLY_FIRMWARE;
	}
	if (starts(line, len, "Cap:")) {
		if (caps)
			parse_cap(line, len, caps);
		return r->kind = MARLIN_REPLY_CAP;
	}
	if (looks_like_temps(line, len) && parse_temps(line, len, st)) {
		r->has_temps = true;
		return r->kind = MARLIN_REPLY_TEMP;
	}
	return r->kind = MARLIN_REPLY_OTHER;
}
