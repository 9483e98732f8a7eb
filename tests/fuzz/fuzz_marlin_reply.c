/*
 * fuzz_marlin_reply.c - Marlin reply classification (marlin_parse_reply,
 * serial/marlin.h) line by line, each line in a heap block of its own exact
 * length: the contract is (line, len) without a NUL, and ASan sees a read
 * past len.
 */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "marlin.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	struct marlin_status st;
	struct marlin_caps caps;

	memset(&st, 0, sizeof(st));
	memset(&caps, 0, sizeof(caps));
	for (size_t at = 0; at < size;) {
		const uint8_t *nl = memchr(data + at, '\n', size - at);
		size_t len = nl ? (size_t)(nl - (data + at)) : size - at;
		char *line = malloc(len ? len : 1);
		struct marlin_reply r;

		if (!line)
			return 0;
		memcpy(line, data + at, len);
		(void)marlin_parse_reply(line, len, &r, &st, &caps);
		(void)marlin_parse_reply(line, len, &r, NULL, NULL);
		free(line);
		at += len + 1;
	}
	return 0;
}
