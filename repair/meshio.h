/*
 * meshio.h - reading and writing mesh files.
 *
 * Readers: binary and ASCII STL (told apart by size arithmetic, not by the
 * "solid" prefix), Wavefront OBJ and OFF (polygons fan-triangulated).  Input
 * is untrusted: every count is checked against the file size, every token is
 * bounded, NaN/Inf are rejected, and a failure fills err with one sentence
 * naming the file and the byte offset (binary) or line (text).
 *
 * Writers go to a temporary file in the target's directory, check every
 * write, fsync and rename, so a failure never leaves a partial file.
 */
#ifndef STRATUM_REPAIR_MESHIO_H
#define STRATUM_REPAIR_MESHIO_H

#include <stddef.h>

#include "mesh.h"
#include "st_error.h"

enum meshio_format {
	MESHIO_AUTO,	   /* decide from content, then extension */
	MESHIO_STL_BINARY,
	MESHIO_STL_ASCII,
	MESHIO_OBJ,
	MESHIO_OFF,
};

/*
 * meshio_read - read path into a new mesh (*out, caller frees with
 * mesh_free).  fmt MESHIO_AUTO detects the format.  Returns 0, or
 * ST_ERR_IO (cannot open/read), ST_ERR_PARSE (malformed, truncated, empty,
 * NaN/Inf, absurd counts), ST_ERR_NOMEM; *out is NULL on error.
 * *detected (may be NULL) receives the format that was read.
 */
int meshio_read(const char *path, enum meshio_format fmt, struct mesh **out,
		enum meshio_format *detected, struct st_error *err);

/*
 * meshio_read_buffer - as meshio_read but from memory; name is used in
 * messages only.  Same errors.
 */
int meshio_read_buffer(const void *buf, size_t len, const char *name,
		       enum meshio_format fmt, struct mesh **out,
		       enum meshio_format *detected, struct st_error *err);

/*
 * meshio_write_stl - write m as binary (fmt MESHIO_STL_BINARY) or ASCII
 * (MESHIO_STL_ASCII) STL, atomically.  Normals are computed from the vertex
 * order.  Returns 0, ST_ERR_IO (target untouched), ST_ERR_ARG, ST_ERR_RANGE
 * (more than 2^32-1 triangles for binary).
 */
int meshio_write_stl(const char *path, const struct mesh *m, enum meshio_format fmt,
		     struct st_error *err);

/* Human name of a format ("binary STL"). */
const char *meshio_format_name(enum meshio_format fmt);

#endif /* STRATUM_REPAIR_MESHIO_H */
