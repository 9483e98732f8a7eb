/*
 * clitest.c - the helpers of clitest.h.
 */
#include <check.h>
#include <jansson.h>
#include <stdint.h>
#include <string.h>

#include "clitest.h"
#include "meshio.h"
#include "testutil.h"

/* Write m to a scratch file as binary STL and return its path. */
const char *write_mesh(struct mesh *m, const char *name)
{
	const char *path = tu_path(name);
	struct st_error err = {0};

	ck_assert_msg(meshio_write_stl(path, m, MESHIO_STL_BINARY, &err) == 0, "%s", err.msg);
	mesh_free(m);
	return path;
}

/* Run `check --json` on path, expect the exit status, return the parsed report. */
json_t *check_json(const char *path, int want_status)
{
	json_error_t jerr;
	json_t *o;
	static char out[1 << 16];
	int status = tu_run(out, sizeof(out), "check --json '%s'", path);

	ck_assert_msg(status == want_status, "exit %d, wanted %d: %s", status, want_status, out);
	o = json_loads(out, 0, &jerr);
	ck_assert_msg(o != NULL, "not JSON (%s): %s", jerr.text, out);
	return o;
}

json_int_t field(json_t *o, const char *key)
{
	json_t *v = json_object_get(o, key);

	ck_assert_msg(json_is_integer(v), "field %s missing or not an integer", key);
	return json_integer_value(v);
}

int has_reason(json_t *o, const char *list, const char *code)
{
	json_t *arr = json_object_get(o, list), *item;
	size_t i;

	json_array_foreach(arr, i, item)
		if (!strcmp(json_string_value(json_object_get(item, "code")), code))
			return 1;
	return 0;
}

/* An 84-byte binary STL header announcing n facets. */
void binary_header(unsigned char *buf, uint32_t n)
{
	memset(buf, ' ', 80);
	memcpy(buf, "generated", 9);
	for (int i = 0; i < 4; i++)
		buf[80 + i] = (unsigned char)(n >> (8 * i));
}
