/*
 * fuzz_x3g_decode.c - the X3G decoder (x3g_decode, serial/x3g.h) over an
 * arbitrary file, command after command as `stratum x3g --decode` reads
 * it, each one formatted and its fields looked up.
 */
#include <stddef.h>
#include <stdint.h>

#include "x3g.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	for (size_t at = 0; at < size;) {
		struct x3g_command cmd;
		struct st_error err = {0};
		char text[1024];
		double v;
		int n = x3g_decode(data + at, size - at, at, &cmd, &err);

		if (n <= 0)
			break;
		if ((size_t)n > size - at)
			__builtin_trap(); /* the contract: a command within the buffer */
		(void)x3g_format(&cmd, text, sizeof(text));
		(void)x3g_format(&cmd, text, 8);
		(void)x3g_field_value(&cmd, "x", &v);
		(void)x3g_field_value(&cmd, "temperature", &v);
		at += (size_t)n;
	}
	return 0;
}
