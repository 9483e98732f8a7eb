/*
 * sliceclitest.c - the helpers of sliceclitest.h.
 */
#include <check.h>

#include "mesh.h"
#include "meshio.h"
#include "sliceclitest.h"
#include "testutil.h"

const char *stl_file(struct mesh *m, const char *name)
{
	const char *path = tu_path(name);
	struct st_error err = {0};
	int rc = meshio_write_stl(path, m, MESHIO_STL_BINARY, &err);

	mesh_free(m);
	ck_assert_msg(rc == 0, "%s", err.msg);
	return path;
}
