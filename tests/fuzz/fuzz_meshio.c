/*
 * fuzz_meshio.c - the mesh readers (binary and ASCII STL, OBJ, OFF;
 * repair/meshio.h) on arbitrary bytes: once detected from the content, as
 * `stratum check` reads a file, and once with one reader forced (by the
 * size, so every reader sees every input family); and as the text of a
 * 3MF's layer height profile (repair/threemf_profile.c), whose zip entry
 * the 3MF reader hands it.
 */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "mesh.h"
#include "meshio.h"
#include "meshio_impl.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	static const enum meshio_format forced[] = {MESHIO_STL_BINARY, MESHIO_STL_ASCII,
						    MESHIO_OBJ, MESHIO_OFF};
	struct st_error err = {0};
	struct mesh *m = NULL;
	enum meshio_format detected;

	if (!meshio_read_buffer(data, size, "fuzz", MESHIO_AUTO, &m, &detected, &err))
		mesh_free(m);
	m = NULL;
	if (!meshio_read_buffer(data, size, "fuzz", forced[size % 4], &m, &detected, &err))
		mesh_free(m);

	char *text = malloc(size + 1);
	struct mio_src src = {.name = "fuzz", .err = &err};
	double *zh = NULL;
	size_t pairs, profiles;

	if (!text)
		return 0;
	memcpy(text, data, size);
	text[size] = '\0';
	if (!threemf_parse_layer_profile(&src, text, 1 + size % 3, &zh, &pairs, &profiles))
		free(zh);
	free(text);
	return 0;
}
