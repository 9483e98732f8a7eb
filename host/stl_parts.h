/*
 * stl_parts.h - `stratum repair`'s output: a mesh written as STL, one file,
 * or with --split one file per manifold-connected part, OUT "dir/part.stl"
 * giving dir/part-1.stl, dir/part-2.stl ... (docs/repair.md).  No file is
 * the input: each part is checked against it just before it is written.
 */
#ifndef STRATUM_HOST_STL_PARTS_H
#define STRATUM_HOST_STL_PARTS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "mesh.h"
#include "meshio.h"

/* The files written, in order (for the report). */
struct stl_outputs {
	char **path;
	size_t count;
};

void stl_outputs_free(struct stl_outputs *o);

/*
 * stl_input_is_a_part - whether in is named like one of the files a split
 * of out makes ("dir/part-K.stl"), in the same directory however either is
 * spelled.
 */
bool stl_input_is_a_part(const char *in, const char *out);

/*
 * stl_write_outputs - write m to out as fmt (MESHIO_STL_BINARY or
 * MESHIO_STL_ASCII): one file, or with split and ncomp > 1 one file per
 * part, component[t] naming triangle t's part (0 .. ncomp-1).  Returns 0,
 * or the exit status (st_error.h) with the reason in msg; o lists what was
 * written, also when a later part failed.  input is never overwritten.
 */
int stl_write_outputs(const char *input, const char *out, const struct mesh *m,
		      const uint32_t *component, size_t ncomp, bool split,
		      enum meshio_format fmt, struct stl_outputs *o, char *msg, size_t cap);

#endif /* STRATUM_HOST_STL_PARTS_H */
