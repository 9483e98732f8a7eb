/*
 * fuzz_x3g_translate.c - G-code file to X3G (serial/x3g.h) as `stratum x3g`
 * does it: the reader's lines through the translator for the Creator Pro
 * machine, both flavours (first byte), to the end of the build; every
 * command written must decode again.
 */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "gcode.h"
#include "x3g.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* Every byte the translator wrote decodes as whole commands. */
static void check_output(const struct x3g_translator *t)
{
	size_t len;
	const uint8_t *out = x3g_output(t, &len);

	for (size_t at = 0; at < len;) {
		struct x3g_command cmd;
		struct st_error err = {0};
		int n = x3g_decode(out + at, len - at, at, &cmd, &err);

		if (n <= 0)
			__builtin_trap();
		at += (size_t)n;
	}
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	struct x3g_options opt = {.flavor = X3G_FLAVOR_REPRAP, .build_name = "fuzz"};
	struct st_error err = {0};
	struct x3g_translator *t;
	struct gcode_reader *r;
	struct x3g_machine m;
	struct gcode_line g;
	uint64_t lineno = 0;
	FILE *f;
	int rc;

	if (size < 2)
		return 0;
	if (data[0] & 1)
		opt.flavor = X3G_FLAVOR_MAKERBOT;
	x3g_machine_fcp(&m);
	if (data[0] & 2)
		m.extruder_count = 2;
	if (x3g_new(&m, &opt, &t, &err))
		return 0;
	f = fmemopen((void *)(data + 1), size - 1, "rb");
	if (!f)
		goto out_free;
	if (!gcode_reader_new(f, "fuzz.gcode", &r, &err)) {
		while ((rc = gcode_reader_next(r, 0, &g, &err)) != 0) {
			lineno++;
			if (rc < 0) {
				if (rc != ST_ERR_PARSE)
					break;
				continue;
			}
			if (x3g_translate(t, &g, lineno, &err) < 0)
				break;
			check_output(t);
		}
		if (x3g_finish(t, &err) >= 0)
			check_output(t);
		gcode_reader_free(r);
	}
	fclose(f);
out_free:
	x3g_free(t);
	return 0;
}
