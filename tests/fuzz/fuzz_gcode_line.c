/*
 * fuzz_gcode_line.c - one G-code line (gcode_parse, serial/gcode.h) and the
 * helpers a caller uses on a parsed line, with and without
 * GCODE_PARSE_KEEP_BAD_CHECKSUM.
 */
#include <stddef.h>
#include <stdint.h>

#include "gcode.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	const char *text = (const char *)data;

	for (unsigned flags = 0; flags < 2; flags++) {
		struct st_error err = {0};
		struct gcode_line g;
		double v, z;
		long layer;

		if (gcode_parse(text, size, flags ? GCODE_PARSE_KEEP_BAD_CHECKSUM : 0, &g, &err))
			continue;
		for (char c = 'A'; c <= 'Z'; c++)
			(void)gcode_word_value(&g, c, &v);
		(void)gcode_layer_comment(&g, &layer, &z);
	}
	(void)gcode_read_number(text, size, &(double){0}, NULL);
	return 0;
}
