/*
 * fuzz_nodeconfig.c - the farm node's config reader (node_config_load,
 * host/serve/config.c) on an arbitrary file, and node_parse_listen on its
 * first line.
 */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fuzz.h"
#include "node.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	static struct node_config cfg; /* large: not on the stack */
	static char path[300];
	struct st_error err = {0};
	FILE *f;

	if (!path[0])
		snprintf(path, sizeof(path), "%s/node.ini", fuzz_tmpdir());
	f = fopen(path, "wb");
	if (!f || fwrite(data, 1, size, f) != size || fclose(f))
		return 0;
	(void)node_config_load(path, &cfg, &err);
	{
		char line[128], addr[64];
		size_t n = size < sizeof(line) - 1 ? size : sizeof(line) - 1;
		uint16_t port;

		memcpy(line, data, n);
		line[n] = '\0';
		(void)node_parse_listen(line, addr, sizeof(addr), &port, &err);
	}
	return 0;
}
