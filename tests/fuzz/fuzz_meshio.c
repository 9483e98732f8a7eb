/*
 * fuzz_meshio.c - the mesh readers (binary and ASCII STL, OBJ, OFF;
 * repair/meshio.h) on arbitrary bytes: once detected from the content, as
 * `stratum check` reads a file, and once with one reader forced (by the
 * size, so every reader sees every input family).
 */
#include <stddef.h>
#include <stdint.h>

#include "mesh.h"
#include "meshio.h"

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
	return 0;
}
