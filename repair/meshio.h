/*
 * meshio.h - reading and writing mesh files.
 *
 * Readers: binary and ASCII STL (told apart by size arithmetic, not by the
 * "solid" prefix), Wavefront OBJ and OFF (polygons fan-triangulated), and
 * 3MF (a zip of XML parts: every build item placed through its transforms
 * and the model's unit, all items in one mesh; docs/repair.md).  Input
 * is untrusted: every count is checked against the file size, every token is
 * bounded, NaN/Inf are rejected, and a failure fills err with one sentence
 * naming the file and the byte offset (binary) or line (text), for 3MF the
 * zip entry and its XML line.
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
	MESHIO_3MF,
};

/* What a read found besides the mesh. */
struct meshio_info {
	enum meshio_format format; /* the format that was read */
	size_t items;		   /* 3MF build items placed; 1 for the other formats */
	size_t skipped_items;	   /* 3MF items left out: printable="0", support or surface */
	size_t meshes;		   /* mesh instances placed (components count each); 1 otherwise */
	size_t objects;		   /* 3MF <object> resources defined; 1 otherwise */
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
 * meshio_read_info, meshio_read_buffer_info - meshio_read and
 * meshio_read_buffer that fill *info (may be NULL) on success.  For 3MF
 * also ST_ERR_RANGE (the zip unpacks to more than 2 GiB, components nest
 * too deep, the build places more than 2^27 triangles) and
 * ST_ERR_UNSUPPORTED (the file requires a 3MF extension we do not read).
 */
int meshio_read_info(const char *path, enum meshio_format fmt, struct mesh **out,
		     struct meshio_info *info, struct st_error *err);
int meshio_read_buffer_info(const void *buf, size_t len, const char *name,
			    enum meshio_format fmt, struct mesh **out,
			    struct meshio_info *info, struct st_error *err);

#define MESHIO_3MF_CONFIG_ENTRY "Metadata/Slic3r_PE.config" /* PrusaSlicer's, in a 3MF */

/*
 * meshio_3mf_config - the text of Metadata/Slic3r_PE.config (PrusaSlicer's
 * print, filament and printer settings) inside the 3MF at path: *text gets
 * a malloc'd NUL-terminated copy (caller frees), or NULL when the file has
 * none.  Returns 0, ST_ERR_IO, ST_ERR_PARSE (not a zip, bad entry),
 * ST_ERR_RANGE (more than 16 MiB), ST_ERR_NOMEM; *text is NULL on error.
 */
int meshio_3mf_config(const char *path, char **text, struct st_error *err);

/* The layer height profiles of PrusaSlicer's variable layer height tool. */
#define MESHIO_3MF_LAYER_PROFILE_ENTRY "Metadata/Slic3r_PE_layer_heights_profile.txt"

/*
 * meshio_3mf_layer_profile - the layer height profile the 3MF at path keeps
 * for its object number `object` (1 = the first, as PrusaSlicer numbers
 * them): *zh gets 2 * *pairs doubles, (z, layer height) in mm, z from the
 * object's bottom, rising; NULL and 0 when there is none for that object.
 * *profiles (may be NULL) gets how many objects have one.  Each line of the
 * entry is `object_id=N|z;h;z;h;...`.  Returns 0, ST_ERR_IO, ST_ERR_PARSE
 * (not a zip; a line not of that form, z not rising, a height not > 0: the
 * message names the entry and the line), ST_ERR_RANGE (more than 16 MiB),
 * ST_ERR_NOMEM; *zh is NULL on error.
 */
int meshio_3mf_layer_profile(const char *path, size_t object, double **zh, size_t *pairs,
			     size_t *profiles, struct st_error *err);

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
