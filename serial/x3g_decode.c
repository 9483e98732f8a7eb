/*
 * x3g_decode.c - the X3G decoder and formatter (x3g.h): layouts of the
 * action commands a file may hold, cut back out of a byte stream.
 */
#include <stdio.h>
#include <string.h>

#include "x3g.h"

/* ---- decoding ------------------------------------------------------------ */

/*
 * Layouts of the action commands an X3G file may hold (s3g protocol
 * document; 155's distance is a float32 as GPX writes it).  Field types:
 * '1' uint8, '2' uint16, '4' uint32, 'i' int32, 'f' float32, 'z' a
 * NUL-terminated string; 136 (tool action) is decoded apart.
 */
struct layout {
	uint8_t code;
	const char *name;
	const char *types;
	const char *fields[X3G_FIELDS_MAX];
};

static const struct layout layouts[] = {
    {129, "queue point absolute", "iii4", {"x", "y", "z", "dda_us"}},
    {130, "set position", "iii", {"x", "y", "z"}},
    {131, "find axes minimum", "142", {"axes", "dda_us", "timeout_s"}},
    {132, "find axes maximum", "142", {"axes", "dda_us", "timeout_s"}},
    {133, "delay", "4", {"ms"}},
    {134, "change tool", "1", {"tool"}},
    {135, "wait for tool ready", "122", {"tool", "poll_ms", "timeout_s"}},
    {136, "tool action", "", {NULL}},
    {137, "enable/disable axes", "1", {"axes"}},
    {139, "queue extended point", "iiiii4", {"x", "y", "z", "a", "b", "dda_us"}},
    {140, "set extended position", "iiiii", {"x", "y", "z", "a", "b"}},
    {141, "wait for platform ready", "122", {"tool", "poll_ms", "timeout_s"}},
    {142, "queue extended point new", "iiiii41",
     {"x", "y", "z", "a", "b", "duration_us", "relative"}},
    {143, "store home positions", "1", {"axes"}},
    {144, "recall home positions", "1", {"axes"}},
    {145, "set potentiometer", "11", {"axis", "value"}},
    {146, "set RGB LED", "11111", {"red", "green", "blue", "blink", "reserved"}},
    {147, "set beep", "221", {"frequency", "ms", "reserved"}},
    {148, "pause for button", "121", {"buttons", "timeout_s", "options"}},
    {149, "display message", "1111z", {"options", "x", "y", "timeout_s"}},
    {150, "set build percentage", "11", {"percent", "reserved"}},
    {151, "queue song", "1", {"song"}},
    {152, "reset to factory", "1", {"reserved"}},
    {153, "build start notification", "4z", {"reserved"}},
    {154, "build end notification", "1", {"reserved"}},
    {155, "queue extended point x3g", "iiiii41f2",
     {"x", "y", "z", "a", "b", "dda_rate", "relative", "distance", "feedrate_x64"}},
    {156, "set segment acceleration", "1", {"on"}},
    {157, "stream version", "11142244" "1",
     {"high", "low", "reserved", "reserved32", "bot_type", "reserved16", "reserved32b",
      "reserved32c", "reserved8"}},
    {158, "pause at z", "f", {"z"}},
};

static const struct layout *find_layout(uint8_t code)
{
	for (size_t i = 0; i < sizeof(layouts) / sizeof(layouts[0]); i++)
		if (layouts[i].code == code)
			return &layouts[i];
	return NULL;
}

static uint32_t get_le(const uint8_t *p, int n)
{
	uint32_t v = 0;

	for (int i = n - 1; i >= 0; i--)
		v = (v << 8) | p[i];
	return v;
}

/* Bytes of the fixed-size fields from ty to the end or the next string. */
static size_t fixed_span(const char *ty)
{
	size_t n = 0;

	for (; *ty && *ty != 'z'; ty++)
		n += *ty == '1' ? 1 : *ty == '2' ? 2 : 4;
	return n;
}

static int cut_short(struct st_error *err, uint64_t offset, const struct layout *lo, size_t need,
		     size_t have)
{
	return st_error_set(err, ST_ERR_PARSE,
			    "byte %llu: command %u (%s) needs %zu bytes but the data ends after %zu",
			    (unsigned long long)offset, lo->code, lo->name, need, have);
}

/* 136: tool, action, payload length, payload (1 byte on/off or int16). */
static int decode_tool_action(const uint8_t *buf, size_t len, uint64_t offset,
			      const struct layout *lo, struct x3g_command *c, struct st_error *err)
{
	size_t n;

	if (len < 4)
		return cut_short(err, offset, lo, 4, len);
	n = buf[3];
	if (4 + n > X3G_PAYLOAD_MAX)
		return st_error_set(err, ST_ERR_PARSE,
				    "byte %llu: tool action states a %zu-byte payload; a command holds "
				    "at most %d bytes",
				    (unsigned long long)offset, n, X3G_PAYLOAD_MAX);
	if (len < 4 + n)
		return cut_short(err, offset, lo, 4 + n, len);
	c->fields[0] = (struct x3g_field){"tool", buf[1]};
	c->fields[1] = (struct x3g_field){"action", buf[2]};
	c->fields[2] = (struct x3g_field){"length", (double)n};
	c->nfields = 3;
	if (n == 1)
		c->fields[c->nfields++] = (struct x3g_field){"value", buf[4]};
	else if (n == 2)
		c->fields[c->nfields++] =
		    (struct x3g_field){"value", (double)(int16_t)(uint16_t)get_le(buf + 4, 2)};
	return (int)(4 + n);
}

int x3g_decode(const uint8_t *buf, size_t len, uint64_t offset, struct x3g_command *cmd,
	       struct st_error *err)
{
	struct x3g_command c;
	const struct layout *lo;
	size_t pos = 1;
	int rc;

	if (len == 0)
		return 0;
	if (!buf || !cmd)
		return st_error_set(err, ST_ERR_ARG, "x3g_decode: no buffer or no command");
	lo = find_layout(buf[0]);
	if (!lo)
		return st_error_set(err, ST_ERR_PARSE,
				    "byte %llu: %u is not an X3G action command (expected 129-158)",
				    (unsigned long long)offset, buf[0]);
	memset(&c, 0, sizeof(c));
	c.code = lo->code;
	c.name = lo->name;
	c.offset = offset;
	if (lo->code == 136) {
		rc = decode_tool_action(buf, len, offset, lo, &c, err);
		if (rc < 0)
			return rc;
		pos = (size_t)rc;
	}
	for (const char *ty = lo->types; *ty; ty++) {
		size_t k = (size_t)(ty - lo->types);

		if (*ty == 'z') {
			const uint8_t *nul;
			size_t room = len - pos;

			if (room > X3G_PAYLOAD_MAX - pos)
				room = X3G_PAYLOAD_MAX - pos;
			nul = memchr(buf + pos, 0, room);
			if (!nul) {
				if (len - pos <= room)
					return cut_short(err, offset, lo, pos + 1, len);
				return st_error_set(err, ST_ERR_PARSE,
						    "byte %llu: command %u (%s) has text without its "
						    "NUL within %d bytes",
						    (unsigned long long)offset, lo->code, lo->name,
						    X3G_PAYLOAD_MAX);
			}
			memcpy(c.text, buf + pos, (size_t)(nul - (buf + pos)));
			c.text[nul - (buf + pos)] = 0;
			c.has_text = true;
			pos = (size_t)(nul - buf) + 1;
			continue;
		}
		{
			int n = *ty == '1' ? 1 : *ty == '2' ? 2 : 4;
			double v;

			/* name the whole command's length, not the field's */
			if (len - pos < (size_t)n)
				return cut_short(err, offset, lo, pos + fixed_span(ty), len);
			if (*ty == 'i') {
				v = (double)(int32_t)get_le(buf + pos, 4);
			} else if (*ty == 'f') {
				uint32_t u = get_le(buf + pos, 4);
				float f;

				memcpy(&f, &u, sizeof(f));
				v = f;
			} else {
				v = get_le(buf + pos, n);
			}
			c.fields[c.nfields++] = (struct x3g_field){lo->fields[k], v};
			pos += (size_t)n;
		}
	}
	c.length = pos;
	*cmd = c;
	return (int)pos;
}

bool x3g_field_value(const struct x3g_command *cmd, const char *name, double *value)
{
	for (size_t i = 0; i < cmd->nfields; i++)
		if (!strcmp(cmd->fields[i].name, name)) {
			*value = cmd->fields[i].value;
			return true;
		}
	return false;
}

int x3g_format(const struct x3g_command *cmd, char *out, size_t cap)
{
	int n = snprintf(out, cap, "%u %s:", cmd->code, cmd->name), total = n;

	for (size_t i = 0; i < cmd->nfields && n >= 0; i++) {
		size_t used = (size_t)total < cap ? (size_t)total : cap;

		n = snprintf(out + used, cap - used, " %s=%.9g", cmd->fields[i].name,
			     cmd->fields[i].value);
		total += n;
	}
	if (cmd->has_text && n >= 0) {
		size_t used = (size_t)total < cap ? (size_t)total : cap;

		n = snprintf(out + used, cap - used, " text=\"%s\"", cmd->text);
		total += n;
	}
	return total;
}

void x3g_build_name(const char *path, char *name, size_t cap)
{
	const char *base = strrchr(path, '/'), *dot;
	size_t n;

	base = base ? base + 1 : path;
	dot = strrchr(base, '.');
	n = dot && dot != base ? (size_t)(dot - base) : strlen(base);
	snprintf(name, cap, "%.*s", (int)n, base);
}
