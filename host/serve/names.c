/*
 * names.c - which uploaded file names the node stores (node.h).  Names are
 * refused, not rewritten, so what the slicer shows is what the node keeps.
 */
#include <ctype.h>
#include <jansson.h>
#include <string.h>

#include "commands.h"
#include "node.h"

int node_check_file_name(const char *name, size_t len, struct st_error *err)
{
	if (!len)
		return st_error_set(err, ST_ERR_PARSE, "the file name is empty");
	if (len > NODE_FILE_NAME_MAX)
		return st_error_set(err, ST_ERR_PARSE, "the file name has %zu bytes; at most %d",
				    len, NODE_FILE_NAME_MAX);
	if (name[0] == '.')
		return st_error_set(err, ST_ERR_PARSE, "the file name starts with '.' (hidden "
						       "files and '..' are refused)");
	if (name[0] == ' ' || name[len - 1] == ' ')
		return st_error_set(err, ST_ERR_PARSE, "the file name starts or ends with a blank");
	for (size_t i = 0; i < len; i++) {
		unsigned char c = (unsigned char)name[i];

		if (c == '/' || c == '\\')
			return st_error_set(err, ST_ERR_PARSE, "the file name contains '%c' at byte "
							       "%zu; give a name without folders",
					    c, i);
		if (c < 0x20 || c == 0x7f)
			return st_error_set(err, ST_ERR_PARSE, "the file name contains the control "
							       "byte 0x%02x at byte %zu", c, i);
	}
	/* The API lists names as JSON strings, which must be UTF-8 (jansson's check). */
	{
		json_t *s = json_stringn(name, len);

		if (!s)
			return st_error_set(err, ST_ERR_PARSE, "the file name is not valid UTF-8");
		json_decref(s);
	}
	return 0;
}

char node_file_kind(const char *name)
{
	if (cmd_has_ext(name, ".gcode") || cmd_has_ext(name, ".gco") || cmd_has_ext(name, ".g"))
		return 'g';
	if (cmd_has_ext(name, ".stl") || cmd_has_ext(name, ".obj") || cmd_has_ext(name, ".off") ||
	    cmd_has_ext(name, ".3mf"))
		return 'm';
	if (cmd_has_ext(name, ".x3g"))
		return 'x';
	return 0;
}
