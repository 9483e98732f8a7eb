/*
 * fuzz_gcode_reader.c - the G-code file reader (gcode_reader_next,
 * serial/gcode.h) over an arbitrary file: long lines, NUL bytes, CR
 * endings, no final newline, and on past a bad line as callers do.
 */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "gcode.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	struct st_error err = {0};
	struct gcode_reader *r;
	struct gcode_line g;
	FILE *f;
	int rc;

	if (!size)
		return 0; /* fmemopen refuses an empty buffer */
	f = fmemopen((void *)data, size, "rb");
	if (!f)
		return 0;
	if (!gcode_reader_new(f, "fuzz.gcode", &r, &err)) {
		while ((rc = gcode_reader_next(r, 0, &g, &err)) != 0)
			if (rc < 0 && rc != ST_ERR_PARSE)
				break;
		gcode_reader_free(r);
	}
	fclose(f);
	return 0;
}
