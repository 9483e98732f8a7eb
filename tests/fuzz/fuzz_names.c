/*
 * fuzz_names.c - the node's upload name checks (host/serve/names.c): any
 * bytes, NUL included, as a file name.
 */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "node.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	struct st_error err = {0};
	char name[300];

	if (node_check_file_name((const char *)data, size, &err) || size >= sizeof(name))
		return 0;
	/* what passed has no NUL byte: it is a C string as stored */
	memcpy(name, data, size);
	name[size] = '\0';
	if (strlen(name) != size)
		__builtin_trap();
	(void)node_file_kind(name);
	return 0;
}
